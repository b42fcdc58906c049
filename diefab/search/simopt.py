"""Design by simulation: fit a family's parameters to pybullet drop frequencies.

The paper's final die came from minimizing Eq. (2) with simulated
frequencies (1000 drops per evaluation).  This module does that with the
noise under control:

* **Common random numbers.**  Every candidate is dropped with the same seed,
  so drop *i* starts from the same pose and spin for every design
  (:func:`diefab.physics.simulate.simulate`); the objective becomes a fixed function
  of the parameters at each drop count, and the difference between two
  nearby candidates is not drowned in sampling noise.
* **A method for rough objectives.**  CMA-ES (pycma) in the unit cube of the
  free parameters (default), or Nelder--Mead restarted from the best point
  (``method="nm"``); ``benchmarks/bench_simopt.py`` compares the two.  For
  one or two calibration parameters with a switch-like effect, a grid
  narrowed by successive halving (``method="grid"``, :func:`~diefab.search.simmethods.run_grid`).  Or,
  with far fewer simulations, defect correction (``method="correction"``):
  the fast model, corrected per throw by the simulated minus modelled face
  probabilities of the dice dropped so far, minimized between rounds of
  drops (:func:`~diefab.search.simmethods.run_correction`); the way to minimize the worst of several
  throws (``robust``) in reasonable time.
* **More drops as it converges.**  When a generation's objective spread
  falls to the noise floor of the current drop count (``(k - 1) / n`` for
  Eq. (2), the expected TVD under the target for TVD) the drops per
  evaluation double, up to `max_sims`; the incumbent is re-evaluated at the
  new count so that "best" always compares like with like.
* **Constraints.**  Parameters stay in the family's box; a candidate whose
  smallest stability margin is below `min_margin` scores ``1 + violation``
  and is not simulated at all, nor is one that cannot be labelled (two
  resting faces that would show the same face on top).

Runs lose nothing: every evaluation is handed to `on_evaluation` as it
finishes (the CLI appends it to ``evaluations.jsonl`` with fsync, see
:class:`~diefab.search.runlog.RunLog`), and a resumed run replays the logged evaluations through
the same deterministic optimizer, so it continues exactly the trajectory an
uninterrupted run would have taken, losing at most the evaluation in flight.

The run's description is :mod:`diefab.search.runspec`, its objective
:mod:`diefab.search.simobjective`, its methods :mod:`diefab.search.simmethods`;
their public names are importable from here too.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.design import Design
from diefab.search.optimize import INFEASIBLE, Problem
from diefab.search.runspec import METHODS, RUN_FORMAT, RunError, RunSpec, check_budget, is_finite_number
from diefab.search.simmethods import BudgetSpent, Evaluator, run_cma, run_correction, run_grid, run_nm
from diefab.search.simobjective import UNLABELABLE, SimulationObjective, noise_floor

__all__ = [
    "INFEASIBLE",
    "METHODS",
    "RUN_FORMAT",
    "UNLABELABLE",
    "RunError",
    "RunSpec",
    "SimulationObjective",
    "SimulationResult",
    "best_design",
    "check_budget",
    "is_finite_number",
    "noise_floor",
    "optimize_by_simulation",
    "start_point",
]


@dataclass
class SimulationResult:
    """Where a run stands: the best evaluation at the highest drop count, and totals."""

    best: dict[str, Any] | None
    evaluations: int
    drops: int
    replayed: int
    finished: bool


def optimize_by_simulation(
    spec: RunSpec,
    *,
    workers: int | None = None,
    scheduler=None,
    history: Sequence[dict[str, Any]] = (),
    on_evaluation: Callable[[dict[str, Any]], None] = lambda record: None,
    on_best: Callable[[dict[str, Any]], None] = lambda record: None,
    budget_seconds: float | None = None,
    max_evaluations: int | None = None,
    objective: Callable[[np.ndarray, int], dict[str, Any]] | None = None,
) -> SimulationResult:
    """Minimize the simulated objective of `spec` until the budget is spent.

    Parameters
    ----------
    spec : RunSpec
    workers, scheduler
        Passed to :func:`diefab.physics.simulate.simulate`.
    history : sequence of dict
        Records of an interrupted run (from :meth:`~diefab.search.runlog.RunLog.read`); they are
        replayed, not simulated again.
    on_evaluation : callable(record)
        Called with each new evaluation's record as soon as it finishes.
    on_best : callable(record)
        Called whenever the incumbent improves (also during the replay).
    budget_seconds : float, optional
        Wall time for the whole run, counting the history's ``elapsed``; an
        evaluation that would end past it (at the latest evaluation's
        seconds per drop) is not started.
    max_evaluations : int, optional
        Stop after this many evaluations in all (history included).
    objective : callable(x, drops) -> record, optional
        Replaces the pybullet objective (for tests of the driver).

    Returns
    -------
    SimulationResult
        ``finished`` is False when the budget or evaluation limit stopped it.
    """
    if budget_seconds is not None and not budget_seconds > 0:
        raise DesignError(f"budget={budget_seconds} seconds must be > 0")
    if max_evaluations is not None and max_evaluations < 0:
        raise DesignError(f"max_evaluations={max_evaluations} must be >= 0")
    objective = objective or SimulationObjective(spec, workers=workers, scheduler=scheduler)
    elapsed0 = float(history[-1].get("elapsed", 0.0)) if history else 0.0
    started = time.monotonic()

    rate = [0.0]  # seconds per drop of the latest simulated evaluation

    def should_stop(i: int, drops: int) -> bool:
        if max_evaluations is not None and i >= max_evaluations:
            return True
        if budget_seconds is None:
            return False
        # an evaluation that would end past the budget is not started
        return elapsed0 + time.monotonic() - started + rate[0] * drops >= budget_seconds

    def record_evaluation(record: dict[str, Any]) -> None:
        record["elapsed"] = elapsed0 + time.monotonic() - started
        if record.get("drops") and record.get("seconds"):
            rate[0] = record["seconds"] / record["drops"]
        on_evaluation(record)

    ev = Evaluator(objective, history, record_evaluation, should_stop)
    ev.on_best = on_best
    k = len(spec.names)
    floor = (lambda n: noise_floor(spec.objective, objective.k, n)) if hasattr(objective, "k") else (lambda n: 0.0)
    finished = True
    try:
        ev.raise_level(spec.sims_per_eval)
        ev(np.array(spec.x0), spec.sims_per_eval, "start")
        if spec.method == "cma":
            run_cma(ev, spec, k, floor)
        elif spec.method == "nm":
            run_nm(ev, spec, k, floor)
        elif spec.method == "grid":
            run_grid(ev, spec, k)
        else:
            run_correction(ev, spec)
    except BudgetSpent:
        finished = False
    return SimulationResult(ev.best, ev.count, ev.total_drops, min(len(history), ev.count), finished)


def start_point(
    design: Design,
    names: Sequence[str],
    *,
    model: str = "fast",
    objective: str = "eq2",
    min_margin: float = 0.05,
    starts: int = 3,
    seed: int = 0,
) -> np.ndarray:
    """Unit-cube starting point: the optimum of a deterministic model, or the design itself.

    `model` ``design`` starts from the design's own parameters, and so does
    any model whose optimum cannot be labelled (two resting faces showing
    the same top face): the simulation run would reject it.
    """
    from diefab.dice.families import family
    from diefab.search.optimize import optimize_design

    problem = Problem(design, tuple(names), "solid-angle", objective, min_margin)
    params = family(design.family).complete(design.params)
    if model != "design":
        result = optimize_design(
            design, model=model, objective=objective, names=names, min_margin=min_margin, starts=starts, seed=seed
        )
        try:
            result.design.label_of  # noqa: B018
            params = result.design.params
        except DesignError:  # the model's optimum cannot be labelled: start from the design itself
            pass
    return np.clip(problem.unit(params), 0.0, 1.0)


def best_design(spec: RunSpec, record: dict[str, Any], name: str) -> Design:
    """The evaluated design of `record`, named `name`, described by its objective."""
    d = spec.design
    return replace(
        d,
        name=name,
        params=record["params"],
        description=(
            f"{d.name} optimized by simulation for {d.target}: {spec.objective} = {record['objective']:.4g} "
            f"at {record['drops']} drops (seed {spec.seed}), min margin {record['min_margin']:.3f}"
        ),
    )
