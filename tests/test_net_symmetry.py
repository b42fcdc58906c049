"""Glue tabs that keep a die's symmetry: the symmetry group, the tab layout, the paper body."""

from __future__ import annotations

import numpy as np
import pytest

from diefab import Polyhedron, load_design
from diefab.geometry.symmetry import off_axis, symmetries
from diefab.made.bodies import net_tab_shapes
from diefab.made.mass import Fill, tab_polygons
from diefab.made.unfold import unfold

#: The tabs' centre of mass on the axis, mm (exact symmetry leaves rounding only).
ON_AXIS_MM = 1e-9
OVERLAP_MM2 = 1e-6

GEMS = {
    "fudge-gem-paper": {},
    "fudge-gem-print": {},
    "square gem": {"a": 1.0, "b": 0.7, "c": 0.75, "d": 1.3, "e": 0.7},  # a square girdle: C4v, 8 symmetries
    "long gem": {"a": 1.4, "b": 0.55, "c": 0.75, "d": 1.1, "e": 1.0},
}


def sphere_points(n: int, seed: int) -> np.ndarray:
    """`n` random points on the unit sphere: a convex polyhedron with no symmetry."""
    x = np.random.default_rng(seed).normal(size=(n, 3))
    return x / np.linalg.norm(x, axis=1)[:, None]


def gem(name: str):
    base = load_design("fudge-gem-paper" if name not in ("fudge-gem-print",) else name)
    return base.with_params(**GEMS[name]) if GEMS[name] else base


def tab_card(design, net) -> tuple[np.ndarray, np.ndarray]:
    """Each tab's area (model units²) and centroid, as the paper body glues it (the mass model's path)."""
    quads = tab_polygons(design.polyhedron, net_tab_shapes(net), design.mm_per_unit)
    areas, centers = [], []
    for tri in (quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]):
        areas.append(np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1) / 2)
        centers.append(tri.mean(axis=1))
    area = areas[0] + areas[1]
    return area, (areas[0][:, None] * centers[0] + areas[1][:, None] * centers[1]) / area[:, None]


def card_center(area: np.ndarray, centers: np.ndarray) -> np.ndarray:
    return (area[:, None] * centers).sum(axis=0) / area.sum()


def test_symmetry_groups_of_known_solids():
    cube = Polyhedron.from_points([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)])
    box = Polyhedron.from_points([[x, y, z] for x in (0, 3) for y in (0, 2) for z in (0, 1)])
    lump = Polyhedron.from_points(sphere_points(12, seed=5))
    assert [len(symmetries(p)) for p in (cube, box, lump)] == [48, 8, 1]
    assert len(symmetries(gem("fudge-gem-paper").polyhedron)) == 4  # two mirrors and the half turn
    assert len(symmetries(gem("square gem").polyhedron)) == 8
    for poly in (cube, gem("long gem").polyhedron):
        group = symmetries(poly)
        assert np.allclose(group.matrices[0], np.eye(3))  # identity first
        for m, perm in zip(group.matrices, group.vertex):
            assert np.allclose(m.T @ m, np.eye(3), atol=1e-9)
            assert np.allclose((poly.vertices - group.center) @ m.T + group.center, poly.vertices[perm], atol=1e-9)
    # the cube's fixed set is its centre; a box's too; a lump's is all of space
    assert off_axis(symmetries(cube), [0.5, 0.5, 0.9]) == pytest.approx(0.4)
    assert off_axis(symmetries(lump), [3.0, 1.0, 2.0]) == pytest.approx(0.0)


@pytest.mark.parametrize("name", sorted(GEMS))
def test_gem_tabs_are_symmetric_and_centred_on_the_axis(name):
    design = gem(name)
    poly = design.polyhedron
    net = unfold(poly, design.mm_per_unit)
    group = symmetries(poly)
    # the symmetries kept carry the set of (edge, face it hangs from) onto itself: all of them on a gem
    # with two mirrors; on a square gem the rotations (a diagonal mirror takes an edge it cuts across
    # to itself with its faces swapped, so no side of that edge is symmetric)
    tabs = {(t.edge, t.face) for t in net.tabs}
    kept = [g for g in range(len(group)) if {(int(group.edge[g, e]), int(group.face[g, f])) for e, f in tabs} == tabs]
    assert len(kept) == net.search["tab_symmetries"] == 4
    if len(group) == 8:
        assert all(np.isclose(np.linalg.det(group.matrices[g]), 1.0) for g in kept)
    # ... and the tab card, as the paper body glues it, onto itself: same areas, centre on the axis
    areas, centers = tab_card(design, net)
    center = card_center(areas, centers)
    assert off_axis(group, center) * design.mm_per_unit < ON_AXIS_MM
    edges = [t.edge for t in net.tabs]
    for g in kept:
        mapped = [edges.index(int(group.edge[g, e])) for e in edges]
        np.testing.assert_allclose(areas[mapped], areas, rtol=1e-9)
    assert net.search["symmetries"] == len(group) and net.search["tab_offset_mm"] < ON_AXIS_MM
    # the gem's axis is y (through the apex): the paper die's centre of mass is on it
    body = design.with_params(**design.params)
    props = body.mass_properties(Fill("paper"))
    assert np.hypot(props.center[0], props.center[2]) * design.mm_per_unit < ON_AXIS_MM


@pytest.mark.parametrize("name", sorted(GEMS))
def test_symmetric_tabs_overlap_nothing(name):
    from shapely.geometry import Polygon

    design = gem(name)
    net = unfold(design.polyhedron, design.mm_per_unit)
    shapes = [(net.face_page[k], Polygon(p)) for k, p in enumerate(net.faces)]
    shapes += [(t.page, Polygon(t.polygon)) for t in net.tabs]
    for i in range(len(shapes)):
        for j in range(i + 1, len(shapes)):
            if shapes[i][0] == shapes[j][0]:
                assert shapes[i][1].intersection(shapes[j][1]).area < OVERLAP_MM2, (i, j)
    assert len(net.tabs) == len(net.poly.edges) - len(net.fold_edges)


def test_cube_tab_centre_is_stated_and_within_a_millimetre():
    """No cube net has a tab set symmetric under the cube's group; the search keeps its centre within 1 mm."""
    d6 = load_design("d6")
    net = unfold(d6.polyhedron, d6.mm_per_unit)
    center = card_center(*tab_card(d6, net))
    offset = off_axis(symmetries(d6.polyhedron), center) * d6.mm_per_unit
    assert offset == pytest.approx(net.search["tab_offset_mm"], abs=1e-6)
    assert offset < 1.0


def test_asymmetric_die_has_one_symmetry_and_no_offset():
    poly = Polyhedron.from_points(sphere_points(9, seed=11))
    net = unfold(poly, 20.0)
    assert net.search["symmetries"] == 1 and net.search["tab_offset_mm"] == 0.0
