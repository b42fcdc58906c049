"""Mass properties: volume, centre of mass and inertia of a die as it is made.

``solid``
    a uniform solid body (what the paper's Eq. (1) describes);
``shell``
    a thin uniform shell, mass proportional to area (an idealised paper model);
``paper``
    a card model: every face a sheet of card of the given thickness and
    grammage (its mid-plane half a card's thickness inside the face), plus the
    glue tabs, each folded in and glued flat to the inside of the face across
    its cut edge (one card further in), plus optional glue on the tabs;
``print``
    a fused-filament print: perimeters (walls) along the sides, solid top and
    bottom layers, the inside filled with a fraction `infill`, and the labels
    engraved (or embossed) in the surface, the walls following the engraving.

Units: ``solid`` and ``print`` give volume of full-density material,
``shell`` and ``paper`` area of card, in model units; scale `mass` and
`inertia` by the real density (or grammage).  Only the centre of mass and
the inertia per unit mass matter to the landing.

Examples
--------
>>> from diefab.geometry.polyhedron import Polyhedron
>>> cube = Polyhedron.from_points([[x, y, z] for x in (0, 2) for y in (0, 2) for z in (0, 2)])
>>> props = mass_properties(cube)
>>> props.mass, props.center.tolist()
(8.0, [1.0, 1.0, 1.0])
>>> bool(np.allclose(props.inertia, 8 * (4 + 4) / 12 * np.eye(3)))
True

A printed cube on the bed keeps its centre over the bed but sinks: the bottom
skin is solid like the top, and both are thicker than the side walls, so the
symmetry holds here:

>>> printed = mass_properties(cube, Fill("print"), mm_per_unit=10.0)
>>> np.round(printed.center, 9).tolist()
[1.0, 1.0, 1.0]
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Literal

import numpy as np

from diefab.core import tolerances as tol
from diefab.core.errors import DesignError, GeometryError
from diefab.geometry.meshes import ClosedMesh
from diefab.geometry.polyhedron import Polyhedron, _cross

__all__ = [
    "Fill",
    "LabelMass",
    "MassProperties",
    "TabShape",
    "bed_face",
    "inset",
    "mass_properties",
    "mesh_mass_properties",
    "stated",
]

_CANONICAL = np.array([[2.0, 1.0, 1.0], [1.0, 2.0, 1.0], [1.0, 1.0, 2.0]]) / 120

#: Density of card, g/cm³: the thickness of a card is its grammage over this (160 g/m² -> 0.2 mm).
CARD_DENSITY = 0.8
#: Extrusion width of a line as a multiple of the nozzle diameter (PrusaSlicer's automatic width).
LINE_WIDTH_FACTOR = 1.125
#: Engraving depth of the labels in the print model of a design, mm (``diefab stl``'s default).
LABEL_DEPTH_MM = 0.6
#: A tab is never wider than this fraction of its edge ("about half the edge").
TAB_MAX_FRACTION = 0.45
#: The tab's outer side keeps at least this fraction of the edge length.
TAB_TOP_FRACTION = 0.1

KINDS = ("solid", "shell", "paper", "print")


def _number(name: str, value, lo: float, hi: float, unit: str, *, lo_open: bool = True, integer: bool = False):
    """Check one Fill field: a real number (not a bool or a string) in its range."""
    kind = "an integer" if integer else "a number"
    unit = f" {unit}" if unit else ""
    ok_type = isinstance(value, (int, np.integer)) if integer else isinstance(value, (int, float, np.number))
    if isinstance(value, (bool, np.bool_)) or not ok_type:
        raise DesignError(f"fill {name}={value!r} must be {kind} in {'(' if lo_open else '['}{lo:g}, {hi:g}]{unit}")
    if not (math.isfinite(value) and (value > lo if lo_open else value >= lo) and value <= hi):
        raise DesignError(f"fill {name}={value!r} is outside {'(' if lo_open else '['}{lo:g}, {hi:g}]{unit}")


@dataclass(frozen=True)
class Fill:
    """How the die is made.

    Parameters
    ----------
    kind : {"solid", "shell", "paper", "print"}
    card_g_m2 : float
        Paper: grammage of the card, g/m² (0, 1000].
    card_mm : float, optional
        Paper: card thickness, mm (0, 2]; default ``card_g_m2 / 800``
        (card of density 0.8 g/cm³).
    tabs : bool
        Paper: include the glue tabs of the die's net.
    tab_mm : float
        Paper: glue-tab width before narrowing, mm (the net's ``--tab-width``).
    glue_g_m2 : float
        Paper: dry glue on every tab, g/m² [0, 500].
    nozzle_mm : float
        Print: nozzle diameter, mm (0, 2]; lines are 1.125 of it wide.
    perimeters : int
        Print: perimeters (wall lines) along the sides, [1, 20].
    layer_mm : float
        Print: layer height, mm, (0, nozzle_mm].
    top_layers, bottom_layers : int
        Print: solid layers under every upward face and above every downward
        one (the bed face included), [0, 50].
    infill : float
        Print: fraction of the inside that is material, [0, 1].
    wall_mm : float, optional
        Print: side-wall thickness, mm, overriding ``perimeters`` lines
        (default: perimeters x line spacing).
    solid_below_mm2 : float
        Print: a layer whose infill region is smaller than this (mm²) is
        filled solid, [0, 10000] (PrusaSlicer's ``solid_infill_below_area``).
    skin_margin_mm : float
        Print: how far the solid layers next to an engraving reach into the
        infill beyond the text, mm, [0, 50] (PrusaSlicer widens top and
        bottom surfaces by 3 mm).
    labels : bool
        Print: include the engraved labels in a design's body.
    """

    kind: Literal["solid", "shell", "paper", "print"] = "solid"
    card_g_m2: float = 160.0
    card_mm: float | None = None
    tabs: bool = True
    tab_mm: float = 5.0
    glue_g_m2: float = 0.0
    nozzle_mm: float = 0.4
    perimeters: int = 2
    layer_mm: float = 0.2
    top_layers: int = 4
    bottom_layers: int = 4
    infill: float = 0.15
    wall_mm: float | None = None
    solid_below_mm2: float = 70.0
    skin_margin_mm: float = 3.0
    labels: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.kind, str) or self.kind not in KINDS:
            raise DesignError(f"fill kind={self.kind!r} is not one of {', '.join(KINDS)}")
        _number("card_g_m2", self.card_g_m2, 0, 1000, "g/m²")
        if self.card_mm is not None:
            _number("card_mm", self.card_mm, 0, 2, "mm")
        for name in ("tabs", "labels"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise DesignError(f"fill {name}={getattr(self, name)!r} must be true or false")
        _number("tab_mm", self.tab_mm, 0, 50, "mm", lo_open=False)
        _number("glue_g_m2", self.glue_g_m2, 0, 500, "g/m²", lo_open=False)
        _number("nozzle_mm", self.nozzle_mm, 0, 2, "mm")
        _number("perimeters", self.perimeters, 1, 20, "", lo_open=False, integer=True)
        _number("layer_mm", self.layer_mm, 0, self.nozzle_mm, "mm (at most the nozzle)")
        _number("top_layers", self.top_layers, 0, 50, "", lo_open=False, integer=True)
        _number("bottom_layers", self.bottom_layers, 0, 50, "", lo_open=False, integer=True)
        _number("infill", self.infill, 0, 1, "", lo_open=False)
        if self.wall_mm is not None:
            _number("wall_mm", self.wall_mm, 0, 50, "mm")
        _number("solid_below_mm2", self.solid_below_mm2, 0, 10000, "mm²", lo_open=False)
        _number("skin_margin_mm", self.skin_margin_mm, 0, 50, "mm", lo_open=False)

    @classmethod
    def from_mapping(cls, data, source: str = "[fill]") -> Fill:
        """A fill from a design's ``[fill]`` table; unknown keys are errors."""
        if not isinstance(data, dict):
            raise DesignError(f"{source} must be a table, got {data!r}")
        known = [f.name for f in fields(cls)]
        unknown = sorted(set(data) - set(known))
        if unknown:
            raise DesignError(f"{source}: unknown key {unknown[0]!r} (keys: {', '.join(known)})")
        return cls(**data)

    def to_mapping(self) -> dict:
        """The fields that matter for this kind, TOML-ready (unset optional fields left out)."""
        keys = {
            "solid": (),
            "shell": (),
            "paper": ("card_g_m2", "card_mm", "tabs", "tab_mm", "glue_g_m2"),
            "print": ("nozzle_mm", "perimeters", "layer_mm", "top_layers", "bottom_layers", "infill", "wall_mm",
                      "solid_below_mm2", "skin_margin_mm", "labels"),
        }[self.kind]  # fmt: skip
        return {"kind": self.kind, **{k: getattr(self, k) for k in keys if getattr(self, k) is not None}}

    @property
    def card_thickness_mm(self) -> float:
        """Thickness of the card, mm."""
        return self.card_mm if self.card_mm is not None else self.card_g_m2 / (1000 * CARD_DENSITY)

    @property
    def line_spacing_mm(self) -> float:
        """Distance between neighbouring perimeter lines, mm: width - layer x (1 - pi/4) (rounded-edge lines)."""
        return LINE_WIDTH_FACTOR * self.nozzle_mm - self.layer_mm * (1 - math.pi / 4)

    @property
    def wall_thickness_mm(self) -> float:
        """Side-wall thickness of a print, mm (the material of `perimeters` lines)."""
        return self.wall_mm if self.wall_mm is not None else self.perimeters * self.line_spacing_mm

    def describe(self) -> str:
        """One line: the settings of this kind."""
        if self.kind == "paper":
            tabs = f"glue tabs {self.tab_mm:g} mm" if self.tabs else "no tabs"
            glue = f", glue {self.glue_g_m2:g} g/m²" if self.glue_g_m2 else ""
            return f"paper {self.card_g_m2:g} g/m² card {self.card_thickness_mm:.2f} mm, {tabs}{glue}"
        if self.kind == "print":
            walls = f"{self.wall_mm:g} mm walls" if self.wall_mm is not None else f"{self.perimeters} perimeters"
            return (
                f"print {self.nozzle_mm:g} mm nozzle, {walls}, {self.layer_mm:g} mm layers, "
                f"{self.top_layers}/{self.bottom_layers} top/bottom layers, {self.infill:.0%} infill"
            )
        return self.kind


@dataclass(frozen=True)
class TabShape:
    """One glue tab of a paper net, in terms of the die's edge it glues.

    The tab hangs off the edge from vertex `a` to vertex `b` (in that order
    around the face it is printed on) and, folded in, lies flat on the inside
    of face `glued`: a trapezoid `width_mm` deep whose far side starts
    ``lean_a * width_mm`` from `a` and ends ``lean_b * width_mm`` before `b`.
    Taken from a laid-out net (:func:`diefab.made.bodies.net_tab_shapes`), it can
    be put on any die of the same combinatorics; a shorter edge narrows it by
    the net's own rule.
    """

    a: int
    b: int
    glued: int
    width_mm: float
    lean_a: float
    lean_b: float


@dataclass(frozen=True)
class LabelMass:
    """The material a label takes away (engraved) or adds (embossed), as a thin prism.

    area_mm2 : text area; centroid_mm : (3,) its centroid on the face;
    normal : (3,) the face's outward normal; face : index of the face;
    depth_mm : engraving depth or embossing height.  Optionally the text's
    outline (shapely, face coordinates x along `baseline`, y along `up`,
    from `origin_mm`), which gives the footprint of the walls that follow
    the engraving; without it they follow the text's own area.
    """

    face: int
    area_mm2: float
    centroid_mm: np.ndarray
    normal: np.ndarray
    depth_mm: float
    emboss: bool = False
    outline: object = None
    origin_mm: np.ndarray | None = None
    baseline: np.ndarray | None = None
    up: np.ndarray | None = None

    def footprint(self, grow_mm: float) -> tuple[float, np.ndarray]:
        """Area (mm²) and centroid (mm, on the face) of the text grown by `grow_mm`."""
        if self.outline is None or grow_mm <= 0:
            return self.area_mm2, np.asarray(self.centroid_mm, dtype=float)
        grown = self.outline.buffer(grow_mm)
        c = grown.centroid
        return float(grown.area), self.origin_mm + c.x * self.baseline + c.y * self.up


@dataclass(frozen=True, eq=False)
class MassProperties:
    """Mass, centre of mass and inertia tensor (about the centre of mass), unit density."""

    mass: float
    center: np.ndarray
    inertia: np.ndarray

    @property
    def principal_moments(self) -> np.ndarray:
        """(3,) float: eigenvalues of :attr:`inertia`, ascending."""
        return np.linalg.eigvalsh(self.inertia)


_Moments = tuple[float, np.ndarray, np.ndarray]  # mass, first moment (3,), second moment ∫ x xᵀ (3, 3)


def _solid_moments(poly: Polyhedron) -> _Moments:
    """Volume, first moment and second moment ∫ x xᵀ dV of the solid."""
    return _solid_moments_of(poly.vertices[poly.triangles])


def _solid_moments_of(v: np.ndarray) -> _Moments:
    """The same for the closed surface of outward triangles `v` ((t, 3, 3), corners of each)."""
    # tetrahedra (0, a, b, c)
    det = np.einsum("ij,ij->i", v[:, 0], _cross(v[:, 1], v[:, 2]))
    volume = det.sum() / 6
    first = (det[:, None] * v.sum(axis=1)).sum(axis=0) / 24
    a = v.transpose(0, 2, 1)  # columns are the tetrahedron's vertices
    second = np.einsum("t,tij,jk,tlk->il", det, a, _CANONICAL, a)
    return float(volume), first, second


def _sheet_moments(v: np.ndarray, weight: np.ndarray | float = 1.0) -> _Moments:
    """Area, first and second moment of triangles `v` (t, 3, 3), each weighted (area density)."""
    area = 0.5 * np.linalg.norm(_cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1) * weight
    s = v.sum(axis=1)
    first = (area[:, None] * s).sum(axis=0) / 3
    second = np.einsum("t,tki,tkj->ij", area, v, v) + np.einsum("t,ti,tj->ij", area, s, s)
    return float(area.sum()), first, second / 12


def _shell_moments_of(v: np.ndarray) -> _Moments:
    """Area, first moment and second moment ∫ x xᵀ dA of the triangles `v` ((t, 3, 3), corners of each)."""
    return _sheet_moments(v)


def _shell_moments(poly: Polyhedron) -> _Moments:
    """Area, first moment and second moment ∫ x xᵀ dA of the surface."""
    return _shell_moments_of(poly.vertices[poly.triangles])


def _point_moments(mass: float, at: np.ndarray) -> _Moments:
    return float(mass), mass * at, mass * np.outer(at, at)


def _combine(*terms: tuple[float, _Moments]) -> _Moments:
    """Σ weight · moments."""
    mass = sum(w * m[0] for w, m in terms)
    first = sum(w * m[1] for w, m in terms)
    second = sum(w * m[2] for w, m in terms)
    return float(mass), first, second


def _properties(mass: float, first: np.ndarray, second: np.ndarray) -> MassProperties:
    center = first / mass
    second_c = second - mass * np.outer(center, center)
    inertia = np.trace(second_c) * np.eye(3) - second_c
    return MassProperties(mass, center, 0.5 * (inertia + inertia.T))


def inset(poly: Polyhedron, distance: float | np.ndarray) -> Polyhedron | None:
    """The polyhedron with every face moved inward by `distance` (one value, or one per face).

    None if nothing is left.
    """
    offsets = poly.offsets - np.broadcast_to(np.asarray(distance, dtype=float), poly.offsets.shape)
    return _halfspace_body(poly.normals, offsets, float(np.ptp(poly.vertices, axis=0).max()))


def _deepest_point(normals: np.ndarray, offsets: np.ndarray, size: float) -> np.ndarray | None:
    """(3,) float: the Chebyshev centre of {x : normals @ x <= offsets}, or None if the body is empty or flat."""
    from scipy.optimize import linprog

    res = linprog(
        c=[0, 0, 0, -1],
        A_ub=np.column_stack([normals, np.ones(len(normals))]),
        b_ub=offsets,
        bounds=[(None, None)] * 3 + [(0, None)],
        method="highs",
    )
    if not res.success or res.x[3] <= tol.LENGTH * max(1.0, size):
        return None
    return res.x[:3]


def _halfspace_body(normals: np.ndarray, offsets: np.ndarray, size: float) -> Polyhedron | None:
    """The convex body {x : normals @ x <= offsets}, or None if it is empty or flat."""
    from scipy.spatial import HalfspaceIntersection, QhullError

    inside = _deepest_point(normals, offsets, size)
    if inside is None:
        return None
    try:
        hs = HalfspaceIntersection(np.column_stack([normals, -offsets]), inside)
    except QhullError:
        return None
    try:
        return Polyhedron.from_points(hs.intersections, strict=False)
    except GeometryError:
        # planes of many small faces meet in near-duplicate corners: merge within a sliver of the die's size
        return Polyhedron.from_points(hs.intersections, strict=False, merge_tolerance=tol.INSET_MERGE * max(1.0, size))


@dataclass(frozen=True, eq=False)
class _Hull:
    """A convex body as scipy's hull of points: what the print model needs, without merging faces."""

    vertices: np.ndarray
    triangles: np.ndarray  # outward
    normals: np.ndarray  # one plane per distinct facet
    offsets: np.ndarray
    edges: np.ndarray

    @classmethod
    def of(cls, points: np.ndarray) -> _Hull | None:
        from scipy.spatial import ConvexHull, QhullError

        try:
            hull = ConvexHull(points)
        except QhullError:
            return None
        v = hull.points[hull.vertices]
        remap = np.full(len(hull.points), -1)
        remap[hull.vertices] = np.arange(len(hull.vertices))
        tri = remap[hull.simplices]
        a, b, c = v[tri[:, 0]], v[tri[:, 1]], v[tri[:, 2]]
        flip = np.einsum("ij,ij->i", _cross(b - a, c - a), hull.equations[:, :3]) < 0
        tri[flip] = tri[flip][:, [0, 2, 1]]
        planes = np.unique(np.round(hull.equations, 12), axis=0)
        edges = np.unique(np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1), axis=0)
        return cls(v, tri, planes[:, :3], -planes[:, 3], edges)


def _halfspace_hull(normals: np.ndarray, offsets: np.ndarray, size: float, guess: np.ndarray) -> _Hull | None:
    """:func:`_halfspace_body` as a :class:`_Hull` (no face merging: fast); `guess` may be an interior point."""
    from scipy.spatial import HalfspaceIntersection, QhullError

    inside = guess
    if np.min(offsets - normals @ guess) <= 1e-3 * size:  # not well inside: the deepest point
        inside = _deepest_point(normals, offsets, size)
        if inside is None:
            return None
    try:
        hs = HalfspaceIntersection(np.column_stack([normals, -offsets]), inside)
    except QhullError:
        return None
    return _Hull.of(hs.intersections)


def _section_areas(poly: Polyhedron, up: np.ndarray, heights: np.ndarray) -> np.ndarray:
    """(k,) float: area of the cross-section of convex `poly` by the plane x·up = h, for each height."""
    from scipy.spatial import ConvexHull, QhullError

    h = poly.vertices @ up
    a, b = poly.vertices[poly.edges[:, 0]], poly.vertices[poly.edges[:, 1]]
    ha, hb = h[poly.edges[:, 0]], h[poly.edges[:, 1]]
    e1 = np.cross(up, [1.0, 0.0, 0.0] if abs(up[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(up, e1)
    out = np.zeros(len(heights))
    for i, z in enumerate(heights):
        cross = (np.minimum(ha, hb) <= z) & (np.maximum(ha, hb) >= z) & (ha != hb)
        t = (z - ha[cross]) / (hb[cross] - ha[cross])
        pts = a[cross] + t[:, None] * (b[cross] - a[cross])
        if len(pts) < 3:
            continue
        try:
            out[i] = ConvexHull(np.column_stack([pts @ e1, pts @ e2])).volume
        except QhullError:  # a degenerate (flat) section
            continue
    return out


# ----------------------------------------------------------------------
# paper


def tab_polygons(poly: Polyhedron, tabs: tuple[TabShape, ...], mm_per_unit: float) -> np.ndarray:
    """(n, 4, 3) float, model units: each tab glued flat on its face's plane (base on the edge first)."""
    out = np.empty((len(tabs), 4, 3))
    for i, t in enumerate(tabs):
        p, q = poly.vertices[t.a], poly.vertices[t.b]
        length = float(np.linalg.norm(q - p)) * mm_per_unit
        u = (q - p) / np.linalg.norm(q - p)
        inward = np.cross(poly.normals[t.glued], u)
        if inward @ (poly.face_centroids[t.glued] - p) < 0:
            inward = -inward
        lean = t.lean_a + t.lean_b
        w = min(t.width_mm, TAB_MAX_FRACTION * length, (1 - TAB_TOP_FRACTION) * length / lean if lean > 0 else math.inf)
        w /= mm_per_unit
        out[i] = [p, q, q + w * inward - w * t.lean_b * u, p + w * inward + w * t.lean_a * u]
    return out


def _paper_moments(poly: Polyhedron, fill: Fill, mm_per_unit: float, tabs: tuple[TabShape, ...]) -> _Moments:
    """Card area (model units²) and its moments: faces, tabs behind them, glue between."""
    t = fill.card_thickness_mm / mm_per_unit
    tri, face = poly.vertices[poly.triangles], poly.triangle_face
    terms = [(1.0, _sheet_moments(tri - 0.5 * t * poly.normals[face][:, None, :]))]
    if tabs:
        quads = tab_polygons(poly, tabs, mm_per_unit)
        shift = poly.normals[[tb.glued for tb in tabs]][:, None, :]
        halves = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
        shift = np.concatenate([shift, shift])
        terms.append((1.0, _sheet_moments(halves - 1.5 * t * shift)))
        if fill.glue_g_m2 > 0:
            terms.append((fill.glue_g_m2 / fill.card_g_m2, _sheet_moments(halves - t * shift)))
    return _combine(*terms)


# ----------------------------------------------------------------------
# print


def bed_face(poly: Polyhedron, overhang_deg: float = 45.0, *, avoid=(), strict: bool = False) -> int:
    """The face to print on: least overhanging area, then a face not in `avoid`, then the largest.

    With face k on the bed, a face whose outward normal is within
    `overhang_deg` of straight down (other than face k) needs support; its
    area counts as overhang.  `avoid` lists faces that carry a label: text on
    the bed face prints poorly, and raised text would stand the print on its
    letters.  With `strict`, any face outside `avoid` beats every face in it,
    whatever the overhang (embossed labels); when all faces are in `avoid`
    the usual choice stands and the caller engraves that face's label.
    """
    limit = math.cos(math.radians(overhang_deg))
    down = poly.normals @ poly.normals.T  # [k, j]: cos between face j's normal and "down" when k is on the bed
    overhang = np.where((down > limit + tol.TIE) & ~np.eye(len(poly.faces), dtype=bool), poly.areas[None, :], 0.0)
    cost = overhang.sum(axis=1)
    labelled = np.isin(np.arange(len(poly.faces)), list(avoid))
    pool = np.flatnonzero(~labelled) if strict and not labelled.all() else np.arange(len(poly.faces))
    best = pool[cost[pool] <= cost[pool].min() + tol.AREA]
    if not labelled[best].all():
        best = best[~labelled[best]]
    return int(best[np.argmax(poly.areas[best])])


def wall_depths(poly: Polyhedron, fill: Fill, mm_per_unit: float, bed: int) -> np.ndarray:
    """(m,) float, model units: how deep the solid material reaches under each face of a print.

    With face `bed` on the bed, a face whose outward normal makes angle θ
    with the vertical has the perimeters' horizontal thickness W behind it,
    W·sin θ along its normal, and the solid top (or bottom) layers' vertical
    thickness T, T·|cos θ| along its normal; the deeper of the two wins.
    """
    up = -poly.normals[bed]
    c = poly.normals @ up
    sides = fill.wall_thickness_mm * np.sqrt(np.clip(1 - c**2, 0, 1))
    skin = np.where(c > 0, fill.top_layers, fill.bottom_layers) * fill.layer_mm * np.abs(c)
    return np.maximum(sides, skin) / mm_per_unit


def _small_layers(poly: Polyhedron, core: _Hull, fill: Fill, mm_per_unit: float, bed: int) -> list[_Hull]:
    """The parts of the core in layers whose infill region is smaller than ``fill.solid_below_mm2``.

    A slicer fills those layers solid.  The core is convex, so the square
    root of its section area is concave in height: the small layers are a
    run at the bottom and a run at the top, whole layers counted from the bed.
    """
    if fill.solid_below_mm2 == 0:
        return []
    up = -poly.normals[bed]
    base = poly.offsets[bed] * -1  # height of the bed plane along `up`
    layer = fill.layer_mm / mm_per_unit
    h = core.vertices @ up
    first, last = int(np.floor((h.min() - base) / layer)), int(np.ceil((h.max() - base) / layer))
    index = np.arange(first, last)
    mids = base + (index + 0.5) * layer
    threshold = fill.solid_below_mm2 / mm_per_unit**2

    def first_big(order: np.ndarray) -> int | None:
        for i in order:  # the run of small layers is short: stop at the first big one
            if _section_areas(core, up, mids[i : i + 1])[0] >= threshold:
                return int(i)
        return None

    low = first_big(np.arange(len(index)))
    if low is None:
        return [core]
    high = first_big(np.arange(len(index))[::-1])
    big = np.array([low, high])
    parts = []
    for normal, offset in ((up, base + index[big[0]] * layer), (-up, -(base + (index[big[-1]] + 1) * layer))):
        part = _clip(core, normal, offset)
        if part is not None:
            parts.append(part)
    return parts


def _clip(body: _Hull, normal: np.ndarray, offset: float) -> _Hull | None:
    """The part of convex `body` where ``x · normal <= offset``: its vertices there and its edges' crossings."""
    h = body.vertices @ normal - offset
    a, b = body.edges.T
    cross = (h[a] < 0) != (h[b] < 0)
    t = h[a[cross]] / (h[a[cross]] - h[b[cross]])
    points = np.vstack(
        [
            body.vertices[h <= 0],
            body.vertices[a[cross]] + t[:, None] * (body.vertices[b[cross]] - body.vertices[a[cross]]),
        ]
    )
    return _Hull.of(points) if len(points) >= 4 else None


def _print_moments(
    poly: Polyhedron, fill: Fill, mm_per_unit: float, bed: int, labels: tuple[LabelMass, ...]
) -> _Moments:
    """Full-density volume (model units³) and its moments of a print with walls, skins, infill and labels."""
    depth = wall_depths(poly, fill, mm_per_unit, bed)
    outer = _solid_moments(poly)
    core = _halfspace_hull(
        poly.normals, poly.offsets - depth, float(np.ptp(poly.vertices, axis=0).max()), poly.centroid
    )
    hollow = 1 - fill.infill
    terms = [(1.0, outer)]
    if core is not None:  # otherwise the walls meet: it prints solid
        terms.append((-hollow, _solid_moments(core)))
        for part in _small_layers(poly, core, fill, mm_per_unit, bed):  # infill there turns solid
            terms.append((hollow, _solid_moments(part)))
    for label in labels:
        n = np.asarray(label.normal, dtype=float)
        c = np.asarray(label.centroid_mm, dtype=float) / mm_per_unit
        d = label.depth_mm / mm_per_unit
        volume = label.area_mm2 * label.depth_mm / mm_per_unit**3
        if label.emboss:  # raised text, printed solid
            terms.append((1.0, _point_moments(volume, c + 0.5 * d * n)))
            continue
        terms.append((-1.0, _point_moments(volume, c - 0.5 * d * n)))  # the pocket
        # The pocket's floor and its sides are surfaces of the print too: the slicer fills the layers next
        # to them solid, widened into the infill by the skin margin, one depth of the pocket deeper than
        # the wall under a plain face.
        if core is not None:
            area, at = label.footprint(fill.skin_margin_mm)
            wrap = area * label.depth_mm / mm_per_unit**3
            terms.append((hollow, _point_moments(wrap, at / mm_per_unit - (depth[label.face] + 0.5 * d) * n)))
    return _combine(*terms)


def mass_properties(
    poly: Polyhedron,
    fill: Fill | None = None,
    *,
    mm_per_unit: float = 1.0,
    tabs: tuple[TabShape, ...] | None = None,
    bed: int | None = None,
    labels: tuple[LabelMass, ...] = (),
) -> MassProperties:
    """Mass properties of `poly` as made with `fill`, unit density.

    Parameters
    ----------
    poly : Polyhedron
        Model units.
    fill : Fill, optional
        Solid by default.
    mm_per_unit : float
        Physical size of one model unit (turns card, wall and layer
        thicknesses into model units).
    tabs : tuple of TabShape, optional
        Paper: the glue tabs; default those of the net :func:`diefab.made.bodies.tab_shapes`
        lays out for `poly` (ignored when ``fill.tabs`` is false).
    bed : int, optional
        Print: the face on the bed (default :func:`bed_face`).
    labels : tuple of LabelMass
        Print: engraved or embossed labels (mm, the die's coordinates).
    """
    fill = fill or Fill()
    if fill.kind == "solid":
        return _properties(*_solid_moments(poly))
    if fill.kind == "shell":
        return _properties(*_shell_moments(poly))
    if fill.kind == "paper":
        if not fill.tabs:
            tabs = ()
        elif tabs is None:
            from diefab.made.bodies import tab_shapes

            tabs = tab_shapes(poly, mm_per_unit, fill.tab_mm)
        return _properties(*_paper_moments(poly, fill, mm_per_unit, tuple(tabs)))
    if bed is None:
        bed = bed_face(poly)
    return _properties(*_print_moments(poly, fill, mm_per_unit, bed, tuple(labels)))


def mesh_mass_properties(mesh: ClosedMesh, fill: Fill | None = None, *, mm_per_unit: float = 1.0) -> MassProperties:
    """Mass properties of the body bounded by a closed, possibly non-convex mesh, unit density.

    ``solid`` and ``shell`` are exact for the mesh; ``paper`` is taken as
    its shell (sheets of uniform card, no tabs).  ``print`` takes the
    wall as a thin layer of the surface, :attr:`Fill.wall_thickness_mm` thick, and the rest of
    the volume at ``infill``: exact to first order in the wall thickness
    over the body's local size (a convex body's print is computed exactly
    by :func:`mass_properties` on its polyhedron).
    """
    fill = fill or Fill()
    v = mesh.corners
    if fill.kind == "solid":
        return _properties(*_solid_moments_of(v))
    if fill.kind == "shell":
        return _properties(*_shell_moments_of(v))
    if fill.kind == "paper":  # card sheets on the surface (the mesh's own net has no tabs)
        return _properties(*_shell_moments_of(v))
    solid, surface = _solid_moments_of(v), _shell_moments_of(v)
    wall = fill.wall_thickness_mm / mm_per_unit
    if wall * surface[0] >= solid[0]:  # walls meet: the print is solid
        return _properties(*solid)
    return _properties(*(fill.infill * a + (1 - fill.infill) * wall * b for a, b in zip(solid, surface)))


def stated(props: MassProperties, center=None, inertia=None) -> MassProperties:
    """`props` with a stated centre of mass and, optionally, inertia per unit mass (model units).

    Parameters
    ----------
    center : (3,) float, optional
        Replaces the centre of mass; the inertia tensor is kept (it is the
        body's about its own centre of mass) unless `inertia` is given.
    inertia : (3, 3) float, optional
        Inertia tensor about the centre of mass divided by the mass,
        model units²: multiplied by the body's mass.
    """
    c = props.center if center is None else np.asarray(center, dtype=float)
    i = props.inertia if inertia is None else props.mass * np.asarray(inertia, dtype=float)
    return MassProperties(props.mass, c, i)
