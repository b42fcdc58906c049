"""Paper nets of designs: the glue between a :class:`~diefab.dice.design.Design` and the net renderers.

Examples
--------
>>> from diefab import load_design
>>> design = load_design("d6")
>>> net = design_net(design)
>>> net.n_pages, len(net.tabs), sorted(render_net(design, net, ("svg",)))
(1, 7, ['svg'])
"""

from __future__ import annotations

import math
from dataclasses import replace

from diefab.core.errors import FabricationError
from diefab.dice.design import Design, design_axis, placed_marks
from diefab.dice.notes import reading_note
from diefab.made.pages import Page, parse_page
from diefab.made.tabs import TAB_WIDTH
from diefab.made.text import MARKS
from diefab.made.unfold import Net, pack_copies, unfold

__all__ = ["FORMATS", "design_net", "footer_texts", "marked_net", "parse_formats", "render_net"]

FORMATS = ("svg", "pdf", "png")


def parse_formats(spec: str) -> tuple[str, ...]:
    """``"svg,pdf"`` -> ``("svg", "pdf")``; unknown names raise FabricationError."""
    items = tuple(dict.fromkeys(s.strip().lower() for s in str(spec).split(",") if s.strip()))
    if not items:
        raise FabricationError(f"--format {spec!r} names no format (choose from {', '.join(FORMATS)})")
    for item in items:
        if item not in FORMATS:
            raise FabricationError(f"unknown format {item!r} in --format {spec!r} (choose from {', '.join(FORMATS)})")
    return items


def footer_texts(design: Design, size_mm: float) -> tuple[str, str]:
    """The footer's title and reading note for `design` at `size_mm`."""
    return f"{design.name}: {size_mm:g} mm die ({design.size_note})", reading_note(design)


def design_net(
    design: Design, *, size_mm: float | None = None, page: Page | str = "A4", tab_width: float = TAB_WIDTH
) -> Net:
    """The net of `design` at `size_mm` (default: the design's size) on `page`.

    The page's footer is made as tall as its wrapped text needs at this page width.
    """
    from diefab.fabricate.sheet import plan_footer

    size = design.size_mm if size_mm is None else size_mm
    if not (isinstance(size, (int, float)) and math.isfinite(size) and size > 0):
        raise FabricationError(f"size {size} mm must be a positive number of millimetres")
    scale = design.mm_per_unit * size / design.size_mm
    page = parse_page(page) if isinstance(page, str) else page
    plan = plan_footer(page.width, page.margin, *footer_texts(design, size))
    page = replace(page, footer=plan.height)
    if min(page.printable) < 20:
        raise FabricationError(
            f"page {page.name} leaves {page.printable[0]:g}x{page.printable[1]:g} mm for the net inside its "
            "margins and footer; need at least 20x20 mm"
        )
    return unfold(design.polyhedron, scale, page=page, tab_width=tab_width, size_mm=size)


def render_net(
    design: Design,
    net: Net,
    formats=("svg", "pdf"),
    *,
    face_names: bool = False,
    copies: int = 1,
    mark: str = "bar",
    pips: bool = False,
    markers=(),
) -> dict[str, bytes]:
    """Render `copies` copies of `net` in each format: ``{"svg": bytes, "pdf": bytes, "png": bytes}``.

    Parameters
    ----------
    mark : {"bar", "period", "none"}
        Mark on a label that reads as another label of the die upside down.
    pips : bool
        Draw value labels 1 to 9 as pips.
    markers : sequence of NetMarker
        The die's markers on `net` (:func:`~diefab.fabricate.markers.net_markers`), printed on every copy.
    """
    from diefab.fabricate.sheet import layout_sheets, plan_footer

    if mark not in MARKS:
        raise FabricationError(f"mark {mark!r} is not one of {', '.join(MARKS)}")
    size = net.mm_per_unit * design.size_mm / design.mm_per_unit
    plan = plan_footer(net.page.width, net.page.margin, *footer_texts(design, round(size, 3)))
    sheets = layout_sheets(
        pack_copies(net, copies), labels=design.label_of, axis=design_axis(design), plan=plan,
        values=[f for f in design.label_of if f not in design.labels], face_names=face_names, mark=mark, pips=pips,
        marks=placed_marks(design), markers=markers,
    )  # fmt: skip
    out: dict[str, bytes] = {}
    for fmt in formats:
        if fmt == "svg":
            from diefab.fabricate.svg import render_svg

            out[fmt] = render_svg(sheets).encode("utf-8")
        elif fmt == "pdf":
            from diefab.fabricate.pdf import render_pdf

            out[fmt] = render_pdf(sheets)
        elif fmt == "png":
            from diefab.fabricate.pdf import render_png

            out[fmt] = render_png(sheets)
        else:
            raise FabricationError(f"unknown format {fmt!r} (choose from {', '.join(FORMATS)})")
    return out


def marked_net(design: Design, net: Net, formats=("svg", "pdf"), *, markers: bool = False, **options):
    """Render `net` as :func:`render_net`, with each face's ArUco marker when `markers` (``net --markers``).

    Returns
    -------
    files : dict of str to bytes
        The rendered formats.
    placed : list of NetMarker
        The markers printed (empty without `markers`).
    """
    placed = []
    if markers:
        from diefab.fabricate.markers import net_markers

        placed = net_markers(design, net)
    return render_net(design, net, formats, markers=placed, **options), placed
