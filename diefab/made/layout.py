"""The search for a net: which spanning tree to unfold along, and where the glue tabs go.

The net is cut along the complement of a spanning tree of the face-adjacency
graph (:mod:`diefab.geometry.trees`): tree edges are folds, every other edge
is cut and glued back with one trapezoidal tab (:mod:`.tabs`).  For small dice
every spanning tree is tried; larger ones get a few hundred candidate trees
(steepest-edge unfoldings towards many directions, random minimum spanning
trees).  A layout is rejected when two faces overlap **or** a glue tab
overlaps a face or another tab; tabs are placed while the layout is checked,
narrowed or moved to the other face when they would collide.  Among valid
layouts the one whose bounding rectangle, rotated to fit the page, has the
smallest area wins; when no single piece fits, the net is split into several
pieces that each fit a page.

The card of the tabs is part of the paper die's body (:mod:`diefab.made.bodies`),
so on a symmetric die (:mod:`diefab.geometry.symmetry`) the tabs are laid out
to keep its symmetry: trees that the most symmetries map onto themselves are
tried first, the tabs of each cut edge's orbit under those symmetries go on
matching sides (edge ``g(e)`` gets its tab on face ``g(f)``) and take the
orbit's common, narrowest shape, and among the valid layouts those whose
tabs' centre of mass lies on the die's symmetry axis (within
:data:`~diefab.core.tolerances.NET_TAB_OFFSET_MM`) come first.

The result, a :class:`NetLayout`, is what both the net's pages
(:func:`diefab.made.unfold.unfold`) and the paper die's mass model
(:func:`diefab.made.unfold.tab_shapes`) are made from.  All lengths are
millimetres, in layout coordinates (y up).
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field

import numpy as np

from diefab.core import tolerances as tol
from diefab.core.errors import FabricationError
from diefab.geometry.flat import convex_hull, extents, fit_box, overlap, stack_polygons
from diefab.geometry.polyhedron import Polyhedron
from diefab.geometry.symmetry import Symmetries, symmetries
from diefab.geometry.trees import all_trees, heuristic_trees, spanning_tree_count
from diefab.made.flatten import count_overlaps, face_frames, hinges_of, homogeneous, place_trees, rooted
from diefab.made.tabs import Grid, Tabs, cell_size, cut_copies, place_tabs, tab_offset

__all__ = ["NetLayout", "lay_out"]

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
#: Trees whose faces are checked for overlaps at a time, as the search comes to them.
CLASH_BATCH = 64


@dataclass
class NetLayout:
    """A net as its search leaves it: the tree, the faces and tabs in layout coordinates, one fit per piece.

    Attributes
    ----------
    tree : tuple of int
        The spanning tree's edges (indices into ``poly.edges``); those whose
        faces lie in one piece are the folds.
    polys : list of (k, 2) float arrays, mm
        Each face in layout coordinates (y up), vertices in the order of ``poly.faces[i]``.
    piece_of, parent : (m,) int
        Each face's piece and its parent face in the tree (the root its own).
    tabs : list of (edge, face, (4, 2) polygon)
        One glue tab per cut edge, on the copy of the edge on `face`.
    fits : list of (area, angle)
        Per piece: the area of its bounding rectangle at the angle (rad) that fits the page.
    """

    tree: tuple[int, ...]
    polys: list[np.ndarray]
    piece_of: np.ndarray
    parent: np.ndarray
    tabs: list
    fits: list[tuple[float, float]]  # (area, angle) per piece
    offset: float = 0.0  # of the tabs' centre from the symmetry axis, mm
    kept: int = 1  # symmetries that map the tabs (edge, face) onto themselves
    stats: dict = field(default_factory=dict)  # how the search went (``Net.search``)

    @property
    def area(self) -> float:
        return sum(a for a, _ in self.fits)

    @property
    def key(self):
        """Centred enough first, then the most symmetries kept, then the smallest, then the fewest pieces."""
        return (max(self.offset, tol.NET_TAB_OFFSET_MM), -self.kept, self.area, len(self.fits))


def lay_out(
    poly: Polyhedron,
    mm_per_unit: float,
    printable: tuple[float, float],
    tab_width: float,
    *,
    seed: int = 0,
    search: bool = True,
) -> NetLayout:
    """Search the layouts of `poly` for the most compact net with glue tabs that fits `printable`.

    Parameters
    ----------
    poly : Polyhedron
        The die, model units.
    mm_per_unit : float
        Scale, millimetres per model unit.
    printable : (2,) float, mm
        Width and height of the page inside its margins.
    tab_width : float, mm
        Width of a glue tab before narrowing; 0 for none.
    seed : int
        Seeds the candidate trees of polyhedra with too many spanning trees to enumerate.
    search : bool
        If false, take the first valid layout instead of the most compact.

    Raises
    ------
    FabricationError
        If the tabs cannot be placed.
    """
    local = face_frames(poly, mm_per_unit)
    hinges, padded = hinges_of(poly, local), homogeneous(local)
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
    world, parents = place_trees(trees, poly, hinges, padded)
    sizes = [len(f) for f in poly.faces]
    est = np.empty(len(trees))
    fits_page = np.empty(len(trees), dtype=bool)
    angles = np.deg2rad(np.arange(0.0, 180.0, 3.0))
    # every face's own corners, without the repeats that pad short faces (the extents are the same)
    k = world.shape[2]
    corners = np.concatenate([f * k + np.arange(len(face)) for f, face in enumerate(poly.faces)])
    for start in range(0, len(trees), 512):
        w, h = extents(world[start : start + 512].reshape(-1, m * k, 2)[:, corners], angles)
        est[start : start + 512] = (w * h).min(axis=1)
        # the faces alone must fit, allowing for the coarse grid
        fits_page[start : start + 512] = ((w <= printable[0] * 1.03) & (h <= printable[1] * 1.03)).any(axis=1)

    stats = {"method": method, "trees": len(trees), "spanning_trees": count, "symmetries": len(group)}
    best: NetLayout | None = None
    tried: dict[int, int] = {}  # finalists per number of symmetries kept
    # the trees that keep the most symmetries first, each group smallest first; a tree whose faces overlap is
    # skipped, and its faces are checked only when it comes up (in batches along this order)
    order = np.lexsort((est, -n_sym))
    n_clash = np.full(len(trees), -1, dtype=np.intp)  # -1: not counted yet
    for i, t in enumerate(order):
        if sum(tried.values()) >= 2 * MAX_FINALISTS:
            break
        if not fits_page[t] or tried.get(n_sym[t], 0) >= MAX_FINALISTS:
            continue
        if best is not None and est[t] * (1 - 0.03) > best.area and best.offset <= tol.NET_TAB_OFFSET_MM:
            continue
        if n_clash[t] < 0:
            batch = order[i : i + CLASH_BATCH]
            batch = batch[fits_page[batch] & (n_clash[batch] < 0)]
            n_clash[batch] = count_overlaps(world[batch], sizes)
        if n_clash[t]:
            continue
        tried[n_sym[t]] = tried.get(n_sym[t], 0) + 1
        layout = _single_piece(
            poly, trees[t], world[t], parents[t], tab_width, printable, group, group.subgroup(keeps[t]), mm_per_unit
        )
        if layout is not None and (best is None or layout.key < best.key):
            best = layout
            if not search:
                break
    stats["finalists"] = sum(tried.values())
    if best is None:
        # split: grow pieces along the trees with the smallest footprint, keep the fewest pieces
        n_split = max(1, min(SPLIT_TREES, int(SPLIT_FACES / m))) if search else 1
        unknown = np.flatnonzero(n_clash < 0)
        n_clash[unknown] = count_overlaps(world[unknown], sizes)
        for t in np.argsort(n_clash * 1e12 + est, kind="stable")[:n_split]:
            layout = _split(poly, trees[t], world[t], tab_width, printable)
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
    best.stats = stats
    return best


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


def _single_piece(poly, tree, world_t, parent, tab_width, printable, group, kept, mm_per_unit) -> NetLayout | None:
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
            return NetLayout(tree, polys, piece_of, parent.copy(), tabs, [fit])
        else:
            offset = tab_offset(poly, mm_per_unit, dict(copies), tabs, group)
            layout = NetLayout(tree, polys, piece_of, parent.copy(), tabs, [fit], offset, _kept(group, tabs))
        if layout is not None and (best is None or layout.key < best.key):
            best = layout
        if (best is not None and best.kept >= len(kept)) or rotations.all():
            break
    return best


def _split(poly, tree, world_t, tab_width, printable) -> NetLayout | None:
    """Grow pieces along the tree.

    A face joins its parent's piece if it overlaps nothing there and the
    piece, with a tab's width all round, still fits the page.
    """
    parent, _, order = rooted(poly, tree)
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
    return NetLayout(tuple(sorted(folds)), polys, piece_of, parent, tabs, fits)
