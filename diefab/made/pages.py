"""Pages of a net: paper sizes, and shelf packing of pieces (and of several copies) onto pages."""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from diefab.core.errors import FabricationError

__all__ = ["PAGES", "Page", "parse_page", "shelf"]

#: Page sizes in millimetres (portrait).
PAGES = {
    "A5": (148.0, 210.0),
    "A4": (210.0, 297.0),
    "A3": (297.0, 420.0),
    "LETTER": (215.9, 279.4),
    "LEGAL": (215.9, 355.6),
}
_PAGE_NAMES = {"LETTER": "Letter", "LEGAL": "Legal"}

#: Gap between pieces on a page, mm.
PIECE_GAP = 4.0


@dataclass(frozen=True)
class Page:
    """A sheet of paper: size and margins in millimetres.

    The footer band (title, legend, calibration bar) sits inside the bottom
    margin area and is not available to the net.
    """

    name: str
    width: float
    height: float
    margin: float = 10.0
    footer: float = 17.0

    @property
    def printable(self) -> tuple[float, float]:
        """Width and height available to the net, mm."""
        return self.width - 2 * self.margin, self.height - 2 * self.margin - self.footer


#: Longest page side, mm: a PDF page is at most 14,400 points (200 inches) a side.
MAX_PAGE_MM = 5080.0


def parse_page(spec: str) -> Page:
    """``A5``, ``A4``, ``A3``, ``Letter``, ``Legal`` or ``WxH`` in millimetres (e.g. ``200x250``).

    >>> parse_page("letter").width
    215.9
    >>> parse_page("150x200").printable
    (130.0, 163.0)
    """
    text = str(spec).strip()
    key = text.upper()
    if key in PAGES:
        w, h = PAGES[key]
        return Page(_PAGE_NAMES.get(key, key), w, h)
    m = re.fullmatch(r"(\d+(?:\.\d+)?)\s*[xX×]\s*(\d+(?:\.\d+)?)", text)
    if not m:
        raise FabricationError(f"page {spec!r} is not A5, A4, A3, Letter, Legal or WxH in millimetres (e.g. 200x250)")
    w, h = float(m.group(1)), float(m.group(2))
    if max(w, h) > MAX_PAGE_MM:
        raise FabricationError(f"page {spec!r} is larger than {MAX_PAGE_MM:g} mm a side, the largest a PDF holds")
    page = Page(f"{w:g}x{h:g}mm", w, h)
    pw, ph = page.printable
    if pw < 20 or ph < 20:
        raise FabricationError(
            f"page {spec!r} leaves {pw:g}x{ph:g} mm inside its margins and footer; need at least 20x20 mm"
        )
    return page


def shelf(sizes, printable) -> dict[int, tuple[int, np.ndarray]]:
    """Shelf packing, tallest first: item index -> (page, offset of its box from the printable corner)."""
    placement: dict[int, tuple[int, np.ndarray]] = {}
    page_no, x, y, shelf = 0, 0.0, 0.0, 0.0
    for k in sorted(range(len(sizes)), key=lambda k: (-sizes[k][1], k)):
        w, h = sizes[k]
        if x > 0 and x + w > printable[0] + 1e-9:
            x, y, shelf = 0.0, y + shelf + PIECE_GAP, 0.0
        if y > 0 and y + h > printable[1] + 1e-9:
            page_no, x, y, shelf = page_no + 1, 0.0, 0.0, 0.0
        placement[k] = (page_no, np.array([x, y]))
        x, shelf = x + w + PIECE_GAP, max(shelf, h)
    return placement
