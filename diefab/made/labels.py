"""What goes on a face and which way up: shared by the paper net and the printed die.

* **Which way up**: "up" in a face is the die's axis (+y, the gem's
  apex-to-top axis, for the gem family; +z otherwise) projected into the face
  plane, so every side label reads upright when the die is held axis vertical,
  top up.  A face nearly perpendicular to the axis (projection shorter than
  ``AXIS_PROJECTION``, e.g. the gem's top) stands its text on its longest
  edge, reading along it.  The net draws each face's label in the same frame,
  carried flat with the face, so paper and plastic dice read alike.
* **What**: the label text (real font outlines, :mod:`.text`), a mark under
  or after a label that reads as another label of the same die upside down,
  pips (``pips:N`` in a design's ``[labels]`` table, or every value label
  from 1 to 9 with ``--pips``) or a symbol drawn in an SVG file
  (``svg:FILE``, the filled shapes of the file, read with svgelements).
* **How large**: the largest that fits inside the face region, centred on the
  middle of the largest inscribed circle's track; :func:`fit_label` returns
  the height and centre, and the callers give all value labels the smallest
  of those heights.

Examples
--------
>>> from diefab.dice.design import load_design
>>> reading_note(load_design("fudge-gem"))
'read the face on top; a point up means 0'
>>> reading_note(load_design("d6"))
'read the face on top'
>>> round(pip_shape(5).area / pip_shape(1).area, 6)
5.0
"""

from __future__ import annotations

import math

import numpy as np

from diefab.core.errors import FabricationError
from diefab.dice.design import Design, format_value
from diefab.made.text import CURVE_STEPS, Font, ambiguous, nest_rings, text_polygons

__all__ = [
    "AXIS_PROJECTION",
    "design_axis",
    "face_frame",
    "fit_label",
    "label_shape",
    "mark_frame",
    "pip_shape",
    "placed_marks",
    "symbol_shape",
    "reading_note",
    "small_die_warning",
]

#: A face whose plane holds less than this much of the die's axis uses the longest-edge rule.
AXIS_PROJECTION = 0.3
#: Pip diameter as a fraction of the pip square's side.
PIP_DIAMETER = 0.24
#: Dice smaller than this (in their size convention) are hard to handle and to read, mm.
SMALL_DIE_MM = 8.0
#: A value read at a corner or along an edge goes in the face shrunk toward that corner (the edge's middle)
#: by this factor.
MARK_REACH = 0.4
#: Largest height of such a value, as a fraction of its face's inscribed diameter.
MARK_FRACTION = 0.2
#: Largest number of pips drawn.
MAX_PIPS = 9
_PIP_SPOTS = {
    1: [(0, 0)],
    2: [(-1, 1), (1, -1)],
    3: [(-1, 1), (0, 0), (1, -1)],
    4: [(-1, -1), (-1, 1), (1, -1), (1, 1)],
    5: [(-1, -1), (-1, 1), (0, 0), (1, -1), (1, 1)],
    6: [(-1, -1), (-1, 0), (-1, 1), (1, -1), (1, 0), (1, 1)],
    7: [(-1, -1), (-1, 0), (-1, 1), (0, 0), (1, -1), (1, 0), (1, 1)],
    8: [(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)],
    9: [(x, y) for x in (-1, 0, 1) for y in (-1, 0, 1)],
}


def design_axis(design: Design) -> np.ndarray:
    """(3,) float: the die's up axis (+y for the gem family, +z otherwise)."""
    return np.array([0.0, 1.0, 0.0]) if design.family == "gem" else np.array([0.0, 0.0, 1.0])


def face_frame(ring: np.ndarray, normal: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Baseline direction u and up direction v of a face (u × v = outward normal).

    ring : (k, 3) float, the face's vertices counter-clockwise seen from outside.
    """
    up = axis - (axis @ normal) * normal
    if np.linalg.norm(up) < AXIS_PROJECTION:
        edges = np.roll(ring, -1, axis=0) - ring
        k = int(np.argmax(np.linalg.norm(edges, axis=1)))
        along = edges[k] / np.linalg.norm(edges[k])
        up = np.cross(normal, along)  # points into the face from edge k (rings are CCW from outside)
    up = up / np.linalg.norm(up)
    return np.cross(up, normal), up


def pip_shape(n: int):
    """`n` pips (1-9) in the usual dice pattern, as a shapely geometry 1 high, centred on the origin."""
    from shapely.geometry import Point
    from shapely.ops import unary_union

    if not 1 <= n <= MAX_PIPS:
        raise FabricationError(f"pips:{n}: a face can show 1 to {MAX_PIPS} pips")
    r = PIP_DIAMETER / 2
    step = 0.5 - r
    return unary_union([Point(x * step, y * step).buffer(r, quad_segs=12) for x, y in _PIP_SPOTS[n]])


def label_shape(text: str, font: Font, *, others=(), mark: str = "bar", pips: bool = False):
    """The outline drawn for label `text`: digit height 1 (pips: 1 high), centred on the origin.

    Parameters
    ----------
    text : str
        ``pips:N`` draws N pips, ``svg:FILE`` the symbol in an SVG file
        (path absolute or relative to the working directory); other text is
        set in `font`.
    others : iterable of str
        The die's other labels: a label that reads as one of them upside down
        gets `mark` ("bar", "period" or "none").
    pips : bool
        Draw a label that is a whole number from 1 to 9 as pips.
    """
    if text.startswith("svg:"):
        return symbol_shape(text[4:].strip())
    if text.startswith("pips:"):
        count = text[5:].strip()
        if not count.isdigit():
            raise FabricationError(f"label {text!r}: pips:N needs a whole number N from 1 to {MAX_PIPS}")
        return pip_shape(int(count))
    if pips and text.isdigit() and 1 <= int(text) <= MAX_PIPS:
        return pip_shape(int(text))
    return text_polygons(text, font, mark if ambiguous(text, others) else "none")


def symbol_shape(path: str):
    """The filled shapes of an SVG file as one outline, 1 high, centred on the origin (y up).

    Every path and basic shape (rect, circle, polygon, ...) is read with its
    transforms applied; subpaths nest even-odd, so a ring drawn inside
    another is a hole.  Strokes are ignored: draw the symbol filled.

    Raises
    ------
    FabricationError
        If svgelements is missing, the file cannot be read or holds no shape.
    """
    from pathlib import Path as FilePath

    from shapely import affinity

    try:
        from svgelements import SVG, Line, Move, Path, Shape
    except ImportError:
        raise FabricationError(
            f"svg:{path}: reading SVG symbols needs svgelements (pip install 'diefab[svg]')"
        ) from None
    file = FilePath(path)
    if not file.is_file():
        raise FabricationError(f"svg:{path}: the file {'is not a regular file' if file.exists() else 'does not exist'}")
    try:
        document = SVG.parse(str(file))
    except Exception as exc:  # svgelements reports malformed files with many exception types
        raise FabricationError(f"svg:{path}: cannot be read as SVG: {exc}") from exc
    rings = []
    t = np.linspace(0, 1, CURVE_STEPS + 1)[1:]
    for element in document.elements():
        if not isinstance(element, Shape):
            continue
        for sub in Path(element).as_subpaths():
            points = []
            for seg in sub:
                if isinstance(seg, (Move, Line)) or seg.start is None:
                    if seg.end is not None:
                        points.append((seg.end.x, seg.end.y))
                else:
                    points.extend(np.asarray(seg.npoint(t)).tolist())
            if len(points) >= 3:
                rings.append(np.array(points, dtype=float) * [1, -1])  # SVG y points down
    shape = nest_rings(rings) if rings else None
    if shape is None or shape.is_empty or shape.area <= 0:
        raise FabricationError(f"svg:{path}: the file holds no filled shape")
    x0, y0, x1, y1 = shape.bounds
    s = 1 / (y1 - y0)
    return affinity.scale(affinity.translate(shape, -(x0 + x1) / 2, -(y0 + y1) / 2), s, s, origin=(0, 0))


def fit_label(region, shape, max_height: float = math.inf) -> tuple[float, float, float]:
    """Largest height (at most `max_height`) at which `shape` fits in `region`, and its centre.

    The centre is the middle of the track of the largest circle inscribed in
    `region` (the centroid of the centres within 10 % of the best radius), so
    a label on a rectangle or trapezoid sits in its middle.

    Parameters
    ----------
    region : shapely Polygon
        Where the label may go (a face shrunk by its margin).
    shape : shapely geometry
        The label at height 1, centred on the origin.

    Returns
    -------
    height, x, y : float
        0 height if nothing fits.
    """
    import shapely
    from shapely.geometry import Polygon
    from shapely.ops import polylabel

    if region.geom_type != "Polygon":
        region = max(getattr(region, "geoms", []), key=lambda g: g.area, default=Polygon())
    if region.is_empty or region.area <= 0:
        return 0.0, 0.0, 0.0
    center = polylabel(region, tolerance=0.01)
    radius = region.exterior.distance(center)
    near_best = region.buffer(-0.9 * radius)
    if not near_best.is_empty and near_best.centroid.within(region):
        center = near_best.centroid
    hull = np.asarray(shape.convex_hull.exterior.coords)
    x0, y0, x1, y1 = region.bounds
    extent = max(min(np.ptp(hull, axis=0)), 1e-9)
    lo, hi = 0.0, 2 * max(x1 - x0, y1 - y0) / extent
    shapely.prepare(region)
    at = np.array([center.x, center.y])
    for _ in range(36):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if region.contains(shapely.polygons(hull * mid + at)) else (lo, mid)
    return min(lo, max_height), float(center.x), float(center.y)


def placed_marks(design: Design) -> list:
    """The values read at a corner or along an edge (:attr:`Design.markings` with a place), in order.

    Empty for a die that no convention reads (net and stl then print the
    face values alone, and :func:`reading_note` says what a point or an edge
    on top means).
    """
    from diefab.core.errors import DesignError

    try:
        return [m for m in design.markings if m.at]
    except DesignError:
        return []


def mark_frame(ring: np.ndarray, at: tuple[int, ...], *, y_down: bool = False):
    """Where on a face a value read at a corner or along an edge goes, and which way up.

    Parameters
    ----------
    ring : (k, 2) float
        The face's corners in a plane frame.
    at : tuple of int
        Positions in `ring` of the corner (one) or of the edge's two ends.
    y_down : bool
        The frame's y points down (a page), so an unmirrored text frame
        turns the other way.

    Returns
    -------
    zone : shapely Polygon
        The face shrunk by :data:`MARK_REACH` toward the corner or the
        edge's middle: the text must lie in it.
    origin, x_axis, y_axis : (2,) float
        The text frame: origin at the corner (edge middle), y (the text's
        up) pointing from the face's centre toward the corner, or square
        out of the edge, so the value reads upright when that corner or
        edge points up on the die.
    """
    from shapely import affinity
    from shapely.geometry import Polygon

    ring = np.asarray(ring, dtype=float)
    face = Polygon(ring)
    centre = np.asarray(face.centroid.coords[0])
    if len(at) == 1:
        origin = ring[at[0]]
        up = origin - centre
    else:
        origin = (ring[at[0]] + ring[at[1]]) / 2
        edge = ring[at[1]] - ring[at[0]]
        up = np.array([-edge[1], edge[0]])
        up = up if up @ (origin - centre) > 0 else -up
    up = up / np.linalg.norm(up)
    x = np.array([up[1], -up[0]])  # (x, up) turns counter-clockwise in a y-up frame
    if y_down:
        x = -x
    zone = affinity.scale(face, MARK_REACH, MARK_REACH, origin=(float(origin[0]), float(origin[1])))
    return zone, origin, x, up


def reading_note(design: Design) -> str:
    """How to read the die: the face on top, and what a point or an edge on top means."""
    poly = design.polyhedron
    extra = []
    for rest, up in design.label_face.items():
        if up is not None or rest not in design.value_of:  # a transitional face: the die never rests on it
            continue
        k = poly.face_index(rest)
        heights = poly.vertices @ -poly.normals[k]
        top = int(np.sum(heights > heights.max() - 1e-6 * max(1.0, float(np.ptp(heights)))))
        what = "a point" if top == 1 else "an edge" if top == 2 else "a small face"
        value = design.value_of[rest]
        extra.append(f"{what} up means {format_value(value, min(design.support) < 0)}")
    return "; ".join(["read the face on top", *dict.fromkeys(extra)])


def small_die_warning(design: Design, size_mm: float | None = None) -> str | None:
    """A warning for a die under about ``SMALL_DIE_MM``, else None."""
    size = design.size_mm if size_mm is None else size_mm
    if size >= SMALL_DIE_MM:
        return None
    return (
        f"a {size:g} mm die ({design.size_note}) is under about {SMALL_DIE_MM:g} mm: "
        "hard to handle, fold or read; consider a larger --size"
    )
