"""What goes on each printed page of a net: shapes, lines and placed text, in mm.

:func:`layout_sheets` turns a :class:`~diefab.fabricate.unfold.Net` into one
:class:`Sheet` per page; the SVG and PDF renderers draw the same sheets, so
both outputs carry the same labels in the same places.  Text is upright on
the page, sized to fit inside its face (centred on the pole of
inaccessibility of the face minus the room taken by edge labels), and a
label that reads as another number upside down (6, 9, 16, ...) is underlined.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .unfold import Net

__all__ = ["Sheet", "Text", "layout_sheets", "needs_underline", "text_width"]

#: Advance widths of DejaVu Sans (the font both renderers use), in em.
_ADVANCE = {
    **dict.fromkeys("0123456789", 0.636),
    "+": 0.838,
    "\u2212": 0.838,
    "-": 0.361,
    " ": 0.318,
    ".": 0.318,
    "d": 0.635,
    "f": 0.352,
    "F": 0.575,
    "m": 0.974,
    "i": 0.278,
    "l": 0.278,
}
#: Cap height of DejaVu Sans, em.
CAP = 0.729
FONT = "DejaVu Sans"
MAX_FACE_TEXT = 14.0
EDGE_TEXT = 2.6
INFO_TEXT = 3.0
_ROTATED = {"0": "0", "1": "1", "6": "9", "8": "8", "9": "6"}


@dataclass(frozen=True)
class Text:
    """Text centred at (x, y) (cap-height centre), `size` = font size in mm."""

    x: float
    y: float
    size: float
    text: str
    kind: str  # face, corner, name, tab, edge, info
    underline: bool = False
    anchor: str = "middle"

    @property
    def baseline(self) -> float:
        return self.y + CAP * self.size / 2


@dataclass
class Sheet:
    """One page: width, height (mm) and what is drawn on it."""

    width: float
    height: float
    number: int
    pages: int
    faces: list[tuple[str, np.ndarray]] = field(default_factory=list)
    tabs: list[tuple[str, np.ndarray]] = field(default_factory=list)
    cut: list[np.ndarray] = field(default_factory=list)
    fold: list[np.ndarray] = field(default_factory=list)
    texts: list[Text] = field(default_factory=list)
    legend: list[tuple[str, np.ndarray]] = field(default_factory=list)  # (style, segment): cut/fold/bar


def text_width(text: str, size: float) -> float:
    """Width of `text` at font size `size` (mm) in DejaVu Sans."""
    return size * sum(_ADVANCE.get(ch, 0.68 if ch.isupper() else 0.6) for ch in text)


def needs_underline(text: str) -> bool:
    """True if `text` reads as a different number upside down (6, 9, 16, 91, ...).

    >>> [needs_underline(t) for t in ("6", "9", "69", "8", "+6", "16")]
    [True, True, False, False, False, True]
    """
    if not text or not all(ch in _ROTATED for ch in text):
        return False
    return "".join(_ROTATED[ch] for ch in reversed(text)) != text


def _box(cx, cy, w, h):
    from shapely.geometry import box

    return box(cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2)


def _fit_text(region, text: str, max_size: float, extra=None):
    """Largest font size (<= max_size) and centre at which `text` fits inside `region`.

    `extra` = (text, ratio): a second line (the face name) under the first at
    `ratio` of its size.  Returns (size, x, y) or None.
    """
    from shapely.geometry import Polygon
    from shapely.ops import polylabel

    if region.is_empty:
        return None
    if region.geom_type != "Polygon":
        region = max(getattr(region, "geoms", []), key=lambda g: g.area, default=None)
        if region is None or not isinstance(region, Polygon):
            return None
    centre = polylabel(region, tolerance=0.05)
    cx, cy = centre.x, centre.y
    size = max_size
    while size > 0.8:
        w, h = text_width(text, size), CAP * size
        if extra:
            w = max(w, text_width(extra[0], size * extra[1]))
            h = h + CAP * size * extra[1] * 1.6
        if region.contains(_box(cx, cy, w, h)):
            return size, cx, cy
        size *= 0.92
    return None


def layout_sheets(net: Net, *, name: str, size_mm: float, size_note: str, labels: dict[str, str], face_names=False,
                  corners=()):  # fmt: skip
    """One :class:`Sheet` per page of `net`.

    Parameters
    ----------
    name : design name, printed in the footer.
    size_mm : the die's size; size_note says what it measures.
    labels : face name -> text printed on it (``Design.label_of``).
    face_names : print the small face names (f1, f2, ...) too.
    corners : (face name, text, vertices) triples: text in a face's corner at
        one vertex, or beside one edge (two vertices), for values read at a
        vertex or an edge that points up (:attr:`Design.markings`).
    """
    from shapely.geometry import Polygon, box

    page = net.page
    sheets = [Sheet(page.width, page.height, k + 1, net.n_pages) for k in range(net.n_pages)]
    names = net.poly.names
    tab_of = {t.edge: t for t in net.tabs}
    for k, poly in enumerate(net.faces):
        sheets[net.face_page[k]].faces.append((names[k], poly))
    for t in net.tabs:
        sheets[t.page].tabs.append((t.label, t.polygon))
    for kind, items in net.lines().items():
        for pg, seg in items:
            getattr(sheets[pg], kind).append(seg)

    # edge labels on the copy without the tab, just inside the face
    occupied: dict[int, list] = {k: [] for k in range(len(net.faces))}
    for k, poly in enumerate(net.faces):
        sheet = sheets[net.face_page[k]]
        for i, e in enumerate(net.face_edges(k)):
            tab = tab_of.get(e)
            if tab is None or tab.face == k:
                continue
            p, q = poly[i], poly[(i + 1) % len(poly)]
            length = float(np.hypot(*(q - p)))
            size = min(EDGE_TEXT, 0.3 * length)
            w, h = text_width(tab.label, size), CAP * size
            centroid = poly.mean(axis=0)
            mid = (p + q) / 2
            normal = np.array([-(q - p)[1], (q - p)[0]]) / length
            if normal @ (centroid - mid) < 0:
                normal = -normal
            reach = 0.5 * (abs(normal[0]) * w + abs(normal[1]) * h) + 0.5
            at = mid + normal * reach
            sheet.texts.append(Text(float(at[0]), float(at[1]), size, tab.label, "edge"))
            occupied[k].append(_box(at[0], at[1], w + 0.6, h + 0.6))
    for t in net.tabs:
        region = Polygon(t.polygon).buffer(-0.3)
        fit = _fit_text(region, t.label, EDGE_TEXT)
        if fit:
            sheets[t.page].texts.append(Text(fit[1], fit[2], fit[0], t.label, "tab"))

    # values read at a vertex or an edge: small text in that corner or beside that edge
    names_index = {n: k for k, n in enumerate(names)}
    for face, text, at in corners:
        k = names_index[face]
        ring = [int(v) for v in net.poly.faces[k]]
        poly = net.faces[k]
        anchor = np.mean([poly[ring.index(v)] for v in at], axis=0)
        centroid = poly.mean(axis=0)
        reach = float(np.hypot(*(centroid - anchor)))
        size = min(MAX_FACE_TEXT / 3, 0.35 * reach)
        at_xy = anchor + (centroid - anchor) * (0.45 if len(at) == 1 else 0.35)
        w, h = text_width(text, size), CAP * size
        sheets[net.face_page[k]].texts.append(
            Text(float(at_xy[0]), float(at_xy[1]), size, text, "corner", needs_underline(text))
        )
        occupied[k].append(_box(at_xy[0], at_xy[1], w + 0.6, h + 0.6))

    # face labels
    for k, poly in enumerate(net.faces):
        sheet = sheets[net.face_page[k]]
        region = Polygon(poly).buffer(-0.8)
        for b in occupied[k]:
            region = region.difference(b)
        text = labels.get(names[k], "")
        extra = (names[k], 0.28) if face_names else None
        if not text and face_names:
            text, extra = names[k], None
        if not text:
            continue
        fit = _fit_text(region, text, MAX_FACE_TEXT, extra)
        if fit is None:
            continue
        size, cx, cy = fit
        if extra:
            small = size * extra[1]
            block = CAP * size + CAP * small * 1.6
            top = cy - block / 2
            sheet.texts.append(Text(cx, top + CAP * size / 2, size, text, "face", needs_underline(text)))
            sheet.texts.append(Text(cx, top + block - CAP * small / 2, small, extra[0], "name"))
        else:
            sheet.texts.append(Text(cx, cy, size, text, "face", needs_underline(text)))

    # footer: title, legend, calibration bar
    for sheet in sheets:
        top = page.height - page.margin - page.footer + 3.0
        left, right = page.margin, page.width - page.margin
        pages = f"  page {sheet.number}/{sheet.pages}" if sheet.pages > 1 else ""
        title = f"{name}: {size_mm:g} mm die ({size_note}){pages}"
        sheet.texts.append(Text(left, top + 2, INFO_TEXT, title, "info", anchor="start"))
        y = top + 9
        sheet.legend.append(("cut", np.array([[left, y], [left + 10, y]])))
        sheet.texts.append(Text(left + 12, y, INFO_TEXT * 0.85, "cut", "info", anchor="start"))
        sheet.legend.append(("fold", np.array([[left + 22, y], [left + 32, y]])))
        sheet.texts.append(
            Text(left + 34, y, INFO_TEXT * 0.85, "fold (score, fold away from you)", "info", anchor="start")
        )
        sheet.tabs.append(("", np.array(box(left + 88, y - 1.6, left + 94, y + 1.6).exterior.coords)[:-1]))
        sheet.texts.append(
            Text(
                left + 96, y, INFO_TEXT * 0.85, "glue tab: goes under the edge with its letter", "info", anchor="start"
            )
        )
        bar = np.array([[right - 10, y + 2.5], [right, y + 2.5]])
        sheet.legend.append(("bar", bar))
        sheet.texts.append(Text(right - 5, y - 1.0, INFO_TEXT * 0.8, "10 mm", "info"))
    return sheets
