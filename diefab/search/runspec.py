"""The description of a simulation run: everything that fixes its trajectory, stored as ``run.json``.

A run of :func:`diefab.search.simopt.optimize_by_simulation` is a function of
its :class:`RunSpec` alone, so a run folder (:mod:`diefab.search.runlog`)
can be resumed and continue exactly where it stopped.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from diefab.core.errors import DesignError, DiefabError
from diefab.dice.design import Design
from diefab.physics.simulate import MAX_DROPS

__all__ = ["METHODS", "RUN_FORMAT", "RunError", "RunSpec", "check_budget", "is_finite_number"]

METHODS = ("cma", "nm", "correction")
#: Version of the run format; a resumed run must match it.
RUN_FORMAT = 1


class RunError(DiefabError, ValueError):
    """A run folder that cannot be resumed (missing, corrupt, another design or settings)."""


def is_finite_number(value: Any) -> bool:
    """A finite JSON number that a float holds."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    return abs(value) < 1e300 if isinstance(value, int) else math.isfinite(value)


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
        if not (is_finite_number(self.min_margin) and self.min_margin >= 0):
            bad(f"min_margin={self.min_margin!r} must be a non-negative number")
        if not (is_finite_number(self.sigma0) and 0 < self.sigma0 <= 0.5):
            bad(f"sigma0={self.sigma0!r} must be in (0, 0.5]")
        object.__setattr__(self, "min_margin", float(self.min_margin))  # a whole number in JSON is a float here
        object.__setattr__(self, "sigma0", float(self.sigma0))
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
