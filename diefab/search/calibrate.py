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

The uncertainty of the fitted settings comes from the curvature of the
deviance at the optimum (a quadratic fitted by least squares to the
evaluations near it): the covariance is ``2 H⁻¹`` where ``H`` is the Hessian
of the total deviance.  It is the uncertainty due to the finite number of
real rolls; a flat direction (a setting the counts do not pin down) is
reported as such, not as a number.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from diefab.core.errors import DiefabError, PhysicsError, StatsError
from diefab.dice.design import Design
from diefab.physics.simulate import MAX_DROPS
from diefab.search.runlog import RunLog
from diefab.search.runspec import RUN_FORMAT, RunError, check_budget

__all__ = [
    "DEFAULT_FREE",
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
    "real_die",
    "realrolls_die",
    "die_report",
    "settings_at",
    "smoothed",
]

#: Pseudo-count added to each value's simulated count (Jeffreys prior).
SMOOTHING = 0.5


class CalibrationError(DiefabError, ValueError):
    """Real dice or calibration settings that cannot be used."""


@dataclass(frozen=True)
class Parameter:
    """A physics setting that calibration can fit.

    ``setting`` is the :class:`diefab.physics.simulate.PhysicsSettings` field it
    changes; for a range (``angular_velocity``, ``linear_velocity``) the
    parameter is the range's upper end.  Over the unit cube u of the search
    the parameter is ``low + (high - low) u ** power``: a power above 1
    spreads the search where small values already matter.
    """

    name: str
    setting: str
    low: float
    high: float
    unit: str
    text: str
    power: float = 1.0


PARAMETERS: dict[str, Parameter] = {
    p.name: p
    for p in (
        Parameter("restitution", "restitution", 0.0, 0.9, "", "restitution of die and ground"),
        Parameter("friction", "friction", 0.1, 1.5, "", "Coulomb friction of die and ground"),
        Parameter("rolling_friction", "rolling_friction", 0.0, 0.06, "units", "Bullet's rolling friction"),
        Parameter("spinning_friction", "spinning_friction", 0.0, 0.02, "", "Bullet's spinning friction"),
        Parameter("spin", "angular_velocity", 0.0, 40.0, "rad/s", "upper end of the initial spin range"),
        Parameter("speed", "linear_velocity", 0.0, 5.0, "units/s", "upper end of the initial horizontal speed"),
        Parameter("drop_height", "drop_height", 2.0, 10.0, "units", "drop height of the centre of mass"),
        Parameter("capture", "capture_energy", 0.0, 1.0, "m g L", "quasi-static capture energy", power=2.0),
    )
}
#: The most points a calibration's grid (``method="grid"``) may have in all.
MAX_GRID = 1024
#: Fitted unless ``free`` says otherwise.
DEFAULT_FREE = ("restitution", "friction", "rolling_friction", "spin", "drop_height")


# ----------------------------------------------------------------------
# real dice


@dataclass(frozen=True, eq=False)
class RealDie:
    """A die with real rolls.

    Parameters
    ----------
    name : str
    design : Design
        The die as made (its fill gives the mass properties).
    counts : (k,) int
        Real rolls of each value of ``design.support`` (increasing values).
    groups : tuple of tuple of int
        Indices into ``design.support`` of values the data name only up to
        relabelling (mirror-image faces); each group has two or more.
    reference : mapping str -> (k,) float
        Other predictions of the die to compare with (e.g. a source's own
        model), keyed by name.
    """

    name: str
    design: Design
    counts: np.ndarray
    groups: tuple[tuple[int, ...], ...] = ()
    reference: Mapping[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        k = len(self.design.support)
        counts = np.asarray(self.counts)
        if counts.shape != (k,):
            raise CalibrationError(
                f"die {self.name!r}: {counts.size} counts for the {k} values {self.design.support} of "
                f"{self.design.name!r}"
            )
        if not np.all(np.isfinite(counts)) or np.any(counts < 0) or np.any(counts != np.round(counts)):
            raise CalibrationError(f"die {self.name!r}: counts {counts.tolist()} must be whole numbers >= 0")
        if counts.sum() <= 0:
            raise CalibrationError(f"die {self.name!r}: no real rolls")
        object.__setattr__(self, "counts", counts.astype(np.int64))
        seen: set[int] = set()
        for g in self.groups:
            if len(g) < 2 or any(not 0 <= i < k for i in g) or seen & set(g):
                raise CalibrationError(f"die {self.name!r}: group {list(g)} must name two or more distinct values")
            seen |= set(g)
        object.__setattr__(self, "groups", tuple(tuple(int(i) for i in g) for g in self.groups))
        ref = {}
        for key, p in self.reference.items():
            p = np.asarray(p, dtype=float)
            if p.shape != (k,) or not np.all(np.isfinite(p)) or np.any(p < 0) or p.sum() <= 0:
                raise CalibrationError(f"die {self.name!r}: reference {key!r} is not a distribution over {k} values")
            ref[key] = p / p.sum()
        object.__setattr__(self, "reference", ref)

    @property
    def n(self) -> int:
        """Real rolls."""
        return int(self.counts.sum())

    @property
    def frequencies(self) -> np.ndarray:
        return self.counts / self.n

    def symmetrized(self, p: np.ndarray) -> np.ndarray:
        """`p` with each group's probabilities replaced by their mean."""
        p = np.array(p, dtype=float)
        for g in self.groups:
            p[list(g)] = p[list(g)].mean()
        return p

    def to_json(self) -> dict[str, Any]:
        from diefab.search.runid import pinned_toml

        return {
            "name": self.name,
            "design_toml": pinned_toml(self.design),
            "counts": self.counts.tolist(),
            "groups": [list(g) for g in self.groups],
            "reference": {k: v.tolist() for k, v in self.reference.items()},
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RealDie:
        from diefab.dice.design import parse_design

        design = parse_design(data["design_toml"], source=f"die {data['name']!r}")
        return cls(data["name"], design, np.array(data["counts"]), tuple(tuple(g) for g in data.get("groups", ())),
                   {k: np.array(v) for k, v in data.get("reference", {}).items()})  # fmt: skip


def real_die(name: str, design: Design, counts: Sequence[int] | str, **kwargs: Any) -> RealDie:
    """A :class:`RealDie` from counts per value or a roll-log path (see :func:`diefab.stats.goodness.read_rolls`)."""
    from pathlib import Path

    from diefab.stats.goodness import counts_from_rolls, parse_counts, read_rolls

    try:
        if isinstance(counts, str):
            path = Path(counts)
            if path.is_file():
                counts = counts_from_rolls(read_rolls(path), design.support)
            else:
                counts = parse_counts(counts)
    except StatsError as exc:
        raise CalibrationError(f"die {name!r}: {exc}") from None
    return RealDie(name, design, np.asarray(counts), **kwargs)


def realrolls_die(path) -> RealDie:
    """A :class:`RealDie` from a file of the real-rolls data (:func:`diefab.physics.realrolls.load_real_rolls`).

    Its design is the data's hull with the printed body's centre of mass and
    inertia; mirror-image outcomes become :attr:`RealDie.groups` and the
    source's own predictions its :attr:`RealDie.reference`.
    """
    from diefab.dice.design import parse_design

    try:
        from diefab.physics.realrolls import load_real_rolls
    except ImportError:
        raise CalibrationError(f"{path}: reading the real-rolls format needs diefab.physics.realrolls, which this "
                               "installation lacks") from None  # fmt: skip
    rolls = load_real_rolls(path)
    (text,) = rolls.design_files().values()
    design = parse_design(text, source=str(path))
    index = {v: i for i, v in enumerate(design.support)}
    missing = [o for o in rolls.outcomes if o not in index]
    if missing or len(index) != len(rolls.outcomes):
        raise CalibrationError(f"{path}: outcome {missing[0] if missing else '?'} has no face the die rests on")
    order = [index[o] for o in rolls.outcomes]

    def aligned(values) -> np.ndarray:
        out = np.zeros(len(index))
        out[order] = values
        return out

    groups = tuple(tuple(index[o] for o in g) for g in rolls.groups)
    reference = {k: aligned(v) for k, v in rolls.reference.items()}
    return RealDie(rolls.name, design, aligned(rolls.counts).astype(np.int64), groups, reference)


# ----------------------------------------------------------------------
# the likelihood


def smoothed(counts: np.ndarray, prior: float = SMOOTHING) -> np.ndarray:
    """Simulated counts -> probabilities with `prior` pseudo-counts per value."""
    counts = np.asarray(counts, dtype=float)
    return (counts + prior) / (counts.sum() + prior * len(counts))


def deviance(counts: np.ndarray, p: np.ndarray) -> float:
    """``G² = 2 Σ c log(c / (n p))`` of real `counts` against probabilities `p` (0 log 0 = 0).

    Examples
    --------
    >>> deviance([10, 10], [0.5, 0.5])
    0.0
    >>> round(deviance([20, 0], [0.5, 0.5]), 4)  # 2 * 20 * log 2
    27.7259
    """
    c = np.asarray(counts, dtype=float)
    p = np.asarray(p, dtype=float)
    n = c.sum()
    m = c > 0
    return float(2.0 * np.sum(c[m] * np.log(c[m] / (n * p[m]))))


def settings_at(base, names: Sequence[str], values: Sequence[float]):
    """`base` (:class:`~diefab.physics.simulate.PhysicsSettings`) with parameters `names` set to `values`."""
    changes: dict[str, Any] = {}
    for name, value in zip(names, values):
        p = PARAMETERS[name]
        value = float(value)
        if p.setting in ("angular_velocity", "linear_velocity"):
            lo = getattr(base, p.setting)[0]
            changes[p.setting] = (min(lo, value), value)
        else:
            changes[p.setting] = value
    return replace(base, **changes)


def parameter_value(settings, name: str) -> float:
    """The value of calibration parameter `name` in `settings`."""
    value = getattr(settings, PARAMETERS[name].setting)
    return float(value[1] if isinstance(value, tuple) else value)


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
    settings that are not fitted.
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
    """Deviance per real roll of the dice's counts under a candidate's simulated frequencies.

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
        return {
            **record,
            "drops": int(drops),  # per die: the driver compares like with like by this count
            "objective": total / self.rolls,
            "deviance": total,
            "feasible": True,
            "dice": dice,
            "seconds": sum(d["seconds"] for d in dice),
        }


def simulate_die(die: RealDie, settings, drops: int, seed: int, workers=None, scheduler=None) -> dict[str, Any]:
    """Drop `die` `drops` times under `settings`: its simulated value counts and its fit to the real counts."""
    from diefab.physics.simulate import simulate

    result = simulate(die.design, drops, seed=seed, workers=workers, settings=settings, scheduler=scheduler)
    counts = result.value_counts(die.design)
    p = die.symmetrized(smoothed(counts))
    return {
        "name": die.name,
        "counts": counts.tolist(),
        "cocked": result.cocked,
        "unsettled": result.unsettled,
        "deviance": deviance(die.counts, p),
        "seconds": result.seconds,
    }


def die_report(die: RealDie, sim_counts: Sequence[int]) -> dict[str, Any]:
    """How well simulated value counts predict `die`'s real rolls.

    ``tvd`` compares the real frequencies with the simulated ones
    (symmetrized within :attr:`RealDie.groups`); ``noise_tvd`` is the TVD that
    sampling alone gives at the die's number of rolls
    (:func:`diefab.stats.goodness.expected_tvd_exact`); ``p_value`` is the chi-squared
    tail of the deviance with k - 1 degrees of freedom (the simulation's own
    noise and the fit are not counted).
    """
    from scipy.stats import chi2

    from diefab.stats.goodness import expected_tvd_exact, tvd

    counts = np.asarray(sim_counts, dtype=float)
    p = die.symmetrized(counts / max(counts.sum(), 1))
    ps = die.symmetrized(smoothed(counts))
    g2 = deviance(die.counts, ps)
    df = len(die.counts) - 1
    return {
        "name": die.name,
        "rolls": die.n,
        "real": die.frequencies.tolist(),
        "simulated": p.tolist(),
        "tvd": tvd(die.frequencies, p),
        "noise_tvd": expected_tvd_exact(die.frequencies, die.n),
        "deviance": g2,
        "df": df,
        "p_value": float(chi2.sf(g2, df)),
    }


# ----------------------------------------------------------------------
# uncertainty


def curvature(
    records: Sequence[Mapping[str, Any]], spec: CalibrationSpec, best: Mapping[str, Any]
) -> dict[str, dict[str, float | None]]:
    """Standard errors of the fitted parameters from the curvature of the deviance at `best`.

    A quadratic in the parameters is fitted by least squares to the total
    deviance of the feasible evaluations at `best`'s drop count nearest to
    it (at least three per coefficient); the covariance is ``2 H⁻¹``.
    Returns ``{name: {"value", "se"}}``; ``se`` is None for a parameter
    that leans on a direction along which the fitted deviance is flat or
    curved downwards (a standard error there would exceed the searched
    range: the counts do not determine it), and for every parameter when
    too few evaluations are near.
    """
    names = spec.names
    d = len(names)
    value = dict(best["params"])
    out: dict[str, dict[str, float | None]] = {n: {"value": float(value[n]), "se": None} for n in names}
    pts = [r for r in records if r.get("feasible") and r.get("drops") == best["drops"] and "deviance" in r]
    ncoef = (d + 1) * (d + 2) // 2
    if len(pts) < ncoef + 2:
        return out
    x0 = np.array(best["x"])
    xs = np.array([r["x"] for r in pts])
    order = np.argsort(np.linalg.norm(xs - x0, axis=1))[: max(3 * ncoef, 20)]
    xs = xs[order] - x0
    ys = np.array([pts[i]["deviance"] for i in order])
    iu = np.triu_indices(d)
    quad = np.einsum("ni,nj->nij", xs, xs)[:, iu[0], iu[1]]
    design = np.hstack([np.ones((len(xs), 1)), xs, quad])
    coef, *_ = np.linalg.lstsq(design, ys, rcond=None)
    h = np.zeros((d, d))
    h[iu] = coef[1 + d :]
    h = h + h.T  # the diagonal's coefficient is h_ii / 2, an off-diagonal's is h_ij
    w, v = np.linalg.eigh(h)
    # a direction whose standard error would exceed the whole searched range is not determined
    good = w > 2.0
    for i, n in enumerate(names):
        if np.all(np.abs(v[i, ~good]) < 0.1):
            se = float(np.sqrt(2.0 * np.sum(v[i, good] ** 2 / w[good])))
            # unit cube -> parameter units: half the image of x ± se (the slope, where the map is linear)
            hi, lo = x0.copy(), x0.copy()
            hi[i], lo[i] = min(x0[i] + se, 1.0), max(x0[i] - se, 0.0)
            span = (spec.values(hi)[i] - spec.values(lo)[i]) / (hi[i] - lo[i]) if hi[i] > lo[i] else 0.0
            out[n]["se"] = float(se * span)
    return out


def grid_interval(records: Sequence[Mapping[str, Any]], spec: CalibrationSpec, best: Mapping[str, Any],
                  rise: float = 1.0) -> dict[str, tuple[float, float]] | None:  # fmt: skip
    """Each parameter's range over the grid points whose deviance is within `rise` of `best`'s.

    Each point counts with its deviance at the most drops it was dropped
    with (a point the halving dropped early keeps its early, noisier value).
    With ``rise=1`` it is the grid's picture of the one-sigma
    likelihood-ratio interval (ΔG² = 1 for one parameter); its ends are grid
    points, so it is no finer than the grid.  None when fewer than three
    points were evaluated.
    """
    latest: dict[tuple, tuple[int, float, np.ndarray]] = {}
    for r in records:
        if r.get("feasible") and "deviance" in r:
            key = tuple(np.round(r["x"], 9))
            if key not in latest or r["drops"] >= latest[key][0]:
                latest[key] = (r["drops"], r["deviance"], spec.values(r["x"]))
    if len(latest) < 3:
        return None
    near = np.array([v for _n, dev, v in latest.values() if dev <= best["deviance"] + rise])
    return {n: (float(near[:, i].min()), float(near[:, i].max())) for i, n in enumerate(spec.names)}


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
