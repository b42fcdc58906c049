"""Unfolding a convex polyhedron into a paper net with glue tabs.

The net is cut along the complement of a spanning tree of the face-adjacency
graph (:mod:`.trees`): tree edges are folds, every other edge is cut and
glued back with one trapezoidal tab (:mod:`.tabs`).  For small dice every spanning tree is tried; larger ones get
a few hundred candidate trees (steepest-edge unfoldings towards many
directions, random minimum spanning trees).  A layout is rejected when two
faces overlap **or** a glue tab overlaps a face or another tab; tabs are
placed while the layout is checked, narrowed or moved to the other face when
they would collide.  Among valid layouts the one whose bounding rectangle,
rotated to fit the page, has the smallest area wins; when no single piece
fits, the net is split into several pieces that each fit a page, and the
pieces are packed onto pages (:mod:`.pages`).

The card of the tabs is part of the paper die's body (:mod:`diefab.made.bodies`),
so on a symmetric die (:mod:`.symmetry`) the tabs are laid out to keep its
symmetry: trees that the most symmetries map onto themselves are tried
first, the tabs of each cut edge's orbit under those symmetries go on
matching sides (edge ``g(e)`` gets its tab on face ``g(f)``) and take the
orbit's common, narrowest shape, and among the valid layouts those whose
tabs' centre of mass lies on the die's symmetry axis (within
:data:`~diefab.core.tolerances.NET_TAB_OFFSET_MM`) come first.  The distance
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
import math
from collections import deque
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from diefab.core import tolerances as tol
from diefab.core.errors import FabricationError
from diefab.geometry.flat import convex_hull, extents, fit_box, overlap, stack_polygons
from diefab.geometry.polyhedron import Polyhedron
from diefab.geometry.symmetry import Symmetries, symmetries
from diefab.geometry.trees import all_trees, edge_key, edge_lookup, face_ring, heuristic_trees, spanning_tree_count
from diefab.made.pages import Page, parse_page, shelf
from diefab.made.tabs import (
    TAB_MIN_WIDTH,
    TAB_WIDTH,
    Grid,
    Tab,
    Tabs,
    cell_size,
    cut_copies,
    place_tabs,
    tab_offset,
)

__all__ = ["Net", "unfold"]

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
        return [edge_lookup(self.poly)[edge_key(a, b)] for a, b in face_ring(self.poly.faces[k])]

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
    flat = stack_polygons(local)
    return np.concatenate([flat, np.ones((*flat.shape[:2], 1))], axis=2)


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
        hit = overlap(world[tt[sl], iu[pp[sl]]], world[tt[sl], ju[pp[sl]]])
        np.add.at(clash, tt[sl][hit], 1)
    return clash


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
        trees, method = all_trees(poly), "all spanning trees"
    else:
        count = max(8, min(HEURISTIC_TREES, int(PAIR_BUDGET / m**2)))
        trees, method = heuristic_trees(poly, count, np.random.default_rng(seed)), "heuristic trees"

    group = symmetries(poly)
    keeps = _tree_symmetries(group, trees)  # (T, g): which symmetries map each tree onto itself
    n_sym = keeps.sum(axis=1)
    world, roots = _place(trees, poly, hinges, padded)
    n_clash = _count_overlaps(world, [len(f) for f in poly.faces])
    est = np.empty(len(trees))
    fits_page = np.empty(len(trees), dtype=bool)
    angles = np.deg2rad(np.arange(0.0, 180.0, 3.0))
    for start in range(0, len(trees), 512):
        w, h = extents(world[start : start + 512].reshape(-1, m * world.shape[2], 2), angles)
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
            copies = dict(cut_copies(poly, best.polys, list(range(len(poly.edges)))))
            best.offset = tab_offset(poly, mm_per_unit, copies, best.tabs, group)
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
    copies = cut_copies(poly, polys, cut)
    best = None
    rotations = np.linalg.det(kept.matrices) > 0
    for sub in (kept, kept.subgroup(rotations)):
        tabs, failed = place_tabs(polys, piece_of, copies, tab_width, sub)
        fit = None if failed is not None else fit_box(np.concatenate(polys + [t for _, _, t in tabs]), printable)
        if fit is None:
            layout = None
        elif len(group) == 1:
            return _Layout(tree, polys, piece_of, rooting[0], tabs, [fit])
        else:
            offset = tab_offset(poly, mm_per_unit, dict(copies), tabs, group)
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
    cell = cell_size(polys)
    grids: list[Grid] = []
    hulls: list[np.ndarray] = []  # each piece's convex hull so far: its fit is the fit of all its faces
    n_pieces = 0
    for f in order:
        p = int(parent[f])
        if p != f:
            k = int(piece_of[p])
            near = grids[k].near(polys[f])
            if not (near and overlap(stack_polygons([polys[g] for g in near]), polys[f]).any()):
                pts = np.concatenate([hulls[k], polys[f]])
                if fit_box(pts, printable, margin=tab_width) is not None:
                    piece_of[f] = k
                    grids[k].add(f, polys[f])
                    hulls[k] = convex_hull(pts)
                    continue
        piece_of[f] = n_pieces
        grids.append(Grid(cell))
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
    copies = dict(cut_copies(poly, polys, list(range(len(poly.edges)))))
    queue = [(-round(float(np.hypot(*(c[0][2] - c[0][1]))), 6), e) for e, c in copies.items() if e not in folds]
    heapq.heapify(queue)
    tabs = Tabs(polys, piece_of, tab_width)
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
        fit = fit_box(pts, printable)
        if fit is None:
            return None
        fits.append(fit)
    return _Layout(tuple(sorted(folds)), polys, piece_of, parent, tabs, fits)


def _check_size(local, printable, tab_width, size_mm) -> None:
    """Every face with a full-width tab margin must fit the page: else say the largest size that does."""

    def fits(scale: float) -> bool:
        return all(fit_box(p * scale, printable, margin=tab_width) is not None for p in local)

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
    placement = shelf([size for *_, size in pieces], printable)
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
        lookup = edge_lookup(poly)
        firsts: dict[int, tuple] = {}
        for k, f in enumerate(poly.faces):
            for i, (a, b) in enumerate(face_ring(f)):
                e = lookup[edge_key(a, b)]
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


def _letters(i: int) -> str:
    """0 -> A, 25 -> Z, 26 -> AA, ..."""
    out = ""
    i += 1
    while i:
        i, r = divmod(i - 1, 26)
        out = chr(65 + r) + out
    return out
