"""The methods of a simulation run: CMA-ES, Nelder--Mead, a halving grid and defect correction.

Each method asks an :class:`Evaluator` for objective values; the evaluator
replays a resumed run's logged evaluations before simulating new ones, keeps
the incumbent at the current drop count, and raises :class:`BudgetSpent`
when the run's budget is spent.  The methods are deterministic given the
run's seed, so a replayed run follows the trajectory it was on.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from diefab.core.errors import DesignError
from diefab.search.optimize import INFEASIBLE, Problem, _polyhedron, candidate_mass
from diefab.search.runspec import RunError, RunSpec

__all__ = ["BudgetSpent", "Evaluator", "run_cma", "run_correction", "run_grid", "run_nm"]


class BudgetSpent(Exception):
    """The budget is spent (raised out of the optimizer)."""


class Evaluator:
    """Evaluates points, replaying the logged history first, and keeps the incumbent."""

    def __init__(self, objective, history, on_evaluation, should_stop) -> None:
        self.objective = objective
        self.history = list(history)
        self.on_evaluation = on_evaluation
        self.should_stop = should_stop
        self.count = 0
        self.total_drops = 0
        self.level = 0  # drops per evaluation of the incumbent's comparisons
        self.best: dict[str, Any] | None = None
        self.last: dict[str, Any] | None = None  # the latest evaluation (replayed or new)

    def __call__(self, x: np.ndarray, drops: int, kind: str) -> float:
        x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
        i = self.count
        if i < len(self.history):
            record = self.history[i]
            if record.get("kind") != kind or len(record["x"]) != len(x) or not np.allclose(record["x"], x, rtol=0,
                                                                                             atol=1e-9) or (
                record["feasible"] and record["drops"] != drops
            ):  # fmt: skip
                raise RunError(
                    f"evaluations.jsonl line {i + 1} does not continue this run's trajectory "
                    "(the run's settings or diefab's version changed)"
                )
        else:
            if self.should_stop(i, drops):
                raise BudgetSpent
            record = {"i": i, "kind": kind, **self.objective(x, drops)}
            self.on_evaluation(record)
        self.count += 1
        self.last = record
        self.total_drops += record["drops"]
        if record["feasible"] and record["drops"] == self.level:
            if self.best is None or record["objective"] < self.best["objective"]:
                self.best = record
                self.on_best(record)
        return float(record["objective"])

    def on_best(self, record: dict[str, Any]) -> None:  # replaced by the driver
        pass

    def raise_level(self, drops: int) -> None:
        """Compare at `drops` from now on: re-evaluate the incumbent there."""
        if drops == self.level:
            return
        level, old = self.level, self.best
        self.level, self.best = drops, None
        if old is not None:
            try:
                self(np.array(old["x"]), drops, "reeval")
            except BudgetSpent:  # out of budget: the incumbent stays the best at the old level
                self.level, self.best = level, old
                raise


def _next_level(drops: int, spec: RunSpec) -> int:
    return min(2 * drops, spec.max_sims)


def run_cma(ev: Evaluator, spec: RunSpec, k: int, floor) -> None:
    import cma

    rng = np.random.default_rng([spec.seed, 6])
    sigma = spec.sigma0
    drops = spec.sims_per_eval
    x = np.array(spec.x0)
    for _restart in range(8):
        es = cma.CMAEvolutionStrategy(
            x.tolist(),
            sigma,
            {
                "bounds": [0.0, 1.0],
                "randn": lambda *shape: rng.standard_normal(shape),
                "seed": np.nan,
                "verbose": -9,
                "verb_log": 0,
                "verb_disp": 0,
                "tolfun": 0.0,
                "tolflatfitness": 10,
                "tolx": 1e-4,
                # pycma 4 bounds each coordinate's step by a third of its range, and in one dimension
                # (one free parameter) it fails when it applies that bound: no bound there
                **({"maxstd": np.inf} if k == 1 else {}),
            },
        )
        while not es.stop():
            xs = es.ask()
            fs = [ev(xi, drops, "cma") for xi in xs]
            es.tell(xs, fs)
            feasible = sorted(f for f in fs if f < INFEASIBLE)
            if len(feasible) >= 2 and np.median(feasible) - feasible[0] < floor(drops) and drops < spec.max_sims:
                drops = _next_level(drops, spec)
                ev.raise_level(drops)
        # converged at this level: restart around the incumbent, smaller and with more drops
        x = np.array(ev.best["x"]) if ev.best is not None else x
        sigma = max(sigma / 2, 0.005)
        drops = _next_level(drops, spec)
        ev.raise_level(drops)


def run_nm(ev: Evaluator, spec: RunSpec, k: int, floor) -> None:
    from scipy.optimize import minimize

    size = spec.sigma0
    drops = spec.sims_per_eval
    for _restart in range(12):
        x = np.array(ev.best["x"]) if ev.best is not None else np.array(spec.x0)
        steps = np.where(x + size <= 1.0, size, -size)
        simplex = np.vstack([x, x + np.diag(steps)])
        minimize(
            lambda y, n=drops: ev(y, n, "nm"),
            x,
            method="Nelder-Mead",
            bounds=[(0.0, 1.0)] * k,
            options={"initial_simplex": simplex, "maxfev": 25 * k, "xatol": 1e-4, "fatol": 0.0},
        )
        drops = _next_level(drops, spec)
        ev.raise_level(drops)
        size = max(size / 2, 0.005)


def run_grid(ev: Evaluator, spec, k: int) -> None:
    """A grid of ``spec.grid_points`` per parameter, then successive halving.

    Every grid point is evaluated at the first drop count; then, level by
    level, the better half (at least three; ties: the earlier point, nearer
    the grid's low corner) is evaluated again at double the drops, until
    the drops reach ``spec.max_sims``.  Made for one or two parameters whose
    effect is too sharp for a smooth search (a switch between regimes): it
    never interpolates, and with common random numbers the halving compares
    every survivor on the same drops.
    """
    axis = np.linspace(0.0, 1.0, spec.grid_points)
    alive = np.array(np.meshgrid(*([axis] * k), indexing="ij")).reshape(k, -1).T
    drops = spec.sims_per_eval
    while True:
        done = {tuple(np.round(ev.last["x"], 9)): ev.last} if ev.last["drops"] == drops else {}
        scores = []
        for x in alive:
            key = tuple(np.round(x, 9))
            scores.append(done[key]["objective"] if key in done else ev(x, drops, "grid"))
        if drops >= spec.max_sims:
            return
        alive = alive[np.argsort(scores, kind="stable")[: max(3, (len(alive) + 1) // 2)]]
        drops = _next_level(drops, spec)
        ev.raise_level(drops)


def _face_frequencies(record: dict[str, Any]) -> np.ndarray:
    """(t, m) simulated face frequencies of an evaluation, one row per throw (one row without ``robust``)."""
    counts = np.array(record.get("throw_face_counts") or [record["face_counts"]], dtype=float)
    return counts / np.maximum(counts.sum(axis=1, keepdims=True), 1.0)


def run_correction(ev: Evaluator, spec: RunSpec, tolerance: float = 1e-3, rounds_per_level: int = 12) -> None:
    """Defect correction: the fast model, corrected per throw by the simulations so far, minimized in between.

    Each round drops the current die (under every throw of ``spec.robust``,
    or under ``spec.physics``) and takes its simulated minus fast-model face
    probabilities as each throw's correction.  The corrections of all rounds
    so far, weighted by their drops, are pooled (the defect varies slowly
    with the shape, and pooling averages the simulation noise out instead
    of chasing it), and the parameters are re-fitted from the current die to
    minimize the worst corrected objective.  Every round uses the run's seed
    (common random numbers), so the rounds' simulated objectives compare
    without sampling noise between them; the incumbent is the best of them.
    When a re-fit no longer moves the die, returns to a die already dropped
    at this drop count, or `rounds_per_level` rounds have passed, the drops
    double (up to ``spec.max_sims``; the incumbent is dropped again and
    its counts join the pool) and the re-fits continue from the incumbent.
    """
    from diefab.models.probabilities import model_probabilities
    from diefab.search.optimize import optimize_design

    design = spec.design
    problem = Problem(design, spec.names, "fast", spec.objective, spec.min_margin)
    drops = spec.sims_per_eval
    pool = {"sums": 0.0, "weight": 0.0}

    def absorb(record: dict[str, Any]) -> None:
        if record["feasible"] and record["drops"]:
            poly = _polyhedron(design, record["params"])
            fast = model_probabilities("fast", poly, candidate_mass(design, poly), design.fill)
            pool["sums"] = pool["sums"] + (_face_frequencies(record) - fast) * record["drops"]
            pool["weight"] += record["drops"]

    absorb(ev.last)
    seen = [np.array(ev.last["x"])]
    while ev.best is not None and pool["weight"] > 0:
        here = ev.last if ev.last["feasible"] else ev.best
        try:
            fit = optimize_design(replace(design, params=here["params"]), model="fast", objective=spec.objective,
                                  names=spec.names, min_margin=spec.min_margin, starts=0, seed=spec.seed,
                                  correction=pool["sums"] / pool["weight"])  # fmt: skip
        except DesignError:
            return
        x = np.clip(problem.unit(fit.design.params), 0.0, 1.0)
        if min(float(np.abs(x - y).max()) for y in seen) < tolerance or len(seen) >= rounds_per_level:
            if drops >= spec.max_sims:
                return
            drops = _next_level(drops, spec)
            ev.raise_level(drops)  # drops the incumbent again
            absorb(ev.last)
            seen = [np.array(ev.last["x"])]
            continue
        ev(x, drops, "correction")
        absorb(ev.last)
        seen.append(x)
