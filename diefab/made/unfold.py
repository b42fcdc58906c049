"""Unfolding a convex polyhedron into a paper net with glue tabs, on pages.

:func:`unfold` searches the layouts (:mod:`.layout`: which spanning tree to
unfold along, where the glue tabs go), turns every piece to the angle that
fits the page, packs the pieces onto pages (:mod:`.pages`) and letters the
cut edges.  :func:`tab_shapes` gives the same search's tabs as they are glued
inside the die, for the paper die's mass model: the net and the body are made
from one :class:`~diefab.made.layout.NetLayout`, computed once for both.

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

import math
from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache

import numpy as np

from diefab.core.errors import FabricationError
from diefab.geometry.flat import fit_box
from diefab.geometry.polyhedron import Polyhedron
from diefab.geometry.trees import edge_key, edge_lookup, face_ring
from diefab.made.fill import TabShape
from diefab.made.flatten import face_frames
from diefab.made.layout import NetLayout, lay_out
from diefab.made.pages import Page, parse_page, shelf
from diefab.made.tabs import TAB_MIN_WIDTH, TAB_WIDTH, Tab

__all__ = ["Net", "net_tab_shapes", "pack_copies", "tab_shapes", "unfold"]


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
    _check_size(face_frames(poly, mm_per_unit), page.printable, tab_width, size_mm)
    layout = net_layout(poly, mm_per_unit, page.printable, tab_width, seed=seed, search=search)
    return _finish(poly, mm_per_unit, page, layout)


@lru_cache(maxsize=64)
def _layout_cached(key: tuple, poly: Polyhedron, mm_per_unit: float, printable: tuple, tab_width: float, seed: int,
                   search: bool) -> NetLayout:  # fmt: skip
    return lay_out(poly, mm_per_unit, printable, tab_width, seed=seed, search=search)


def net_layout(
    poly: Polyhedron, mm_per_unit: float, printable: tuple[float, float], tab_width: float, *, seed: int = 0,
    search: bool = True,
) -> NetLayout:  # fmt: skip
    """:func:`~diefab.made.layout.lay_out`, remembered: the net and the mass model of one die share one search.

    The result is shared between callers: read it, do not change it.
    """
    key = (poly.vertices.tobytes(), tuple(tuple(int(v) for v in f) for f in poly.faces))
    printable = (float(printable[0]), float(printable[1]))
    return _layout_cached(key, poly, float(mm_per_unit), printable, float(tab_width), int(seed), bool(search))


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


def _finish(poly, mm_per_unit, page: Page, layout: NetLayout) -> Net:
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
        search=dict(layout.stats),
    )


def _letters(i: int) -> str:
    """0 -> A, 25 -> Z, 26 -> AA, ..."""
    out = ""
    i += 1
    while i:
        i, r = divmod(i - 1, 26)
        out = chr(65 + r) + out
    return out


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
    placement = shelf([b[3] for b in boxes], net.page.printable)
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


# ----------------------------------------------------------------------
# the tabs of a net, for the mass model


def _tab_shape(poly: Polyhedron, ring: np.ndarray, edge: int, face: int, polygon: np.ndarray) -> TabShape:
    """The tab `polygon` on `edge`'s copy on `face` (laid out as `ring`), as a shape on the die's edge."""
    p, q, far_q, far_p = polygon
    i = int(np.argmin(np.linalg.norm(ring - p, axis=1)))
    n = len(ring)
    a, b = int(poly.faces[face][i]), int(poly.faces[face][(i + 1) % n])
    u = (q - p) / np.linalg.norm(q - p)
    normal = np.array([-u[1], u[0]])
    width = abs(float((far_p - p) @ normal))
    lean_a = float((far_p - p) @ u) / width
    lean_b = float((q - far_q) @ u) / width
    faces = poly.edge_faces[edge]
    glued = int(faces[0] if faces[1] == face else faces[1])
    return TabShape(a, b, glued, width, lean_a, lean_b)


def net_tab_shapes(net: Net) -> tuple[TabShape, ...]:
    """The tabs of a laid-out net, as :class:`~diefab.made.fill.TabShape` on the die's edges."""
    return tuple(_tab_shape(net.poly, net.faces[t.face], t.edge, t.face, t.polygon) for t in net.tabs)


def tab_shapes(poly: Polyhedron, mm_per_unit: float, tab_mm: float) -> tuple[TabShape, ...]:
    """The glue tabs of the net of `poly` that :func:`unfold` lays out on A4 (none when `tab_mm` is 0).

    They come from the same search as the net's (:func:`net_layout`), without
    turning and packing its pieces onto pages; the shapes do not depend on where a piece lies.
    """
    if tab_mm == 0:
        return ()
    layout = net_layout(poly, mm_per_unit, parse_page("A4").printable, tab_mm)
    return tuple(_tab_shape(poly, layout.polys[f], e, f, t) for e, f, t in layout.tabs)
