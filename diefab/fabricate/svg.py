"""SVG rendering of a net at true scale (user units are millimetres).

The document's ``width``/``height`` are in mm and its ``viewBox`` spans the
same numbers, so one user unit is one millimetre.  Pages of a multi-page net
are stacked top to bottom.  Groups for cutting machines: ``<g id="faces">``
(one ``<polygon data-face="f1">`` per face), ``<g id="tabs">`` (``data-tab``
with the edge label), ``<g id="cut">`` (solid), ``<g id="fold">`` (dashed),
``<g id="labels">`` and ``<g id="info">`` (title, legend, calibration bar).
"""

from __future__ import annotations

from xml.sax.saxutils import escape, quoteattr

import numpy as np

from .sheet import FONT, Sheet, text_width

__all__ = ["render_svg"]

CUT_MM = 0.3
FOLD_MM = 0.25
DASH = "2.5,1.5"
FACE_FILL = "#fbfaf5"
TAB_FILL = "#dcdcdc"


def _pts(poly: np.ndarray, dy: float) -> str:
    return " ".join(f"{x:.4f},{y + dy:.4f}" for x, y in poly)


def _line(seg: np.ndarray, dy: float) -> str:
    (x1, y1), (x2, y2) = seg
    return f'<line x1="{x1:.4f}" y1="{y1 + dy:.4f}" x2="{x2:.4f}" y2="{y2 + dy:.4f}"/>'


def render_svg(sheets: list[Sheet]) -> str:
    """The sheets of a net as one SVG document (str), millimetre units."""
    width = sheets[0].width
    height = sum(s.height for s in sheets)
    faces, tabs, cut, fold, labels, info = [], [], [], [], [], []
    dy = 0.0
    for sheet in sheets:
        if len(sheets) > 1:
            info.append(
                f'<rect x="0" y="{dy:.4f}" width="{sheet.width:.4f}" height="{sheet.height:.4f}" '
                'fill="none" stroke="#bbbbbb" stroke-width="0.2"/>'
            )
        for name, poly in sheet.faces:
            faces.append(f"<polygon data-face={quoteattr(name)} points={quoteattr(_pts(poly, dy))}/>")
        for label, poly in sheet.tabs:
            attr = f"data-tab={quoteattr(label)} " if label else ""
            (tabs if label else info).append(
                f'<polygon {attr}points={quoteattr(_pts(poly, dy))} fill={quoteattr(TAB_FILL)} stroke="none"/>'
            )
        cut.extend(_line(seg, dy) for seg in sheet.cut)
        fold.extend(_line(seg, dy) for seg in sheet.fold)
        for style, seg in sheet.legend:
            if style == "cut":
                info.append(_line(seg, dy).replace("/>", f' stroke="black" stroke-width="{CUT_MM}"/>'))
            elif style == "fold":
                info.append(
                    _line(seg, dy).replace(
                        "/>", f' stroke="black" stroke-width="{FOLD_MM}" stroke-dasharray="{DASH}"/>'
                    )
                )
            else:
                (x1, y), (x2, _) = seg
                y += dy
                info.append(
                    f'<path d="M{x1:.4f},{y - 1.5:.4f} V{y + 1.5:.4f} M{x1:.4f},{y:.4f} H{x2:.4f} '
                    f'M{x2:.4f},{y - 1.5:.4f} V{y + 1.5:.4f}" stroke="black" stroke-width="0.3" fill="none"/>'
                )
        for t in sheet.texts:
            anchor = "start" if t.anchor == "start" else "middle"
            element = (
                f'<text x="{t.x:.4f}" y="{t.baseline + dy:.4f}" font-size="{t.size:.4f}" '
                f'text-anchor="{anchor}" class="{t.kind}">{escape(t.text)}</text>'
            )
            (info if t.kind == "info" else labels).append(element)
            if t.underline:
                w = text_width(t.text, t.size)
                y = t.baseline + dy + 0.12 * t.size
                labels.append(
                    f'<line x1="{t.x - w / 2:.4f}" y1="{y:.4f}" x2="{t.x + w / 2:.4f}" y2="{y:.4f}" '
                    f'stroke="black" stroke-width="{0.07 * t.size:.4f}"/>'
                )
        dy += sheet.height
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width:g}mm" height="{height:g}mm" '
        f'viewBox="0 0 {width:g} {height:g}">',
        f'<g id="faces" fill="{FACE_FILL}" stroke="none">',
        *faces,
        "</g>",
        '<g id="tabs">',
        *tabs,
        "</g>",
        f'<g id="fold" stroke="black" stroke-width="{FOLD_MM}" stroke-dasharray="{DASH}" fill="none">',
        *fold,
        "</g>",
        f'<g id="cut" stroke="black" stroke-width="{CUT_MM}" stroke-linecap="round" fill="none">',
        *cut,
        "</g>",
        f'<g id="labels" font-family={quoteattr(FONT + ", Verdana, sans-serif")} fill="black">',
        *labels,
        "</g>",
        f'<g id="info" font-family={quoteattr(FONT + ", Verdana, sans-serif")} fill="black">',
        *info,
        "</g>",
        "</svg>",
    ]
    return "\n".join(out) + "\n"
