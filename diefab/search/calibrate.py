"""Calibration: fit the physics settings to dice with real rolls.

Simulation is only as good as its throw: restitution, friction, the spin and
speed of the throw and the drop height all move a die's distribution by more
than the sampling noise of a few hundred real rolls.  This module fits those
settings to the real counts of one or more dice (:class:`RealDie`) by
maximizing the simulated likelihood of the counts:

* each die's value probabilities under a candidate setting are its simulated
  frequencies, smoothed by half a count per value (a Jeffreys prior), so that
  a value that was rolled but never simulated costs a finite amount;
* the objective is the deviance ``G² = 2 Σ c log(c / (n p))`` summed over the
  dice, divided by the number of real rolls (the deviance per roll; its
  minimum is the maximum of the likelihood);
* every candidate drops every die with the same seed (common random numbers):
  drop *i* starts from the same pose and the same uniform draws, scaled to
  the candidate's ranges, so the objective is a fixed function of the
  settings at each drop count and nearby candidates compare without
  sampling noise between them;
* the optimizer is :mod:`diefab.search.simopt`'s (CMA-ES or Nelder-Mead restarts in
  the unit cube of the free settings, more drops as it converges, the
  resumable run log), so a run loses nothing and a resumed run continues
  the trajectory an uninterrupted one would have taken.

Outcomes that the data name only up to relabelling (mirror-image faces whose
physical labels were not recorded, :attr:`RealDie.groups`) are compared with
the simulated probabilities averaged within the group, so the labelling
does not matter.

With two or more dice, :func:`held_out` scores each die at the candidate
the *other* dice fit best (leave one die out): what the fitted physics is
worth on a die it never saw, beside the in-sample fit.

The uncertainty of the fitted settings comes from the curvature of the
deviance at the optimum (a quadratic fitted by least squares to the
evaluations near it): the covariance is ``2 H⁻¹`` where ``H`` is the Hessian
of the total deviance.  It is the uncertainty due to the finite number of
real rolls; a flat direction (a setting the counts do not pin down) is
reported as such, not as a number.

The pieces live in modules of their own, and their names are importable
from here too: :mod:`diefab.search.realdie` (the dice),
:mod:`diefab.search.parameters` (what can be fitted),
:mod:`diefab.search.likelihood` (the deviance) and
:mod:`diefab.search.uncertainty` (the curvature and the grid interval).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from diefab.core.errors import DiefabError, PhysicsError
from diefab.physics.simulate import MAX_DROPS
from diefab.search.likelihood import SMOOTHING, deviance, die_report, simulate_die, smoothed
from diefab.search.parameters import DEFAULT_FREE, MAX_GRID, PARAMETERS, Parameter, parameter_value, settings_at
from diefab.search.realdie import CalibrationError, RealDie, real_die, realrolls_die
from diefab.search.runlog import RunLog
from diefab.search.runspec import RUN_FORMAT, RunError, check_budget
from diefab.search.uncertainty import curvature, grid_interval

__all__ = [
    "DEFAULT_FREE",
    "MAX_GRID",
    "MIN_PRIOR_SD",
    "SMOOTHING",
    "PARAMETERS",
    "CalibrationError",
    "CalibrationLog",
    "CalibrationObjective",
    "CalibrationSpec",
    "Parameter",
    "RealDie",
    "calibrate",
    "curvature",
    "deviance",
    "grid_interval",
    "held_out",
    "parameter_value",
    "real_die",
    "realrolls_die",
    "die_report",
    "settings_at",
    "simulate_die",
    "smoothed",
]


#: Tightest prior a calibration takes (in the unit cube): tighter holds the start and fits nothing.
MIN_PRIOR_SD = 1e-6


# ----------------------------------------------------------------------
# run description


@dataclass(frozen=True)
class CalibrationSpec:
    """Everything that determines a calibration run (stored as ``run.json``).

    The fields the optimizer reads (`names`, `x0`, `seed`, `sims_per_eval`,
    `max_sims`, `method`, `sigma0`) mean what they mean in
    :class:`diefab.search.simopt.RunSpec`; `method` may also be ``"grid"``:
    `grid_points` evenly spaced points per parameter in the unit cube,
    narrowed by successive halving (:func:`diefab.search.simmethods.run_grid`).
    `bounds` maps the unit cube to the settings and `physics` holds the
    settings that are not fitted.  `prior_sd` (None: no prior) adds a
    normal prior toward the start `x0` in the unit cube, with this standard
    deviation in each coordinate: the objective becomes the deviance plus
    ``sum(((x - x0) / prior_sd)**2)`` (minus twice the log prior), so a
    setting must earn its distance from the start on the counts.
    """

    dice: tuple[dict[str, Any], ...]
    names: tuple[str, ...]
    bounds: tuple[tuple[float, float], ...]
    x0: tuple[float, ...]
    seed: int = 0
    sims_per_eval: int = 1000
    max_sims: int = 8000
    method: str = "cma"
    sigma0: float = 0.2
    grid_points: int = 11
    physics: dict[str, Any] = field(default_factory=dict)
    objective: str = "deviance"
    format: int = RUN_FORMAT
    budget_minutes: float | None = None
    max_evaluations: int | None = None
    prior_sd: float | None = None

    def __post_init__(self) -> None:
        def bad(msg: str) -> None:
            raise CalibrationError(msg)

        if not self.dice:
            bad("calibration needs at least one die with real rolls")
        names = [d["name"] for d in self.dice]
        if len(set(names)) != len(names):
            bad(f"two dice are called {next(n for n in names if names.count(n) > 1)!r}: give them different names")
        if not self.names:
            bad("no physics parameter is free")
        unknown = [n for n in self.names if n not in PARAMETERS]
        if unknown:
            bad(f"{unknown[0]!r} is not a calibration parameter (parameters: {', '.join(PARAMETERS)})")
        if len(set(self.names)) != len(self.names):
            bad(f"parameters {list(self.names)} name one twice")
        if len(self.bounds) != len(self.names) or len(self.x0) != len(self.names):
            bad(f"bounds and x0 must have one entry per parameter {list(self.names)}")
        for name, (lo, hi) in zip(self.names, self.bounds):
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                bad(f"bounds of {name} [{lo}, {hi}] must be finite with low < high")
        for name, (lo, hi) in zip(self.names, self.bounds):
            for end in (lo, hi):  # each setting is monotonic in its parameter: the ends decide
                try:
                    settings_at(self.base, [name], [end])
                except PhysicsError as exc:
                    bad(f"bounds of {name} [{lo:g}, {hi:g}] reach beyond what the physics takes: {exc}")
        for name in ("seed", "sims_per_eval", "max_sims"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                bad(f"{name}={value!r} must be an integer")
        if self.seed < 0:
            bad(f"seed={self.seed} must be >= 0")
        if not 1 <= self.sims_per_eval <= self.max_sims:
            bad(f"drops per evaluation {self.sims_per_eval} must be >= 1 and <= max {self.max_sims}")
        for key, value in (("drops per evaluation", self.sims_per_eval), ("most drops per evaluation", self.max_sims)):
            if value > MAX_DROPS:
                bad(f"{key} {value} must be at most {MAX_DROPS:,}")
        if self.method not in ("cma", "nm", "grid"):
            bad(f"method={self.method!r} must be cma, nm or grid")
        if isinstance(self.grid_points, bool) or not isinstance(self.grid_points, (int, np.integer)):
            bad(f"grid_points={self.grid_points!r} must be an integer")
        if self.method == "grid" and not (2 <= self.grid_points and self.grid_points ** len(self.names) <= MAX_GRID):
            bad(f"a grid of {self.grid_points} points per parameter over {len(self.names)} parameters must have "
                f"2 points or more and {MAX_GRID} in all at most")  # fmt: skip
        if not (math.isfinite(self.sigma0) and 0 < self.sigma0 <= 0.5):
            bad(f"sigma0={self.sigma0} must be in (0, 0.5]")
        if self.prior_sd is not None and not (
            isinstance(self.prior_sd, (int, float)) and not isinstance(self.prior_sd, bool)
            and math.isfinite(self.prior_sd) and self.prior_sd >= MIN_PRIOR_SD
        ):  # fmt: skip
            bad(f"prior_sd={self.prior_sd!r} must be a number >= {MIN_PRIOR_SD:g} (the prior's standard deviation)")
        check_budget(self, bad)

    @property
    def real_dice(self) -> list[RealDie]:
        return [RealDie.from_json(d) for d in self.dice]

    @property
    def base(self):
        from diefab.physics.simulate import PhysicsSettings

        return PhysicsSettings.from_mapping(self.physics)

    @property
    def powers(self) -> np.ndarray:
        """(d,) float: each parameter's :attr:`Parameter.power` (unit cube -> values)."""
        return np.array([PARAMETERS[n].power for n in self.names], dtype=float)

    def values(self, x: Sequence[float]) -> np.ndarray:
        """Unit-cube point -> parameter values."""
        lo, hi = np.array(self.bounds).T
        return lo + np.clip(np.asarray(x, dtype=float), 0.0, 1.0) ** self.powers * (hi - lo)

    def unit(self, values: Sequence[float]) -> np.ndarray:
        lo, hi = np.array(self.bounds).T
        u = (np.asarray(values, dtype=float) - lo) / (hi - lo)
        return np.sign(u) * np.abs(u) ** (1.0 / self.powers)

    def settings(self, x: Sequence[float]):
        return settings_at(self.base, self.names, self.values(x))

    def prior(self, x: Sequence[float]) -> float:
        """Minus twice the log prior at unit-cube point `x`, up to a constant (0 without a prior)."""
        from diefab.search.crossval import prior_cost

        return float(prior_cost(x, self.x0, math.inf if self.prior_sd is None else self.prior_sd))

    def to_json(self) -> str:
        data = asdict(self)
        data["dice"], data["names"] = list(self.dice), list(self.names)
        data["bounds"], data["x0"] = [list(b) for b in self.bounds], list(self.x0)
        return json.dumps(data, indent=2) + "\n"

    @classmethod
    def from_json(cls, text: str, source: str = "run.json") -> CalibrationSpec:
        try:
            data = json.loads(text)
            if not isinstance(data, dict) or data.get("objective") != "deviance":
                optimize = isinstance(data, dict) and "objective" in data
                raise ValueError("it is an optimize run (continue it with diefab optimize --resume)" if optimize
                                 else "it describes no calibration")  # fmt: skip
            data["dice"], data["names"] = tuple(data["dice"]), tuple(data["names"])
            data["bounds"] = tuple((float(lo), float(hi)) for lo, hi in data["bounds"])
            data["x0"] = tuple(float(v) for v in data["x0"])
            return cls(**data)
        except (ValueError, KeyError, TypeError, AttributeError, IndexError, RecursionError) as exc:
            raise RunError(f"{source} is not a diefab calibration run: {exc}") from None


class CalibrationLog(RunLog):
    """A calibration run folder: ``run.json`` (:class:`CalibrationSpec`) and ``evaluations.jsonl``."""

    FEASIBLE = ("deviance",)

    def spec(self) -> CalibrationSpec:
        text = self.spec_text()
        spec = CalibrationSpec.from_json(text, str(self.spec_path))
        try:
            spec.real_dice  # noqa: B018 -- every die's design must load before anything runs
        except (DiefabError, ValueError, KeyError, TypeError, AttributeError) as exc:
            raise RunError(f"{self.spec_path} is not a diefab calibration run: {exc}") from None
        self.check_identity(text)
        return spec

    def read(self) -> tuple[list[dict[str, Any]], str | None]:
        """The logged records (see :meth:`RunLog.read`); a simulated record must hold counts for every die."""
        records, warning = super().read()
        sizes = [len(d["counts"]) for d in self.spec().dice]
        for number, record in enumerate(records, start=1):
            dice = record.get("dice") if record["feasible"] else []
            ok = isinstance(dice, list) and (not record["feasible"] or len(dice) == len(sizes))
            ok = ok and all(isinstance(d, dict) and _is_counts(d.get("counts"), k, record["drops"])
                            for d, k in zip(dice, sizes))  # fmt: skip
            if not ok:
                raise RunError(f"{self.path} line {number} is corrupt (not the counts of this run's dice); the run "
                               "cannot be resumed")  # fmt: skip
        return records, warning


def _is_counts(value: Any, k: int, drops: int) -> bool:
    """True when `value` is a list of `k` whole numbers >= 0 (JSON) that add up to at most `drops`."""
    return (isinstance(value, list) and len(value) == k
            and all(isinstance(c, int) and not isinstance(c, bool) and c >= 0 for c in value)
            and sum(value) <= drops)  # fmt: skip


def make_spec(
    dice: Sequence[RealDie],
    *,
    free: Sequence[str] = DEFAULT_FREE,
    base=None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    **options: Any,
) -> CalibrationSpec:
    """A :class:`CalibrationSpec` starting from `base` settings (default: the paper's).

    The drop height's lower bound is raised so that every die starts above
    the ground; the start is `base`'s own values, clipped into the bounds.
    """
    from diefab.physics.simulate import PhysicsSettings, _body

    base = base or PhysicsSettings()
    bounds = dict(bounds or {})
    unknown = [n for n in list(free) + list(bounds) if n not in PARAMETERS]
    if unknown:
        raise CalibrationError(f"{unknown[0]!r} is not a calibration parameter (parameters: {', '.join(PARAMETERS)})")
    fixed = [n for n in bounds if n not in free]
    if fixed:
        raise CalibrationError(f"bounds given for {fixed[0]!r}, which is not fitted (free: {', '.join(free)})")
    box = []
    for name in free:
        lo, hi = bounds.get(name, (PARAMETERS[name].low, PARAMETERS[name].high))
        if name == "drop_height" and dice:
            lowest = max(_body(d.design).radius for d in dice) + base.height_jitter + 0.05
            lo = max(lo, lowest)
            if hi <= lo:
                raise CalibrationError(f"drop_height bounds must reach above {lowest:.3f} (the dice's radius + jitter)")
        box.append((float(lo), float(hi)))
    spec = CalibrationSpec(dice=tuple(d.to_json() for d in dice), names=tuple(free), bounds=tuple(box),
                           x0=(0.0,) * len(box), physics=base.as_dict(), **options)  # fmt: skip
    start = [parameter_value(base, n) for n in free]
    x0 = np.clip(spec.unit(start), 0.0, 1.0) if box else np.zeros(0)
    return replace(spec, x0=tuple(float(v) for v in x0))


# ----------------------------------------------------------------------
# the objective


class CalibrationObjective:
    """Deviance per real roll of the dice's counts under a candidate's simulated frequencies (plus the prior).

    Parameters
    ----------
    spec : CalibrationSpec
    workers, scheduler
        Passed to :func:`diefab.physics.simulate.simulate`.
    """

    def __init__(self, spec: CalibrationSpec, *, workers: int | None = None, scheduler=None) -> None:
        self.spec = spec
        self.dice = spec.real_dice
        self.workers, self.scheduler = workers, scheduler
        self.rolls = sum(d.n for d in self.dice)

    def __call__(self, x: np.ndarray, drops: int) -> dict[str, Any]:
        """Evaluate unit-cube point `x` with `drops` drops of every die; a JSON-ready record."""
        from diefab.core.errors import PhysicsError

        x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
        values = self.spec.values(x)
        record: dict[str, Any] = {"x": x.tolist(), "params": dict(zip(self.spec.names, values.tolist())), "drops": 0}
        try:
            settings = settings_at(self.spec.base, self.spec.names, values)
        except PhysicsError as exc:  # a combination the engine cannot take
            return {**record, "objective": 1e6, "feasible": False, "error": str(exc)}
        dice = [simulate_die(d, settings, int(drops), self.spec.seed, self.workers, self.scheduler) for d in self.dice]
        total = sum(d["deviance"] for d in dice)
        prior = self.spec.prior(x)
        return {
            **record,
            "drops": int(drops),  # per die: the driver compares like with like by this count
            "objective": (total + prior) / self.rolls,
            "deviance": total,
            **({"prior": prior} if self.spec.prior_sd is not None else {}),
            "feasible": True,
            "dice": dice,
            "seconds": sum(d["seconds"] for d in dice),
        }


# ----------------------------------------------------------------------
# the driver


def calibrate(spec: CalibrationSpec, **kwargs: Any):
    """Minimize the deviance per roll of `spec`'s dice over its free physics settings.

    Takes the keyword arguments of :func:`diefab.search.simopt.optimize_by_simulation`
    (workers, scheduler, history, on_evaluation, on_best, budget_seconds,
    max_evaluations, objective) and returns its
    :class:`diefab.search.simopt.SimulationResult`.
    """
    from diefab.search.simopt import optimize_by_simulation

    if kwargs.get("objective") is None:
        kwargs["objective"] = CalibrationObjective(spec, workers=kwargs.get("workers"),
                                                   scheduler=kwargs.get("scheduler"))  # fmt: skip
    return optimize_by_simulation(spec, **kwargs)


def held_out(records: Sequence[Mapping[str, Any]], dice: Sequence[RealDie], *, x0: Sequence[float] | None = None,
             prior_sd: float | None = None) -> list[dict[str, Any]] | None:  # fmt: skip
    """Each die scored at the evaluated candidate of least deviance of the other dice: leave one die out.

    With `prior_sd`, the choice adds the run's prior toward `x0` (the unit-cube
    start), as the fit itself does.

    The candidates are the run's feasible evaluations at its first drop
    count, the count every candidate was first simulated at: every point of
    a grid, whose choice no die took part in, and the points CMA-ES or
    Nelder-Mead proposed, whose path every die steered (there a die is held
    out of the choice among those points, not of their proposal).

    Returns
    -------
    list of dict or None
        Per die, :func:`die_report` of its own simulated counts at the
        candidate chosen without it (its evaluation of most drops,
        ``drops``), with that candidate's ``params``; None with fewer than
        two dice or no feasible evaluation.
    """
    from diefab.search.crossval import deviance_table, pick_candidate

    feasible = [r for r in records if r.get("feasible")]
    if len(dice) < 2 or not feasible:
        return None
    drops = min(r["drops"] for r in feasible)
    candidates = [r for r in feasible if r["drops"] == drops]
    dev = deviance_table(dice, [[smoothed(np.asarray(r["dice"][k]["counts"])) for r in candidates]
                                for k in range(len(dice))])  # fmt: skip
    coords = np.array([r["x"] for r in candidates], dtype=float)
    start = np.zeros(coords.shape[1]) if x0 is None else np.asarray(x0, dtype=float)
    sd = math.inf if prior_sd is None else prior_sd
    rows = []
    for k, die in enumerate(dice):
        chosen = candidates[pick_candidate(dev, [i for i in range(len(dice)) if i != k], coords, start, sd)]
        scored = max((r for r in feasible if r["x"] == chosen["x"]), key=lambda r: r["drops"])  # its most drops
        rows.append({**die_report(die, scored["dice"][k]["counts"]), "params": dict(chosen["params"]),
                     "drops": scored["drops"]})  # fmt: skip
    return rows
