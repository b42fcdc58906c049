"""The fast landing model: a probability distribution, symmetric, uniform on Platonic solids."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from diefab.core.errors import DesignError
from diefab.dice.design import load_design
from diefab.dice.families import GEM, gem_parameters, gem_polyhedron
from diefab.geometry.polyhedron import Polyhedron, face_margins
from diefab.made.mass import Fill, mass_properties
from diefab.models.fast import (
    Discrepancy,
    fast_model,
    gem_discrepancy,
    landing_probabilities,
    roll_retention,
    tipping_barriers,
)
from diefab.models.probabilities import MODELS, value_probabilities
from diefab.models import fast as fastmodel

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
    from diefab.search.optimize import optimize_design

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


# ---------------------------------------------------------------------------
# the gem discrepancy


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(0, 1), min_size=5, max_size=5))
def test_gem_parameters_are_read_back_from_any_gem(u):
    params = dict(zip("abcde", BOUNDS[:, 0] + np.asarray(u) * (BOUNDS[:, 1] - BOUNDS[:, 0])))
    poly = _unit_gem(u)
    if poly is None:
        return
    assert gem_parameters(poly) == params


def test_other_dice_are_not_gems():
    gem = load_design("fudge-gem").polyhedron
    assert gem_parameters(load_design("d6").polyhedron) is None
    # the gem's vertices rebuilt as a new convex hull: same shape, but not the family's topology
    assert gem_parameters(Polyhedron.from_points(gem.vertices)) is None
    # the family's topology on vertices that no parameters give (the apex off the axis)
    moved = gem.vertices.copy()
    moved[8, 0] += 0.01
    assert gem_parameters(gem.with_vertices(moved)) is None


def _synthetic(points):
    """Mirror-symmetric residuals that sum to zero, linear in the parameters."""
    x = (points - BOUNDS[:, 0]) / (BOUNDS[:, 1] - BOUNDS[:, 0])
    r = np.zeros((len(points), 9))
    r[:, 4] = 0.02 * x[:, 0] - 0.01 * x[:, 3]
    r[:, [0, 2]] = (0.01 * x[:, 1] - 0.005 * x[:, 4])[:, None]
    r[:, [5, 7]] = -(r[:, 4] + 2 * r[:, 0])[:, None] / 2
    return r


def test_discrepancy_interpolates_a_linear_residual_exactly():
    # thin-plate splines reproduce linear functions: the residual is recovered anywhere in the box
    rng = np.random.default_rng(3)

    def designs(n):
        points = BOUNDS[:, 0] + rng.random((n, 5)) * (BOUNDS[:, 1] - BOUNDS[:, 0])
        return points, rng.uniform(0, 0.5, (n, 9)), rng.dirichlet(np.ones(9), size=n)

    points, margins, chain = designs(80)
    # frequencies with mirror-antisymmetric noise on top: learning averages it away over mirror faces
    noise = rng.normal(0, 0.01, (80, 4))
    frequencies = chain + _synthetic(points)
    for k, (i, j) in enumerate(((0, 2), (1, 3), (5, 7), (6, 8))):
        frequencies[:, i] += noise[:, k]
        frequencies[:, j] -= noise[:, k]
    fit = Discrepancy.learn(points, margins, chain, frequencies, smoothing=1e-3)
    new = designs(20)
    got = np.array([fit(dict(zip("abcde", x)), m, p) for x, m, p in zip(*new)])
    assert np.allclose(got, _synthetic(new[0]), atol=1e-9)
    # outside the box: no correction
    assert fit(dict(zip("abcde", BOUNDS[:, 1] + 0.1)), margins[0], chain[0]) is None


def test_correction_keeps_a_distribution_and_fades_out_below_the_training_margins():
    fit = gem_discrepancy()
    floor = fit.margins.min()
    i = int(np.argmax(np.abs(fit.residuals).sum(axis=1)))  # a training gem with a large correction
    params, p = dict(zip("abcde", fit.points[i])), fit.chain[i]
    full = fit.correct(p, params, fit.margins[i])
    assert np.all(full >= 0) and full.sum() == pytest.approx(1.0)
    assert not np.allclose(full, p, atol=1e-3)
    # the same gem, told its smallest margin is half the training floor: half the correction (before clipping)
    margins = fit.margins[i] - fit.margins[i].min() + floor / 2
    half = fit.correct(p, params, margins)
    r = fit(params, margins, p)
    expected = np.clip(p + r / 2, 0, None)
    assert np.allclose(half, expected / expected.sum(), atol=1e-12)
    # an unstable face: the chain alone
    unstable = fit.margins[i].copy()
    unstable[4] = -0.01
    assert np.array_equal(fit.correct(p, params, unstable), p)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"points": np.zeros((30, 4))}, "points must be"),
        ({"margins": np.full((30, 9), -0.1)}, "stable on every face"),
        ({"n": 12}, "training designs for"),
    ],
)
def test_learning_checks_its_input(change, message):
    rng = np.random.default_rng(0)
    n = change.pop("n", 30)
    kw = {
        "points": BOUNDS[:, 0] + rng.random((n, 5)) * (BOUNDS[:, 1] - BOUNDS[:, 0]),
        "margins": rng.uniform(0.1, 0.5, (n, 9)),
        "chain": rng.dirichlet(np.ones(9), size=n),
        "frequencies": rng.dirichlet(np.ones(9), size=n),
    }
    kw.update(change)
    with pytest.raises(DesignError, match=message):
        Discrepancy.learn(**kw, smoothing=1e-3)


def test_discrepancy_json_round_trip():
    fit = gem_discrepancy()
    again = Discrepancy.from_json(fit.to_json())
    x = dict(zip("abcde", BOUNDS.mean(axis=1)))
    margins, chain = fit.margins[0], fit.chain[0]
    assert np.allclose(again(x, margins, chain), fit(x, margins, chain), atol=1e-12)
    # a design file's parameters may leave e out: it is a*b, as the family says
    paper = load_design("fudge-gem").params
    assert "e" not in paper
    assert np.array_equal(fit(paper, margins, chain), fit({**paper, "e": paper["a"] * paper["b"]}, margins, chain))
    assert again.info == fit.info


def test_packaged_discrepancy_matches_the_chain_and_the_family():
    fit = gem_discrepancy()
    assert fit.parameters == tuple("abcde")
    assert np.allclose(np.c_[fit.lower, fit.upper], BOUNDS)
    # learned against the chain constants in the code: refitting the chain needs relearning
    chain = fit.info["chain"]
    for name in ("temperature", "tau", "area_power", "roll_power", "height_weight"):
        assert chain[name] == getattr(fastmodel, name.upper())
    # and against the chain as the code computes it now, on the physics version the validator runs
    from diefab.physics.world import OUTCOME_VERSION

    assert fit.info["physics"] == f"outcomes-{OUTCOME_VERSION}"
    base = load_design("fudge-gem")
    for k in range(0, len(fit.points), len(fit.points) // 5):
        d = base.with_params(**dict(zip("abcde", fit.points[k])))
        c = d.mass_properties().center
        assert np.allclose(landing_probabilities(d.polyhedron, c), fit.chain[k], atol=1e-5)
        assert np.allclose(d.margins(), fit.margins[k], atol=1e-5)
    # differences of two distributions; mirror-image faces equal
    assert np.allclose(fit.residuals.sum(axis=1), 0, atol=1e-4)
    for i, j in ((0, 2), (1, 3), (5, 7), (6, 8)):
        assert np.array_equal(fit.residuals[:, i], fit.residuals[:, j])
    # every training design in the box and stable on every face by the benchmark's floor
    assert np.all((fit.points >= fit.lower) & (fit.points <= fit.upper))
    assert fit.margins.min() >= fit.info["min_margin"]


def test_fast_model_is_the_general_correction_for_non_gems_and_the_discrepancy_for_gems():
    from diefab.models.correction import corrected

    d6 = load_design("d6")
    c = d6.mass_properties().center
    assert np.array_equal(fast_model(d6.polyhedron, c), corrected(d6.polyhedron, c))
    gem = load_design("fudge-gem")
    c = gem.mass_properties().center
    assert not np.allclose(fast_model(gem.polyhedron, c), landing_probabilities(gem.polyhedron, c), atol=1e-3)


@pytest.mark.slow
def test_fast_model_tracks_pybullet_on_fresh_random_gems():
    # Gems no model was fitted on (another design seed than the benchmark's sets), 4000 drops each:
    # the fast model is within the sampling noise plus its own error, far closer than solid angles.
    from diefab.physics.simulate import simulate
    from diefab.stats.goodness import tvd

    base = load_design("fudge-gem")
    rng = np.random.default_rng(2026)
    fast, chain, solid = [], [], []
    while len(fast) < 4:
        params = dict(zip("abcde", BOUNDS[:, 0] + rng.random(5) * (BOUNDS[:, 1] - BOUNDS[:, 0])))
        try:
            d = base.with_params(**params)
        except DesignError:
            continue
        if d.margins().min() < 0.02:
            continue
        counts = simulate(d, 4000, seed=5, workers=2).face_counts
        q = counts / counts.sum()
        c = d.mass_properties().center
        fast.append(tvd(fast_model(d.polyhedron, c), q))
        chain.append(tvd(landing_probabilities(d.polyhedron, c), q))
        solid.append(tvd(MODELS["solid-angle"](d.polyhedron, c), q))
    assert np.median(fast) < 0.035  # sampling noise alone is ~0.015 at 4000 drops
    assert np.median(fast) < np.median(chain)
    assert np.median(fast) < np.median(solid) / 4
