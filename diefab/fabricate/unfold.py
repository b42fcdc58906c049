"""Unfolding a convex polyhedron into a paper net with glue tabs.

The net is cut along the complement of a spanning tree of the face-adjacency
graph: tree edges are folds, every other edge is cut and glued back with one
trapezoidal tab.  For small dice every spanning tree is tried; larger ones get
a few hundred candidate trees (steepest-edge unfoldings towards many
directions, random minimum spanning trees).  A layout is rejected when two
faces overlap **or** a glue tab overlaps a face or another tab; tabs are
placed while the layout is checked, narrowed or moved to the other face when
they would collide.  Among valid layouts the one whose bounding rectangle,
rotated to fit the page, has the smallest area wins; when no single piece
fits, the net is split into several pieces that each fit a page.

The card of the tabs is part of the paper die's body (:mod:`diefab.bodies`),
so on a symmetric die (:mod:`.symmetry`) the tabs are laid out to keep its
symmetry: trees that the most symmetries map onto themselves are tried
first, the tabs of each cut edge's orbit under those symmetries go on
matching sides (edge ``g(e)`` gets its tab on face ``g(f)``) and take the
orbit's common, narrowest shape, and among the valid layouts those whose
tabs' centre of mass lies on the die's symmetry axis (within
:data:`~diefab.tolerances.NET_TAB_OFFSET_MM`) come first.  The distance
that remains is ``net.search["tab_offset_mm"]``.

All lengths here are millimetres; layout coordinates have y pointing up, and
the final page coordinates (in :class:`Net`) have y pointing down from the
page's top-left corner, as SVG and PDF draw them.

Examples
--------
>>> from diefab import Polyhedron
>>> cube = Polyhedron.from_points([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)])
>>> net = unfold(cube, mm_per_unit=20.0)
>>> net.n_pieces, len(net.fold_edges), len(net.tabs)
(1, 5, 7)
"""

from __future__ import annotations

import heapq
import itertools
import math
import re
from collections import deque
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from .. import tolerances as tol
from ..errors import FabricationError
from ..geometry import Polyhedron
from .symmetry import Symmetries, off_axis, symmetries

__all__ = ["PAGES", "Net", "Page", "Tab", "pack_copies", "parse_page", "unfold"]

#: Page sizes in millimetres (portrait).
PAGES = {
    "A5": (148.0, 210.0),
    "A4": (210.0, 297.0),
    "A3": (297.0, 420.0),
    "LETTER": (215.9, 279.4),
    "LEGAL": (215.9, 355.6),
}
_PAGE_NAMES = {"LETTER": "Letter", "LEGAL": "Legal"}

#: Default glue-tab width, mm.
TAB_WIDTH = 5.0
#: A tab is never wider than this fraction of its edge ("about half the edge").
TAB_MAX_FRACTION = 0.45
#: The tab's outer side keeps at least this fraction of the edge length.
TAB_TOP_FRACTION = 0.1
#: Narrowest tab worth gluing, mm (edges shorter than ~3 mm may take narrower tabs,
#: down to 0.3 of their length).
TAB_MIN_WIDTH = 1.0
#: Spanning trees are enumerated when there are at most this many.
TREE_LIMIT = 20_000
#: Candidate trees for larger polyhedra.
HEURISTIC_TREES = 400
#: Face pairs checked for overlap over all heuristic trees: a die with many faces tries fewer trees.
PAIR_BUDGET = 4e7
#: Finalists (the layouts with the smallest faces-only footprint) whose tabs are
#: built and whose exact bounding rectangle is measured: this many per number of
#: the die's symmetries a tree keeps, twice this many in all.
MAX_FINALISTS = 25
#: Trees grown into pieces when no single piece fits, and the face count over which fewer are tried
#: (a tree's pieces cost time in proportion to the faces).
SPLIT_TREES = 12
SPLIT_FACES = 2400
#: Widths a tab tries, as fractions of the tab width, before the edge counts as taking none.
TAB_FACTORS = (1.0, 0.6, 0.35)
#: Gap between pieces on a page, mm.
PIECE_GAP = 4.0
_GRID = np.deg2rad(np.arange(0.0, 180.0, 1.0))


@dataclass(frozen=True)
class Page:
    """A sheet of paper: size and margins in millimetres.

    The footer band (title, legend, calibration bar) sits inside the bottom
    margin area and is not available to the net.
    """

    name: str
    width: float
    height: float
    margin: float = 10.0
    footer: float = 17.0

    @property
    def printable(self) -> tuple[float, float]:
        """Width and height available to the net, mm."""
        return self.width - 2 * self.margin, self.height - 2 * self.margin - self.footer


def parse_page(spec: str) -> Page:
    """``A5``, ``A4``, ``A3``, ``Letter``, ``Legal`` or ``WxH`` in millimetres (e.g. ``200x250``).

    >>> parse_page("letter").width
    215.9
    >>> parse_page("150x200").printable
    (130.0, 163.0)
    """
    text = str(spec).strip()
    key = text.upper()
    if key in PAGES:
        w, h = PAGES[key]
        return Page(_PAGE_NAMES.get(key, key), w, h)
    m = re.fullmatch(r"(\d+(?:\.\d+)?)\s*[xX×]\s*(\d+(?:\.\d+)?)", text)
    if not m:
        raise FabricationError(f"page {spec!r} is not A5, A4, A3, Letter, Legal or WxH in millimetres (e.g. 200x250)")
    w, h = float(m.group(1)), float(m.group(2))
    page = Page(f"{w:g}x{h:g}mm", w, h)
    pw, ph = page.printable
    if pw < 20 or ph < 20:
        raise FabricationError(
            f"page {spec!r} leaves {pw:g}x{ph:g} mm inside its margins and footer; need at least 20x20 mm"
        )
    return page


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


@dataclass(frozen=True, eq=False)
class Net:
    """A laid-out net, in page coordinates (mm, y down from the top-left corner).

    Attributes
    ----------
    poly : Polyhedron
        The die, model units.
    mm_per_unit : float
    page : Page
    faces : tuple of (k, 2) float arrays
        Each face's polygon, vertices in the order of ``poly.faces[i]``.
    face_page, face_piece : (m,) int
        Page and piece of each face.
    fold_edges : (m - pieces,) int
        Indices into ``poly.edges`` of the edges folded (tree edges).
    tabs : tuple of Tab
        One per cut edge.
    edge_labels : dict edge index -> str
        The letter of every cut edge, shared by its tab and the matching edge
        (without tabs, printed on both sides of the cut).
    """

    poly: Polyhedron
    mm_per_unit: float
    page: Page
    faces: tuple[np.ndarray, ...]
    face_page: np.ndarray
    face_piece: np.ndarray
    fold_edges: np.ndarray
    tabs: tuple[Tab, ...]
    edge_labels: dict[int, str] = field(default_factory=dict)
    search: dict = field(default_factory=dict)

    @property
    def n_pieces(self) -> int:
        return int(self.face_piece.max()) + 1

    @property
    def n_pages(self) -> int:
        return int(self.face_page.max()) + 1

    @cached_property
    def cut_edges(self) -> np.ndarray:
        """Indices into ``poly.edges`` of the edges cut (and glued with a tab)."""
        return np.setdiff1d(np.arange(len(self.poly.edges)), self.fold_edges)

    def face_edges(self, k: int) -> list[int]:
        """Edge indices along face `k`: entry i joins vertex i and i + 1."""
        return [_edge_lookup(self.poly)[_key(a, b)] for a, b in _ring(self.poly.faces[k])]

    def lines(self) -> dict[str, list[tuple[int, np.ndarray]]]:
        """``{"cut": [...], "fold": [...]}``: (page, (2, 2) segment) lists.

        Folds are the tree edges (drawn once) and the base of every tab; cuts
        are the cut edges without a tab on that copy and each tab's outer sides.
        """
        folds = set(int(e) for e in self.fold_edges)
        tab_at = {(t.edge, t.face) for t in self.tabs}
        out: dict[str, list[tuple[int, np.ndarray]]] = {"cut": [], "fold": []}
        drawn: set[int] = set()
        for k, poly in enumerate(self.faces):
            for i, e in enumerate(self.face_edges(k)):
                seg = np.array([poly[i], poly[(i + 1) % len(poly)]])
                if e in folds:
                    if e not in drawn:
                        out["fold"].append((int(self.face_page[k]), seg))
                        drawn.add(e)
                elif (e, k) in tab_at:
                    out["fold"].append((int(self.face_page[k]), seg))
                else:
                    out["cut"].append((int(self.face_page[k]), seg))
        for t in self.tabs:
            p = t.polygon
            for a, b in ((1, 2), (2, 3), (3, 0)):
                out["cut"].append((t.page, np.array([p[a], p[b]])))
        return out


# ----------------------------------------------------------------------
# topology helpers


def _ring(face: np.ndarray):
    return zip(face.tolist(), np.roll(face, -1).tolist())


def _key(a: int, b: int) -> tuple[int, int]:
    return (a, b) if a < b else (b, a)


def _edge_lookup(poly: Polyhedron) -> dict[tuple[int, int], int]:
    cache = poly.__dict__.setdefault("_net_edge_lookup", None)
    if cache is None:
        cache = {(int(a), int(b)): e for e, (a, b) in enumerate(poly.edges)}
        poly.__dict__["_net_edge_lookup"] = cache
    return cache


def spanning_tree_count(poly: Polyhedron) -> int:
    """Number of spanning trees of the face-adjacency graph (Kirchhoff's theorem).

    Exact while it fits a float's mantissa; beyond, its order of magnitude
    (a die with hundreds of faces has more than 10**300).
    """
    m = len(poly.faces)
    lap = np.zeros((m, m))
    for a, b in poly.edge_faces:
        lap[a, b] -= 1
        lap[b, a] -= 1
        lap[a, a] += 1
        lap[b, b] += 1
    _, log_count = np.linalg.slogdet(lap[1:, 1:])
    if log_count < 700:
        return int(round(math.exp(log_count)))
    return 10 ** int(log_count / math.log(10))


def _find(parent: list[int], x: int) -> int:
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


def _all_trees(poly: Polyhedron) -> list[tuple[int, ...]]:
    """Every spanning tree, as sorted tuples of edge indices."""
    m, ef = len(poly.faces), poly.edge_faces
    out = []
    pairs = [(int(a), int(b)) for a, b in ef]
    for combo in itertools.combinations(range(len(ef)), m - 1):
        parent = list(range(m))
        for e in combo:
            ra, rb = _find(parent, pairs[e][0]), _find(parent, pairs[e][1])
            if ra == rb:
                break
            parent[ra] = rb
        else:
            out.append(combo)
    return out


def _kruskal(poly: Polyhedron, weights: np.ndarray) -> tuple[int, ...]:
    m, ef = len(poly.faces), poly.edge_faces
    parent = list(range(m))
    tree = []
    for e in np.argsort(weights, kind="stable"):
        ra, rb = _find(parent, int(ef[e, 0])), _find(parent, int(ef[e, 1]))
        if ra != rb:
            parent[ra] = rb
            tree.append(int(e))
    return tuple(sorted(tree))


def _steepest_edge_tree(poly: Polyhedron, direction: np.ndarray) -> tuple[int, ...]:
    """Schlickeiser's steepest-edge unfolding: every vertex but the highest cuts its steepest upward edge.

    The cut edges span the vertices, so the remaining (fold) edges form a
    spanning tree of the faces.
    """
    v, edges = poly.vertices, poly.edges
    d = v[edges[:, 1]] - v[edges[:, 0]]
    slope = d @ direction / np.linalg.norm(d, axis=1)
    best = np.full(len(v), -np.inf)
    choice = np.full(len(v), -1)
    for e, (a, b) in enumerate(edges):
        # the edge rises from a to b with slope[e]
        if slope[e] > best[a]:
            best[a], choice[a] = slope[e], e
        if -slope[e] > best[b]:
            best[b], choice[b] = -slope[e], e
    top = int(np.argmax(v @ direction))
    cut = {int(choice[i]) for i in range(len(v)) if i != top}
    folds = tuple(e for e in range(len(edges)) if e not in cut)
    return folds if len(folds) == len(poly.faces) - 1 else ()


def _heuristic_trees(poly: Polyhedron, count: int, rng: np.random.Generator) -> list[tuple[int, ...]]:
    trees: dict[tuple[int, ...], None] = {}
    k = np.arange(count) + 0.5
    phi, theta = np.arccos(1 - 2 * k / count), np.pi * (1 + 5**0.5) * k
    dirs = np.column_stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)])
    for d in dirs:
        t = _steepest_edge_tree(poly, d)
        if t and _is_tree(poly, t):
            trees[t] = None
    lengths = np.linalg.norm(np.diff(poly.vertices[poly.edges], axis=1)[:, 0], axis=1)
    for _ in range(count // 2):
        # long edges are good folds (they keep the net compact); jitter for variety
        trees[_kruskal(poly, -lengths * rng.uniform(0.5, 1.5, len(lengths)))] = None
        trees[_kruskal(poly, rng.random(len(lengths)))] = None
    return list(trees)


def _is_tree(poly: Polyhedron, tree: tuple[int, ...]) -> bool:
    """True if the edges `tree` connect all faces without a cycle."""
    weights = np.ones(len(poly.edges))
    weights[list(tree)] = 0.0
    return len(tree) == len(poly.faces) - 1 and set(_kruskal(poly, weights)) == set(tree)


# ----------------------------------------------------------------------
# flat geometry


def _face_frames(poly: Polyhedron, scale: float) -> list[np.ndarray]:
    """Each face in its own plane frame, mm, counter-clockwise seen from outside."""
    out = []
    for k, f in enumerate(poly.faces):
        p = poly.vertices[f] * scale
        u = p[1] - p[0]
        u /= np.linalg.norm(u)
        w = np.cross(poly.normals[k], u)
        out.append(np.column_stack([(p - p[0]) @ u, (p - p[0]) @ w]))
    return out


def _rigid(src_a, src_b, dst_a, dst_b) -> np.ndarray:
    """3x3 rotation + translation taking segment src to segment dst."""
    ang = math.atan2(*(dst_b - dst_a)[::-1]) - math.atan2(*(src_b - src_a)[::-1])
    c, s = math.cos(ang), math.sin(ang)
    rot = np.array([[c, -s], [s, c]])
    out = np.eye(3)
    out[:2, :2] = rot
    out[:2, 2] = dst_a - rot @ src_a
    return out


def _hinges(poly: Polyhedron, local: list[np.ndarray]) -> np.ndarray:
    """(e, 2, 3, 3): ``[e, 0]`` maps face ``edge_faces[e, 1]``'s frame into ``edge_faces[e, 0]``'s; ``[e, 1]`` back."""
    out = np.empty((len(poly.edges), 2, 3, 3))
    pos = [{int(v): i for i, v in enumerate(f)} for f in poly.faces]
    for e, ((a, b), (fi, fj)) in enumerate(zip(poly.edges, poly.edge_faces)):
        a, b = int(a), int(b)
        m = _rigid(local[fj][pos[fj][a]], local[fj][pos[fj][b]], local[fi][pos[fi][a]], local[fi][pos[fi][b]])
        out[e, 0] = m
        out[e, 1] = np.linalg.inv(m)
    return out


def _rooted(poly: Polyhedron, tree: tuple[int, ...], root: int = 0):
    """Parent face, hinge (edge, direction) and BFS order of a spanning tree rooted at `root`."""
    m, ef = len(poly.faces), poly.edge_faces
    adj: list[list[tuple[int, int, int]]] = [[] for _ in range(m)]
    for e in tree:
        a, b = int(ef[e, 0]), int(ef[e, 1])
        adj[a].append((b, e, 0))  # child b in parent a's frame: hinge [e, 0]
        adj[b].append((a, e, 1))
    parent = np.full(m, -1)
    parent[root] = root
    hinge = np.full((m, 2), -1)
    order, queue = [root], deque([root])
    while queue:
        f = queue.popleft()
        for g, e, d in adj[f]:
            if parent[g] < 0:
                parent[g], hinge[g] = f, (e, d)
                order.append(g)
                queue.append(g)
    return parent, hinge, order


def _padded(local: list[np.ndarray]) -> np.ndarray:
    """(m, K, 3) homogeneous coordinates, short faces padded by repeating their last vertex."""
    k = max(len(p) for p in local)
    out = np.ones((len(local), k, 3))
    for i, p in enumerate(local):
        out[i, : len(p), :2] = p
        out[i, len(p) :, :2] = p[-1]
    return out


def _place(trees: list[tuple[int, ...]], poly, hinges, padded) -> tuple[np.ndarray, list]:
    """(T, m, K, 2) face polygons of every tree's layout, and each tree's rooting."""
    m = len(poly.faces)
    rel = np.tile(np.eye(3), (len(trees), m, 1, 1))
    par = np.empty((len(trees), m), dtype=np.intp)
    roots = []
    for t, tree in enumerate(trees):
        parent, hinge, order = _rooted(poly, tree)
        roots.append((parent, hinge, order))
        par[t] = parent
        ok = hinge[:, 0] >= 0
        rel[t, ok] = hinges[hinge[ok, 0], hinge[ok, 1]]
    # pointer jumping: world[f] is the product of the hinges from the root down to f; each pass doubles
    # the stretch of path it covers (the root's own transform is the identity, and its parent itself)
    world = rel.copy()
    rows = np.arange(len(trees))[:, None]
    up = par.copy()
    for _ in range(max(1, int(np.ceil(np.log2(max(m, 2)))))):
        world = world[rows, up] @ world
        up = up[rows, up]
    return np.einsum("tmij,mkj->tmki", world, padded)[..., :2], roots


def _overlap(a: np.ndarray, b: np.ndarray, eps: float = tol.NET_OVERLAP_MM) -> np.ndarray:
    """Separating-axis test of convex polygons, broadcast over leading axes.

    a : (..., K, 2), b : (..., L, 2), vertices in order (repeats allowed).
    Returns true where the interiors overlap by more than `eps` (mm) along
    every axis; polygons that only touch along an edge or at a vertex do not.
    """
    a, b = np.broadcast_arrays(a[..., :, None, :], b[..., None, :, :])
    a, b = a[..., :, 0, :], b[..., 0, :, :]
    edges = np.concatenate([np.roll(a, -1, axis=-2) - a, np.roll(b, -1, axis=-2) - b], axis=-2)
    length = np.linalg.norm(edges, axis=-1)
    valid = length > tol.NET_OVERLAP_MM
    axes = np.stack([edges[..., 1], -edges[..., 0]], axis=-1) / np.where(valid, length, 1.0)[..., None]
    pa = np.einsum("...ad,...vd->...av", axes, a)
    pb = np.einsum("...ad,...vd->...av", axes, b)
    sep = (pa.max(-1) <= pb.min(-1) + eps) | (pb.max(-1) <= pa.min(-1) + eps)
    return ~(sep & valid).any(-1)


def _count_overlaps(world: np.ndarray, sizes: list[int]) -> np.ndarray:
    """(T,) number of overlapping face pairs in each layout of `world` (T, m, K, 2).

    Pairs whose circumscribing circles are apart are skipped before the
    separating-axis test.
    """
    t, m = world.shape[:2]
    iu, ju = np.triu_indices(m, 1)
    step = max(1, int(4e6 // len(iu)))  # layouts per pass: bounded memory for dice with many faces
    if t > step:
        return np.concatenate([_count_overlaps(world[k : k + step], sizes) for k in range(0, t, step)])
    mask = np.arange(world.shape[2])[None, :] < np.array(sizes)[:, None]
    centre = (world * mask[None, :, :, None]).sum(axis=2) / np.array(sizes)[None, :, None]
    radius = np.linalg.norm(world - centre[:, :, None], axis=-1).max(axis=2)
    near = np.linalg.norm(centre[:, iu] - centre[:, ju], axis=-1) < radius[:, iu] + radius[:, ju]
    tt, pp = np.nonzero(near)
    clash = np.zeros(t, dtype=np.intp)
    for start in range(0, len(tt), 4096):
        sl = slice(start, start + 4096)
        hit = _overlap(world[tt[sl], iu[pp[sl]]], world[tt[sl], ju[pp[sl]]])
        np.add.at(clash, tt[sl][hit], 1)
    return clash


def _extents(points: np.ndarray, angles: np.ndarray = _GRID) -> tuple[np.ndarray, np.ndarray]:
    """Width and height of the bounding box of `points` (..., n, 2) rotated by each angle: (..., A) each."""
    c, s = np.cos(angles), np.sin(angles)
    x = points[..., 0, None] * c - points[..., 1, None] * s
    y = points[..., 0, None] * s + points[..., 1, None] * c
    return np.ptp(x, axis=-2), np.ptp(y, axis=-2)


def _hull(points: np.ndarray) -> np.ndarray:
    """Convex hull vertices of 2D points, counter-clockwise (Andrew's monotone chain)."""
    pts = sorted(set(map(tuple, np.round(points, 9).tolist())))
    if len(pts) < 3:
        return np.array(pts)

    def half(seq):
        out: list = []
        for p in seq:
            while (
                len(out) >= 2
                and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1]) - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0]))
                <= 0
            ):
                out.pop()
            out.append(p)
        return out

    return np.array(half(pts)[:-1] + half(pts[::-1])[:-1])


def _fit(points: np.ndarray, printable: tuple[float, float], margin: float = 0.0) -> tuple[float, float] | None:
    """(area, angle) of the smallest bounding box, over rotations that fit `printable`; None if none does.

    Candidate angles: a 1-degree grid and every convex-hull edge laid along
    either axis (the minimum-area rectangle has a side on a hull edge).
    """
    hull = _hull(points)
    d = np.roll(hull, -1, axis=0) - hull
    base = -np.arctan2(d[:, 1], d[:, 0])
    angles = np.concatenate([_GRID, base, base + np.pi / 2])
    w, h = _extents(hull, angles)
    w, h = w + 2 * margin, h + 2 * margin
    ok = (w <= printable[0] + 1e-9) & (h <= printable[1] + 1e-9)
    if not ok.any():
        return None
    area = np.where(ok, w * h, np.inf)
    i = int(np.argmin(area))
    return float(area[i]), float(angles[i])


# ----------------------------------------------------------------------
# tabs


def _trapezoid(p, q, width, cp, cq) -> np.ndarray | None:
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


def _free_angle(point, direction, shapes) -> float:
    """Clockwise angle (rad) from `direction` at `point` to the nearest edge of `shapes` leaving `point`."""
    base = math.atan2(direction[1], direction[0])
    best = 2 * math.pi
    for shape in shapes:
        near = np.flatnonzero(np.hypot(*(shape - point).T) < 1e-6)
        for i in near:
            for j in ((i - 1) % len(shape), (i + 1) % len(shape)):
                d = shape[j] - point
                if np.hypot(*d) < 1e-6:
                    continue
                cw = (base - math.atan2(d[1], d[0])) % (2 * math.pi)
                if cw > 1e-9:
                    best = min(best, cw)
    return best


def _place_tabs(polys, piece_of, cut_copies, width, group: Symmetries | None = None):
    """Greedy tabs: for every cut edge the widest shape, on either copy, that overlaps nothing in its piece.

    polys : list of (k, 2) arrays (layout coordinates); cut_copies : list of
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
    tabs = _Tabs(polys, piece_of, width)
    copies = dict(cut_copies)
    done: set[int] = set()
    matched = []
    for e, _ in cut_copies:
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


def _place_orbit(tabs: _Tabs, orbit: list[int], sides: list[dict[int, int]], copies: dict) -> bool:
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
            new[x] = (face, _trapezoid(p, q, width, lean[a], lean[b]))
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
        x1, y1 = np.roll(x, -1), np.roll(y, -1)
        cross = x * y1 - x1 * y
        area = cross.sum() / 2
        if abs(area) < tol.AREA:
            continue
        along, out = ((x + x1) * cross).sum() / (6 * area), ((y + y1) * cross).sum() / (6 * area)
        glued = int(next(f for f in poly.edge_faces[e] if f != face))
        start, end = poly.vertices[a], poly.vertices[b]
        u3 = (end - start) / np.linalg.norm(end - start)
        inward = np.cross(poly.normals[glued], u3)
        if inward @ (poly.face_centroids[glued] - start) < 0:
            inward = -inward
        moment += abs(area) * (start + (along * u3 + out * inward) / mm_per_unit)
        total += abs(area)
    return moment / total if total > 0 else None


def _tab_offset(poly, mm_per_unit, copies, placed, group: Symmetries) -> float:
    """Distance of the tabs' centre from the die's symmetry axis (plane, centre), mm; 0 without tabs."""
    center = _tabs_centroid(poly, mm_per_unit, copies, placed)
    return 0.0 if center is None else off_axis(group, center) * mm_per_unit


class _Tabs:
    """Glue tabs placed one cut edge at a time on a layout whose pieces may still be split.

    Each end of a tab leans in by at most 45 degrees and by less where a
    neighbouring face or tab leaves less room at that vertex.  A tab is
    tested only against the shapes of its piece that a :class:`_Grid`
    finds near it, so a die with hundreds of faces costs about as much per
    edge as a small one.  `piece_of` is read at every test: a caller may
    move faces (with their tabs) to a new piece between placements, and the
    tabs already placed stay valid, since a piece only ever loses shapes.
    """

    def __init__(self, polys: list[np.ndarray], piece_of: np.ndarray, width: float) -> None:
        self.piece_of, self.width = piece_of, width
        self.shapes = list(polys)  # faces first, then the tabs as they are placed
        self.owner = list(range(len(polys)))  # the face each shape belongs to
        self.grid = _Grid(_cell_size(polys))
        for k, p in enumerate(polys):
            self.grid.add(k, p)
        self.placed: list[tuple[int, int, np.ndarray]] = []

    def _near(self, piece: int, points: np.ndarray, pad: float = 0.0) -> list[np.ndarray]:
        return [self.shapes[i] for i in self.grid.near(points, pad) if self.piece_of[self.owner[i]] == piece]

    def _fit(self, face: int, p: np.ndarray, q: np.ndarray, factor: float) -> np.ndarray | None:
        """The tab `factor` times the width on copy (face, p, q) if it overlaps nothing in its piece, else None."""
        piece = self.piece_of[face]
        ends = self._near(piece, np.array([p, q]), pad=1e-6)
        u = (q - p) / np.hypot(*(q - p))
        # room at p turning clockwise from p->q, at q turning counter-clockwise from q->p
        ap = min(math.pi / 4, 0.9 * _free_angle(p, u, ends))
        aq = min(math.pi / 4, 0.9 * _free_angle_ccw(q, -u, ends))
        if min(ap, aq) < math.radians(3):
            return None
        tab = _trapezoid(p, q, factor * self.width, 1 / math.tan(ap), 1 / math.tan(aq))
        if tab is None:
            return None
        near = self._near(piece, tab)
        if near and _overlap(_stack(near), tab).any():
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


class _Grid:
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


def _cell_size(polys: list[np.ndarray]) -> float:
    """A grid cell about the size of a typical face, mm."""
    return max(float(np.median([np.ptp(p, axis=0).max() for p in polys])), 1e-3)


def _stack(shapes: list[np.ndarray]) -> np.ndarray:
    """(n, K, 2): polygons of different lengths, short ones padded by repeating their last vertex."""
    k = max(len(p) for p in shapes)
    return np.array([p if len(p) == k else np.concatenate([p, np.repeat(p[-1:], k - len(p), axis=0)]) for p in shapes])


def _free_angle_ccw(point, direction, shapes) -> float:
    """Counter-clockwise angle (rad) from `direction` at `point` to the nearest edge of `shapes` leaving it."""
    mirrored = [np.column_stack([s[:, 0], -s[:, 1]]) for s in shapes]
    return _free_angle(np.array([point[0], -point[1]]), np.array([direction[0], -direction[1]]), mirrored)


def _cut_copies(poly: Polyhedron, polys: list[np.ndarray], cut: list[int]):
    """For every cut edge, its two copies (face, start, end, start vertex, end vertex) in face-CCW order.

    Longest edges first.
    """
    lookup = _edge_lookup(poly)
    copies: dict[int, list] = {e: [] for e in cut}
    for k, f in enumerate(poly.faces):
        for i, (a, b) in enumerate(_ring(f)):
            e = lookup[_key(a, b)]
            if e in copies:
                copies[e].append((k, polys[k][i], polys[k][(i + 1) % len(f)], a, b))
    lengths = {e: float(np.hypot(*(c[0][2] - c[0][1]))) for e, c in copies.items()}
    return sorted(copies.items(), key=lambda item: (-round(lengths[item[0]], 6), item[0]))


# ----------------------------------------------------------------------
# the search


@dataclass
class _Layout:
    tree: tuple[int, ...]
    polys: list[np.ndarray]
    piece_of: np.ndarray
    parent: np.ndarray
    tabs: list
    fits: list[tuple[float, float]]  # (area, angle) per piece
    offset: float = 0.0  # of the tabs' centre from the symmetry axis, mm
    kept: int = 1  # symmetries that map the tabs (edge, face) onto themselves

    @property
    def area(self) -> float:
        return sum(a for a, _ in self.fits)

    @property
    def key(self):
        """Centred enough first, then the most symmetries kept, then the smallest, then the fewest pieces."""
        return (max(self.offset, tol.NET_TAB_OFFSET_MM), -self.kept, self.area, len(self.fits))


def unfold(
    poly: Polyhedron,
    mm_per_unit: float,
    *,
    page: Page | str = "A4",
    tab_width: float = TAB_WIDTH,
    seed: int = 0,
    search: bool = True,
    size_mm: float | None = None,
) -> Net:
    """Lay `poly` out flat as a net with glue tabs on one or more pages.

    Parameters
    ----------
    poly : Polyhedron
        The die, model units.
    mm_per_unit : float
        Scale (``Design.mm_per_unit``).
    page : Page or str
        Paper size (see :func:`parse_page`).
    tab_width : float, mm
        Width of a glue tab before narrowing; 0 for no tabs (every cut edge
        is then lettered on both sides, to be taped or glued edge to edge).
    seed : int
        Seeds the candidate trees of polyhedra with too many spanning trees
        to enumerate.
    search : bool
        If false, take the first valid layout instead of the most compact
        (the baseline of ``benchmarks/bench_net.py``).
    size_mm : float, optional
        The die's size as the user gave it; only used to state the largest
        size that fits when the die is too large for the page.

    Raises
    ------
    FabricationError
        If the die is too large for the page (the message gives the largest
        size that fits) or tabs cannot be placed.
    """
    if isinstance(page, str):
        page = parse_page(page)
    if not (math.isfinite(mm_per_unit) and mm_per_unit > 0):
        raise FabricationError(f"mm_per_unit={mm_per_unit} must be a positive number")
    if not (math.isfinite(tab_width) and (tab_width >= TAB_MIN_WIDTH or tab_width == 0)):
        raise FabricationError(f"tab width {tab_width} mm must be 0 (no tabs) or at least {TAB_MIN_WIDTH:g} mm")
    printable = page.printable
    local = _face_frames(poly, mm_per_unit)
    _check_size(local, printable, tab_width, size_mm)
    hinges, padded = _hinges(poly, local), _padded(local)

    count = spanning_tree_count(poly)
    m, n_edges = len(poly.faces), len(poly.edges)
    if count <= TREE_LIMIT and math.comb(n_edges, m - 1) <= 20 * TREE_LIMIT:
        trees, method = _all_trees(poly), "all spanning trees"
    else:
        count = max(8, min(HEURISTIC_TREES, int(PAIR_BUDGET / m**2)))
        trees, method = _heuristic_trees(poly, count, np.random.default_rng(seed)), "heuristic trees"

    group = symmetries(poly)
    keeps = _tree_symmetries(group, trees)  # (T, g): which symmetries map each tree onto itself
    n_sym = keeps.sum(axis=1)
    world, roots = _place(trees, poly, hinges, padded)
    n_clash = _count_overlaps(world, [len(f) for f in poly.faces])
    est = np.empty(len(trees))
    fits_page = np.empty(len(trees), dtype=bool)
    angles = np.deg2rad(np.arange(0.0, 180.0, 3.0))
    for start in range(0, len(trees), 512):
        w, h = _extents(world[start : start + 512].reshape(-1, m * world.shape[2], 2), angles)
        est[start : start + 512] = (w * h).min(axis=1)
        # the faces alone must fit, allowing for the coarse grid
        fits_page[start : start + 512] = ((w <= printable[0] * 1.03) & (h <= printable[1] * 1.03)).any(axis=1)

    stats = {"method": method, "trees": len(trees), "spanning_trees": count, "overlap_free": int((n_clash == 0).sum()),
             "symmetries": len(group)}  # fmt: skip
    best: _Layout | None = None
    tried: dict[int, int] = {}  # finalists per number of symmetries kept
    # the trees that keep the most symmetries first, each group smallest first
    order = np.lexsort((est, -n_sym, n_clash > 0))
    for t in order:
        if sum(tried.values()) >= 2 * MAX_FINALISTS:
            break
        if n_clash[t] or not fits_page[t] or tried.get(n_sym[t], 0) >= MAX_FINALISTS:
            continue
        if best is not None and est[t] * (1 - 0.03) > best.area and best.offset <= tol.NET_TAB_OFFSET_MM:
            continue
        tried[n_sym[t]] = tried.get(n_sym[t], 0) + 1
        layout = _single_piece(
            poly, trees[t], world[t], roots[t], tab_width, printable, group, group.subgroup(keeps[t]), mm_per_unit
        )
        if layout is not None and (best is None or layout.key < best.key):
            best = layout
            if not search:
                break
    stats["finalists"] = sum(tried.values())
    if best is None:
        # split: grow pieces along the trees with the smallest footprint, keep the fewest pieces
        n_split = max(1, min(SPLIT_TREES, int(SPLIT_FACES / m))) if search else 1
        for t in np.argsort(n_clash * 1e12 + est, kind="stable")[:n_split]:
            layout = _split(poly, trees[t], world[t], roots[t], tab_width, printable)
            if layout is not None and (best is None or (len(layout.fits), layout.area) < (len(best.fits), best.area)):
                best = layout
        if best is not None:
            copies = dict(_cut_copies(poly, best.polys, list(range(len(poly.edges)))))
            best.offset = _tab_offset(poly, mm_per_unit, copies, best.tabs, group)
            best.kept = _kept(group, best.tabs)
    if best is None:
        raise FabricationError("cannot place glue tabs on this net; try a smaller --tab-width")
    stats["pieces"] = len(best.fits)
    stats["tab_offset_mm"] = best.offset
    stats["tab_symmetries"] = best.kept if len(group) > 1 else 1
    stats["symmetric_about"] = group.fixed_set
    return _finish(poly, mm_per_unit, page, best, stats)


def _kept(group: Symmetries, tabs: list) -> int:
    """How many symmetries map the tabs (which edge, on which face) onto themselves."""
    own = {(e, f) for e, f, _ in tabs}
    return sum({(int(ge[e]), int(gf[f])) for e, f in own} == own for ge, gf in zip(group.edge, group.face))


def _tree_symmetries(group: Symmetries, trees: list[tuple[int, ...]]) -> np.ndarray:
    """(T, g) bool: symmetry g maps tree t's edges onto themselves (then it maps the cut edges so too)."""
    if len(group) == 1 or not trees:
        return np.ones((len(trees), len(group)), dtype=bool)
    edges = np.array(trees)
    own = np.sort(edges, axis=1)
    return np.stack([(np.sort(perm[edges], axis=1) == own).all(axis=1) for perm in group.edge], axis=1)


def _single_piece(poly, tree, world_t, rooting, tab_width, printable, group, kept, mm_per_unit) -> _Layout | None:
    """The layout of `tree` as one piece with its tabs, or None if it does not fit.

    The tabs keep the symmetries `kept` (those that map the tree onto
    itself) where they can; when they cannot keep them all (a mirror plane
    that cuts across a cut edge leaves that edge no symmetric side), the
    rotations among them are tried too, and the better layout is kept.
    """
    m = len(poly.faces)
    polys = [world_t[k, : len(poly.faces[k])] for k in range(m)]
    piece_of = np.zeros(m, dtype=np.intp)
    cut = sorted(set(range(len(poly.edges))) - set(tree))
    copies = _cut_copies(poly, polys, cut)
    best = None
    rotations = np.linalg.det(kept.matrices) > 0
    for sub in (kept, kept.subgroup(rotations)):
        tabs, failed = _place_tabs(polys, piece_of, copies, tab_width, sub)
        fit = None if failed is not None else _fit(np.concatenate(polys + [t for _, _, t in tabs]), printable)
        if fit is None:
            layout = None
        elif len(group) == 1:
            return _Layout(tree, polys, piece_of, rooting[0], tabs, [fit])
        else:
            offset = _tab_offset(poly, mm_per_unit, dict(copies), tabs, group)
            layout = _Layout(tree, polys, piece_of, rooting[0], tabs, [fit], offset, _kept(group, tabs))
        if layout is not None and (best is None or layout.key < best.key):
            best = layout
        if (best is not None and best.kept >= len(kept)) or rotations.all():
            break
    return best


def _split(poly, tree, world_t, rooting, tab_width, printable) -> _Layout | None:
    """Grow pieces along the tree.

    A face joins its parent's piece if it overlaps nothing there and the
    piece, with a tab's width all round, still fits the page.
    """
    parent, _, order = rooting
    m = len(poly.faces)
    polys = [world_t[k, : len(poly.faces[k])] for k in range(m)]
    piece_of = np.full(m, -1, dtype=np.intp)
    cell = _cell_size(polys)
    grids: list[_Grid] = []
    hulls: list[np.ndarray] = []  # each piece's convex hull so far: its fit is the fit of all its faces
    n_pieces = 0
    for f in order:
        p = int(parent[f])
        if p != f:
            k = int(piece_of[p])
            near = grids[k].near(polys[f])
            if not (near and _overlap(_stack([polys[g] for g in near]), polys[f]).any()):
                pts = np.concatenate([hulls[k], polys[f]])
                if _fit(pts, printable, margin=tab_width) is not None:
                    piece_of[f] = k
                    grids[k].add(f, polys[f])
                    hulls[k] = _hull(pts)
                    continue
        piece_of[f] = n_pieces
        grids.append(_Grid(cell))
        grids[-1].add(f, polys[f])
        hulls.append(polys[f])
        n_pieces += 1
    children: list[list[int]] = [[] for _ in range(m)]
    for f in range(m):
        if parent[f] != f:
            children[int(parent[f])].append(f)
    at_vertex: dict[int, list[int]] = {}
    for k, ring in enumerate(poly.faces):
        for v in ring.tolist():
            at_vertex.setdefault(v, []).append(k)
    # tabs longest edge first; an edge that takes none detaches a face next to it, with its subtree, into a
    # piece of its own (the fold it hung from is cut and queued) and is tried again
    ef = poly.edge_faces
    folds = {e for e in tree if piece_of[ef[e, 0]] == piece_of[ef[e, 1]]}
    copies = dict(_cut_copies(poly, polys, list(range(len(poly.edges)))))
    queue = [(-round(float(np.hypot(*(c[0][2] - c[0][1]))), 6), e) for e, c in copies.items() if e not in folds]
    heapq.heapify(queue)
    tabs = _Tabs(polys, piece_of, tab_width)
    for _ in range(m + len(copies) + 1):
        if not queue or tab_width == 0:
            break
        length, failed = queue[0]
        if tabs.place(failed, copies[failed]):
            heapq.heappop(queue)
            continue
        around = sorted({k for v in poly.edges[failed].tolist() for k in at_vertex[v]} - set(ef[failed].tolist()))
        pieces = {int(piece_of[k]) for k in ef[failed]}
        movable = [
            int(f)
            for f in [*ef[failed], *around]
            if parent[f] != f and piece_of[parent[f]] == piece_of[f] and piece_of[f] in pieces
        ]
        if not movable:
            return None
        f = movable[0]
        old, stack = piece_of[f], [f]
        while stack:
            g = stack.pop()
            piece_of[g] = n_pieces
            stack.extend(h for h in children[g] if piece_of[h] == old)
        n_pieces += 1
        hinge = next(e for e in folds if set(ef[e].tolist()) == {f, int(parent[f])})
        folds.discard(hinge)
        heapq.heappush(queue, (-round(float(np.hypot(*(copies[hinge][0][2] - copies[hinge][0][1]))), 6), hinge))
    else:
        return None
    tabs = tabs.placed
    fits = []
    for k in range(n_pieces):
        pts = np.concatenate(
            [polys[f] for f in np.flatnonzero(piece_of == k)] + [t for _, f, t in tabs if piece_of[f] == k]
        )
        fit = _fit(pts, printable)
        if fit is None:
            return None
        fits.append(fit)
    return _Layout(tuple(sorted(folds)), polys, piece_of, parent, tabs, fits)


def _check_size(local, printable, tab_width, size_mm) -> None:
    """Every face with a full-width tab margin must fit the page: else say the largest size that does."""

    def fits(scale: float) -> bool:
        return all(_fit(p * scale, printable, margin=tab_width) is not None for p in local)

    if fits(1.0):
        return
    lo, hi = 0.0, 1.0
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    largest = (
        f"the largest size that fits is {math.floor(lo * size_mm * 10) / 10:g} mm"
        if size_mm
        else f"the largest scale that fits is {lo:.4g} times this one"
    )
    raise FabricationError(
        f"the die is too large for the page: a face with its glue tabs does not fit the "
        f"{printable[0]:g}x{printable[1]:g} mm inside the margins; {largest}"
    )


def _finish(poly, mm_per_unit, page: Page, layout: _Layout, stats) -> Net:
    """Rotate every piece to its chosen angle, pack pieces onto pages, label the cut edges."""
    m = len(poly.faces)
    printable = page.printable
    pieces = []
    for k, (_, angle) in enumerate(layout.fits):
        c, s = math.cos(angle), math.sin(angle)
        rot = np.array([[c, -s], [s, c]])
        members = np.flatnonzero(layout.piece_of == k)
        tabs = [(e, f, t @ rot.T) for e, f, t in layout.tabs if layout.piece_of[f] == k]
        polys = {int(f): layout.polys[f] @ rot.T for f in members}
        pts = np.concatenate(list(polys.values()) + [t for _, _, t in tabs])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        pieces.append((polys, tabs, lo, hi - lo))
    placement = _shelf([size for *_, size in pieces], printable)
    faces: list[np.ndarray | None] = [None] * m
    face_page = np.zeros(m, dtype=np.intp)
    raw_tabs = []
    for k, (polys, tabs, lo, size) in enumerate(pieces):
        pg, at = placement[k]
        # centre a lone piece on its page
        alone = sum(1 for v in placement.values() if v[0] == pg) == 1
        off = (np.array(printable) - size) / 2 if alone else at
        origin = np.array([page.margin, page.margin]) + off

        def to_page(p, lo=lo, size=size, origin=origin):
            # layout y up -> page y down, without mirroring the picture
            return np.column_stack([p[:, 0] - lo[0], size[1] - (p[:, 1] - lo[1])]) + origin

        for f, p in polys.items():
            faces[f] = to_page(p)
            face_page[f] = pg
        for e, f, t in tabs:
            raw_tabs.append((e, f, to_page(t), pg))
    # letters in reading order of the tabs (without tabs: of the first copy of each cut edge)
    raw_tabs.sort(key=lambda r: (r[3], round(r[2].mean(axis=0)[1] / 10), r[2].mean(axis=0)[0]))
    letter_of = {e: _letters(i) for i, (e, *_) in enumerate(raw_tabs)}
    if not raw_tabs:
        lookup = _edge_lookup(poly)
        firsts: dict[int, tuple] = {}
        for k, f in enumerate(poly.faces):
            for i, (a, b) in enumerate(_ring(f)):
                e = lookup[_key(a, b)]
                if e not in layout.tree and e not in firsts:
                    mid = (faces[k][i] + faces[k][(i + 1) % len(f)]) / 2
                    firsts[e] = (int(face_page[k]), round(mid[1] / 10), mid[0])
        letter_of = {e: _letters(i) for i, e in enumerate(sorted(firsts, key=firsts.get))}
    tabs_out = tuple(Tab(letter_of[e], int(e), int(f), t, int(pg)) for e, f, t, pg in raw_tabs)
    folds = np.array(
        sorted(
            e for e in layout.tree if layout.piece_of[poly.edge_faces[e, 0]] == layout.piece_of[poly.edge_faces[e, 1]]
        ),
        dtype=np.intp,
    )
    return Net(
        poly=poly,
        mm_per_unit=mm_per_unit,
        page=page,
        faces=tuple(faces),
        face_page=face_page,
        face_piece=layout.piece_of.copy(),
        fold_edges=folds,
        tabs=tabs_out,
        edge_labels=letter_of,
        search=stats,
    )


def _shelf(sizes, printable) -> dict[int, tuple[int, np.ndarray]]:
    """Shelf packing, tallest first: item index -> (page, offset of its box from the printable corner)."""
    placement: dict[int, tuple[int, np.ndarray]] = {}
    page_no, x, y, shelf = 0, 0.0, 0.0, 0.0
    for k in sorted(range(len(sizes)), key=lambda k: (-sizes[k][1], k)):
        w, h = sizes[k]
        if x > 0 and x + w > printable[0] + 1e-9:
            x, y, shelf = 0.0, y + shelf + PIECE_GAP, 0.0
        if y > 0 and y + h > printable[1] + 1e-9:
            page_no, x, y, shelf = page_no + 1, 0.0, 0.0, 0.0
        placement[k] = (page_no, np.array([x, y]))
        x, shelf = x + w + PIECE_GAP, max(shelf, h)
    return placement


def pack_copies(net: Net, copies: int) -> tuple[Net, ...]:
    """`copies` copies of `net`, their pieces packed together onto as few pages as the shelf packer finds.

    Each copy is a :class:`Net` of its own (same faces, tabs and letters,
    other positions); ``max(n.n_pages for n in result)`` pages in all.
    """
    if isinstance(copies, bool) or not isinstance(copies, (int, np.integer)) or copies < 1:
        raise FabricationError(f"copies={copies!r} must be a whole number >= 1")
    if copies == 1:
        return (net,)
    boxes = []  # (copy, piece, page, lo, size)
    for c in range(copies):
        for piece in range(net.n_pieces):
            members = np.flatnonzero(net.face_piece == piece)
            pts = np.concatenate(
                [net.faces[f] for f in members] + [t.polygon for t in net.tabs if net.face_piece[t.face] == piece]
            )
            lo = pts.min(axis=0)
            boxes.append((c, piece, lo, pts.max(axis=0) - lo))
    placement = _shelf([b[3] for b in boxes], net.page.printable)
    corner = np.array([net.page.margin, net.page.margin])
    moved: list[dict[int, tuple[int, np.ndarray]]] = [{} for _ in range(copies)]
    for i, (c, piece, lo, _) in enumerate(boxes):
        pg, at = placement[i]
        moved[c][piece] = (pg, corner + at - lo)
    out = []
    for c in range(copies):
        shift = [moved[c][int(p)] for p in net.face_piece]
        faces = tuple(poly + shift[f][1] for f, poly in enumerate(net.faces))
        tabs = tuple(replace(t, polygon=t.polygon + shift[t.face][1], page=shift[t.face][0]) for t in net.tabs)
        out.append(replace(net, faces=faces, face_page=np.array([s[0] for s in shift]), tabs=tabs))
    return tuple(out)


def _letters(i: int) -> str:
    """0 -> A, 25 -> Z, 26 -> AA, ..."""
    out = ""
    i += 1
    while i:
        i, r = divmod(i - 1, 26)
        out = chr(65 + r) + out
    return out
