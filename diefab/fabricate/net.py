"""Paper nets of designs: the glue between a :class:`~diefab.design.Design` and the net renderers.

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

from ..design import Design
from ..errors import FabricationError
from .unfold import TAB_WIDTH, Net, Page, parse_page, unfold

__all__ = ["FORMATS", "design_net", "parse_formats", "render_net", "size_note"]

FORMATS = ("svg", "pdf", "png")


def size_note(design: Design) -> str:
    """What ``size_mm`` measures on this design."""
    from ..families import family

    return f"size = {family(design.family).reference}"


def corner_labels(design: Design) -> list[tuple[str, str, tuple[int, ...]]]:
    """Values read at a vertex or an edge that points up: (face, text, vertices) for every face around it.

    A die the readings cannot read gets none (its face labels are still printed).  A hand-set label
    on the face a value would sit on (``[labels]``) replaces it: the paper's gem keeps its apex blank.
    """
    from ..errors import DesignError

    try:
        marks = design.markings
    except DesignError:
        return []
    return [(m.face, m.text, m.at) for m in marks if m.at and m.face not in design.labels]


def parse_formats(spec: str) -> tuple[str, ...]:
    """``"svg,pdf"`` -> ``("svg", "pdf")``; unknown names raise FabricationError."""
    items = tuple(dict.fromkeys(s.strip().lower() for s in str(spec).split(",") if s.strip()))
    if not items:
        raise FabricationError(f"--format {spec!r} names no format (choose from {', '.join(FORMATS)})")
    for item in items:
        if item not in FORMATS:
            raise FabricationError(f"unknown format {item!r} in --format {spec!r} (choose from {', '.join(FORMATS)})")
    return items


def design_net(
    design: Design, *, size_mm: float | None = None, page: Page | str = "A4", tab_width: float = TAB_WIDTH
) -> Net:
    """The net of `design` at `size_mm` (default: the design's size) on `page`."""
    size = design.size_mm if size_mm is None else size_mm
    if not (isinstance(size, (int, float)) and math.isfinite(size) and size > 0):
        raise FabricationError(f"size {size} mm must be a positive number of millimetres")
    scale = design.mm_per_unit * size / design.size_mm
    page = parse_page(page) if isinstance(page, str) else page
    return unfold(design.polyhedron, scale, page=page, tab_width=tab_width, size_mm=size)


def render_net(design: Design, net: Net, formats=("svg", "pdf"), *, face_names: bool = False) -> dict[str, bytes]:
    """Render `net` in each format: ``{"svg": bytes, "pdf": bytes, "png": bytes}``."""
    from .sheet import layout_sheets

    size = net.mm_per_unit * design.size_mm / design.mm_per_unit
    sheets = layout_sheets(
        net, name=design.name, size_mm=round(size, 3), size_note=size_note(design), labels=design.label_of,
        face_names=face_names, corners=corner_labels(design),
    )  # fmt: skip
    out: dict[str, bytes] = {}
    for fmt in formats:
        if fmt == "svg":
            from .svg import render_svg

            out[fmt] = render_svg(sheets).encode("utf-8")
        elif fmt == "pdf":
            from .pdf import render_pdf

            out[fmt] = render_pdf(sheets)
        elif fmt == "png":
            from .pdf import render_png

            out[fmt] = render_png(sheets)
        else:
            raise FabricationError(f"unknown format {fmt!r} (choose from {', '.join(FORMATS)})")
    return out
