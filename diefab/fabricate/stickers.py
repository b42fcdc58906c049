"""Marker stickers: one sticker per marked face, cut to the face, with its markers and its value, true scale.

For a printed die, or one made elsewhere: print the sheet, cut each sticker
along its outline and stick it on its face (the face name is in the SVG's
``data-face``).  The marker squares are the design's
(:func:`~diefab.dice.markers.marker_layout`), so the reader finds every
corner where it expects it; each value label is fitted beside its marker, as
large as the face allows.  The sheets are drawn by the net's renderers
(:mod:`.svg`, :mod:`.pdf`).
"""

from __future__ import annotations

import numpy as np

from diefab.core.errors import FabricationError
from diefab.dice.design import Design, design_axis
from diefab.dice.markers import marker_cells, marker_layout
from diefab.fabricate.sheet import FACE_MARGIN, MAX_FACE_TEXT, Sheet, Text, check_text_fits
from diefab.made.inlays import cell_outline
from diefab.made.labels import face_frame, fit_label, label_shape
from diefab.made.pages import parse_page
from diefab.made.text import load_font

__all__ = ["GAP", "sticker_sheets"]

#: Space between two stickers, mm.
GAP = 3.0


def sticker_sheets(design: Design, *, size_mm: float | None = None, page: str = "A4") -> list[Sheet]:
    """The sticker sheets of `design` at `size_mm` (default: the design's size), one :class:`Sheet` per page."""
    from shapely.geometry import Polygon
    from shapely.ops import polylabel

    size = design.size_mm if size_mm is None else size_mm
    if not (isinstance(size, (int, float)) and np.isfinite(size) and size > 0):
        raise FabricationError(f"size {size} mm must be a positive number of millimetres")
    paper = parse_page(page)
    s = design.mm_per_unit * size / design.size_mm
    layout = marker_layout(design)
    poly = design.polyhedron
    axis = design_axis(design)
    bold = load_font()
    labels = design.label_of
    stickers = []
    for k in dict.fromkeys(int(f) for f in layout.faces):  # each marked face once, in order
        ring = poly.vertices[poly.faces[k]]
        u, v = face_frame(ring, poly.normals[k], axis)
        origin = ring.mean(axis=0)
        flat = np.column_stack([(ring - origin) @ u, -((ring - origin) @ v)]) * s  # page y points down
        squares = []
        for row in np.flatnonzero(layout.faces == k):
            quad = layout.corners[row] - origin
            squares.append((int(layout.ids[row]), np.column_stack([quad @ u, -(quad @ v)]) * s))
        stickers.append((poly.names[k], flat, squares))
    width, height = paper.width - 2 * paper.margin, paper.height - 2 * paper.margin
    sheets: list[Sheet] = []
    x = y = shelf = 0.0
    for name, flat, squares in stickers:
        lo, hi = flat.min(axis=0), flat.max(axis=0)
        w, h = hi - lo
        if w > width or h > height:
            raise FabricationError(f"face {name} at {size:g} mm does not fit on a {paper.name} page")
        if x + w > width:
            x, y, shelf = 0.0, y + shelf + GAP, 0.0
        if not sheets or y + h > height:
            sheets.append(Sheet(paper.width, paper.height, len(sheets) + 1, 0))
            x = y = shelf = 0.0
        shift = np.array([paper.margin + x, paper.margin + y]) - lo
        face = flat + shift
        sheet = sheets[-1]
        sheet.faces.append((name, face))
        sheet.cut.append(face)
        region = Polygon(face).buffer(-FACE_MARGIN, join_style="mitre")
        for marker_id, quad in squares:
            corners = quad + shift
            marker = cell_outline(marker_cells(layout.dictionary, marker_id), corners)
            side = float(np.linalg.norm(corners[1] - corners[0]))
            sheet.texts.append(Text(f"marker {marker_id}", "marker", marker, name, side))
            region = region.difference(Polygon(corners).buffer(0.8))
        text = labels.get(name)
        if text:
            whole = Polygon(face)
            largest = min(MAX_FACE_TEXT, whole.exterior.distance(polylabel(whole, 0.01)))
            shape = label_shape(text, bold, others=labels.values())
            from shapely import affinity

            flipped = affinity.scale(shape, 1.0, -1.0, origin=(0, 0))  # page y points down
            h_text, cx, cy = fit_label(region, flipped, largest)
            check_text_fits(text, name, h_text)
            placed = affinity.translate(affinity.scale(flipped, h_text, h_text, origin=(0, 0)), cx, cy)
            sheet.texts.append(Text(text, "face", placed, name, h_text))
        x += w + GAP
        shelf = max(shelf, h)
    for sheet in sheets:
        sheet.pages = len(sheets)
    return sheets
