"""PDF (one page per sheet) and PNG preview of a net, drawn with matplotlib.

True scale: each figure is exactly the page size in inches (mm / 25.4) with
one axes spanning it whose data limits are the page in millimetres, so one
data unit prints as one millimetre.  Text is drawn as the sheets' font
outlines (filled paths), line widths are converted from mm to points
(x 72 / 25.4); cut lines are red and solid, score lines blue and dashed.
"""

from __future__ import annotations

import io

import numpy as np

from diefab.fabricate.sheet import Sheet
from diefab.fabricate.svg import CUT_COLOR, CUT_MM, FACE_FILL, FOLD_MM, SCORE_COLOR, TAB_FILL

__all__ = ["render_pdf", "render_png"]

PT = 72 / 25.4  # points per mm
DASH_MM = (2.5, 1.5)


def _shape_path(shape):
    """A matplotlib compound path of a shapely (Multi)Polygon, holes wound against their outline."""
    from matplotlib.path import Path
    from shapely.geometry.polygon import orient

    verts, codes = [], []
    for part in getattr(shape, "geoms", [shape]):
        if part.is_empty:
            continue
        part = orient(part, 1.0)
        for ring in (part.exterior, *part.interiors):
            pts = np.asarray(ring.coords)
            verts.extend(pts)
            codes.extend([Path.MOVETO] + [Path.LINETO] * (len(pts) - 2) + [Path.CLOSEPOLY])
    return Path(np.array(verts), codes) if verts else None


def _draw(ax, sheet: Sheet) -> None:
    from matplotlib.collections import LineCollection, PathCollection, PolyCollection

    ax.set_xlim(0, sheet.width)
    ax.set_ylim(sheet.height, 0)
    ax.set_axis_off()
    ax.add_collection(PolyCollection([p for _, p in sheet.faces], facecolors=FACE_FILL, edgecolors="none"))
    tabs = [p for _, p in sheet.tabs] + [p for style, p in sheet.legend if style == "swatch"]
    ax.add_collection(PolyCollection(tabs, facecolors=TAB_FILL, edgecolors="none"))
    dashes = (0, tuple(d * PT for d in DASH_MM))
    score = sheet.score + [s for style, s in sheet.legend if style == "score"]
    ax.add_collection(LineCollection(score, colors=SCORE_COLOR, linewidths=FOLD_MM * PT, linestyles=[dashes]))
    cut = [np.vstack([r, r[:1]]) for r in sheet.cut] + [s for style, s in sheet.legend if style == "cut"]
    ax.add_collection(LineCollection(cut, colors=CUT_COLOR, linewidths=CUT_MM * PT, joinstyle="round"))
    for style, seg in sheet.legend:
        if style == "bar":
            (x1, y), (x2, _) = seg
            bar = [[(x1, y - 1.5), (x1, y + 1.5)], [(x1, y), (x2, y)], [(x2, y - 1.5), (x2, y + 1.5)]]
            ax.add_collection(LineCollection(bar, colors="black", linewidths=0.3 * PT))
    paths = [p for p in (_shape_path(t.shape) for t in sheet.texts) if p is not None]
    ax.add_collection(PathCollection(paths, facecolors="black", edgecolors="none", transform=ax.transData))


def _figure(width_mm: float, height_mm: float):
    from matplotlib.figure import Figure

    return Figure(figsize=(width_mm / 25.4, height_mm / 25.4))


def render_pdf(sheets: list[Sheet]) -> bytes:
    """The sheets as a PDF document, one page each, at true scale."""
    from matplotlib import rc_context
    from matplotlib.backends.backend_pdf import FigureCanvasPdf, PdfPages

    buf = io.BytesIO()
    with (
        rc_context({"lines.scale_dashes": False}),
        PdfPages(buf, metadata={"Creator": "diefab"}) as pdf,
    ):
        for sheet in sheets:
            fig = _figure(sheet.width, sheet.height)
            FigureCanvasPdf(fig)
            ax = fig.add_axes((0, 0, 1, 1))
            _draw(ax, sheet)
            pdf.savefig(fig)
    return buf.getvalue()


def render_png(sheets: list[Sheet], dpi: int = 150) -> bytes:
    """A preview: every page side by side, as PNG bytes."""
    from matplotlib import rc_context
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    width = sum(s.width for s in sheets)
    fig = _figure(width, sheets[0].height)
    FigureCanvasAgg(fig)
    x = 0.0
    with rc_context({"lines.scale_dashes": False}):
        for sheet in sheets:
            ax = fig.add_axes((x / width, 0, sheet.width / width, 1))
            _draw(ax, sheet)
            ax.add_patch(_frame(sheet))
            x += sheet.width
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=dpi, facecolor="white")
    return buf.getvalue()


def _frame(sheet: Sheet):
    from matplotlib.patches import Rectangle

    return Rectangle((0, 0), sheet.width, sheet.height, fill=False, edgecolor="#999999", linewidth=1)
