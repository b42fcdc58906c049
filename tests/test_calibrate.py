"""Physics profiles and calibration of the physics to real rolls."""

from __future__ import annotations

import json

import numpy as np
import pytest

from diefab.core.errors import PhysicsError
from diefab.physics.profiles import load_profile, profile_to_toml, read_profile
from diefab.physics.simulate import PhysicsSettings

# ----------------------------------------------------------------------
# physics profiles


def test_profile_round_trips(tmp_path):
    settings = PhysicsSettings(restitution=0.45, friction=0.6, angular_velocity=(0.0, 22.5), drop_height=3.0)
    path = tmp_path / "p.toml"
    path.write_text(profile_to_toml(settings, name="x", calibration={"deviance": 1.5}, comment="hello"))
    assert load_profile(path) == settings


def test_profile_lies_between_design_and_options(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text("[physics]\nrestitution = 0.5\n")
    s = load_profile(path, base={"restitution": 0.1, "friction": 0.3}, friction=None, drop_height=4.0)
    assert (s.restitution, s.friction, s.drop_height) == (0.5, 0.3, 4.0)


@pytest.mark.parametrize(
    "text, words",
    [
        ("[physics]\nrestitution = 2\n", "restitution=2.0"),
        ("[physics]\nspin = 2\n", "unknown physics setting 'spin'"),
        ("foo = 1\n[physics]\n", "unknown key 'foo'"),
        ("physics = 3\n", "[physics] table"),
        ("[physics\n", "malformed TOML"),
        ('[physics]\nangular_velocity = "fast"\n', "angular_velocity"),
        ("[physics]\n[domain]\nfills = 'solid'\n", "is not a list of fills"),
        ("[physics]\n[domain]\nfills = []\n", "is not a list of fills"),
        ("[physics]\n[domain]\nfills = ['wood']\n", "is not a list of fills"),
        ("[physics]\n[domain]\nfills = ['solid']\nsurface = 'felt'\n", "unknown key 'surface' in [domain]"),
        ("[physics]\n[domain]\nfills = ['solid']\nrolled = 3\n", "domain.rolled = 3"),
    ],
)
def test_bad_profile_is_named(tmp_path, text, words):
    path = tmp_path / "p.toml"
    path.write_text(text)
    with pytest.raises(PhysicsError, match=None) as info:
        load_profile(path)
    assert words in str(info.value) and str(path) in str(info.value)


def test_a_profile_names_the_dice_it_was_fitted_on(tmp_path):
    from diefab.physics.profiles import domain_note, fitted_profiles

    path = tmp_path / "p.toml"
    path.write_text(profile_to_toml(PhysicsSettings(), domain={"fills": ["solid", "print"], "rolled": "on felt"}))
    assert domain_note(path, "solid") is None and domain_note(path, "print") is None
    note = domain_note(path, "paper")
    assert "solid and print dice rolled on felt" in note and "this die is paper" in note
    assert domain_note("soft-tray", "paper") is None  # fitted on no die: nothing to lie outside of
    assert all(domain_note(name, "paper") is not None for name in fitted_profiles())  # each fitted on solid dice


def test_cli_notes_a_die_outside_the_profiles_dice(run):
    code, _, err = run("validate", "fudge-gem-paper", "--physics", "printed-table", "--sims", "20", "--workers", "1",
                       "--json")  # fmt: skip
    assert code == 0, err
    assert "'printed-table' was fitted on solid dice" in err and "this die is paper" in err
    code, _, err = run("validate", "d6", "--physics", "printed-table", "--sims", "20", "--workers", "1", "--json")
    assert code == 0 and "note" not in err


def test_missing_profile(tmp_path):
    with pytest.raises(PhysicsError, match="does not exist"):
        load_profile(tmp_path / "nope.toml")
    with pytest.raises(PhysicsError, match="unknown physics profile"):
        load_profile("no-such-profile")


@pytest.mark.parametrize("command", [["validate", "d6", "--sims", "10", "--workers", "1"], ["optimize", "fudge-gem"]])
def test_cli_bad_profile_is_one_line_exit_2(tmp_path, bad, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.toml").write_text("[physics]\nfriction = -1\n")
    assert "friction" in bad(*command, "--physics", "p.toml")


def test_cli_validate_uses_profile_then_options(tmp_path, run):
    path = tmp_path / "p.toml"
    path.write_text(profile_to_toml(PhysicsSettings(restitution=0.5, angular_velocity=(0.0, 20.0))))
    code, out, err = run("validate", "d6", "--sims", "20", "--workers", "1", "--physics", path, "--friction", "0.5",
                         "--json")  # fmt: skip
    assert code == 0, err
    settings = json.loads(out)["settings"]
    assert (settings["restitution"], settings["friction"], settings["angular_velocity"]) == (0.5, 0.5, [0.0, 20.0])


# ----------------------------------------------------------------------
# calibration


@pytest.fixture(scope="module")
def cube_die():
    from diefab.dice.design import load_design
    from diefab.search.calibrate import real_die

    return real_die("cube", load_design("d6"), "10,11,9,10,12,8")


def test_deviance_is_zero_at_the_frequencies_and_positive_elsewhere():
    from diefab.search.calibrate import deviance

    c = np.array([3, 7, 10])
    assert deviance(c, c / c.sum()) == pytest.approx(0.0, abs=1e-12)
    assert deviance(c, [1 / 3, 1 / 3, 1 / 3]) > 0


def test_a_die_is_compared_up_to_relabelling_within_its_groups(cube_die):
    """Outcomes the data name only up to relabelling: the least TVD over relabellings, in every report."""
    from dataclasses import replace

    from diefab.search.likelihood import die_report

    die = replace(cube_die, groups=((0, 1),))  # the real counts are 10, 11, 9, 10, 12, 8 of 60
    swapped = np.array([11, 10, 9, 10, 12, 8]) / 60
    assert die.tvd(swapped) == pytest.approx(0.0, abs=1e-12)  # the first two outcomes relabelled
    assert cube_die.tvd(swapped) == pytest.approx(1 / 60)  # without the group: one roll moved
    short = np.append(swapped[:5], 0.0)  # 8/60 of the mass on no value: it counts as misplaced
    assert die.tvd(short) == pytest.approx(0.5 * 8 / 60 + 0.5 * 8 / 60)
    report = die_report(die, [110, 100, 90, 100, 120, 80])
    assert report["tvd"] == pytest.approx(0.0, abs=1e-12) and report["simulated"][0] == pytest.approx(110 / 600)


def test_smoothing_keeps_unsimulated_values_possible():
    from diefab.search.calibrate import smoothed

    p = smoothed([0, 10, 30])
    assert p.sum() == pytest.approx(1.0) and p[0] > 0 and p[0] == pytest.approx(0.5 / 41.5)


def test_groups_average_within_a_mirror_pair():
    from diefab.dice.design import load_design
    from diefab.search.calibrate import RealDie

    die = RealDie("cube", load_design("d6"), np.array([1, 2, 3, 4, 5, 6]), groups=((0, 5),))
    assert die.symmetrized(np.array([0.1, 0.2, 0.2, 0.2, 0.1, 0.2]))[[0, 5]] == pytest.approx([0.15, 0.15])


def test_settings_at_sets_the_top_of_a_range():
    from diefab.search.calibrate import parameter_value, settings_at

    s = settings_at(PhysicsSettings(angular_velocity=(2.0, 10.0)), ["spin", "restitution"], [25.0, 0.6])
    assert s.angular_velocity == (2.0, 25.0) and s.restitution == 0.6
    assert parameter_value(s, "spin") == 25.0
    assert settings_at(PhysicsSettings(angular_velocity=(2.0, 10.0)), ["spin"], [1.0]).angular_velocity == (1.0, 1.0)


def test_spec_starts_at_the_base_settings_and_keeps_dice_above_ground(cube_die):
    from diefab.physics.simulate import _body
    from diefab.search.calibrate import CalibrationSpec, make_spec

    spec = make_spec([cube_die], free=["restitution", "drop_height"], bounds={"drop_height": (0.1, 8.0)})
    assert spec.values(spec.x0) == pytest.approx([0.3, 5.0])
    assert spec.bounds[1][0] > _body(cube_die.design).radius + PhysicsSettings().height_jitter
    again = CalibrationSpec.from_json(spec.to_json())
    assert again == spec and again.real_dice[0].counts.tolist() == cube_die.counts.tolist()


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"free": ["spinn"]}, "not a calibration parameter"),
        ({"free": []}, "no physics parameter"),
        ({"free": ["spin", "spin"]}, "name one twice"),
        ({"bounds": {"spin": (5.0, 1.0)}}, "low < high"),
        ({"sims_per_eval": 0}, "drops per evaluation"),
        ({"method": "grid", "grid_points": 1}, "2 points or more"),
        ({"method": "grid", "grid_points": 33, "free": ["spin", "restitution"]}, "1024 in all"),
        ({"method": "grid", "grid_points": 2.5}, "must be an integer"),
    ],
)
def test_bad_spec(cube_die, kwargs, words):
    from diefab.search.calibrate import CalibrationError, make_spec

    with pytest.raises(CalibrationError, match=words):
        make_spec([cube_die], **kwargs)


def test_bad_counts(tmp_path):
    from diefab.dice.design import load_design
    from diefab.search.calibrate import CalibrationError, real_die

    for counts, words in (("1,2,3", "6 values"), ("1,2,3,4,5,-6", "negative"), ("0,0,0,0,0,0", "no real rolls"),
                          (str(tmp_path), "is not a regular file")):  # fmt: skip
        with pytest.raises(CalibrationError, match=words):
            real_die("cube", load_design("d6"), counts)


def test_a_real_die_from_a_stored_run_refuses_what_it_cannot_count():
    """A run's stored dice go through the same checks as the command line's: one error, never a cast's warning."""
    from diefab.dice.design import load_design
    from diefab.search.calibrate import CalibrationError, RealDie

    cube = load_design("d6")
    for name, counts, words in (
        ("cube", [9.3e18, 1, 1, 1, 1, 1], "more than the 1e\\+15"),
        ("cube", ["x", 1, 1, 1, 1, 1], "must be numbers"),
        (None, [1] * 6, "non-empty string"),
        (3, [1] * 6, "non-empty string"),
    ):
        with pytest.raises(CalibrationError, match=words):
            RealDie(name, cube, counts)


def _quadratic(spec, centre, hessian):
    """A fake objective: total deviance (x - centre)' H (x - centre) / 2 in the unit cube, plus 10."""

    def objective(x, drops):
        x = np.clip(np.asarray(x, float), 0, 1)
        dx = x - centre
        dev = 10.0 + 0.5 * dx @ hessian @ dx
        return {"x": x.tolist(), "params": dict(zip(spec.names, spec.values(x).tolist())), "drops": int(drops),
                "objective": dev / 100, "deviance": dev, "feasible": True, "dice": []}  # fmt: skip

    return objective


def test_curvature_recovers_the_standard_errors_of_a_quadratic(cube_die):
    from diefab.search.calibrate import curvature, make_spec

    spec = make_spec([cube_die], free=["restitution", "spin"])
    h = np.array([[400.0, 100.0], [100.0, 200.0]])
    objective = _quadratic(spec, np.array([0.4, 0.6]), h)
    rng = np.random.default_rng(0)
    records = [objective(np.array([0.4, 0.6]) + 0.05 * rng.standard_normal(2), 100) for _ in range(30)]
    best = objective(np.array([0.4, 0.6]), 100)
    fitted = curvature(records, spec, best)
    se = np.sqrt(np.diag(2 * np.linalg.inv(h))) * np.diff(np.array(spec.bounds), axis=1)[:, 0]
    assert [fitted[n]["se"] for n in spec.names] == pytest.approx(se.tolist(), rel=1e-6)


def test_curvature_leaves_a_flat_direction_undetermined(cube_die):
    from diefab.search.calibrate import curvature, make_spec

    spec = make_spec([cube_die], free=["restitution", "spin"])
    objective = _quadratic(spec, np.array([0.4, 0.6]), np.array([[400.0, 0.0], [0.0, 0.0]]))
    rng = np.random.default_rng(1)
    records = [objective(np.array([0.4, 0.6]) + 0.05 * rng.standard_normal(2), 100) for _ in range(30)]
    fitted = curvature(records, spec, objective(np.array([0.4, 0.6]), 100))
    assert fitted["restitution"]["se"] is not None and fitted["spin"]["se"] is None


def test_driver_finds_the_minimum_and_a_resumed_run_continues_it(cube_die):
    from diefab.search.calibrate import calibrate, make_spec

    spec = make_spec([cube_die], free=["restitution", "spin"], sims_per_eval=100, max_sims=100)
    objective = _quadratic(spec, np.array([0.7, 0.2]), np.diag([50.0, 50.0]))
    full: list = []
    whole = calibrate(spec, objective=objective, on_evaluation=full.append, max_evaluations=120)
    assert whole.best["x"] == pytest.approx([0.7, 0.2], abs=0.02)
    first: list = []
    calibrate(spec, objective=objective, on_evaluation=first.append, max_evaluations=50)
    rest: list = []
    again = calibrate(spec, objective=objective, history=first, on_evaluation=rest.append, max_evaluations=120)
    assert again.replayed == 50 and [r["x"] for r in first + rest] == [r["x"] for r in full]


def test_grid_halves_toward_the_minimum_on_ever_more_drops(cube_die):
    from diefab.search.calibrate import calibrate, grid_interval, make_spec

    spec = make_spec([cube_die], free=["restitution"], method="grid", grid_points=11, sims_per_eval=100,
                     max_sims=800)  # fmt: skip
    objective = _quadratic(spec, np.array([0.68]), np.array([[50.0]]))
    records: list = []
    result = calibrate(spec, objective=objective, on_evaluation=records.append)
    assert result.finished and result.best["x"] == pytest.approx([0.7]) and result.best["drops"] == 800
    grid = [r for r in records if r["kind"] == "grid"]
    # the start (restitution 0.3 is no grid point) and 11 points at 100 drops, then the better half at each doubling
    assert sorted(round(r["x"][0], 9) for r in grid if r["drops"] == 100) == pytest.approx(np.linspace(0, 1, 11))
    survivors = {n: sorted(round(r["x"][0], 1) for r in records if r["drops"] == n and r["kind"] != "start")
                 for n in (200, 400, 800)}  # fmt: skip
    assert survivors == {200: [0.4, 0.5, 0.6, 0.7, 0.8, 0.9], 400: [0.6, 0.7, 0.8], 800: [0.6, 0.7, 0.8]}
    again = calibrate(spec, objective=objective, history=records[:7])
    assert again.replayed == 7 and again.best["x"] == result.best["x"] and again.evaluations == len(records)
    # deviance 10 + 25 (x - 0.68)^2 is within 1 of the best's on the grid points 0.5 ... 0.8
    lo, hi = grid_interval(records, spec, result.best)["restitution"]
    assert (lo, hi) == pytest.approx((spec.values([0.5])[0], spec.values([0.8])[0]))


@pytest.mark.parametrize(
    "args, words",
    [
        ([], "at least one die"),
        (["--die", "d6", "1,1,1,1,1,1", "--method", "grid", "--grid-points", "1"], "2 points or more"),
        (["--die", "d6", "1,2,3"], "6 values"),
        (["--die", "d6", "1,1,1,1,1,1", "--free", "spinn"], "not a calibration parameter"),
        (["--die", "d6", "1,1,1,1,1,1", "--bound", "spin=3"], "NAME=LOW:HIGH"),
        (["--die", "d6", "1,1,1,1,1,1", "--sims-per-eval", "0"], "must be > 0"),
        (["--die", "d6", "1,1,1,1,1,1", "--name", "../x"], "plain name"),
        (["--die", "nope", "1,1,1,1,1,1"], "unknown template"),
        (["--resume", "nowhere"], "does not exist"),
    ],
)
def test_cli_bad_input_is_one_line_exit_2(tmp_path, bad, monkeypatch, args, words):
    monkeypatch.chdir(tmp_path)
    assert words in bad("calibrate", *args)
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").rglob("*.toml"))


def test_cli_calibrates_writes_a_profile_and_resumes(tmp_path, run):
    args = ["calibrate", "--die", "d6", "10,11,9,10,12,8", "--free", "restitution", "--sims-per-eval", "30",
            "--workers", "1", "--out", tmp_path, "--json"]  # fmt: skip
    code, out, err = run(*args, "--max-evals", "3")
    assert code == 0, err
    report = json.loads(out)
    assert report["evaluations"] == 3 and not report["finished"]
    settings = load_profile(report["profile"])
    assert settings.restitution == pytest.approx(report["fitted"]["restitution"]["value"])
    assert read_profile(report["profile"])[0]["domain"] == {"fills": ["solid"]}  # the fill of the d6 it was fitted on
    code, out, err = run("calibrate", "--resume", tmp_path / "calibrated", "--max-evals", "5", "--json")
    assert code == 0, err
    again = json.loads(out)
    assert (again["evaluations"], again["replayed"]) == (5, 3)
    assert len((tmp_path / "calibrated" / "evaluations.jsonl").read_text().splitlines()) == 5
    assert "already holds a run" in run(*args)[2]
    code, _, err = run("calibrate", "--resume", tmp_path / "calibrated", "--free", "spin")
    assert code == 2 and "leave out --free" in err


# ----------------------------------------------------------------------
# shipped profiles and sensitivity


def test_standard_profiles_are_shipped_and_valid():
    from diefab.physics.profiles import STANDARD, list_profiles

    assert set(STANDARD) <= set(list_profiles())
    for name in STANDARD:
        assert isinstance(load_profile(name), PhysicsSettings)


def test_sensitivity_drops_each_profile_with_its_settings(run):
    code, out, err = run("validate", "d6", "--sensitivity", "--sims", "30", "--workers", "1", "--friction", "0.7",
                         "--json")  # fmt: skip
    assert code == 0, err
    report = json.loads(out)
    rows = {r["profile"]: r for r in report["profiles"]}
    assert rows["hard-tray"]["settings"]["restitution"] == 0.7 and rows["low-spin"]["settings"]["restitution"] == 0.3
    assert all(r["settings"]["friction"] == 0.7 for r in rows.values())  # the option overrides every profile
    assert all(sum(r["counts"]) + r["cocked"] + r["unsettled"] == 30 for r in rows.values())
    assert report["worst_tvd"] == max(r["tvd"] for r in rows.values())


def test_robust_objective_is_the_worst_throw_and_resumes(tmp_path):
    from diefab.dice.design import design_to_toml, load_design
    from diefab.search.simopt import RunSpec, SimulationObjective, start_point

    d = load_design("fudge-gem")
    names = ("a", "b", "c", "d")
    throws = tuple(load_profile(p).as_dict() for p in ("soft-tray", "hard-tray"))
    spec = RunSpec(design_toml=design_to_toml(d), names=names, x0=tuple(start_point(d, names, model="design")),
                   sims_per_eval=20, max_sims=40, physics=PhysicsSettings().as_dict(), robust=throws)  # fmt: skip
    assert RunSpec.from_json(spec.to_json()) == spec
    record = SimulationObjective(spec, workers=1)(np.array(spec.x0), 20)
    assert len(record["objectives"]) == 2 and record["objective"] == max(record["objectives"])
    worst = int(np.argmax(record["objectives"]))
    assert record["throw_face_counts"][worst] == record["face_counts"]  # every throw's counts, for corrections


def test_cli_robust_optimizes_by_defect_correction_unless_told(run, tmp_path):
    code, out, err = run("optimize", "fudge-gem", "--model", "simulation", "--robust", "--start", "design",
                         "--sims-per-eval", "20", "--max-sims-per-eval", "20", "--max-evals", "2", "--workers", "1",
                         "--out", tmp_path, "--name", "r", "--json")  # fmt: skip
    assert code == 0, err
    report = json.loads(out)
    spec = json.loads((tmp_path / "r" / "run.json").read_text())
    assert spec["method"] == "correction" and len(spec["robust"]) == 5
    assert report["evaluations"] == 2 and len(report["objectives"]) == 5
    records = [json.loads(line) for line in (tmp_path / "r" / "evaluations.jsonl").read_text().splitlines()]
    assert [r["kind"] for r in records] == ["start", "correction"]


def test_cli_robust_needs_simulation(bad):
    assert "--model simulation" in bad("optimize", "fudge-gem", "--robust")


REALROLLS = "/work/shared/realrolls/binom3.json"


def test_realrolls_die_keeps_counts_groups_and_references():
    from pathlib import Path

    pytest.importorskip("diefab.physics.realrolls")
    if not Path(REALROLLS).is_file():
        pytest.skip("the real-rolls data are not on this machine")
    from diefab.search.calibrate import realrolls_die

    data = json.loads(Path(REALROLLS).read_text())
    die = realrolls_die(REALROLLS)
    assert die.n == data["physical"]["n"] and sorted(die.counts.tolist()) == sorted(data["physical"]["counts"])
    assert len(die.groups) == len(data["ambiguous_groups"]) and {"ours", "bullet"} <= set(die.reference)


# ----------------------------------------------------------------------
# response surfaces of simulated counts


def _true_surface(d: int = 2):
    """A known 3-value surface, quadratic in the logits, and its probabilities."""
    from diefab.search.surface import ResponseSurface, quadratic_features

    rng = np.random.default_rng(3)
    coef = np.zeros((quadratic_features(np.zeros((1, d))).shape[1], 3))
    coef[:, 1:] = rng.normal(scale=1.0, size=(coef.shape[0], 2))
    return ResponseSurface(coef, 400)


def test_surface_recovers_a_quadratic_logit_from_multinomial_counts():
    from diefab.search.surface import fit_surface

    truth = _true_surface()
    rng = np.random.default_rng(0)
    xs = rng.random((40, 2))
    counts = np.array([rng.multinomial(400, p) for p in truth.probabilities(xs)])
    fitted = fit_surface(xs, counts, ridge=1e-6)
    grid = rng.random((200, 2))
    gap = 0.5 * np.abs(fitted.probabilities(grid) - truth.probabilities(grid)).sum(axis=1)
    # pooling 40 x 400 drops: far below one point's simulation noise (about 0.03 TVD for 3 values)
    assert gap.mean() < 0.01 and gap.max() < 0.03
    assert np.allclose(fitted.probabilities(grid).sum(axis=1), 1.0)
    assert fitted.drops == 400


def test_surface_keeps_a_value_never_simulated_possible():
    from diefab.search.surface import fit_surface

    xs = np.linspace(0, 1, 6)[:, None]
    counts = np.c_[np.full(6, 50), np.full(6, 50), np.zeros(6)]
    s = fit_surface(xs, counts)
    p = s.smoothed(np.array([0.3]))
    assert np.all(p > 0) and p[2] < 0.01 and p.sum() == pytest.approx(1.0)


def test_fit_settings_finds_the_setting_that_made_the_rolls_and_the_prior_pulls_toward_the_start():
    from diefab.dice.design import load_design
    from diefab.search.calibrate import RealDie
    from diefab.search.surface import ResponseSurface, fit_settings, quadratic_features

    cube = load_design("d6")  # six values
    rng = np.random.default_rng(5)
    features = quadratic_features(np.zeros((1, 2))).shape[1]
    dice, surfaces = [], []
    for k in range(3):  # three dice with their own responses to one physics x* = (0.7, 0.3)
        coef = np.zeros((features, 6))
        coef[:, 1:] = rng.normal(scale=1.5, size=(features, 5))
        surface = ResponseSurface(coef, 400)
        counts = rng.multinomial(2_000, surface.probabilities(np.array([0.7, 0.3])))
        dice.append(RealDie(f"die{k}", cube, counts))
        surfaces.append(surface)
    x, _ = fit_settings(dice, surfaces, np.array([0.5, 0.5]), starts=[np.array([0.2, 0.8])])
    assert np.allclose(x, [0.7, 0.3], atol=0.05)
    tight, _ = fit_settings(dice, surfaces, np.array([0.5, 0.5]), sigma=1e-4)
    assert np.allclose(tight, [0.5, 0.5], atol=0.01)


def test_held_out_scores_each_die_at_the_candidate_the_other_dice_choose():
    from diefab.dice.design import load_design
    from diefab.search.calibrate import RealDie, held_out

    cube = load_design("d6")
    rng = np.random.default_rng(2)
    # Three candidates: each a distribution of the six values; die 0 was rolled from candidate 0,
    # dice 1 to 3 from candidate 2.
    truth = [np.full(6, 1 / 6), np.array([3, 1, 1, 1, 1, 3]) / 10, np.array([1, 1, 3, 3, 1, 1]) / 10]
    dice = [RealDie(f"die{k}", cube, rng.multinomial(600, truth[c])) for k, c in enumerate((0, 2, 2, 2))]

    def record(c, drops):
        sims = [rng.multinomial(drops, truth[c]) for _ in dice]
        return {"x": [c / 2], "params": {"restitution": c / 2}, "drops": drops, "feasible": True,
                "dice": [{"counts": s.tolist()} for s in sims]}  # fmt: skip

    records = [record(c, 400) for c in range(3)] + [record(2, 4000), {"x": [1.0], "feasible": False}]
    rows = held_out(records, dice)
    # die 0 is out-voted: its candidate is the others' choice, 2, and it scores far off; the others get 2 too
    assert [r["params"]["restitution"] for r in rows] == [1.0] * 4
    assert rows[0]["tvd"] > 0.2 > 0.05 > max(r["tvd"] for r in rows[1:])
    assert all(r["drops"] == 4000 for r in rows)  # scored on the chosen candidate's evaluation of most drops
    assert held_out(records, dice[:1]) is None and held_out(records[-1:], dice) is None


def test_cli_calibrate_reports_each_die_held_out(tmp_path, run):
    code, out, err = run("calibrate", "--die", "d6", "10,11,9,10,12,8", "--die", "d6", "12,9,10,10,11,8",
                         "--free", "restitution", "--method", "grid", "--grid-points", "3", "--sims-per-eval", "30",
                         "--workers", "1", "--out", tmp_path, "--json")  # fmt: skip
    assert code == 0, err
    report = json.loads(out)
    assert report["held_out_candidates"] == "grid"
    grid = {0.0, 0.45, 0.9}  # restitution's range [0, 0.9] in three points
    for die in report["dice"]:
        held = die["held_out"]
        assert held["name"] == die["name"] and 0 <= held["tvd"] <= 1 and held["params"]["restitution"] in grid
    kept = read_profile(report["profile"])[0]["calibration"]  # the profile keeps its scores
    assert kept["tvd_held_out"] == [round(d["held_out"]["tvd"], 4) for d in report["dice"]]
    assert kept["tvd_fitted"] == [round(d["tvd"], 4) for d in report["dice"]] and kept["held_out_candidates"] == "grid"


def test_predict_report_is_the_uniform_cube_and_says_when_the_model_cannot_predict(cube_die, monkeypatch):
    from diefab.core.errors import GeometryError
    from diefab.models import probabilities
    from diefab.search.likelihood import predict_report

    assert predict_report(cube_die) == {"model": "fast", "tvd": pytest.approx(0.05, abs=1e-3)}

    def refuse(design, model):
        raise GeometryError("no prediction")

    monkeypatch.setattr(probabilities, "value_probabilities", refuse)
    assert predict_report(cube_die) == {"model": "fast", "tvd": None, "error": "no prediction"}


def test_cli_calibrate_scores_what_predict_gives_beside_the_fit(tmp_path, run, capsys):
    """Each die also gets diefab predict's TVD, unfitted: a fair cube's model is uniform, so it is analytic."""
    from diefab.cli.calibrate import print_report

    args = ["calibrate", "--die", "d6", "10,11,9,10,12,8", "--die", "d6", "12,9,10,10,11,8", "--free",
            "restitution", "--method", "grid", "--grid-points", "3", "--sims-per-eval", "30", "--workers", "1",
            "--out", tmp_path]  # fmt: skip
    code, out, err = run(*args, "--json")
    assert code == 0, err
    report = json.loads(out)
    for die in report["dice"]:
        assert die["predict"]["model"] == "fast"
        assert die["predict"]["tvd"] == pytest.approx(0.05, abs=1e-3)  # |counts - 10| sums to 6 of 60 rolls
    print_report(report)  # what the same run prints without --json
    out = capsys.readouterr().out
    assert "predict" in out and "is closer to these rolls than the fitted physics" in out


def test_the_prior_is_minus_twice_its_log_density_and_is_checked():
    from diefab.dice.design import load_design
    from diefab.search.calibrate import CalibrationError, RealDie, make_spec

    die = RealDie("cube", load_design("d6"), np.array([10, 11, 9, 10, 12, 8]))
    spec = make_spec([die], free=["restitution", "friction"], prior_sd=0.25)
    x0 = np.array(spec.x0)
    assert spec.prior(x0) == 0.0
    assert spec.prior(x0 + [0.25, 0.0]) == pytest.approx(1.0) and spec.prior(x0 + [0.5, -0.25]) == pytest.approx(5.0)
    assert make_spec([die], free=["restitution"]).prior([1.0]) == 0.0  # no prior
    for bad in (0.0, -1.0, 1e-300, float("nan"), float("inf"), True):
        with pytest.raises(CalibrationError, match="prior_sd"):
            make_spec([die], free=["restitution"], prior_sd=bad)


def test_held_out_with_a_prior_needs_the_other_dice_to_earn_the_distance():
    from diefab.dice.design import load_design
    from diefab.search.calibrate import RealDie, held_out

    cube = load_design("d6")
    near, far = np.full(6, 1 / 6), np.array([2, 1, 1, 1, 1, 2]) / 8
    dice = [RealDie(f"die{k}", cube, np.round(600 * p).astype(int)) for k, p in enumerate((near, far, far))]
    records = [{"x": [x], "params": {"restitution": x}, "drops": 10_000, "feasible": True,
                "dice": [{"counts": np.round(10_000 * p).astype(int).tolist()} for _ in dice]}
               for x, p in ((0.0, near), (1.0, far))]  # fmt: skip
    free = held_out(records, dice)
    assert [r["params"]["restitution"] for r in free] == [1.0, 1.0, 1.0]
    # a prior of sd 0.01 toward x = 0 costs 10,000 at x = 1: more than the other dice's deviance can pay
    tight = held_out(records, dice, x0=[0.0], prior_sd=0.01)
    assert [r["params"]["restitution"] for r in tight] == [0.0, 0.0, 0.0]
    assert tight[0]["tvd"] < 0.01 < 0.05 < free[0]["tvd"]


def test_cli_calibrate_with_a_tight_prior_stays_at_the_start_and_keeps_it(tmp_path, run):
    args = ["calibrate", "--die", "d6", "3,30,3,3,30,3", "--free", "restitution", "--method", "grid",
            "--grid-points", "3", "--sims-per-eval", "30", "--workers", "1", "--out", tmp_path, "--json"]  # fmt: skip
    code, out, err = run(*args, "--prior", "0.001")
    assert code == 0, err
    report = json.loads(out)
    assert report["prior_sd"] == 0.001 and report["fitted"]["restitution"]["value"] == pytest.approx(0.3)
    assert read_profile(report["profile"])[0]["calibration"]["prior_sd"] == 0.001
    code, _, err = run("calibrate", "--resume", tmp_path / "calibrated", "--prior", "0.5")
    assert code == 2 and "--prior 0.5 differs from the run's 0.001" in err
