"""The fast landing model: a probability distribution, symmetric, uniform on Platonic solids."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from diefab.design import load_design
from diefab.errors import DesignError
from diefab.families import GEM, gem_polyhedron
from diefab.fastmodel import fast_model, landing_probabilities, roll_retention, tipping_barriers
from diefab.geometry import Polyhedron, face_margins
from diefab.mass import Fill, mass_properties
from diefab.models import MODELS, value_probabilities

BOUNDS = GEM.bounds(["a", "b", "c", "d", "e"])


def _unit_gem(u):
    params = dict(zip("abcde", BOUNDS[:, 0] + np.asarray(u) * (BOUNDS[:, 1] - BOUNDS[:, 0])))
    try:
        return gem_polyhedron(params)
    except DesignError:
        return None


@settings(max_examples=150, deadline=None)
@given(st.lists(st.floats(0, 1), min_size=5, max_size=5))
def test_probabilities_for_any_gem(u):
    poly = _unit_gem(u)
    if poly is None:  # not convex: not a design
        return
    center = mass_properties(poly, Fill()).center
    p = fast_model(poly, center)
    assert p.shape == (9,)
    assert np.all(p >= 0)
    assert p.sum() == pytest.approx(1.0, abs=1e-12)
    # a face the die cannot rest on gets nothing: its share topples onto stable faces
    margins = face_margins(poly, center)
    assert np.all(p[margins < 0] < 1e-12)
    # mirror-image faces of the gem (x -> -x: f2 <-> f4, f7 <-> f9; z -> -z: f1 <-> f3, f6 <-> f8)
    for i, j in ((0, 2), (1, 3), (5, 7), (6, 8)):
        assert p[i] == pytest.approx(p[j], abs=1e-9)


@pytest.mark.parametrize("name", ["d6", "d8"])
def test_platonic_solids_are_uniform(name):
    d = load_design(name)
    p = fast_model(d.polyhedron, d.mass_properties().center)
    assert np.allclose(p, 1 / len(p), atol=1e-12)


def _tetra_and_dodeca():
    phi = (1 + 5**0.5) / 2
    tetra = Polyhedron.from_points([(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)])
    pts = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    for a, b in ((1 / phi, phi), (-1 / phi, phi), (1 / phi, -phi), (-1 / phi, -phi)):
        pts += [(0, a, b), (a, b, 0), (b, 0, a)]
    return tetra, Polyhedron.from_points(pts)


def test_more_platonic_solids_are_uniform():
    for poly in _tetra_and_dodeca():
        p = fast_model(poly, poly.centroid)
        assert np.allclose(p, 1 / len(p), atol=1e-12)


def test_mirror_image_of_an_irregular_die_mirrors_the_probabilities():
    rng = np.random.default_rng(7)
    pts = rng.normal(size=(14, 3))
    poly = Polyhedron.from_points(
        pts / np.linalg.norm(pts, axis=1)[:, None] * rng.uniform(0.8, 1.0, (14, 1)), strict=False
    )
    mirror = Polyhedron(poly.vertices * [-1, 1, 1], tuple(f[::-1] for f in poly.faces))
    c = poly.centroid
    p = fast_model(poly, c)
    q = fast_model(mirror, c * [-1, 1, 1])
    assert np.allclose(p, q, atol=1e-12)
    # and it is not just the solid angles
    assert not np.allclose(p, MODELS["solid-angle"](poly, c), atol=1e-3)


def test_barriers_of_a_cube():
    d = load_design("d6")
    poly = d.polyhedron
    barrier, share, across = tipping_barriers(poly, poly.centroid)
    half = np.ptp(poly.vertices[:, 0]) / 2
    assert np.allclose(barrier, half * (2**0.5 - 1))  # the centre rises from h to h * sqrt(2)
    assert np.allclose(share, 0.25)
    # across each edge lies a different, adjacent face (never the face itself)
    _, _, face, _ = poly._ring
    assert np.all(across != face)


def test_no_tumbling_is_the_solid_angle_model_on_a_stable_die():
    d = load_design("fudge-gem")
    c = d.mass_properties().center
    p = landing_probabilities(d.polyhedron, c, tau=0.0, height_weight=0.0)
    assert np.allclose(p, MODELS["solid-angle"](d.polyhedron, c), atol=1e-12)


def test_registered_for_predict_and_optimize():
    d = load_design("fudge-gem")
    assert value_probabilities(d, "fast").sum() == pytest.approx(1.0)


def test_optimize_with_the_fast_model():
    from diefab.optimize import optimize_design

    result = optimize_design(load_design("fudge-gem"), model="fast", starts=1, seed=0, max_evaluations=300)
    assert result.margins.min() >= 0.05
    assert result.objective < 0.1


def test_roll_retention_of_a_cube_is_the_rolling_polygon_law():
    # cube of side 2 about its centre: k^2 = 2/3 about an edge-parallel axis, r^2 = 2, the faces turn 90 degrees
    d6 = load_design("d6")
    eta = roll_retention(d6.polyhedron, d6.mass_properties().center)
    assert np.allclose(eta, ((2 / 3) / (2 / 3 + 2)) ** 2)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(0, 1), min_size=5, max_size=5))
def test_roll_retention_is_an_energy_share_and_the_same_from_both_sides(u):
    poly = _unit_gem(u)
    if poly is None:
        return
    eta = roll_retention(poly, mass_properties(poly, Fill()).center)
    assert np.all((eta >= 0) & (eta <= 1))
    tail, head, _, _ = poly._ring
    n = len(poly.vertices)
    code = tail * n + head
    reverse = np.argsort(code)[np.searchsorted(np.sort(code), head * n + tail)]
    assert np.allclose(eta, eta[reverse])


def test_no_rolling_term_is_the_barrier_chain():
    d = load_design("fudge-gem")
    c = d.mass_properties().center
    p = landing_probabilities(d.polyhedron, c, roll_power=0.0)
    assert np.all(p >= 0) and p.sum() == pytest.approx(1.0)
    assert not np.allclose(p, fast_model(d.polyhedron, c))
