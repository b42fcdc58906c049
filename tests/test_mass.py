"""Mass properties: the paper's Eq. (1), shells, prints and inertia."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from diefab.errors import DesignError
from diefab.families import GEM, gem_center_of_mass_y, gem_polyhedron
from diefab.geometry import Polyhedron
from diefab.mass import Fill, inset, mass_properties

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
    hollow = mass_properties(poly, Fill("print", wall_mm=1.0, infill=0.0), mm_per_unit=15)
    inner = inset(poly, 1.0 / 15)
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
