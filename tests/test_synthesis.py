"""diefab design: candidates, synthesis and the command."""

from __future__ import annotations

import json

import numpy as np
import pytest

from diefab.cli import main
from diefab.core.errors import DesignError
from diefab.dice.design import load_design
from diefab.dice.readings import unreadable
from diefab.dice.targets import parse_target
from diefab.models.probabilities import value_probabilities
from diefab.search.synthesis import candidates, synthesize


def test_candidates_carry_every_value():
    for spec in ("2d6", "3df", "binomial:4", "uniform:3", "1:3,2:3,3:3,4:3,5:3,6:5", "4df"):
        target = parse_target(spec)
        found = candidates(target)
        assert found and all(c.faces >= len(target.values) for c in found)
        for c in found:
            c.polyhedron()  # every starting shape is a valid die
    assert {c.family for c in candidates(parse_target("1:3,2:3,3:3,4:3,5:3,6:5"))} >= {"cuboid", "ngem"}
    assert [c.faces for c in candidates(parse_target("2d6"), faces=13, family="ngem")] == [13]
    # a family no target-driven rule proposes still gives its member with one face per value
    assert [(c.family, c.faces) for c in candidates(parse_target("4df"), family="gem")] == [("gem", 9)]
    with pytest.raises(DesignError, match="no family gem fits"):
        candidates(parse_target("2d6"), family="gem")
    with pytest.raises(DesignError, match="fewer than"):
        candidates(parse_target("2d6"), faces=7)
    with pytest.raises(DesignError, match="unknown family"):
        candidates(parse_target("2d6"), family="sphere")


def test_a_face_count_that_fits_nothing_says_why_and_what_fits():
    with pytest.raises(DesignError, match=r"tips by less than 12° .*have 11, 13, 24 faces") as refused:
        candidates(parse_target("2d6"), faces=36)
    fits = [int(n) for n in str(refused.value).rsplit("have ", 1)[1].split(" faces")[0].split(", ")]
    assert all(candidates(parse_target("2d6"), faces=n) for n in fits)


@pytest.mark.parametrize(("spec", "family"), [("1:3,2:3,3:3,4:3,5:3,6:5", "cuboid"), ("uniform:3", "prism")])
def test_synthesis_under_the_solid_angle_model_hits_the_target(spec, family):
    target = parse_target(spec)
    found = synthesize(target, family=family, model="solid-angle", budget_seconds=20, seed=1)
    d = found.design
    d.check_stable(0.0)
    assert unreadable(d.polyhedron, d.values) is None
    probs = value_probabilities(d, "solid-angle")
    np.testing.assert_allclose(probs, found.predicted, atol=1e-9)
    assert np.abs(probs - target.aligned(d.support)).sum() / 2 < 0.01


def test_design_command_writes_a_design_that_loads(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["design", "uniform:3", "--family", "cuboid", "--model", "solid-angle", "--budget", "0.2",
              "--validate-sims", "300", "--workers", "1", "--out", str(tmp_path), "--json"])  # fmt: skip
    assert exit_.value.code == 0
    report = json.loads(capsys.readouterr().out)
    assert {"design_file", "family", "params", "faces", "values", "predicted", "objective", "tvd", "validated",
            "seconds"} <= set(report)  # fmt: skip
    assert set(report["validated"]) >= {"n", "tvd", "p_value"} and report["validated"]["n"] == 300
    d = load_design(report["design_file"])
    assert d.family == "cuboid" and sorted(set(d.values.values())) == [1, 2, 3]
    assert report["tvd"] < 0.01


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["2d6", "--faces", "5"], "fewer than"),
        (["nonsense"], "unknown target"),
        (["2d6", "--family", "sphere"], "unknown family"),
        (["2d6", "--budget", "-1"], "budget"),
        (["2d6", "--name", "../x"], "name"),
        (["1:0,2:1,3:1"], "probability 0"),
        (["1:1"], "one value"),
        (["2d6", "--family", "cuboid"], "no family cuboid fits"),
    ],
)
def test_design_command_refuses_bad_input_in_one_line(args, message, tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["design", *args, "--out", str(tmp_path)])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("family", "params", "target"),
    [
        ("ngem", {"n": 5, "a": 1.3, "b": 0.6, "c": 0.5, "d": 1.5}, "2d6"),
        ("prism", {"n": 5, "l": 1.5, "k": 1.0}, "binomial:4"),
        ("bipyramid", {"n": 4, "h": 1.2, "g": 1.0}, "1:1,2:1"),
        ("trapezohedron", {"n": 5, "t": 0.7, "u": 0.8}, "1:1,2:1"),
        ("cuboid", {"x": 1.0, "z": 0.9, "t": 0.1}, "1:3,2:3,3:3,4:3,5:3,6:5"),
        ("freeform", {"n": 8}, "uniform:4"),
    ],
)
def test_optimize_works_for_every_family_with_parameters(family, params, target):
    from diefab.search.optimize import optimize_design
    from diefab.search.synthesis import Candidate, _start

    start = _start(Candidate(family, params, 0), parse_target(target), "x", load_design("d6").fill, 30.0)
    before = np.abs(value_probabilities(start) - start.target_distribution.aligned(start.support)).sum()
    result = optimize_design(start, starts=0, max_evaluations=80, seed=0)
    after = np.abs(result.values - start.target_distribution.aligned(start.support)).sum()
    assert after <= before + 1e-12 or before > 1  # never worse than a feasible start
    assert result.min_margin >= 0.05 and set(result.design.params) >= {n for n in params if n != "n"} - {"k"}
