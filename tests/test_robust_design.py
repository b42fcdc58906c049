"""Designing under a physics profile and against several throws at once."""

from __future__ import annotations

import json

import numpy as np
import pytest

from diefab.cli import main
from diefab.dice.design import load_design
from diefab.physics.profiles import load_profile
from diefab.search.optimize import Problem


def test_several_corrections_score_the_worst_of_them():
    d = load_design("fudge-gem")
    names = ("a", "b", "c", "d")
    m = len(d.polyhedron.names)
    rng = np.random.default_rng(0)
    rows = rng.normal(scale=0.02, size=(3, m))
    rows -= rows.mean(axis=1, keepdims=True)
    params = {**d.params, "a": 1.2, "d": 1.5}
    alone = [Problem(d, names, "solid-angle", correction=r).evaluate(params) for r in rows]
    score, values, _ = Problem(d, names, "solid-angle", correction=rows).evaluate(params)
    worst = int(np.argmax([s for s, _, _ in alone]))
    assert score == pytest.approx(alone[worst][0], rel=1e-12)
    np.testing.assert_allclose(values, alone[worst][1])
    # one row is the plain correction
    one, _, _ = Problem(d, names, "solid-angle", correction=rows[:1]).evaluate(params)
    assert one == pytest.approx(alone[0][0], rel=1e-12)


def test_design_keeps_the_physics_profile_and_checks_under_it(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["design", "uniform:3", "--family", "cuboid", "--model", "solid-angle",
              "--tolerance", "0.5", "--validate-sims", "200", "--workers", "1", "--physics", "wooden-table",
              "--out", str(tmp_path), "--json"])  # fmt: skip
    assert exit_.value.code == 0
    report = json.loads(capsys.readouterr().out)
    d = load_design(report["design_file"])
    profile = load_profile("wooden-table")
    assert d.physics["restitution"] == profile.restitution and d.physics["friction"] == profile.friction
    assert report["physics"] == "wooden-table" and report["validated"]["n"] == 200


@pytest.mark.parametrize(
    ("args", "words"),
    [(["--physics", "no-such-table"], "unknown physics profile"), (["--robust", "--model", "fast"], "--robust")],
)
def test_design_refuses_a_bad_profile_or_robust_without_simulation(args, words, tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["design", "uniform:3", *args, "--out", str(tmp_path)])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_robust_refinement_drops_every_throw_and_keeps_the_worst(monkeypatch):
    import diefab.search.refinement as refinement
    import diefab.search.synthesis as synthesis
    from diefab.dice.targets import parse_target

    monkeypatch.setattr(refinement, "REFINE_DROPS", 600)
    monkeypatch.setattr(refinement, "MIN_THROW_DROPS", 300)
    throws = [load_profile(p).as_dict() for p in ("soft-tray", "hard-tray")]
    found = synthesis.synthesize(parse_target("uniform:3"), family="cuboid", model="simulation", max_drops=1200,
                                 seed=2, workers=1, throws=throws)  # fmt: skip
    assert found.steps, "the refinement ran"
    for step in found.steps:
        assert len(step["throw_tvds"]) == 2 and step["drops"] == 300
        assert step["simulated_tvd"] == max(step["throw_tvds"])
    best = min(s["simulated_tvd"] for s in found.steps)
    kept = next(s for s in found.steps if s["simulated_tvd"] == best)
    assert found.design.params == kept["params"]
