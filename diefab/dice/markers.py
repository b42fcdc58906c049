"""Fiducial markers on a die's faces: which marker goes on which face, and where.

Every face large enough carries one ArUco marker (OpenCV's ``cv2.aruco``
dictionaries), and a face so large that one marker toward each of its corners
is still large (:data:`MULTI_SIDE_FRACTION`: a cube's) carries one there, so
that a finger over part of a die that shows only that face leaves a marker in
view.  The markers are numbered 0, 1, ... face by face in the smallest
dictionary that holds them all (:data:`DICTIONARIES`), so the layout follows
from the design alone.  A marker is a square in the face's label frame (x
along the baseline, y up, as the value label reads): as large as the face
allows inside a margin, and where the face also carries a value label, a share
of that size pushed to the side that leaves the label the most room (or, with
a marker toward each corner, the middle of the face).

The layout is geometry only (model units); the sticker sheet, the net, the
solid and the camera all read the same squares, so a printed die and the
reader agree on every corner.

Examples
--------
>>> from diefab.dice.design import load_design
>>> layout = marker_layout(load_design("d6"))
>>> layout.dictionary, len(layout.ids), layout.faces[:8].tolist()
('DICT_4X4_50', 24, [0, 0, 0, 0, 1, 1, 1, 1])
>>> bool(np.allclose(np.linalg.norm(layout.corners[0, 0] - layout.corners[0, 1]), layout.sides[0]))
True
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.design import design_axis
from diefab.made.labels import MARK_REACH, face_frame

if TYPE_CHECKING:
    from diefab.dice.design import Design

__all__ = [
    "DICTIONARIES",
    "MarkerLayout",
    "dictionary_for",
    "marker_cells",
    "marker_layout",
]

#: ArUco dictionaries by size: (OpenCV name, number of ids, bits per side).  Fewer bits mean larger cells.
DICTIONARIES = (
    ("DICT_4X4_50", 50, 4),
    ("DICT_5X5_100", 100, 5),
    ("DICT_6X6_250", 250, 6),
    ("DICT_7X7_1000", 1000, 7),
)
#: Free border between a face's edge and its marker, as a fraction of the face's inscribed radius.
MARGIN_FRACTION = 0.12
#: Side of a marker that shares its face with a value label, as a fraction of the largest square that fits
#: centred; the marker grows past it while the label keeps :data:`LABEL_ROOM`.
LABEL_SHARE = 0.62
#: Room left for a value label beside a grown marker: the inradius of what is left of the face, as a fraction
#: of the face's inradius.  A thin face (a bipyramid's) fits a larger marker toward its base this way.
LABEL_ROOM = 0.55
#: A face whose marker would be smaller than this fraction of the die's reference size carries none.
MIN_SIDE_FRACTION = 0.08
#: A face carries one marker toward each of its corners, instead of one marker, when each of them is still at
#: least this fraction of the die's reference size: a die that shows only its top face (a cube seen from above)
#: is then still read with a finger over part of it.
MULTI_SIDE_FRACTION = 0.18
#: Room left for the value label in the middle of a face with a marker toward each corner, as a fraction of the
#: face's inradius: the label is then centred and upright, and a little smaller than beside one marker.
CORNERS_LABEL_ROOM = 0.45


def dictionary_for(n_ids: int) -> str:
    """The smallest ArUco dictionary of :data:`DICTIONARIES` with `n_ids` ids.

    >>> dictionary_for(6), dictionary_for(60), dictionary_for(200)
    ('DICT_4X4_50', 'DICT_5X5_100', 'DICT_6X6_250')
    """
    for name, size, _ in DICTIONARIES:
        if n_ids <= size:
            return name
    raise DesignError(f"a die with {n_ids} faces has more faces than the largest marker dictionary has ids (1000)")


@dataclass(frozen=True, eq=False)
class MarkerLayout:
    """The markers of one die, model units.

    Attributes
    ----------
    dictionary : str
        OpenCV name of the ArUco dictionary (``DICT_4X4_50``, ...).
    faces : (n,) int
        The faces that carry a marker, increasing.
    ids : (n,) int
        Marker id on each of them (the face index).
    corners : (n, 4, 3) float
        Each marker's outer corners on the die, model units, in ArUco's
        order: top-left, top-right, bottom-right, bottom-left as the marker
        is seen from outside the die, upright in its face's label frame.
    sides : (n,) float
        Side of each marker, model units.
    bits : int
        Cells per side of the marker's code (the marker is ``bits + 2`` cells
        wide with its black border).
    """

    dictionary: str
    faces: np.ndarray
    ids: np.ndarray
    corners: np.ndarray
    sides: np.ndarray
    bits: int

    def face_of(self, marker_id: int) -> int | None:
        """The face that carries `marker_id`, or None when no face does."""
        hit = np.flatnonzero(self.ids == marker_id)
        return int(self.faces[hit[0]]) if len(hit) else None

    def squares(self, k: int, frame: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
        """(4, 2) float: marker `k`'s corners in a face frame given as (origin, u, v) (3D vectors)."""
        origin, u, v = frame
        rel = self.corners[k] - origin
        return np.column_stack([rel @ u, rel @ v])


def _largest_square(region, center) -> float:
    """Side of the largest axis-aligned square centred at `center` inside `region`."""
    import shapely

    x0, y0, x1, y1 = region.bounds
    lo, hi = 0.0, max(x1 - x0, y1 - y0)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if region.contains(
            shapely.box(center[0] - mid / 2, center[1] - mid / 2, center[0] + mid / 2, center[1] + mid / 2)
        ):
            lo = mid
        else:
            hi = mid
    return lo


def _room(region, center: np.ndarray, side: float) -> float:
    """Inradius of what `region` keeps for a label beside a square of `side` at `center` (and a gap)."""
    import shapely
    from shapely.ops import polylabel

    gap = 0.1 * side
    rest = region.difference(shapely.box(*(center - side / 2 - gap), *(center + side / 2 + gap)))
    if rest.geom_type != "Polygon":
        rest = max(getattr(rest, "geoms", []), key=lambda g: g.area, default=None)
    return 0.0 if rest is None or rest.is_empty else rest.exterior.distance(polylabel(rest, 1e-3 * side))


def _reach(region, center, side: float, direction: np.ndarray) -> np.ndarray | None:
    """The centre farthest along `direction` from `center` at which a square of `side` fits in `region`, or None."""
    import shapely

    x0, y0, x1, y1 = region.bounds
    h = side / 2

    def fits(t: float) -> bool:
        c = center + t * direction
        return region.contains(shapely.box(c[0] - h, c[1] - h, c[0] + h, c[1] + h))

    ts = np.linspace(0.0, max(x1 - x0, y1 - y0), 33)
    ok = [i for i, t in enumerate(ts) if fits(t)]
    if not ok:
        return None
    lo, hi = ts[ok[-1]], ts[min(ok[-1] + 1, len(ts) - 1)]
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return center + lo * direction


#: Directions a labelled face's marker is pushed in, in the order that breaks ties: below the label, above, left, right.
_DIRECTIONS = tuple(np.array(d) for d in ((0.0, -1.0), (0.0, 1.0), (-1.0, 0.0), (1.0, 0.0)))


def _beside_label(region, center, side: float) -> tuple[float, np.ndarray] | None:
    """The placement of a square of `side` pushed to the side that leaves the label the most room."""
    options = [(_room(region, c, side), c) for d in _DIRECTIONS if (c := _reach(region, center, side, d)) is not None]
    return max(options, key=lambda o: o[0]) if options else None  # max keeps the first of equals


def _at_corners(region, ring: np.ndarray, labelled: bool, inradius: float) -> tuple[float, list[np.ndarray]]:
    """Side and centres of equal squares, one pushed toward each corner of the face `ring` ((m, 2), label frame).

    As large as they fit in `region` apart from each other (by a gap of a tenth of their side) and, on a
    labelled face, leaving the label a room of :data:`CORNERS_LABEL_ROOM` times the face's `inradius` between them.
    (0, []) when no such squares fit.
    """
    import shapely
    from shapely.ops import polylabel, unary_union

    if region.is_empty or region.area <= 0:
        return 0.0, []
    if region.geom_type != "Polygon":
        region = max(region.geoms, key=lambda g: g.area)
    shapely.prepare(region)
    p = polylabel(region, tolerance=1e-4 * np.sqrt(region.area))
    center = np.array([p.x, p.y])
    toward = [(q - center) / np.linalg.norm(q - center) for q in ring]

    def fit(side: float) -> list[np.ndarray] | None:
        centres = [_reach(region, center, side, d) for d in toward]
        if any(c is None for c in centres):
            return None
        gap = 0.1 * side
        boxes = [shapely.box(*(c - side / 2 - gap / 2), *(c + side / 2 + gap / 2)) for c in centres]
        if any(a.intersects(b) for i, a in enumerate(boxes) for b in boxes[i + 1 :]):
            return None
        if labelled:
            rest = region.difference(unary_union(boxes).buffer(gap / 2, join_style="mitre"))
            if rest.geom_type != "Polygon":
                rest = max(getattr(rest, "geoms", []), key=lambda g: g.area, default=None)
            if (
                rest is None
                or rest.is_empty
                or rest.exterior.distance(polylabel(rest, 1e-3 * side)) < (CORNERS_LABEL_ROOM * inradius)
            ):
                return None
        return centres

    lo, hi, best = 0.0, _largest_square(region, center), []
    for _ in range(14):
        mid = 0.5 * (lo + hi)
        centres = fit(mid)
        if centres is None:
            hi = mid
        else:
            lo, best = mid, centres
    return (lo, best) if best else (0.0, [])


def _place(region, labelled: bool, inradius: float) -> tuple[float, np.ndarray]:
    """Side and centre of the marker in a face region (label-frame coordinates).

    An unlabelled face carries the largest square centred in it.  A labelled face carries a square of
    :data:`LABEL_SHARE` of that, pushed aside for the label, grown as long as the label keeps a room of
    :data:`LABEL_ROOM` times the face's `inradius`.
    """
    import shapely
    from shapely.ops import polylabel

    if region.is_empty or region.area <= 0:
        return 0.0, np.zeros(2)
    if region.geom_type != "Polygon":
        region = max(region.geoms, key=lambda g: g.area)
    shapely.prepare(region)
    p = polylabel(region, tolerance=1e-4 * np.sqrt(region.area))
    center = np.array([p.x, p.y])
    best = _largest_square(region, center)
    if not labelled:
        return best, center
    side = LABEL_SHARE * best
    _, c = _beside_label(region, center, side)
    x0, y0, x1, y1 = region.bounds
    lo, hi = side, max(x1 - x0, y1 - y0)
    need = LABEL_ROOM * inradius
    for _ in range(16):  # the room left for the label shrinks as the marker grows
        mid = 0.5 * (lo + hi)
        placed = _beside_label(region, center, mid)
        if placed is not None and placed[0] >= need:
            lo, c = mid, placed[1]
        else:
            hi = mid
    return lo, c


def marker_layout(design: Design) -> MarkerLayout:
    """The markers of `design`: one per face large enough (one toward each corner of a large face), ids 0, 1, ...

    Raises
    ------
    DesignError
        If the die has more faces than the largest dictionary has ids, or
        no face is large enough for a marker.
    """
    return _layout_cached(design)


@lru_cache(maxsize=32)
def _layout_cached(design: Design) -> MarkerLayout:
    from shapely.geometry import Polygon
    from shapely.ops import polylabel

    from diefab.dice.readings import markings

    poly = design.polyhedron
    axis = design_axis(design)
    size = float(np.ptp(poly.vertices, axis=0).max())
    labelled = set(design.label_of)
    try:
        marks = [m for m in markings(poly, design.values, {n: str(v) for n, v in design.values.items()}) if m.at]
    except DesignError:
        marks = []
    faces, corners, sides = [], [], []
    for k, ring_ids in enumerate(poly.faces):
        ring = poly.vertices[ring_ids]
        u, v = face_frame(ring, poly.normals[k], axis)
        origin = ring.mean(axis=0)
        flat = np.column_stack([(ring - origin) @ u, (ring - origin) @ v])
        face = Polygon(flat)
        inradius = face.exterior.distance(polylabel(face, 1e-4 * size))
        region = face.buffer(-MARGIN_FRACTION * inradius, join_style="mitre")
        for m in marks:
            if m.face == poly.names[k]:
                at = [list(ring_ids).index(i) for i in m.at]
                corner = flat[at].mean(axis=0)
                zone = Polygon(corner + MARK_REACH * (flat - corner))
                region = region.difference(zone)
        has_label = poly.names[k] in labelled or any(m.face == poly.names[k] for m in marks)
        side, c = _place(region, has_label, inradius)
        placed = [c]
        if side >= 2 * MULTI_SIDE_FRACTION * size:  # room, perhaps, for one marker toward each corner
            several, centres = _at_corners(region, flat, has_label, inradius)
            if several >= MULTI_SIDE_FRACTION * size:
                side, placed = several, centres
        if side < MIN_SIDE_FRACTION * size:
            continue
        h = side / 2
        for c in placed:
            square = np.array([[-h, h], [h, h], [h, -h], [-h, -h]]) + c  # TL, TR, BR, BL in the label frame
            faces.append(k)
            corners.append(origin + square[:, :1] * u + square[:, 1:] * v)
            sides.append(side)
    if not faces:
        raise DesignError(f"design {design.name!r} has no face large enough to carry a marker")
    name, _, bits = next(d for d in DICTIONARIES if d[0] == dictionary_for(len(faces)))
    ids = np.arange(len(faces))
    return MarkerLayout(name, np.array(faces, dtype=int), ids, np.array(corners), np.array(sides), bits)


def marker_cells(dictionary: str, marker_id: int) -> np.ndarray:
    """((bits + 2), (bits + 2)) bool: the black cells of marker `marker_id`, border included, row 0 on top."""
    import cv2

    d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
    n = d.markerSize + 2
    image = cv2.aruco.generateImageMarker(d, int(marker_id), n)
    return image < 128
