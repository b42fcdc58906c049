"""Design by simulation: resumable runs, corrupt logs, bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from diefab.cli import main
from diefab.dice.design import design_to_toml, load_design
from diefab.physics.simulate import PhysicsSettings
from diefab.search.runlog import RunLog
from diefab.search.simopt import RunError, RunSpec, noise_floor, optimize_by_simulation, start_point


def _spec(**kw) -> RunSpec:
    d = load_design("fudge-gem")
    names = ("a", "b", "c", "d", "e")
    base = dict(
        design_toml=design_to_toml(d),
        names=names,
        x0=tuple(start_point(d, names, model="design").tolist()),
        sims_per_eval=20,
        max_sims=40,
        seed=3,
        physics=PhysicsSettings().as_dict(),
    )
    base.update(kw)
    return RunSpec(**base)


@pytest.mark.parametrize(("field", "value"), [("min_margin", 10**400), ("min_margin", True), ("sigma0", 10**30)])
def test_a_stored_number_beyond_a_float_or_not_a_number_is_refused(field, value):
    from diefab.core.errors import DesignError

    with pytest.raises(DesignError, match=field):
        _spec(**{field: value})
    for whole in (0, 10**30):  # a whole number in JSON is read as the float it stands for
        margin = _spec(min_margin=whole).min_margin
        assert margin == float(whole) and isinstance(margin, float)


def _run(spec, folder, max_evaluations, history=()):
    log = RunLog(folder)
    if not history:
        log.create(spec)
    else:
        log.read()
    log.open()
    try:
        return optimize_by_simulation(
            spec, workers=1, history=history, on_evaluation=log.append, max_evaluations=max_evaluations
        )
    finally:
        log.close()


def _records(folder):
    return [json.loads(line) for line in (folder / "evaluations.jsonl").read_text().splitlines()]


@pytest.mark.parametrize("method", ["cma", "nm", pytest.param("correction", marks=pytest.mark.slow)])
def test_resume_after_a_kill_continues_the_same_trajectory(tmp_path, method):
    spec = _spec(method=method)
    if method == "correction":  # each round re-fits the fast model: two parameters keep that quick
        names = ("a", "d")
        spec = _spec(method=method, names=names, x0=tuple(start_point(load_design("fudge-gem"), names, model="design")))
    whole = _run(spec, tmp_path / "whole", 9)
    _run(spec, tmp_path / "killed", 6)
    # the kill: the 6th evaluation was being written when the process died
    log_path = tmp_path / "killed" / "evaluations.jsonl"
    raw = log_path.read_bytes()
    log_path.write_bytes(raw[:-25])
    log = RunLog(tmp_path / "killed")
    history, warning = log.read()
    assert len(history) == 5 and "line 6" in warning
    resumed = _run(log.spec(), tmp_path / "killed", 9, history)
    assert resumed.replayed == 5
    a, b = _records(tmp_path / "whole"), _records(tmp_path / "killed")
    assert len(a) == len(b) == 9
    for x, y in zip(a, b):
        assert x["x"] == y["x"] and x["drops"] == y["drops"] and x["objective"] == y["objective"]
    assert whole.best["objective"] == resumed.best["objective"]


def test_corrupt_earlier_line_is_an_error_naming_it(tmp_path):
    spec = _spec()
    _run(spec, tmp_path / "run", 3)
    path = tmp_path / "run" / "evaluations.jsonl"
    lines = path.read_text().splitlines()
    lines[1] = lines[1][:40]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RunError, match="line 2"):
        RunLog(tmp_path / "run").read()


def test_corrupt_last_complete_line_is_skipped(tmp_path):
    spec = _spec()
    _run(spec, tmp_path / "run", 3)
    path = tmp_path / "run" / "evaluations.jsonl"
    path.write_text(path.read_text() + "{not json\n")
    log = RunLog(tmp_path / "run")
    history, warning = log.read()
    assert len(history) == 3 and "line 4" in warning
    log.open()  # cuts the torn line off before appending
    log.close()
    assert len(path.read_text().splitlines()) == 3


def test_driver_stops_on_budget_and_reports_the_best():
    calls = []

    class Fake:
        k = 9  # values: sets the noise floor (k - 1) / drops

        def __call__(self, x, drops):
            calls.append(drops)
            f = float(np.sum((np.asarray(x) - 0.3) ** 2))
            return {"x": list(x), "params": {}, "drops": drops, "objective": f, "feasible": True, "min_margin": 1.0}

    result = optimize_by_simulation(_spec(sims_per_eval=100, max_sims=400), objective=Fake(), max_evaluations=200)
    assert not result.finished and result.evaluations == 200
    assert result.best["objective"] < 0.05
    assert max(calls) == 400  # more drops as it converged


@pytest.mark.parametrize("method", ["cma", "nm"])
def test_a_stop_at_any_evaluation_keeps_a_best(method):
    class Fake:
        k = 9

        def __call__(self, x, drops):
            f = float(np.sum((np.asarray(x) - 0.3) ** 2))
            return {"x": list(x), "params": {}, "drops": drops, "objective": f, "feasible": True, "min_margin": 1.0}

    spec = _spec(sims_per_eval=100, max_sims=800, method=method)
    for limit in range(1, 300):
        assert optimize_by_simulation(spec, objective=Fake(), max_evaluations=limit).best is not None


def test_defect_correction_finds_the_minimax_of_the_corrected_model():
    """A 'simulation' that is the fast model plus a fixed defect per throw: the first re-fit is the answer."""
    from diefab.models.probabilities import model_probabilities
    from diefab.search.optimize import OBJECTIVES, Problem, _polyhedron, candidate_mass, optimize_design

    d = load_design("fudge-gem")
    names = ("a", "d")  # each round re-fits the fast model: two parameters keep that quick
    m = len(d.polyhedron.names)
    rng = np.random.default_rng(1)
    defects = rng.normal(scale=0.01, size=(2, m))
    defects -= defects.mean(axis=1, keepdims=True)
    problem = Problem(d, names, "fast")
    goal = d.target_distribution.aligned(d.support)
    index = np.array([d.support.index(d.values[n]) for n in d.polyhedron.names])

    class Fake:
        k = 9

        def __call__(self, x, drops):
            params = problem.params(np.asarray(x))
            poly = _polyhedron(d, params)
            fast = model_probabilities("fast", poly, candidate_mass(d, poly), d.fill)
            rows = np.clip(fast + defects, 0, None)
            rows /= rows.sum(axis=1, keepdims=True)
            each = [float(OBJECTIVES["eq2"](np.bincount(index, weights=r, minlength=9), goal)) for r in rows]
            return {
                "x": list(x),
                "params": params,
                "drops": drops,
                "objective": max(each),
                "feasible": True,
                "min_margin": 1.0,
                "objectives": each,
                "throw_face_counts": (rows * drops).tolist(),
            }

    x0 = tuple(start_point(d, names, model="design"))
    spec = _spec(method="correction", names=names, x0=x0, sims_per_eval=100, max_sims=200, robust=({}, {}))
    result = optimize_by_simulation(spec, objective=Fake(), max_evaluations=20)
    assert result.finished  # converged at each drop count, then out of drop counts
    start = Fake()(np.array(spec.x0), 100)["objective"]
    minimax = optimize_design(d, model="fast", names=names, starts=0, correction=defects).objective
    assert result.best["objective"] < start
    assert result.best["objective"] == pytest.approx(minimax, rel=0.05)


def test_noise_floor():
    assert noise_floor("eq2", 9, 1000) == pytest.approx(0.008)
    assert noise_floor("tvd", 9, 30000) == pytest.approx(np.sqrt(8 / (2 * np.pi * 30000)), rel=0.2)


@pytest.mark.parametrize(
    "extra, text",
    [
        (["--budget", "0"], "--budget"),
        (["--budget", "-1"], "--budget"),
        (["--sims-per-eval", "0"], "--sims-per-eval"),
        (["--sims-per-eval", "-5"], "--sims-per-eval"),
        (["--resume", "/nonexistent/run"], "does not exist"),
        (["--target", "2d6"], "2d6"),
        (["--objective", "jsd"], "eq2 or tvd"),
    ],
)
def test_bad_input(tmp_path, bad, extra, text):
    err = bad("optimize", "fudge-gem", "--model", "simulation", "--out", tmp_path, *extra)
    assert text in err
    assert not any(tmp_path.iterdir())


def test_resume_from_another_design_or_corrupt_folder(tmp_path, bad):
    spec = _spec()
    _run(spec, tmp_path / "run", 2)
    err = bad("optimize", "fudge-gem-solid-angle", "--model", "simulation", "--resume", tmp_path / "run")
    assert "fudge-gem" in err
    (tmp_path / "empty").mkdir()
    err = bad("optimize", "fudge-gem", "--model", "simulation", "--resume", tmp_path / "empty")
    assert "not a diefab run folder" in err
    path = tmp_path / "run" / "evaluations.jsonl"
    path.write_text("garbage\n" + path.read_text())
    err = bad("optimize", "fudge-gem", "--model", "simulation", "--resume", tmp_path / "run")
    assert "line 1" in err


def test_cli_run_and_resume(tmp_path, capsys, bad):
    args = ["optimize", "fudge-gem", "--model", "simulation", "--start", "design", "--sims-per-eval", "20",
            "--workers", "1", "--out", str(tmp_path), "--json"]  # fmt: skip
    with pytest.raises(SystemExit) as exc:
        main([*args, "--max-evals", "3"])
    assert exc.value.code == 0
    report = json.loads(capsys.readouterr().out)
    run = tmp_path / "fudge-gem-simulation-opt"
    assert report["evaluations"] == 3 and (run / "fudge-gem-simulation-opt.toml").is_file()
    best = load_design(run / "fudge-gem-simulation-opt.toml")
    assert best.params == pytest.approx(report["params"])
    # the same folder again without --resume is refused; with it, the run continues
    bad(*args, "--max-evals", "4")
    with pytest.raises(SystemExit) as exc:
        main([*args, "--max-evals", "5", "--resume", str(run)])
    assert exc.value.code == 0
    report = json.loads(capsys.readouterr().out)
    assert report["evaluations"] == 5 and report["replayed"] == 3
    assert len(_records(run)) == 5
    # a different seed or fill cannot continue it
    err = bad(*args, "--seed", "9", "--resume", run)
    assert "--seed" in err
    assert "differs from the run's (solid" in bad(*args, "--fill", "print", "--resume", run)


def test_fast_model_through_optimize(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["optimize", "fudge-gem", "--model", "fast", "--starts", "0", "--out", str(tmp_path), "--json"])
    assert exc.value.code == 0
    report = json.loads(capsys.readouterr().out)
    assert report["min_margin"] >= 0.05 and report["objective"] < 0.1


def test_unreadable_candidates_are_infeasible_and_not_simulated():
    from diefab.search.simopt import INFEASIBLE, UNLABELABLE, SimulationObjective

    spec = _spec()
    objective = SimulationObjective(spec, workers=1)
    # stable, but resting on f1 and on f6 would both show f3 on top
    params = {"a": 1.2154, "b": 0.8882, "c": 0.9828, "d": 1.3545, "e": 1.1750}
    record = objective(objective.problem.unit(params), 1000)
    assert record["min_margin"] > 0.2
    assert record["objective"] == INFEASIBLE + UNLABELABLE and record["drops"] == 0 and not record["feasible"]


def test_cli_run_on_a_dask_cluster_matches_local_workers(tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    args = ["optimize", "fudge-gem", "--model", "simulation", "--start", "design", "--sims-per-eval", "20",
            "--max-evals", "3", "--json"]  # fmt: skip
    with pytest.raises(SystemExit) as exc:
        main([*args, "--workers", "1", "--out", str(tmp_path / "local")])
    assert exc.value.code == 0
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as lc:
        with pytest.raises(SystemExit) as exc:
            main([*args, "--scheduler", lc.scheduler_address, "--out", str(tmp_path / "dask")])
    assert exc.value.code == 0
    capsys.readouterr()
    local = _records(tmp_path / "local" / "fudge-gem-simulation-opt")
    remote = _records(tmp_path / "dask" / "fudge-gem-simulation-opt")
    assert [r["face_counts"] for r in local] == [r["face_counts"] for r in remote]
    assert [r["objective"] for r in local] == [r["objective"] for r in remote]


@pytest.mark.parametrize("start", [0.05, 0.5, 0.95])
def test_cma_with_one_free_parameter_runs_to_its_budget_and_finds_the_minimum(start):
    """One free parameter (a calibration of restitution alone) is a one-dimensional CMA-ES run."""
    from types import SimpleNamespace

    from diefab.search.simmethods import BudgetSpent, Evaluator, run_cma

    def objective(x, drops):
        return {"x": x.tolist(), "drops": drops, "feasible": True, "objective": float((x[0] - 0.3) ** 2)}

    ev = Evaluator(objective, [], lambda record: None, lambda i, drops: i >= 300)
    spec = SimpleNamespace(seed=3, sigma0=0.3, sims_per_eval=20, max_sims=40, x0=(start,))
    ev.raise_level(spec.sims_per_eval)
    with pytest.raises(BudgetSpent):
        run_cma(ev, spec, 1, lambda drops: 0.0)
    assert ev.count == 300
    assert ev.best["x"][0] == pytest.approx(0.3, abs=1e-3)
