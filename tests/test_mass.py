"""Mass properties: the paper's Eq. (1), shells, prints and inertia."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from diefab.core.errors import DesignError
from diefab.dice.families import GEM, gem_center_of_mass_y, gem_polyhedron
from diefab.geometry.polyhedron import Polyhedron
from diefab.made.mass import Fill, inset, mass_properties, wall_depths

gem_params = st.fixed_dictionaries(
    {name: st.floats(p.lower, p.upper) for name, p in zip("abcd", GEM.parameters, strict=False)}
)


@settings(max_examples=300, deadline=None)
@given(gem_params)
def test_eq1_equals_the_numeric_solid_centroid(params):
    poly = gem_polyhedron(params)
    com = mass_properties(poly).center
    assert abs(com[1] - gem_center_of_mass_y(**params)) <= 1e-12
    assert abs(com[0]) <= 1e-12 and abs(com[2]) <= 1e-12


def test_shell_centre_is_the_area_weighted_face_centroid():
    poly = gem_polyhedron({"a": 1.18, "b": 0.52, "c": 0.72, "d": 1.41})
    props = mass_properties(poly, Fill("shell"))
    expected = (poly.areas[:, None] * poly.face_centroids).sum(axis=0) / poly.areas.sum()
    np.testing.assert_allclose(props.center, expected, atol=1e-14)
    assert props.mass == pytest.approx(poly.surface_area)


def test_cube_inertia_solid_and_shell():
    a = 2.0
    cube = Polyhedron.from_points([[x, y, z] for x in (0, a) for y in (0, a) for z in (0, a)])
    solid = mass_properties(cube)
    np.testing.assert_allclose(solid.inertia, a**3 * 2 * a**2 / 12 * np.eye(3), atol=1e-12)
    shell = mass_properties(cube, Fill("shell"))
    # thin-walled cube of side a, mass M = 6 a^2: I = 5/18 M a^2
    np.testing.assert_allclose(shell.inertia, 5 / 18 * 6 * a**2 * a**2 * np.eye(3), atol=1e-12)


def test_inertia_is_invariant_under_translation():
    pts = np.random.default_rng(1).normal(size=(20, 3))
    poly = Polyhedron.from_points(pts, strict=False)
    moved = poly.with_vertices(poly.vertices + [3.0, -2.0, 5.0])
    for fill in (Fill("solid"), Fill("shell")):
        np.testing.assert_allclose(mass_properties(poly, fill).inertia, mass_properties(moved, fill).inertia, atol=1e-9)


def test_print_fill_interpolates_between_shell_like_and_solid():
    poly = gem_polyhedron({"a": 1.18, "b": 0.52, "c": 0.72, "d": 1.41})
    solid = mass_properties(poly)
    full = mass_properties(poly, Fill("print", wall_mm=1.0, infill=1.0), mm_per_unit=15)
    np.testing.assert_allclose(full.center, solid.center, atol=1e-12)
    assert full.mass == pytest.approx(solid.mass)
    fill = Fill("print", wall_mm=1.0, infill=0.0, solid_below_mm2=0.0)
    hollow = mass_properties(poly, fill, mm_per_unit=15, bed=5)
    inner = inset(poly, wall_depths(poly, fill, 15, 5))
    assert hollow.mass == pytest.approx(poly.volume - inner.volume)
    # a hollow print's centre moves towards the shell's
    shell = mass_properties(poly, Fill("shell"))
    assert abs(hollow.center[1] - shell.center[1]) < abs(solid.center[1] - shell.center[1])


def test_inset_of_a_cube_and_a_wall_thicker_than_the_die():
    cube = Polyhedron.from_points([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    assert inset(cube, 0.25).volume == pytest.approx(1.5**3)
    assert inset(cube, 1.5) is None
    thick = mass_properties(cube, Fill("print", wall_mm=30, infill=0.1), mm_per_unit=10)
    assert thick.mass == pytest.approx(8.0)


@pytest.mark.parametrize("kwargs", [{"kind": "hollow"}, {"wall_mm": 0}, {"infill": 1.5}, {"infill": float("nan")}])
def test_bad_fill_is_rejected(kwargs):
    with pytest.raises(DesignError):
        Fill(**kwargs)


# ----------------------------------------------------------------------
# Fill settings


NUMERIC = ["card_g_m2", "card_mm", "tab_mm", "glue_g_m2", "nozzle_mm", "perimeters", "layer_mm", "top_layers",
           "bottom_layers", "infill", "wall_mm"]  # fmt: skip


@pytest.mark.parametrize("field", NUMERIC)
@pytest.mark.parametrize("value", [True, "1", None, float("inf"), -1, 1e6])
def test_every_numeric_fill_field_checks_type_and_range(field, value):
    if value is None and field in ("card_mm", "wall_mm"):
        return  # optional: None means "derive it"
    with pytest.raises(DesignError) as info:
        Fill(**{field: value})
    assert field in str(info.value) and repr(value) in str(info.value)


@pytest.mark.parametrize("kwargs", [{"perimeters": 2.5}, {"top_layers": 1.0}, {"layer_mm": 0.5}, {"tabs": 1},
                                    {"labels": "yes"}, {"kind": 3}, {"kind": "paper "}])  # fmt: skip
def test_fill_rejects_wrong_kinds_of_value(kwargs):
    with pytest.raises(DesignError, match=next(iter(kwargs))):
        Fill(**kwargs)


def test_fill_defaults_are_common_practice():
    fill = Fill("print")
    assert (fill.nozzle_mm, fill.perimeters, fill.layer_mm, fill.top_layers, fill.infill) == (0.4, 2, 0.2, 4, 0.15)
    # two 0.45 mm lines of 0.2 mm layers, rounded edges: 2 x (0.45 - 0.2 (1 - pi/4))
    assert fill.wall_thickness_mm == pytest.approx(2 * (0.45 - 0.2 * (1 - np.pi / 4)))
    assert Fill("paper").card_thickness_mm == pytest.approx(0.2)
    assert Fill.from_mapping(Fill("paper", glue_g_m2=20.0).to_mapping()) == Fill("paper", glue_g_m2=20.0)
    with pytest.raises(DesignError, match="unknown key 'walls'"):
        Fill.from_mapping({"kind": "print", "walls": 3})


# ----------------------------------------------------------------------
# paper and print bodies

CUBE = Polyhedron.from_points([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])


def test_card_thickness_moves_no_centre_and_tabs_add_their_own_area():
    poly = gem_polyhedron({"a": 1.18, "b": 0.52, "c": 0.72, "d": 1.41})
    shell = mass_properties(poly, Fill("shell"))
    bare = mass_properties(poly, Fill("paper", tabs=False), mm_per_unit=15)
    # each face moves in along its normal; Σ area · normal = 0 for a closed surface
    np.testing.assert_allclose(bare.center, shell.center, atol=1e-12)
    assert bare.mass == pytest.approx(poly.surface_area)
    from diefab.made.bodies import tab_shapes
    from diefab.made.mass import tab_polygons
    from diefab.made.unfold import unfold

    net = unfold(poly, 15.0)
    tabs = tab_shapes(poly, 15.0, 5.0)
    quads = tab_polygons(poly, tabs, 15.0)
    page_area = sum(
        0.5
        * abs(
            np.dot(t.polygon[:, 0], np.roll(t.polygon[:, 1], -1))
            - np.dot(t.polygon[:, 1], np.roll(t.polygon[:, 0], -1))
        )
        for t in net.tabs
    )
    area = sum(0.5 * np.linalg.norm(np.cross(q[1] - q[0], q[2] - q[0]) + np.cross(q[2] - q[0], q[3] - q[0]))
               for q in quads)  # fmt: skip
    assert area * 15.0**2 == pytest.approx(page_area, rel=1e-9)  # the net's own trapezoids
    for tab, quad in zip(tabs, quads):  # flat on the face they are glued to, inside it
        k = tab.glued
        np.testing.assert_allclose(quad @ poly.normals[k], poly.offsets[k], atol=1e-12)
        assert (quad @ poly.normals.T <= poly.offsets + 1e-12).all()
    paper = mass_properties(poly, Fill("paper"), mm_per_unit=15)
    assert paper.mass == pytest.approx(poly.surface_area + area)
    glued = mass_properties(poly, Fill("paper", glue_g_m2=80.0), mm_per_unit=15)
    assert glued.mass == pytest.approx(paper.mass + 0.5 * area)


def test_print_walls_and_skins_of_a_cube():
    # 20 mm cube, bed face at -z: the side walls are W thick, the top and bottom T thick
    fill = Fill("print", wall_mm=1.0, top_layers=5, bottom_layers=5, layer_mm=0.2, infill=0.0, solid_below_mm2=0.0)
    bed = int(np.argmin(CUBE.normals[:, 2]))
    props = mass_properties(CUBE, fill, mm_per_unit=10, bed=bed)
    assert props.mass == pytest.approx(8 - 1.8**3)
    np.testing.assert_allclose(props.center, 0, atol=1e-12)
    thicker_top = mass_properties(CUBE, Fill("print", wall_mm=1.0, top_layers=10, infill=0.0), mm_per_unit=10, bed=bed)
    assert thicker_top.center[2] > 0
    full = mass_properties(CUBE, Fill("print", infill=1.0), mm_per_unit=10, bed=bed)
    assert full.mass == pytest.approx(8.0)


def test_an_engraved_label_takes_material_and_pulls_the_wall_in():
    from diefab.made.mass import LabelMass

    fill = Fill("print", infill=0.2)
    bed = int(np.argmin(CUBE.normals[:, 2]))
    top = int(np.argmax(CUBE.normals[:, 2]))
    plain = mass_properties(CUBE, fill, mm_per_unit=10, bed=bed)
    label = LabelMass(top, 20.0, np.array([0.0, 0.0, 10.0]), np.array([0.0, 0.0, 1.0]), 0.5)
    engraved = mass_properties(CUBE, fill, mm_per_unit=10, bed=bed, labels=(label,))
    # 10 mm³ of pocket out, and 10 mm³ of infill below it turned to wall: net 10 (1 - 0.8) = 2 mm³ less
    assert (plain.mass - engraved.mass) * 1000 == pytest.approx(10 * 0.2)
    assert engraved.center[2] < plain.center[2]
    raised = mass_properties(
        CUBE, fill, mm_per_unit=10, bed=bed, labels=(LabelMass(**{**label.__dict__, "emboss": True}),)
    )
    assert (raised.mass - plain.mass) * 1000 == pytest.approx(10.0)


def test_small_layers_print_solid():
    # a 20 mm cube: every layer's infill region is 18.4² = 339 mm², under a 400 mm² threshold all are solid
    bed = int(np.argmin(CUBE.normals[:, 2]))
    some = mass_properties(CUBE, Fill("print", infill=0.0, solid_below_mm2=300.0), mm_per_unit=10, bed=bed)
    full = mass_properties(CUBE, Fill("print", infill=0.0, solid_below_mm2=400.0), mm_per_unit=10, bed=bed)
    assert some.mass < 8.0 and full.mass == pytest.approx(8.0)
    # a gem's pointed end has small sections: the threshold adds mass there, nowhere else
    poly = gem_polyhedron({"a": 1.18, "b": 0.52, "c": 0.72, "d": 1.41})
    plain = mass_properties(poly, Fill("print", solid_below_mm2=0.0), mm_per_unit=15, bed=4)
    small = mass_properties(poly, Fill("print", solid_below_mm2=70.0), mm_per_unit=15, bed=4)
    assert small.mass > plain.mass and small.center[1] < plain.center[1]
