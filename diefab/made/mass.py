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
from dataclasses import dataclass

import numpy as np

from diefab.core import tolerances as tol
from diefab.core.errors import GeometryError
from diefab.geometry.meshes import ClosedMesh
from diefab.geometry.moments import (
    MassProperties,
    Moments,
    combine,
    point_moments,
    properties,
    sheet_moments,
    shell_moments,
    shell_moments_of,
    solid_moments,
    solid_moments_of,
)
from diefab.geometry.polyhedron import Polyhedron, _cross
from diefab.made.fill import TAB_MAX_FRACTION, TAB_TOP_FRACTION, Fill, LabelMass, TabShape
from diefab.made.unfold import tab_shapes

__all__ = [
    "bed_face",
    "inset",
    "mass_properties",
    "mesh_mass_properties",
    "tab_polygons",
    "wall_depths",
]


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


def _paper_moments(poly: Polyhedron, fill: Fill, mm_per_unit: float, tabs: tuple[TabShape, ...]) -> Moments:
    """Card area (model units²) and its moments: faces, tabs behind them, glue between."""
    t = fill.card_thickness_mm / mm_per_unit
    tri, face = poly.vertices[poly.triangles], poly.triangle_face
    terms = [(1.0, sheet_moments(tri - 0.5 * t * poly.normals[face][:, None, :]))]
    if tabs:
        quads = tab_polygons(poly, tabs, mm_per_unit)
        shift = poly.normals[[tb.glued for tb in tabs]][:, None, :]
        halves = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
        shift = np.concatenate([shift, shift])
        terms.append((1.0, sheet_moments(halves - 1.5 * t * shift)))
        if fill.glue_g_m2 > 0:
            terms.append((fill.glue_g_m2 / fill.card_g_m2, sheet_moments(halves - t * shift)))
    return combine(*terms)


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
) -> Moments:
    """Full-density volume (model units³) and its moments of a print with walls, skins, infill and labels."""
    depth = wall_depths(poly, fill, mm_per_unit, bed)
    outer = solid_moments(poly)
    core = _halfspace_hull(
        poly.normals, poly.offsets - depth, float(np.ptp(poly.vertices, axis=0).max()), poly.centroid
    )
    hollow = 1 - fill.infill
    terms = [(1.0, outer)]
    if core is not None:  # otherwise the walls meet: it prints solid
        terms.append((-hollow, solid_moments(core)))
        for part in _small_layers(poly, core, fill, mm_per_unit, bed):  # infill there turns solid
            terms.append((hollow, solid_moments(part)))
    for label in labels:
        n = np.asarray(label.normal, dtype=float)
        c = np.asarray(label.centroid_mm, dtype=float) / mm_per_unit
        d = label.depth_mm / mm_per_unit
        volume = label.area_mm2 * label.depth_mm / mm_per_unit**3
        if label.emboss:  # raised text, printed solid
            terms.append((1.0, point_moments(volume, c + 0.5 * d * n)))
            continue
        terms.append((-1.0, point_moments(volume, c - 0.5 * d * n)))  # the pocket
        # The pocket's floor and its sides are surfaces of the print too: the slicer fills the layers next
        # to them solid, widened into the infill by the skin margin, one depth of the pocket deeper than
        # the wall under a plain face.
        if core is not None:
            area, at = label.footprint(fill.skin_margin_mm)
            wrap = area * label.depth_mm / mm_per_unit**3
            terms.append((hollow, point_moments(wrap, at / mm_per_unit - (depth[label.face] + 0.5 * d) * n)))
    return combine(*terms)


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
        Paper: the glue tabs; default those of the net :func:`diefab.made.unfold.tab_shapes`
        lays out for `poly` (ignored when ``fill.tabs`` is false).
    bed : int, optional
        Print: the face on the bed (default :func:`bed_face`).
    labels : tuple of LabelMass
        Print: engraved or embossed labels (mm, the die's coordinates).
    """
    fill = fill or Fill()
    if fill.kind == "solid":
        return properties(*solid_moments(poly))
    if fill.kind == "shell":
        return properties(*shell_moments(poly))
    if fill.kind == "paper":
        if not fill.tabs:
            tabs = ()
        elif tabs is None:
            tabs = tab_shapes(poly, mm_per_unit, fill.tab_mm)
        return properties(*_paper_moments(poly, fill, mm_per_unit, tuple(tabs)))
    if bed is None:
        bed = bed_face(poly)
    return properties(*_print_moments(poly, fill, mm_per_unit, bed, tuple(labels)))


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
        return properties(*solid_moments_of(v))
    if fill.kind == "shell":
        return properties(*shell_moments_of(v))
    if fill.kind == "paper":  # card sheets on the surface (the mesh's own net has no tabs)
        return properties(*shell_moments_of(v))
    solid, surface = solid_moments_of(v), shell_moments_of(v)
    wall = fill.wall_thickness_mm / mm_per_unit
    if wall * surface[0] >= solid[0]:  # walls meet: the print is solid
        return properties(*solid)
    return properties(*(fill.infill * a + (1 - fill.infill) * wall * b for a, b in zip(solid, surface)))
