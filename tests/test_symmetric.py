"""Symmetric dice: fair dice and two-class dice whose faces are counted out to a target."""

from __future__ import annotations

import numpy as np
import pytest

from diefab.dice.design import Design
from diefab.dice.families import family
from diefab.dice.readings import unreadable
from diefab.dice.targets import parse_target
from diefab.geometry.polyhedron import solid_angles
from diefab.made.fill import Fill
from diefab.models.probabilities import MODELS, value_probabilities
from diefab.search.symmetric import (
    MIN_TIPPING,
    denominator,
    face_counts,
    fair_faces,
    fair_shapes,
    fair_values,
    tipping_angle,
    tune_share,
    two_class_plans,
    two_class_values,
)
from diefab.search.synthesis import synthesize

TARGETS = ["2d6", "3df", "binomial:4", "1:3,2:3,3:3,4:3,5:3,6:5", "uniform:3", "uniform:5", "1:1,2:2,3:1"]


def test_denominators_and_counts():
    assert denominator(parse_target("2d6")) == 36
    assert denominator(parse_target("4df")) == 81
    assert face_counts(parse_target("binomial:4"), 16).tolist() == [1, 4, 6, 4, 1]
    assert face_counts(parse_target("binomial:4"), 12) is None
    assert fair_faces(parse_target("1:3,2:3,3:3,4:3,5:3,6:5")) == 20
    assert fair_faces(parse_target("uniform:3")) == 6  # at least six faces
    assert fair_faces(parse_target("3df")) == 54  # even: 27 faces cannot be fair with parallel faces
    assert fair_faces(parse_target("4df")) is None  # 162 faces: too many


def test_fair_shapes_are_the_platonic_solids_where_they_exist():
    ((name, params),) = fair_shapes(6)
    assert name == "trapezohedron" and params["t"] == pytest.approx(1 / np.sqrt(2), abs=1e-5)  # the cube
    ((name, params),) = fair_shapes(8)
    assert name == "bipyramid" and params["h"] == pytest.approx(1.0, abs=1e-5)  # the octahedron
    assert fair_shapes(36) == []  # a 36-faced fair die tips by under MIN_TIPPING degrees: it rolls on
    assert fair_shapes(7) == [] and fair_shapes(4) == []


@pytest.mark.parametrize("faces", [6, 8, 10, 12, 14, 16, 18, 20])
def test_fair_shapes_land_uniformly_and_read_face_up(faces):
    for name, params in fair_shapes(faces):
        poly = family(name).polyhedron(params)
        c = poly.centroid
        assert len(poly.faces) == faces
        np.testing.assert_allclose(solid_angles(poly, c) / (4 * np.pi), 1 / faces, atol=1e-9)
        for model in ("solid-angle", "fast"):
            np.testing.assert_allclose(MODELS[model](poly, c), 1 / faces, atol=1e-6)
        n = poly.normals
        assert np.allclose(np.min(n @ n.T, axis=1), -1, atol=1e-9)  # every face has a parallel opposite
        assert tipping_angle(poly, c) >= MIN_TIPPING


@pytest.mark.parametrize("spec", TARGETS)
def test_fair_values_count_out_the_target(spec):
    target = parse_target(spec)
    m = fair_faces(target)
    shapes = fair_shapes(m)
    if not shapes:
        pytest.skip(f"no steady fair die for {spec}")
    poly = family(shapes[0][0]).polyhedron(shapes[0][1])
    values = fair_values(poly, target, face_counts(target, m))
    assert sorted(values) == sorted(poly.names)
    counts = [list(values.values()).count(int(v)) for v in target.values]
    np.testing.assert_allclose(np.array(counts) / m, target.probabilities, atol=1e-12)
    assert unreadable(poly, values) is None
    q = target.probabilities
    if np.allclose(q, q[::-1]) and (len(q) % 2 == 0 or counts[len(q) // 2] % 2 == 0):
        n = poly.normals
        opposite = np.argmin(n @ n.T, axis=1)
        total = {values[poly.names[f]] + values[poly.names[g]] for f, g in enumerate(opposite)}
        assert total == {int(target.values[0] + target.values[-1])}  # opposite faces sum alike, as on a d6


@pytest.mark.parametrize("spec", TARGETS)
def test_two_class_plans_roll_the_target_exactly_at_their_share(spec):
    target = parse_target(spec)
    for plan in two_class_plans(target):
        alpha, beta = np.array(plan.alpha), np.array(plan.beta)
        assert alpha.sum() == beta.sum() == plan.n and np.any(alpha != beta)
        per_value = (alpha * plan.share + beta * (1 - plan.share)) / plan.n
        np.testing.assert_allclose(per_value, target.probabilities, atol=1e-12)


def test_two_class_dice_keep_each_half_equally_likely():
    plan = two_class_plans(parse_target("2d6"))[0]
    assert plan.faces == 24 and plan.share == pytest.approx(2 / 3)
    for value in (1.5, 2.0, 2.6):
        poly = family(plan.family).polyhedron({**plan.params, plan.other: value})
        p = MODELS["solid-angle"](poly, poly.centroid)
        top, bottom = p[: plan.n], p[plan.n :]
        assert np.ptp(top) < 1e-12 and np.ptp(bottom) < 1e-12
        values = two_class_values(poly, parse_target("2d6"), plan)
        d = Design("x", plan.family, {**plan.params, plan.other: value}, values=values, target="2d6")
        share = top.sum()
        expect = (np.array(plan.alpha) * share + np.array(plan.beta) * (1 - share)) / plan.n
        np.testing.assert_allclose(value_probabilities(d, "solid-angle"), expect, atol=1e-12)


def test_tune_share_finds_a_noisy_root():
    rng_root = 1.37

    def share_of(value, n, seed):
        rng = np.random.default_rng([seed, int(value * 1e6)])
        p = 1 / (1 + np.exp(-3 * (value - rng_root))) * 0.6 + 0.2
        landed = n
        return rng.binomial(landed, p) / landed, landed

    goal = 0.5
    found = tune_share(share_of, 0.3, (0.0, 3.0), goal, slope=0.3, seed=4, precision=0.015)
    assert abs(found.value - rng_root) < 0.08
    again = tune_share(share_of, 0.3, (0.0, 3.0), goal, slope=0.3, seed=4, precision=0.015)
    assert again.value == found.value  # deterministic


@pytest.mark.parametrize(("spec", "faces"), [("binomial:4", 16), ("1:3,2:3,3:3,4:3,5:3,6:5", 20), ("uniform:3", 6)])
def test_design_prefers_the_fair_die(spec, faces):
    target = parse_target(spec)
    found = synthesize(target, model="fast", budget_seconds=5, seed=0)
    d = found.design
    assert len(d.values) == faces and d.family in ("bipyramid", "trapezohedron")
    np.testing.assert_allclose(found.predicted, target.aligned(d.support), atol=1e-6)
    d.check_stable(0.0)


def test_design_tunes_a_two_class_die_under_a_model():
    target = parse_target("2d6")
    found = synthesize(target, model="fast", budget_seconds=5, seed=0, fill=Fill())
    d = found.design
    assert len(d.values) == 24 and d.family == "bipyramid"
    np.testing.assert_allclose(value_probabilities(d, "fast"), target.aligned(d.support), atol=1e-6)
    assert unreadable(d.polyhedron, d.values) is None


def test_design_command_reports_how_the_die_carries_the_target(tmp_path, capsys):
    import json

    from diefab.cli import main
    from diefab.dice.design import load_design

    with pytest.raises(SystemExit) as exit_:
        main(["design", "binomial:4", "--model", "fast", "--validate-sims", "0", "--out", str(tmp_path), "--json"])
    assert exit_.value.code == 0
    report = json.loads(capsys.readouterr().out)
    assert report["method"] == "fair" and len(report["values"]) == 16 and report["tvd"] < 1e-6
    d = load_design(report["design_file"])
    assert sorted(d.values.values()).count(2) == 6


def test_a_counted_die_below_the_margin_asked_says_so(tmp_path, capsys):
    import json

    from diefab.cli import main
    from diefab.dice.design import load_design

    with pytest.raises(SystemExit) as exit_:
        main(["design", "binomial:4", "--model", "fast", "--validate-sims", "0", "--min-margin", "5",
              "--out", str(tmp_path), "--json"])  # fmt: skip
    assert exit_.value.code == 0
    captured = capsys.readouterr()
    report = json.loads(captured.out)
    d = load_design(report["design_file"])
    assert report["smallest_margin"] == pytest.approx(min(d.margins()[d.resting_mask()]))
    assert report["smallest_margin"] < report["min_margin"] == 5
    assert "not above --min-margin 5" in captured.err
