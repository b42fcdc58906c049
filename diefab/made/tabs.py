"""Glue tabs: trapezoids on the cut edges of a net, placed so that they overlap nothing.

Each cut edge has two copies in the layout; its tab goes on one of them,
as wide as fits (:data:`TAB_FACTORS`), leaning in where a neighbour leaves
less room.  On a symmetric die (:mod:`.symmetry`) the tabs of each orbit of
cut edges go on matching sides and take one common shape, so the card of
the tabs, part of the paper die's body, keeps the die's symmetry.

All lengths are millimetres, in layout coordinates (y up).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from diefab.core import tolerances as tol
from diefab.geometry.flat import overlap, stack_polygons
from diefab.geometry.polyhedron import Polyhedron
from diefab.geometry.symmetry import Symmetries, off_axis
from diefab.geometry.trees import edge_key, edge_lookup, face_ring
from diefab.made.fill import TAB_MAX_FRACTION, TAB_TOP_FRACTION

#: Default glue-tab width, mm.
TAB_WIDTH = 5.0
#: Narrowest tab worth gluing, mm (edges shorter than ~3 mm may take narrower tabs,
#: down to 0.3 of their length).
TAB_MIN_WIDTH = 1.0

#: Widths a tab tries, as fractions of the tab width, before the edge counts as taking none.
TAB_FACTORS = (1.0, 0.6, 0.35)


@dataclass(frozen=True)
class Tab:
    """A glue tab: a trapezoid on one copy of a cut edge.

    polygon : (4, 2) float, mm, page coordinates: the base (on the face's
    edge) first, then the outer side.
    """

    label: str
    edge: int
    face: int
    polygon: np.ndarray
    page: int


def trapezoid(p, q, width, cp, cq) -> np.ndarray | None:
    """Tab on edge p->q of a counter-clockwise face (outside = right-hand side), or None if too narrow.

    Its sides lean in by `cp` and `cq` (cotangents of their angles to the edge) at p and q.
    """
    d = q - p
    length = float(np.hypot(*d))
    u = d / length
    n = np.array([u[1], -u[0]])
    w = min(width, TAB_MAX_FRACTION * length, (1 - TAB_TOP_FRACTION) * length / (cp + cq))
    if w < min(TAB_MIN_WIDTH, 0.3 * length) - 1e-12:
        return None
    return np.array([p, q, q + w * n - w * cq * u, p + w * n + w * cp * u])


def free_angle(point, direction, shapes) -> float:
    """Clockwise angle (rad) from `direction` at `point` to the nearest edge of `shapes` leaving `point`."""
    return _free_angle(point, direction, *_corners(shapes))


def _corners(shapes: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every vertex of `shapes`, (n, 2), with the vertex before it and the one after it around its own shape."""
    if not shapes:
        empty = np.empty((0, 2))
        return empty, empty, empty
    pts = np.concatenate(shapes)
    sizes = np.array([len(s) for s in shapes])
    start, size = np.repeat(np.cumsum(sizes) - sizes, sizes), np.repeat(sizes, sizes)
    local = np.arange(len(pts)) - start
    return pts, pts[start + (local - 1) % size], pts[start + (local + 1) % size]


def _free_angle(point, direction, pts: np.ndarray, before: np.ndarray, after: np.ndarray) -> float:
    """:func:`free_angle` over the vertices `pts` of the shapes and their neighbours (see :func:`_corners`)."""
    base = math.atan2(direction[1], direction[0])
    best = 2 * math.pi
    near = np.hypot(pts[:, 0] - point[0], pts[:, 1] - point[1]) < 1e-6
    for d in np.concatenate([before[near], after[near]]) - point:
        if np.hypot(*d) < 1e-6:
            continue
        cw = (base - math.atan2(d[1], d[0])) % (2 * math.pi)
        if cw > 1e-9:
            best = min(best, cw)
    return best


def _mirrored(points: np.ndarray) -> np.ndarray:
    """`points` (..., 2) reflected in the x axis."""
    out = np.array(points, dtype=float)
    out[..., 1] = -out[..., 1]
    return out


def place_tabs(polys, piece_of, cuts, width, group: Symmetries | None = None):
    """Greedy tabs: for every cut edge the widest shape, on either copy, that overlaps nothing in its piece.

    polys : list of (k, 2) arrays (layout coordinates); cuts : list of
    (edge, [(face, p, q, a, b), (face, p, q, a, b)]).  With `group` (symmetries
    that map the cut edges onto themselves) the edges go orbit by orbit: every
    edge of an orbit takes its tab on the side a symmetry carries the first
    edge's side to, all of one width, and then the orbit's common shape (see
    :func:`_symmetrize`); an orbit that cannot is placed one edge at a time.
    Returns ``(tabs, None)`` with (edge, face, polygon) per cut edge, or
    ``(partial, edge)`` naming the first edge that can take no tab.
    """
    if width == 0:
        return [], None
    tabs = Tabs(polys, piece_of, width)
    copies = dict(cuts)
    done: set[int] = set()
    matched = []
    for e, _ in cuts:
        if e in done:
            continue
        orbit, sides = _orbit_sides(e, copies, group)
        done.update(orbit)
        if _place_orbit(tabs, orbit, sides, copies):
            matched.append(orbit)
            continue
        for g in orbit:
            if not tabs.place(g, copies[g]):
                return tabs.placed, g
    if group is not None and len(group) > 1:
        _symmetrize(tabs.placed, matched, copies, group)
    return tabs.placed, None


def _orbit_sides(e: int, copies: dict, group: Symmetries | None) -> tuple[list[int], list[dict[int, int]]]:
    """The orbit of cut edge `e` (in the order of `copies`) and its consistent tab sides (edge -> face each).

    A side is consistent when no symmetry asks one edge for both of its faces
    (an edge lying in a mirror plane has none).
    """
    if group is None or len(group) == 1:
        return [e], [{e: c[0]} for c in copies[e]]
    orbit = set(group.edge[:, e].tolist())
    sides = []
    for face, *_ in copies[e]:
        side: dict[int, int] = {}
        for g in range(len(group)):
            e2, f2 = int(group.edge[g, e]), int(group.face[g, face])
            if side.setdefault(e2, f2) != f2:
                break
        else:
            sides.append(side)
    return [g for g in copies if g in orbit], sides


def _place_orbit(tabs: Tabs, orbit: list[int], sides: list[dict[int, int]], copies: dict) -> bool:
    """Tabs on every edge of `orbit` on one of `sides`, all at the widest factor that fits; False if none does."""
    for factor in TAB_FACTORS:
        for side in sides:
            items = [(g, next(c for c in copies[g] if c[0] == side[g])) for g in orbit]
            if tabs.place_all(items, factor):
                return True
    return False


def _shape(tab: np.ndarray, p: np.ndarray, q: np.ndarray) -> tuple[float, float, float]:
    """Width and the two leans (cotangents at p and at q) of a tab on edge p->q."""
    u = (q - p) / np.hypot(*(q - p))
    n = np.array([u[1], -u[0]])
    w = float((tab[3] - p) @ n)
    return w, float((tab[3] - p) @ u) / w, float((q - tab[2]) @ u) / w


def _symmetrize(placed: list, orbits: list[list[int]], copies: dict, group: Symmetries) -> None:
    """Give the tabs of each orbit one shape (in place): the narrowest width and, at each vertex, the steepest lean.

    The lean at vertex v of the tab on edge x becomes the largest lean at
    g(v) of the tab on g(x) over the symmetries g, so a symmetry carries
    every tab onto its image.  The new shape lies inside the old one, so
    the layout stays free of overlaps.
    """
    at = {e: i for i, (e, _, _) in enumerate(placed)}
    for orbit in orbits:
        shape, ends = {}, {}
        for x in orbit:
            face, tab = placed[at[x]][1:]
            _, p, q, a, b = next(c for c in copies[x] if c[0] == face)
            w, cp, cq = _shape(tab, p, q)
            shape[x], ends[x] = (w, {a: cp, b: cq}), (face, p, q, a, b)
        width = min(w for w, _ in shape.values())
        new = {}
        for x in orbit:
            lean = dict(shape[x][1])
            for g in range(len(group)):
                y = int(group.edge[g, x])
                for v in lean:
                    lean[v] = max(lean[v], shape[y][1][int(group.vertex[g, v])])
            face, p, q, a, b = ends[x]
            new[x] = (face, trapezoid(p, q, width, lean[a], lean[b]))
        if all(t is not None for _, t in new.values()):
            for x, (face, t) in new.items():
                placed[at[x]] = (x, face, t)


def _tabs_centroid(poly: Polyhedron, mm_per_unit: float, copies: dict, placed: list) -> np.ndarray | None:
    """Centre of the tabs' card as glued inside the die, model units (each tab on its glued face's plane)."""
    total, moment = 0.0, np.zeros(3)
    for e, face, tab in placed:
        _, p, q, a, b = next(c for c in copies[e] if c[0] == face)
        u = (q - p) / np.hypot(*(q - p))
        local = np.column_stack([(tab - p) @ u, (tab - p) @ np.array([u[1], -u[0]])])  # along, outward
        x, y = local.T
        turn = np.r_[1 : len(x), 0]
        x1, y1 = x[turn], y[turn]
        cross = x * y1 - x1 * y
        area = cross.sum() / 2
        if abs(area) < tol.AREA:
            continue
        along, out = ((x + x1) * cross).sum() / (6 * area), ((y + y1) * cross).sum() / (6 * area)
        start, u3, inward = _glued_frame(poly, e, face, a, b)
        moment += abs(area) * (start + (along * u3 + out * inward) / mm_per_unit)
        total += abs(area)
    return moment / total if total > 0 else None


@lru_cache(maxsize=4096)
def _glued_frame(poly: Polyhedron, e: int, face: int, a: int, b: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where the tab on edge `e`'s copy on `face` lies once glued: vertex `a`, unit a->b, unit into the glued face."""
    glued = int(next(f for f in poly.edge_faces[e] if f != face))
    start, end = poly.vertices[a], poly.vertices[b]
    u3 = (end - start) / np.linalg.norm(end - start)
    inward = np.cross(poly.normals[glued], u3)
    if inward @ (poly.face_centroids[glued] - start) < 0:
        inward = -inward
    return start, u3, inward


def tab_offset(poly, mm_per_unit, copies, placed, group: Symmetries) -> float:
    """Distance of the tabs' centre from the die's symmetry axis (plane, centre), mm; 0 without tabs."""
    center = _tabs_centroid(poly, mm_per_unit, copies, placed)
    return 0.0 if center is None else off_axis(group, center) * mm_per_unit


class Tabs:
    """Glue tabs placed one cut edge at a time on a layout whose pieces may still be split.

    Each end of a tab leans in by at most 45 degrees and by less where a
    neighbouring face or tab leaves less room at that vertex.  A tab is
    tested only against the shapes of its piece that a :class:`Grid`
    finds near it, so a die with hundreds of faces costs about as much per
    edge as a small one.  `piece_of` is read at every test: a caller may
    move faces (with their tabs) to a new piece between placements, and the
    tabs already placed stay valid, since a piece only ever loses shapes.
    """

    def __init__(self, polys: list[np.ndarray], piece_of: np.ndarray, width: float) -> None:
        self.piece_of, self.width = piece_of, width
        self.shapes = list(polys)  # faces first, then the tabs as they are placed
        self.owner = list(range(len(polys)))  # the face each shape belongs to
        self.grid = Grid(cell_size(polys))
        for k, p in enumerate(polys):
            self.grid.add(k, p)
        self.placed: list[tuple[int, int, np.ndarray]] = []

    def _near(self, piece: int, points: np.ndarray, pad: float = 0.0) -> list[np.ndarray]:
        return [self.shapes[i] for i in self.grid.near(points, pad) if self.piece_of[self.owner[i]] == piece]

    def _fit(self, face: int, p: np.ndarray, q: np.ndarray, factor: float) -> np.ndarray | None:
        """The tab `factor` times the width on copy (face, p, q) if it overlaps nothing in its piece, else None."""
        piece = self.piece_of[face]
        corners = _corners(self._near(piece, np.array([p, q]), pad=1e-6))
        u = (q - p) / np.hypot(*(q - p))
        # room at p turning clockwise from p->q, at q turning counter-clockwise from q->p (in the mirror image)
        ap = min(math.pi / 4, 0.9 * _free_angle(p, u, *corners))
        aq = min(math.pi / 4, 0.9 * _free_angle(_mirrored(q), _mirrored(-u), *map(_mirrored, corners)))
        if min(ap, aq) < math.radians(3):
            return None
        tab = trapezoid(p, q, factor * self.width, 1 / math.tan(ap), 1 / math.tan(aq))
        if tab is None:
            return None
        near = self._near(piece, tab)
        if near and overlap(stack_polygons(near), tab).any():
            return None
        return tab

    def _add(self, e: int, face: int, tab: np.ndarray) -> None:
        self.grid.add(len(self.shapes), tab)
        self.shapes.append(tab)
        self.owner.append(face)
        self.placed.append((e, face, tab))

    def _undo(self, count: int) -> None:
        """Take back the last `count` tabs."""
        for _ in range(count):
            self.grid.remove(len(self.shapes) - 1, self.shapes.pop())
            self.owner.pop()
            self.placed.pop()

    def place(self, e: int, copies) -> bool:
        """Place the widest tab that fits on cut edge `e` (copies: (face, p, q, ...) each); False if none does."""
        for factor in TAB_FACTORS:
            for face, p, q, *_ in copies:
                tab = self._fit(face, p, q, factor)
                if tab is not None:
                    self._add(e, face, tab)
                    return True
        return False

    def place_all(self, items, factor: float) -> bool:
        """A tab `factor` times the width on every (edge, (face, p, q, ...)) of `items`, or on none of them."""
        for k, (e, (face, p, q, *_)) in enumerate(items):
            tab = self._fit(face, p, q, factor)
            if tab is None:
                self._undo(k)
                return False
            self._add(e, face, tab)
        return True


class Grid:
    """Shapes filed by their bounding boxes in square cells: which of them may meet a query box.

    A spatial index that grows as shapes are added (tabs are placed one
    by one), unlike a bulk-loaded R-tree.
    """

    def __init__(self, cell: float) -> None:
        self.cell = cell
        self.cells: dict[tuple[int, int], list[int]] = {}

    def _span(self, points: np.ndarray, pad: float):
        lo = np.floor((points.min(axis=0) - pad) / self.cell).astype(int)
        hi = np.floor((points.max(axis=0) + pad) / self.cell).astype(int)
        return itertools.product(range(lo[0], hi[0] + 1), range(lo[1], hi[1] + 1))

    def add(self, key: int, points: np.ndarray) -> None:
        for c in self._span(points, 0.0):
            self.cells.setdefault(c, []).append(key)

    def remove(self, key: int, points: np.ndarray) -> None:
        """Forget `key`, filed with `points`."""
        for c in self._span(points, 0.0):
            self.cells[c].remove(key)

    def near(self, points: np.ndarray, pad: float = 0.0) -> list[int]:
        """Keys of the shapes whose cells meet the bounding box of `points` grown by `pad`, increasing."""
        out: set[int] = set()
        for c in self._span(points, pad):
            out.update(self.cells.get(c, ()))
        return sorted(out)


def cell_size(polys: list[np.ndarray]) -> float:
    """A grid cell about the size of a typical face, mm."""
    return max(float(np.median([np.ptp(p, axis=0).max() for p in polys])), 1e-3)


def free_angle_ccw(point, direction, shapes) -> float:
    """Counter-clockwise angle (rad) from `direction` at `point` to the nearest edge of `shapes` leaving it."""
    return _free_angle(_mirrored(point), _mirrored(direction), *map(_mirrored, _corners(shapes)))


def cut_copies(poly: Polyhedron, polys: list[np.ndarray], cut: list[int]):
    """For every cut edge, its two copies (face, start, end, start vertex, end vertex) in face-CCW order.

    Longest edges first.
    """
    lookup = edge_lookup(poly)
    copies: dict[int, list] = {e: [] for e in cut}
    for k, f in enumerate(poly.faces):
        for i, (a, b) in enumerate(face_ring(f)):
            e = lookup[edge_key(a, b)]
            if e in copies:
                copies[e].append((k, polys[k][i], polys[k][(i + 1) % len(f)], a, b))
    lengths = {e: float(np.hypot(*(c[0][2] - c[0][1]))) for e, c in copies.items()}
    return sorted(copies.items(), key=lambda item: (-round(lengths[item[0]], 6), item[0]))
