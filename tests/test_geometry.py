"""Polyhedron construction, validation and the exact solid-angle model."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from diefab.core.errors import GeometryError
from diefab.dice.families import GEM, gem_polyhedron
from diefab.geometry.polyhedron import Polyhedron, face_margins, resting_faces, solid_angles, up_faces
from diefab.models.basins import RestBasins

CUBE = [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
OCTAHEDRON = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]
PHI = (1 + 5**0.5) / 2
ICOSAHEDRON = [p for a, b in itertools.product((-1, 1), (-PHI, PHI)) for p in ([0, a, b], [a, b, 0], [b, 0, a])]
TETRAHEDRON = [[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]
DODECAHEDRON = (
    [list(p) for p in itertools.product((-1, 1), repeat=3)]
    + [[0, a / PHI, b * PHI] for a in (-1, 1) for b in (-1, 1)]
    + [[a / PHI, b * PHI, 0] for a in (-1, 1) for b in (-1, 1)]
    + [[a * PHI, 0, b / PHI] for a in (-1, 1) for b in (-1, 1)]
)

gem_params = st.fixed_dictionaries(
    {name: st.floats(p.lower, p.upper) for name, p in zip("abcd", GEM.parameters, strict=False)}
)


@pytest.mark.parametrize(
    ("points", "faces", "sides"),
    [(TETRAHEDRON, 4, 3), (CUBE, 6, 4), (OCTAHEDRON, 8, 3), (DODECAHEDRON, 12, 5), (ICOSAHEDRON, 20, 3)],
)
def test_platonic_solids_are_uniform_under_solid_angles(points, faces, sides):
    poly = Polyhedron.from_points(points)
    assert len(poly.faces) == faces
    assert {len(f) for f in poly.faces} == {sides}  # coplanar hull triangles merged
    omega = solid_angles(poly, poly.centroid)
    np.testing.assert_allclose(omega, 4 * np.pi / faces, rtol=1e-12)


def test_cube_measures():
    cube = Polyhedron.from_points(CUBE)
    assert cube.volume == pytest.approx(8)
    assert cube.surface_area == pytest.approx(24)
    np.testing.assert_allclose(cube.centroid, 0, atol=1e-15)
    assert len(cube.edges) == 12
    # every edge joins two distinct faces whose normals are perpendicular
    n = cube.normals[cube.edge_faces]
    np.testing.assert_allclose(np.einsum("ij,ij->i", n[:, 0], n[:, 1]), 0, atol=1e-15)
    np.testing.assert_allclose(face_margins(cube, cube.centroid), 1.0)


def test_margin_sign_follows_projection():
    cube = Polyhedron.from_points(CUBE)
    # centre of mass shifted 1.5 along +x projects outside the four side faces, inside the +-x faces
    margins = face_margins(cube, [1.5, 0, 0])
    normals = cube.normals
    side = np.abs(normals[:, 0]) < 0.5
    np.testing.assert_allclose(margins[side], -0.5)
    np.testing.assert_allclose(margins[~side], 1.0)


def test_solid_angles_at_a_vertex_region_point_still_sum_to_4pi():
    poly = Polyhedron.from_points(ICOSAHEDRON)
    point = 0.9 * poly.vertices[0]
    assert solid_angles(poly, point).sum() == pytest.approx(4 * np.pi, rel=1e-12)


@settings(max_examples=200, deadline=None)
@given(gem_params, st.floats(0, 1))
def test_gem_solid_angle_probabilities_are_a_distribution(params, t):
    poly = gem_polyhedron(params)
    # any point inside: blend centroid and a vertex
    point = (1 - 0.9 * t) * poly.centroid + 0.9 * t * poly.vertices[8]
    omega = solid_angles(poly, point)
    assert np.all(omega > 0)
    assert omega.sum() == pytest.approx(4 * np.pi, rel=1e-10)


@settings(max_examples=100, deadline=None)
@given(gem_params)
def test_gem_mirror_faces_get_equal_solid_angle(params):
    poly = gem_polyhedron(params)
    omega = solid_angles(poly, poly.centroid)
    for a, b in [(0, 2), (1, 3), (5, 7), (6, 8)]:  # f1/f3, f2/f4, f6/f8, f7/f9
        assert omega[a] == pytest.approx(omega[b], rel=1e-10)


def test_gem_faces_follow_the_paper():
    poly = gem_polyhedron({"a": 1.18, "b": 0.52, "c": 0.72, "d": 1.41})
    assert poly.names == tuple(f"f{k}" for k in range(1, 10))
    np.testing.assert_allclose(poly.normals[4], [0, 1, 0])  # f5 is the top
    assert [len(f) for f in poly.faces] == [4, 4, 4, 4, 4, 3, 3, 3, 3]
    assert np.all(poly.normals[5:, 1] < 0)  # f6..f9 face down


def test_up_faces_of_the_gem():
    poly = gem_polyhedron({"a": 1.18, "b": 0.52, "c": 0.72, "d": 1.41})
    up = up_faces(poly)
    assert up[6] == 3  # resting on f7 puts f4 up
    assert up[4] is None  # resting on f5 puts the apex up
    assert sorted(u for u in up if u is not None) == [0, 1, 2, 3, 5, 6, 7, 8]  # a bijection


def test_up_faces_of_a_cube_are_opposite():
    cube = Polyhedron.from_points(CUBE)
    for k, u in enumerate(up_faces(cube)):
        np.testing.assert_allclose(cube.normals[u], -cube.normals[k])


@pytest.mark.parametrize(
    ("vertices", "faces", "message"),
    [
        (CUBE, [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4]], "not closed"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2], [0, 2, 1], [1, 2, 3]], None),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, np.nan]], [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], "NaN"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2], [0, 3, 1], [1, 3, 2], [0, 2, 3]], "inward"),
    ],
)
def test_invalid_polyhedra_are_rejected(vertices, faces, message):
    with pytest.raises(GeometryError, match=message):
        Polyhedron(np.array(vertices, dtype=float), faces)


def test_non_convex_faces_are_rejected():
    # a cube with one top vertex pushed down: the top quad is no longer planar
    v = np.array(CUBE, dtype=float)
    v[7, 2] = 0.5
    cube = Polyhedron.from_points(CUBE)
    with pytest.raises(GeometryError, match="planar"):
        cube.with_vertices(v)
    # a dent: a vertex moved inward past the neighbouring planes
    poly = Polyhedron.from_points(OCTAHEDRON)
    w = poly.vertices.copy()
    w[0] *= -0.2
    with pytest.raises(GeometryError, match="convex"):
        Polyhedron(w, poly.faces)


def test_points_not_in_convex_position_are_rejected():
    with pytest.raises(GeometryError, match="not a vertex"):
        Polyhedron.from_points([*CUBE, [0, 0, 0]])
    with pytest.raises(GeometryError, match="degenerate|no volume"):
        Polyhedron.from_points([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 2, 0]])


@pytest.mark.parametrize("off", [1e-12, 1e-9, 1e-8, 1e-6, 1e-4])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_points_a_hair_off_a_face_give_the_hull_they_span(off, seed):
    """Near-coplanar hull triangles (a corner lifted, a point just above a face) make a valid hull of the same volume.

    Triangles coplanar only within tolerance are merged only where they make
    one flat convex polygon; otherwise they stay triangles, so the result is
    always a closed convex solid whose volume is the hull's.
    """
    from scipy.spatial import ConvexHull

    rng = np.random.default_rng(seed)
    cube = np.array(list(itertools.product([-1.0, 1.0], repeat=3)))
    lifted = cube.copy()
    lifted[rng.integers(8), 2] += off * np.sign(lifted[0, 2])  # one corner off its faces' planes
    bump = np.array([[*rng.uniform(-0.9, 0.9, 2), 1 + off]])  # a point just above the top face
    for points in (lifted, np.vstack([cube, bump]), np.vstack([lifted, bump]) + rng.normal(0, off, (9, 3))):
        poly = Polyhedron.from_points(points, strict=False)
        assert poly.volume == pytest.approx(ConvexHull(points).volume, abs=1e-8)  # faces flat within 1e-9
        assert np.all(poly.vertices @ poly.normals.T - poly.offsets <= 1e-9)


def test_from_mesh_merges_coplanar_triangles(tmp_path):
    import trimesh

    box = trimesh.creation.box(extents=(2, 3, 4)).subdivide()  # 4 triangles per original one
    for ext in ("stl", "obj"):
        path = tmp_path / f"box.{ext}"
        box.export(path)
        poly = Polyhedron.from_mesh(path)
        assert len(poly.faces) == 6
        assert poly.volume == pytest.approx(24)
        assert sorted(len(f) for f in poly.faces) == [4] * 6


def test_non_convex_mesh_is_rejected(tmp_path):
    import trimesh

    a = trimesh.creation.box(extents=(1, 1, 1))
    b = trimesh.creation.box(extents=(1, 1, 1))
    b.apply_translation([1.0, 1.0, 0])
    path = tmp_path / "l.stl"
    trimesh.util.concatenate([a, b]).export(path)  # two cubes touching along an edge: not convex
    with pytest.raises(GeometryError):
        Polyhedron.from_mesh(path)
    path = tmp_path / "garbage.stl"
    path.write_bytes(b"not a mesh")
    with pytest.raises(GeometryError):
        Polyhedron.from_mesh(path)


# ----------------------------------------------------------------------
# rest basins: where a die creeping downhill ends


def _unit(rng, n: int) -> np.ndarray:
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1)[:, None]


def _gem_design(params):
    from diefab.dice.design import load_design

    return load_design("fudge-gem").with_params(**params)


def test_cube_basins_are_the_nearest_face_and_the_barrier_is_sqrt2_minus_1():
    cube = Polyhedron.from_points([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    basins = RestBasins.of(cube, np.zeros(3))
    d = _unit(np.random.default_rng(0), 2000)
    assert np.array_equal(basins.face_of(d), np.argmax(d @ cube.normals.T, axis=1))
    assert np.allclose(basins.barriers, np.sqrt(2) - 1)


def test_a_face_normal_lies_in_its_own_basin():
    for params in ({}, {"a": 1.3, "b": 0.66, "c": 0.79, "d": 0.72, "e": 0.46}, {"c": 0.45, "d": 2.6}):
        design = _gem_design(params)
        assert design.margins().min() > 0
        basins = RestBasins.of(design.polyhedron, design.mass_properties().center)
        assert np.array_equal(basins.face_of(design.polyhedron.normals), np.arange(9))


#: A gem that cannot rest on some of its faces (transitional faces).
TIPPY = {"a": 1.0, "b": 0.5, "c": 0.2, "d": 0.3}


def _descend(poly, center, d):
    """Brute-force gradient descent of the support function on the sphere: the face each direction ends on."""
    vertices = poly.vertices - center
    x = d.copy()
    for _ in range(4000):
        v = vertices[np.argmax(x @ vertices.T, axis=1)]
        x -= 0.002 * (v - np.einsum("ij,ij->i", v, x)[:, None] * x)
        x /= np.linalg.norm(x, axis=1)[:, None]
    return np.argmax(x @ poly.normals.T, axis=1)


@pytest.mark.parametrize("params", [{}, TIPPY], ids=["stable", "transitional"])
def test_gem_basins_follow_the_downhill_flow(params):
    """Against a brute-force gradient descent of the support function on the sphere."""
    poly = gem_polyhedron({**load_params(), **params})
    center = poly.centroid
    basins = RestBasins.of(poly, center)
    d = _unit(np.random.default_rng(1), 400)
    assert np.mean(basins.face_of(d) == _descend(poly, center, d)) >= 0.99


def load_params():
    from diefab.dice.design import load_design

    return dict(load_design("fudge-gem").params)


@pytest.mark.parametrize("params", [{}, {"a": 1.3, "b": 0.66, "c": 0.79, "d": 0.72, "e": 0.46}, TIPPY])
def test_basin_rims_never_dip_below_the_barrier(params):
    """Where two basins meet the centre of mass is at least the barrier above either face's rest."""
    from scipy.spatial import cKDTree

    rng = np.random.default_rng(2)
    poly = gem_polyhedron({**load_params(), **params})
    center = poly.centroid
    basins = RestBasins.of(poly, center)
    d = _unit(rng, 60_000)
    face = basins.face_of(d)
    height = (d @ (poly.vertices - center).T).max(axis=1) - (poly.offsets - poly.normals @ center)[face]
    pairs = cKDTree(d).query_pairs(0.02, output_type="ndarray")
    rim = np.unique(pairs[face[pairs[:, 0]] != face[pairs[:, 1]]])
    assert len(rim) > 100
    assert np.all(height[rim] >= basins.barriers[face[rim]] * (1 - 1e-9))


def test_basin_lookup_matches_the_exact_flow():
    design = _gem_design({"a": 1.3, "b": 0.66, "c": 0.79, "d": 0.72, "e": 0.46})
    basins = RestBasins.of(design.polyhedron, design.mass_properties().center)
    d = _unit(np.random.default_rng(3), 50_000)
    assert np.array_equal(basins.lookup(d), basins.face_of(d))


def test_transitional_faces_have_empty_basins_and_drain_downhill():
    poly = gem_polyhedron(TIPPY)
    center = poly.centroid
    resting = resting_faces(poly, center)
    assert face_margins(poly, center).min() < 0 and resting.any() and not resting.all()
    basins = RestBasins.of(poly, center)
    assert np.array_equal(basins.resting, resting)
    heights = poly.offsets - poly.normals @ center
    for g in np.flatnonzero(~resting):
        assert resting[basins.targets[g]] and heights[basins.targets[g]] < heights[g]
    face = basins.face_of(_unit(np.random.default_rng(4), 20_000))
    assert np.all(resting[face])
    assert np.array_equal(basins.lookup(poly.normals), basins.targets)
    assert np.all(np.isfinite(basins.barriers[resting]) | (resting.sum() == 1))


def test_basins_need_the_center_inside():
    cube = Polyhedron.from_points([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    with pytest.raises(GeometryError):
        RestBasins.of(cube, np.array([3.0, 0, 0]))


def test_hull_diameter_is_the_largest_distance_between_two_points():
    from scipy.spatial.distance import pdist

    from diefab.geometry.polyhedron import hull_diameter

    rng = np.random.default_rng(5)
    for n in (4, 50, 3000):  # 3000 points on a sphere: all on the hull, more than one block of distances
        pts = rng.normal(size=(n, 3)) * (1.0, 2.0, 0.5)
        if n == 3000:
            pts /= np.linalg.norm(pts, axis=1, keepdims=True)
        assert hull_diameter(pts) == pytest.approx(pdist(pts).max(), rel=1e-12)
    with pytest.raises(GeometryError, match="degenerate|no volume"):
        hull_diameter([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])


def test_solids_cut_by_random_planes_have_counter_clockwise_faces_on_their_planes():
    from diefab.dice.families.planes import polyhedron_from_planes, unit

    rng = np.random.default_rng(11)
    built = 0
    for _ in range(400):
        m = int(rng.integers(6, 25))
        normals, offsets = unit(rng.normal(size=(m, 3))), rng.uniform(0.7, 1.3, m)
        try:
            poly = polyhedron_from_planes(normals, offsets)
        except GeometryError:
            continue
        built += 1
        assert np.allclose(poly.normals, normals, atol=1e-9)  # face k on plane k, its ring CCW seen from outside
        assert np.allclose(poly.offsets, offsets, atol=1e-9)
        tail, head, face, start = poly._ring
        assert np.array_equal(head, np.concatenate([np.roll(f, -1) for f in poly.faces]))
        assert np.array_equal(tail[start], [f[0] for f in poly.faces]) and np.array_equal(face[start], np.arange(m))
    assert built > 40
