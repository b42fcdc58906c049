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
  narrowed by successive halving (``method="grid"``, :func:`_run_grid`).  Or,
  with far fewer simulations, defect correction (``method="correction"``):
  the fast model, corrected per throw by the simulated minus modelled face
  probabilities of the dice dropped so far, minimized between rounds of
  drops (:func:`_run_correction`); the way to minimize the worst of several
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
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from diefab.core.errors import DesignError, DiefabError
from diefab.dice.design import Design
from diefab.geometry.polyhedron import face_margins
from diefab.physics.simulate import MAX_DROPS
from diefab.search.optimize import INFEASIBLE, INVALID, OBJECTIVES, Problem, _outside, _polyhedron, candidate_mass
from diefab.stats.goodness import expected_tvd

__all__ = [
    "METHODS",
    "RunError",
    "RunSpec",
    "SimulationObjective",
    "SimulationResult",
    "noise_floor",
    "optimize_by_simulation",
    "start_point",
]

METHODS = ("cma", "nm", "correction")
#: Version of the run format; a resumed run must match it.
RUN_FORMAT = 1
#: Extra score of a stable candidate whose values cannot all be read on a top face.
UNLABELABLE = 0.05


class RunError(DiefabError, ValueError):
    """A run folder that cannot be resumed (missing, corrupt, another design or settings)."""


def noise_floor(objective: str, k: int, n: int) -> float:
    """Expected objective of a perfect die estimated from `n` drops over `k` values.

    Eq. (2) times n is asymptotically chi-squared with k - 1 degrees of
    freedom, so its mean is ``(k - 1) / n``; for TVD it is
    :func:`diefab.stats.goodness.expected_tvd`.
    """
    if objective == "tvd":
        return expected_tvd(k, n)
    return (k - 1) / n


def is_finite_number(value: Any) -> bool:
    """A finite JSON number that a float holds."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    return abs(value) < 1e300 if isinstance(value, int) else math.isfinite(value)


# ----------------------------------------------------------------------
# run settings


def check_budget(spec, bad: Callable[[str], None]) -> None:
    """Call ``bad(message)`` if `spec`'s ``budget_minutes`` or ``max_evaluations`` (None: none) is not valid."""
    budget, most = spec.budget_minutes, spec.max_evaluations
    if budget is not None and (isinstance(budget, bool) or not isinstance(budget, (int, float))
                               or not (math.isfinite(budget) and budget > 0)):  # fmt: skip
        bad(f"budget_minutes={budget!r} must be a positive number")
    if most is not None and (isinstance(most, bool) or not isinstance(most, int) or most <= 0):
        bad(f"max_evaluations={most!r} must be a positive integer")


@dataclass(frozen=True)
class RunSpec:
    """Everything that determines a run's trajectory (stored as ``run.json``).

    Parameters
    ----------
    design_toml : str
        The starting design as a template TOML (its own parameters are not
        the start: `x0` is).
    names : tuple of str
        Free parameters, in the order of `x0`.
    x0 : tuple of float
        Starting point in the unit cube of the free parameters.
    objective : str
        ``eq2`` or ``tvd``.
    min_margin : float
        Smallest stability margin of every face, model units.
    seed : int
        Physics seed: the common random numbers of every evaluation.
    sims_per_eval, max_sims : int
        Drops per evaluation at the start and at most.
    method : str
        ``cma``, ``nm`` or ``correction`` (see the module docstring).
    sigma0 : float
        Initial step size in the unit cube.
    physics : dict
        :meth:`diefab.physics.simulate.PhysicsSettings.as_dict` of the simulation.
    start : str
        How `x0` was found (``fast``, ``solid-angle`` or ``design``).
    labels : bool
        Require a readable die: every resting face must put a different face
        on top (:attr:`diefab.dice.design.Design.label_of`); a candidate that
        fails scores ``1 + UNLABELABLE`` and is not simulated.
    robust : tuple of dict
        Physics settings (as `physics`) of several throws and tables: when
        given, every candidate is dropped under each (same seed) and scores
        the worst of their objectives; `physics` is then not used.
    budget_minutes : float, optional
        Wall-time budget of the whole run (not of the trajectory: a resumed
        run continues with it unless given a new one).
    max_evaluations : int, optional
        Stop after this many evaluations in all.
    """

    design_toml: str
    names: tuple[str, ...]
    x0: tuple[float, ...]
    objective: str = "eq2"
    min_margin: float = 0.05
    seed: int = 0
    sims_per_eval: int = 2000
    max_sims: int = 16000
    method: str = "cma"
    sigma0: float = 0.1
    physics: dict[str, Any] = field(default_factory=dict)
    start: str = "fast"
    labels: bool = True
    robust: tuple[dict[str, Any], ...] = ()
    format: int = RUN_FORMAT
    budget_minutes: float | None = None
    max_evaluations: int | None = None

    def __post_init__(self) -> None:
        def bad(msg: str) -> None:
            raise DesignError(msg)

        kinds = {"design_toml": str, "start": str, "labels": bool, "physics": dict}
        for name, kind in kinds.items():
            if not isinstance(getattr(self, name), kind):
                bad(f"{name}={getattr(self, name)!r} must be a {kind.__name__}")
        if not all(isinstance(n, str) for n in self.names) or not all(map(is_finite_number, self.x0)):
            bad(f"names {self.names!r} must be strings and x0 {self.x0!r} finite numbers")
        if not all(isinstance(t, dict) for t in self.robust):
            bad(f"robust={self.robust!r} must be a list of physics tables")
        if self.objective not in ("eq2", "tvd"):
            bad(f"objective={self.objective!r} must be eq2 or tvd for a simulation run")
        if self.method not in METHODS:
            bad(f"method={self.method!r} must be one of {', '.join(METHODS)}")
        for name in ("sims_per_eval", "max_sims", "seed"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                bad(f"{name}={value!r} must be an integer")
        if self.sims_per_eval <= 0:
            bad(f"sims_per_eval={self.sims_per_eval} must be > 0")
        if self.max_sims < self.sims_per_eval:
            bad(f"max_sims={self.max_sims} must be >= sims_per_eval={self.sims_per_eval}")
        if self.max_sims > MAX_DROPS:
            bad(f"most drops per evaluation {self.max_sims} must be at most {MAX_DROPS:,}")
        if self.seed < 0:
            bad(f"seed={self.seed} must be >= 0")
        if not (math.isfinite(self.min_margin) and self.min_margin >= 0):
            bad(f"min_margin={self.min_margin} must be a non-negative number")
        if not (math.isfinite(self.sigma0) and 0 < self.sigma0 <= 0.5):
            bad(f"sigma0={self.sigma0} must be in (0, 0.5]")
        check_budget(self, bad)
        if len(self.x0) != len(self.names) or not self.names:
            bad(f"x0 has {len(self.x0)} coordinates for parameters {self.names}")

    @property
    def design(self) -> Design:
        from diefab.dice.design import parse_design

        return parse_design(self.design_toml, source="run.json")

    def to_json(self) -> str:
        data = asdict(self)
        data["names"], data["x0"] = list(self.names), list(self.x0)
        data["robust"] = list(self.robust)
        return json.dumps(data, indent=2) + "\n"

    @classmethod
    def from_json(cls, text: str, source: str = "run.json") -> RunSpec:
        try:
            data = json.loads(text)
            if isinstance(data, dict) and data.get("objective") == "deviance":
                raise ValueError("it is a calibration run (continue it with diefab calibrate --resume)")
            data["names"], data["x0"] = tuple(data["names"]), tuple(float(v) for v in data["x0"])
            data["robust"] = tuple(data.get("robust", ()))
            return cls(**data)
        except (ValueError, KeyError, TypeError, AttributeError, IndexError, RecursionError) as exc:
            raise RunError(f"{source} is not a diefab run description: {exc}") from None


# ----------------------------------------------------------------------
# the objective


class SimulationObjective:
    """Eq. (2) or TVD of a candidate's simulated value frequencies to the target.

    Parameters
    ----------
    spec : RunSpec
    workers : int, optional
        Worker processes of :func:`diefab.physics.simulate.simulate`.
    scheduler : str or distributed.Client, optional
        Dask cluster to run the drops on.
    """

    def __init__(self, spec: RunSpec, *, workers: int | None = None, scheduler=None) -> None:
        from diefab.physics.simulate import PhysicsSettings

        self.spec = spec
        self.design = spec.design
        self.problem = Problem(self.design, spec.names, "solid-angle", spec.objective, spec.min_margin)
        self.settings = PhysicsSettings.from_mapping(spec.physics)
        self.robust = [PhysicsSettings.from_mapping(p) for p in spec.robust]
        self.workers, self.scheduler = workers, scheduler
        self._target = self.design.target_distribution.aligned(self.design.support)

    @property
    def k(self) -> int:
        """Number of values."""
        return len(self.design.support)

    def __call__(self, x: np.ndarray, drops: int) -> dict[str, Any]:
        """Evaluate the unit-cube point `x` with `drops` drops; a JSON-ready record."""
        from diefab.physics.simulate import simulate

        x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
        params = self.problem.params(x)
        record: dict[str, Any] = {"x": x.tolist(), "params": params, "drops": 0}
        try:
            poly = _polyhedron(self.design, params)
        except DesignError:
            return {**record, "objective": INVALID, "feasible": False, "min_margin": None}
        center = candidate_mass(self.design, poly).center
        if _outside(poly, center) >= 0:  # a stated centre of mass the candidate no longer holds
            return {**record, "objective": INFEASIBLE + 1 + _outside(poly, center), "feasible": False}
        margins = face_margins(poly, center)
        margin = float(margins[self.design.resting_mask()].min())
        record["min_margin"] = margin
        violation = self.problem.violation(margins)
        if violation >= 0:
            return {**record, "objective": INFEASIBLE + violation, "feasible": False}
        candidate = replace(self.design, params=params)
        if self.spec.labels:
            try:
                candidate.label_of  # noqa: B018 -- raises if two resting faces would show the same top face
            except DesignError:
                return {**record, "objective": INFEASIBLE + UNLABELABLE, "feasible": False, "labelable": False}
        rows = []
        for settings in self.robust or [self.settings]:
            result = simulate(
                candidate, int(drops), seed=self.spec.seed, workers=self.workers, settings=settings,
                scheduler=self.scheduler,
            )  # fmt: skip
            counts = result.value_counts(candidate)
            q = counts / max(counts.sum(), 1)
            rows.append((float(OBJECTIVES[self.spec.objective](q, self._target)), result))
        objective, result = max(rows, key=lambda row: row[0])  # the worst throw and table
        record = {
            **record,
            "drops": int(drops),
            "objective": objective,
            "feasible": True,
            "face_counts": result.face_counts.tolist(),
            "cocked": result.cocked,
            "unsettled": result.unsettled,
            "seconds": sum(r.seconds for _, r in rows),
        }
        if self.robust:
            record["objectives"] = [o for o, _ in rows]
            record["throw_face_counts"] = [r.face_counts.tolist() for _, r in rows]
        return record


# ----------------------------------------------------------------------
# the driver


class _Stop(Exception):
    """The budget is spent (raised out of the optimizer)."""


@dataclass
class SimulationResult:
    """Where a run stands: the best evaluation at the highest drop count, and totals."""

    best: dict[str, Any] | None
    evaluations: int
    drops: int
    replayed: int
    finished: bool


class _Evaluator:
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
                raise _Stop
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
            except _Stop:  # out of budget: the incumbent stays the best at the old level
                self.level, self.best = level, old
                raise


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

    ev = _Evaluator(objective, history, record_evaluation, should_stop)
    ev.on_best = on_best
    k = len(spec.names)
    floor = (lambda n: noise_floor(spec.objective, objective.k, n)) if hasattr(objective, "k") else (lambda n: 0.0)
    finished = True
    try:
        ev.raise_level(spec.sims_per_eval)
        ev(np.array(spec.x0), spec.sims_per_eval, "start")
        if spec.method == "cma":
            _run_cma(ev, spec, k, floor)
        elif spec.method == "nm":
            _run_nm(ev, spec, k, floor)
        elif spec.method == "grid":
            _run_grid(ev, spec, k)
        else:
            _run_correction(ev, spec)
    except _Stop:
        finished = False
    return SimulationResult(ev.best, ev.count, ev.total_drops, min(len(history), ev.count), finished)


def _next_level(drops: int, spec: RunSpec) -> int:
    return min(2 * drops, spec.max_sims)


def _run_cma(ev: _Evaluator, spec: RunSpec, k: int, floor) -> None:
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


def _run_nm(ev: _Evaluator, spec: RunSpec, k: int, floor) -> None:
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


def _run_grid(ev: _Evaluator, spec, k: int) -> None:
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


def _run_correction(ev: _Evaluator, spec: RunSpec, tolerance: float = 1e-3, rounds_per_level: int = 12) -> None:
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
