"""SVG rendering of a net at true scale (user units are millimetres), ready for a cutting machine.

The document's ``width``/``height`` are in mm and its ``viewBox`` spans the
same numbers, so one user unit is one millimetre.  Pages of a multi-page net
are stacked top to bottom.  Three Inkscape layers (``<g
inkscape:groupmode="layer">``, also read by Cricut Design Space and
Silhouette Studio as groups):

* ``print`` -- everything to print: faces (``<polygon data-face="f1">``),
  glue tabs (``data-tab``), labels and the footer as filled outlines
  (``<path data-text="...">``, no font needed), the legend and scale bar;
* ``score`` -- fold lines, blue and dashed;
* ``cut`` -- one closed red ``<path data-piece="n">`` per piece.
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

import numpy as np

from diefab.fabricate.sheet import Sheet

__all__ = ["CUT_COLOR", "SCORE_COLOR", "render_svg", "shape_path"]

CUT_MM = 0.3
FOLD_MM = 0.25
DASH = "2.5,1.5"
FACE_FILL = "#fbfaf5"
TAB_FILL = "#dcdcdc"
CUT_COLOR = "#d40000"
SCORE_COLOR = "#0055d4"
_INKSCAPE = "http://www.inkscape.org/namespaces/inkscape"


def _pts(poly: np.ndarray, dy: float) -> str:
    return " ".join(f"{x:.4f},{y + dy:.4f}" for x, y in poly)


def _line(seg: np.ndarray, dy: float, extra: str = "") -> str:
    (x1, y1), (x2, y2) = seg
    return f'<line x1="{x1:.4f}" y1="{y1 + dy:.4f}" x2="{x2:.4f}" y2="{y2 + dy:.4f}"{extra}/>'


def _ring(points: np.ndarray, dy: float) -> str:
    head, *rest = points
    return f"M{head[0]:.4f},{head[1] + dy:.4f}" + "".join(f"L{x:.4f},{y + dy:.4f}" for x, y in rest) + "Z"


def shape_path(shape, dy: float = 0.0) -> str:
    """SVG path data of a shapely (Multi)Polygon: every ring closed, holes included (even-odd)."""
    out = []
    for part in getattr(shape, "geoms", [shape]):
        if part.is_empty:
            continue
        out.append(_ring(np.asarray(part.exterior.coords)[:-1], dy))
        out.extend(_ring(np.asarray(r.coords)[:-1], dy) for r in part.interiors)
    return "".join(out)


def _layer(name: str, attrs: str, body: list[str]) -> list[str]:
    return [f'<g inkscape:groupmode="layer" inkscape:label="{name}" id="{name}" {attrs}>', *body, "</g>"]


def render_svg(sheets: list[Sheet]) -> str:
    """The sheets of a net as one SVG document (str), millimetre units."""
    width = sheets[0].width
    height = sum(s.height for s in sheets)
    faces, tabs, labels, info, score, cut = [], [], [], [], [], []
    dy = 0.0
    piece = 0
    for sheet in sheets:
        if len(sheets) > 1:
            info.append(
                f'<rect x="0" y="{dy:.4f}" width="{sheet.width:.4f}" height="{sheet.height:.4f}" '
                'fill="none" stroke="#bbbbbb" stroke-width="0.2"/>'
            )
        for name, poly in sheet.faces:
            faces.append(f"<polygon data-face={quoteattr(name)} points={quoteattr(_pts(poly, dy))}/>")
        for label, poly in sheet.tabs:
            tabs.append(f"<polygon data-tab={quoteattr(label)} points={quoteattr(_pts(poly, dy))}/>")
        score.extend(_line(seg, dy) for seg in sheet.score)
        for ring in sheet.cut:
            piece += 1
            cut.append(f'<path data-piece="{piece}" d="{_ring(ring, dy)}"/>')
        for style, pts in sheet.legend:
            if style == "cut":
                info.append(_line(pts, dy, f' stroke="{CUT_COLOR}" stroke-width="{CUT_MM}"'))
            elif style == "score":
                info.append(
                    _line(pts, dy, f' stroke="{SCORE_COLOR}" stroke-width="{FOLD_MM}" stroke-dasharray="{DASH}"')
                )
            elif style == "swatch":
                info.append(f'<polygon points={quoteattr(_pts(pts, dy))} fill="{TAB_FILL}" stroke="none"/>')
            else:
                (x1, y), (x2, _) = pts
                y += dy
                info.append(
                    f'<path d="M{x1:.4f},{y - 1.5:.4f} V{y + 1.5:.4f} M{x1:.4f},{y:.4f} H{x2:.4f} '
                    f'M{x2:.4f},{y - 1.5:.4f} V{y + 1.5:.4f}" stroke="black" stroke-width="0.3" fill="none"/>'
                )
        for t in sheet.texts:
            face = f" data-face={quoteattr(t.face)}" if t.face else ""
            d = quoteattr(shape_path(t.shape, dy))
            element = f"<path class={quoteattr(t.kind)} data-text={quoteattr(t.text)}{face} d={d}/>"
            (info if t.kind == "info" else labels).append(element)
        dy += sheet.height
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="{_INKSCAPE}" '
        f'width="{width:g}mm" height="{height:g}mm" viewBox="0 0 {width:g} {height:g}">',
        *_layer(
            "print",
            'fill="black" stroke="none"',
            [
                f'<g id="faces" fill="{FACE_FILL}">',
                *faces,
                "</g>",
                f'<g id="tabs" fill="{TAB_FILL}">',
                *tabs,
                "</g>",
                '<g id="labels" fill="black" fill-rule="evenodd">',
                *labels,
                "</g>",
                '<g id="info" fill="black" fill-rule="evenodd">',
                *info,
                "</g>",
            ],
        ),
        *_layer(
            "score",
            f'fill="none" stroke="{SCORE_COLOR}" stroke-width="{FOLD_MM}" stroke-dasharray="{DASH}"',
            score,
        ),
        *_layer("cut", f'fill="none" stroke="{CUT_COLOR}" stroke-width="{CUT_MM}" stroke-linejoin="round"', cut),
        "</svg>",
    ]
    return "\n".join(out) + "\n"
