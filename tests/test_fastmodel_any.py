"""The fast model's general correction: learnable, a distribution, symmetric, deterministic."""

from __future__ import annotations

import numpy as np
import pytest

from diefab.dice.design import load_design
from diefab.dice.families.sampling import RANDOM_FAMILIES, design_record, random_design, record_design
from diefab.geometry.polyhedron import resting_faces
from diefab.models.correction import FEATURES, Correction, corner_shares, corrected, face_features, packaged_correction
from diefab.models.fast import fast_model, landing_probabilities


def _dice(k: int, seed: int = 7):
    names = list(RANDOM_FAMILIES)
    return [random_design(names[i % len(names)], np.random.default_rng([seed, i])) for i in range(k)]


@pytest.fixture(scope="module")
def dice():
    return _dice(24)


def _features(dice):
    out = []
    for d in dice:
        poly, c = d.polyhedron, d.mass_properties().center
        chain = landing_probabilities(poly, c)
        x, resting = face_features(poly, c, chain)
        out.append((x[resting], chain[resting] / chain[resting].sum()))
    return out


def test_fit_recovers_a_known_residual(dice):
    # frequencies made by a known linear logit correction are learned back: weights and probabilities
    data = _features(dice)
    x = np.vstack([f for f, _ in data])
    w = np.random.default_rng(3).normal(scale=0.3, size=len(FEATURES))
    truth = Correction("linear", x.mean(axis=0), np.where(x.std(axis=0) > 0, x.std(axis=0), 1), w, 0.0)
    q = [truth.correct(c, f, np.ones(len(c), bool)) for f, c in data]
    fit = Correction.fit([f for f, _ in data], [c for _, c in data], q, penalty=1e-9)
    assert np.allclose(fit.weights, w, atol=1e-3)
    for (f, c), target in zip(data, q):
        assert np.abs(fit.correct(c, f, np.ones(len(c), bool)) - target).sum() / 2 < 1e-4


def test_fit_with_no_residual_learns_nothing(dice):
    data = _features(dice)
    k = len(FEATURES)
    none = Correction("quadratic", np.zeros(k), np.ones(k), np.zeros(k + k * (k + 1) // 2), 0.0)
    q = [none.correct(c, f, np.ones(len(c), bool)) for f, c in data]  # the chain (floored at 1e-4)
    fit = Correction.fit([f for f, _ in data], [c for _, c in data], q, expansion="quadratic")
    assert np.abs(fit.weights).max() < 1e-4


def test_corrected_is_a_distribution_on_random_dice_of_every_family(dice):
    for d in dice:
        poly, c = d.polyhedron, d.mass_properties().center
        p = fast_model(poly, c)
        assert np.all(p >= 0) and p.sum() == pytest.approx(1, abs=1e-12)
        assert np.all(p[~resting_faces(poly, c)] == 0)


def test_deterministic(dice):
    d = dice[5]
    poly, c = d.polyhedron, d.mass_properties().center
    assert np.array_equal(fast_model(poly, c), fast_model(poly, c))
    again = record_design(design_record(d))
    assert np.array_equal(fast_model(again.polyhedron, again.mass_properties().center), fast_model(poly, c))


@pytest.mark.parametrize("name", ["d6", "d8", "d20"])
def test_platonic_dice_stay_uniform(name):
    d = load_design(name)
    p = fast_model(d.polyhedron, d.mass_properties().center)
    assert np.allclose(p, 1 / len(p), atol=1e-9)


def test_symmetric_faces_stay_equal():
    # a bipyramid's faces above the equator are images of each other under its rotations, so are those below
    d = random_design("bipyramid", np.random.default_rng(1), {"n": 5})
    p = corrected(d.polyhedron, d.mass_properties().center)
    up = d.polyhedron.normals[:, 1] > 0  # the axis is y
    assert np.ptp(p[up]) < 1e-9 and np.ptp(p[~up]) < 1e-9
    assert abs(p[up][0] - p[~up][0]) > 1e-3  # h and g differ: the two halves do not


def test_transitional_faces_stay_at_zero_with_a_stated_center_of_mass():
    # a d6 loaded so far toward one face that the die cannot rest on the four sides
    d6 = load_design("d6")
    poly = d6.polyhedron
    center = poly.centroid + np.array([0.0, 0.0, -0.75]) * (np.ptp(poly.vertices[:, 2]) / 2)
    resting = resting_faces(poly, center)
    p = fast_model(poly, center)
    assert p.sum() == pytest.approx(1) and np.all(p[~resting] == 0)
    light = resting_faces(poly, poly.centroid + np.array([0, 0, -0.2]))
    assert light.all()
    q = fast_model(poly, poly.centroid + np.array([0, 0, -0.2]))
    bottom = int(np.argmin(poly.normals[:, 2]))
    assert q[bottom] > 1 / 6 > q[int(np.argmax(poly.normals[:, 2]))]


def test_packaged_correction_was_fitted_on_every_family():
    fit = packaged_correction()
    assert set(fit.info["families"]) == set(RANDOM_FAMILIES)
    assert np.all(np.isfinite(fit.weights))
    assert Correction.from_json(fit.to_json()).weights.tolist() == fit.weights.tolist()


@pytest.mark.parametrize("expansion", ["small", "linear", "quadratic", "rbf"])
def test_every_expansion_round_trips_through_json_and_keeps_symmetry(dice, expansion):
    data = _features(dice)
    q = [np.roll(c, 1) * 0.5 + c * 0.5 for _, c in data]  # some residual to learn
    fit = Correction.fit([f for f, _ in data], [c for _, c in data], q, expansion=expansion, penalty=1e-2)
    back = Correction.from_json(fit.to_json())
    d8 = load_design("d8")
    c = d8.mass_properties().center
    assert np.allclose(back(d8.polyhedron, c), 1 / 8, atol=1e-9)
    f, chain = data[3]
    ones = np.ones(len(chain), bool)
    assert np.allclose(back.correct(chain, f, ones), fit.correct(chain, f, ones), atol=1e-4)


def test_random_dice_rest_on_every_face_and_are_reproducible(dice):
    for d in dice:
        assert d.margins().min() >= 0.02
        assert len(d.values) == len(d.polyhedron.faces)
    again = _dice(3)
    assert [design_record(a) for a in again] == [design_record(b) for b in dice[:3]]
    with pytest.raises(ValueError, match="no random dice of family"):
        random_design("mesh", np.random.default_rng(0))


def test_corner_shares_are_a_distribution_invariant_under_motion_and_scale(dice):
    from scipy.spatial.transform import Rotation

    from diefab.geometry.polyhedron import Polyhedron

    for d in dice[:8]:
        poly = d.polyhedron
        s = corner_shares(poly)
        assert np.all(s >= 0) and s.sum() == pytest.approx(1, abs=1e-12)
        moved = Rotation.from_rotvec([0.3, -1.1, 0.7]).apply(np.array(poly.vertices)) * 2.5 + [1.0, -2.0, 0.5]
        assert np.allclose(corner_shares(Polyhedron(moved, poly.faces)), s, atol=1e-12)


def test_corner_shares_of_a_box_are_uniform_whatever_its_proportions():
    # every corner of a box has defect pi/2 and three right angles: each face collects 4 * (pi/2) / 3 of 4 pi
    from diefab.geometry.polyhedron import Polyhedron

    box = Polyhedron.from_points(np.array([[x, y, z] for x in (0, 3) for y in (0, 1) for z in (0, 0.4)], float))
    assert np.allclose(corner_shares(box), 1 / 6, atol=1e-12)


def test_features_of_mirror_image_faces_are_equal():
    # a bipyramid's rotations map the faces of each half onto each other: every feature row agrees
    d = random_design("bipyramid", np.random.default_rng(2), {"n": 6})
    x, resting = face_features(d.polyhedron, d.mass_properties().center)
    up = d.polyhedron.normals[:, 1] > 0
    assert resting.all()
    assert np.ptp(x[up], axis=0).max() < 1e-9 and np.ptp(x[~up], axis=0).max() < 1e-9
