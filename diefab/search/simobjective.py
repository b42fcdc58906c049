"""The objective of a simulation run: Eq. (2) or TVD of a candidate's simulated frequencies to its target.

Every candidate is dropped with the run's seed (common random numbers), so
the objective is a fixed function of the parameters at each drop count.
Candidates outside the constraints (stability margin, a centre of mass they
cannot hold, faces that cannot be labelled) score above
:data:`~diefab.search.optimize.INFEASIBLE` and are not simulated.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from diefab.core.errors import DesignError
from diefab.geometry.polyhedron import face_margins
from diefab.search.optimize import INFEASIBLE, INVALID, OBJECTIVES, Problem, _outside, _polyhedron, candidate_mass
from diefab.search.runspec import RunSpec
from diefab.stats.goodness import expected_tvd

__all__ = ["UNLABELABLE", "SimulationObjective", "noise_floor"]

#: Extra score of a stable candidate whose values cannot all be read on a top face.
UNLABELABLE = 0.05


def noise_floor(objective: str, k: int, n: int) -> float:
    """Expected objective of a perfect die estimated from `n` drops over `k` values.

    Eq. (2) times n is asymptotically chi-squared with k - 1 degrees of
    freedom, so its mean is ``(k - 1) / n``; for TVD it is
    :func:`diefab.stats.goodness.expected_tvd`.
    """
    if objective == "tvd":
        return expected_tvd(k, n)
    return (k - 1) / n


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
