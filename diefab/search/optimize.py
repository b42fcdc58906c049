"""Fit a family's parameters to a target distribution (the paper's Section 2).

The objective is the paper's Eq. (2), ``sum (q - p)^2 / p`` over values, for
a deterministic landing model (``solid-angle``, or any model in
:data:`diefab.models.probabilities.MODELS`).  Nelder--Mead runs from seeded random starts
in the parameter box; the stability constraint is an extreme barrier: a point
whose smallest face margin is below `min_margin` scores ``1 + violation``,
far above any feasible objective, so the simplex is pushed back inside
without the optimum being dragged onto the boundary.  A stable point that
cannot be read (:mod:`diefab.dice.readings`: nothing clearly on top, or two
values printed in one place) scores ``1 + UNREADABLE``.

Examples
--------
>>> from diefab.dice.design import load_design
>>> result = optimize_design(load_design("fudge-gem"), starts=4, seed=1)
>>> bool(result.objective < 0.02 and result.margins.min() >= 0.05)
True
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.design import Design
from diefab.dice.families import family
from diefab.dice.readings import KINDS, unreadable
from diefab.geometry.polyhedron import Polyhedron, face_margins
from diefab.made.mass import MassProperties, mass_properties, stated
from diefab.models.probabilities import MODELS, model_probabilities
from diefab.stats.goodness import jsd, pearson_divergence, tvd

__all__ = ["OBJECTIVES", "OptimizationResult", "Problem", "optimize_design"]

OBJECTIVES: dict[str, Callable[[np.ndarray, np.ndarray], float]] = {
    "eq2": pearson_divergence,
    "tvd": tvd,
    "jsd": lambda q, p: jsd(p, q),
}

#: Score of a point that violates the stability constraint (plus the violation).
INFEASIBLE = 1.0
#: Added to the score of a stable point that cannot be read (see :mod:`diefab.dice.readings`).
UNREADABLE = 0.5
#: Score of a point that is not a valid polyhedron at all.
INVALID = 1e6
#: Fresh-simplex restarts from the best point found.
POLISH_RESTARTS = 5


def _corrected(probs: np.ndarray, correction: np.ndarray | None) -> list[np.ndarray]:
    """`probs` with each row of `correction` added, clipped at 0 and renormalized (`probs` itself without one)."""
    if correction is None:
        return [probs]
    rows = np.clip(probs + np.atleast_2d(correction), 0.0, None)
    return list(rows / rows.sum(axis=1, keepdims=True))


@dataclass(frozen=True, eq=False)
class Problem:
    """A design's free parameters mapped to the unit cube, and its evaluation.

    Parameters
    ----------
    design : Design
        Supplies the family, fixed parameters, values, target and fill.
    names : sequence of str
        Parameters to optimize (the family's required ones by default).
    model : str
        Landing model name in :data:`diefab.models.probabilities.MODELS`.
    objective : str
        ``eq2`` (the paper's Eq. (2)), ``tvd`` or ``jsd``.
    min_margin : float
        Smallest acceptable stability margin of every face, model units.
    correction : (m,) or (t, m) float, optional
        Added to the model's face probabilities (then clipped at 0 and
        renormalized): simulated minus modelled frequencies at a nearby
        design, so that the model is corrected where the simulation was run.
        With one row per throw (physics settings), the objective is the
        worst over the rows and the values are those of the worst row.
    read_by : tuple of str
        The reading conventions a resting face may use
        (:data:`diefab.dice.readings.KINDS`; e.g. ``("face", "vertex")``: no value
        read from an edge).
    """

    design: Design
    names: tuple[str, ...]
    model: str = "solid-angle"
    objective: str = "eq2"
    min_margin: float = 0.05
    correction: np.ndarray | None = None
    read_by: tuple[str, ...] = KINDS

    def __post_init__(self) -> None:
        if self.model not in MODELS:
            raise DesignError(f"model {self.model!r} is not deterministic (models: {', '.join(MODELS)})")
        if self.objective not in OBJECTIVES:
            raise DesignError(f"unknown objective {self.objective!r} (objectives: {', '.join(OBJECTIVES)})")
        if not np.isfinite(self.min_margin) or self.min_margin < 0:
            raise DesignError(f"min_margin={self.min_margin} must be a non-negative number")
        if not self.names:
            raise DesignError(f"family {self.design.family!r} has no parameters to optimize")
        if not self.read_by or set(self.read_by) - set(KINDS):
            raise DesignError(f"read_by={list(self.read_by)} must be some of {', '.join(KINDS)}")

    @cached_property
    def bounds(self) -> np.ndarray:
        return family(self.design.family).bounds(list(self.names))

    def params(self, x: np.ndarray) -> dict[str, float]:
        """Unit-cube point -> parameter mapping (fixed parameters included)."""
        lo, hi = self.bounds.T
        free = np.clip(lo + np.clip(x, 0, 1) * (hi - lo), lo, hi)  # rounding must not step past a bound
        return {**self.design.params, **{n: float(v) for n, v in zip(self.names, free)}}

    def unit(self, params: dict[str, float]) -> np.ndarray:
        lo, hi = self.bounds.T
        return (np.array([params[n] for n in self.names]) - lo) / (hi - lo)

    def evaluate(self, params: dict[str, float]) -> tuple[float, np.ndarray, np.ndarray]:
        """Objective, value probabilities and face margins at `params`.

        The objective carries the barrier: ``INFEASIBLE + violation`` below
        the minimum margin, ``INVALID`` for a non-convex point.
        """
        design = self.design
        try:
            poly = _polyhedron(design, params)
        except DesignError:
            return INVALID, np.full(len(design.support), np.nan), np.full(len(design.values), -np.inf)
        body = candidate_mass(design, poly, tabs=self._tabs)
        margins = face_margins(poly, body.center)
        if _outside(poly, body.center) >= 0:  # a stated centre of mass the candidate no longer holds
            return INFEASIBLE + 1 + _outside(poly, body.center), np.full(len(design.support), np.nan), margins
        probs = model_probabilities(self.model, poly, body, design.fill)
        score, values = -np.inf, None
        for corrected in _corrected(probs, self.correction):
            v = np.bincount(self._value_index, weights=np.where(self._resting, corrected, 0.0),
                            minlength=len(design.support))  # fmt: skip
            s = OBJECTIVES[self.objective](v, self._target)
            if s > score:
                score, values = s, v
        violation = self.violation(margins)
        if violation >= 0:
            score = INFEASIBLE + violation
        elif not self._readable(poly):
            score = INFEASIBLE + UNREADABLE
        return score, values, margins

    def violation(self, margins: np.ndarray) -> float:
        """How far a die with these face margins is from feasible (< 0: feasible).

        Every face with a value must hold the die by more than `min_margin`;
        every transitional face must tip it off by more than `min_margin`.
        """
        mask = self._resting
        need = self.min_margin - margins[mask].min()
        if not mask.all():
            need = max(need, self.min_margin + margins[~mask].max())
        return float(need)

    @cached_property
    def _resting(self) -> np.ndarray:
        return self.design.resting_mask()

    def _readable(self, poly: Polyhedron) -> bool:
        """True if every resting face can be read (:mod:`diefab.dice.readings`; hand-set labels excepted)."""
        return unreadable(poly, self.design.values, tuple(self.design.labels), self.read_by) is None

    @cached_property
    def _tabs(self):
        """A paper die's glue tabs: those of the start design's net, carried to every candidate."""
        fill = self.design.fill
        if fill.kind != "paper" or not fill.tabs:
            return None
        from diefab.made.bodies import tab_shapes

        return tab_shapes(self.design.polyhedron, self.design.mm_per_unit, fill.tab_mm)

    @cached_property
    def _value_index(self) -> np.ndarray:
        """(m,) int: each face's value index; transitional faces (probability 0) count for the first."""
        index = {v: i for i, v in enumerate(self.design.support)}
        return np.array(
            [index[self.design.values.get(n, self.design.support[0])] for n in self.design.polyhedron.names]
        )

    @cached_property
    def _target(self) -> np.ndarray:
        return self.design.target_distribution.aligned(self.design.support)


def candidate_mass(design: Design, poly: Polyhedron, *, tabs=None) -> MassProperties:
    """Mass properties of `poly`, a candidate shape of `design`, in the design's fill.

    A centre of mass and inertia the design states (a weighted die, an
    insert) replace the fill's, as in :meth:`Design.mass_properties`: a
    candidate changes the shape around them, not them.
    """
    props = mass_properties(poly, design.fill, mm_per_unit=design.mm_per_unit, tabs=tabs)
    if design.center_of_mass is None and design.inertia is None:
        return props
    center = None if design.center_of_mass is None else np.array(design.center_of_mass) * design._file_scale
    return stated(props, center, stated_inertia(design))


def stated_inertia(design: Design) -> np.ndarray | None:
    """(3, 3) float: the design's stated inertia per unit mass in model units, or None."""
    return None if design.inertia is None else np.array(design.inertia) * design._file_scale**2


def _outside(poly: Polyhedron, center: np.ndarray) -> float:
    """How far `center` lies outside `poly` (model units; <= 0 inside)."""
    return float(np.max(poly.normals @ center - poly.offsets))


def _polyhedron(design: Design, params: dict[str, float]) -> Polyhedron:
    fam = family(design.family)
    if fam.build is not None:
        return fam.polyhedron(params)
    return replace(design, params=params).polyhedron


class _OutOfTime(Exception):
    """The optimizer's deadline passed."""


@dataclass(frozen=True, eq=False)
class OptimizationResult:
    """The best design found and how it was found."""

    design: Design
    objective: float
    values: np.ndarray
    margins: np.ndarray
    evaluations: int
    starts: int
    feasible_starts: int

    @property
    def binding_face(self) -> str:
        """The face with a value with the smallest stability margin."""
        return self.design.polyhedron.names[int(np.argmin(np.where(self.design.resting_mask(), self.margins, np.inf)))]

    @property
    def min_margin(self) -> float:
        """The smallest stability margin of a face with a value."""
        return float(self.margins[self.design.resting_mask()].min())


def optimize_design(
    design: Design,
    *,
    model: str = "solid-angle",
    objective: str = "eq2",
    names: Sequence[str] | None = None,
    min_margin: float = 0.05,
    starts: int = 6,
    seed: int = 0,
    name: str | None = None,
    max_evaluations: int = 4000,
    correction: np.ndarray | None = None,
    deadline: float | None = None,
    read_by: Sequence[str] = KINDS,
) -> OptimizationResult:
    """Multi-start Nelder--Mead over the family's parameters.

    Parameters
    ----------
    design : Design
        Starting design: family, values, target, fill; its own parameters are
        one of the starts.
    model, objective, min_margin, correction, read_by
        See :class:`Problem`.
    names : sequence of str, optional
        Parameters to optimize; default the family's free ones for this die
        (:meth:`~diefab.dice.families.Family.free_names`: for the gem a, b, c, d
        and the paper's suggested fifth, e; pass ``("a", "b", "c", "d")`` for
        the paper's four-parameter gem with e = a b).
    starts : int
        Random starting points, drawn with ``numpy.random.default_rng(seed)``
        uniformly in the box, in addition to the design itself.
    max_evaluations : int
        Limit per start.
    deadline : float, optional
        A :func:`time.monotonic` time: the search stops there with the best
        point seen so far.

    Returns
    -------
    OptimizationResult
        Its design is named `name` (default ``<design>-<model>-opt``).

    Raises
    ------
    DesignError
        If no start reaches a stable design.
    """
    from scipy.optimize import minimize

    if starts < 0:
        raise DesignError(f"starts={starts} must be >= 0")
    fam = family(design.family)
    if names is None:
        names = fam.free_names(design.params)
    problem = Problem(design, tuple(names), model, objective, min_margin, correction, tuple(read_by))
    rng = np.random.default_rng(seed)
    x0s = [problem.unit(fam.complete(design.params)), *rng.random((starts, len(names)))]
    evaluations = 0
    best_x, best_f, feasible = None, np.inf, 0
    seen = {"x": None, "f": np.inf}

    def score(x: np.ndarray) -> float:
        if deadline is not None and time.monotonic() > deadline:
            raise _OutOfTime
        f = problem.evaluate(problem.params(x))[0]
        if f < seen["f"]:
            seen["x"], seen["f"] = np.clip(x, 0, 1), f
        return f

    def simplex(x0: np.ndarray):
        return minimize(
            score,
            np.clip(x0, 0, 1),
            method="Nelder-Mead",
            bounds=[(0, 1)] * len(names),
            options={"xatol": 1e-5, "fatol": 1e-8, "maxfev": max_evaluations, "adaptive": len(names) > 4},
        )

    try:
        for x0 in x0s:
            seen["f"] = np.inf
            res = simplex(x0)
            evaluations += res.nfev
            feasible += res.fun < INFEASIBLE
            if res.fun < best_f:
                best_x, best_f = res.x, float(res.fun)
        # A simplex that has collapsed against the stability barrier often stops
        # short; restarting it from the best point with a fresh simplex is the
        # standard remedy.
        for _ in range(POLISH_RESTARTS):
            if best_x is None:
                break
            res = simplex(best_x)
            evaluations += res.nfev
            if not res.fun < best_f - 1e-12:
                break
            best_x, best_f = res.x, float(res.fun)
    except _OutOfTime:  # keep the best point seen, in the interrupted simplex too
        if seen["f"] < best_f:
            best_x, best_f = seen["x"], float(seen["f"])
    if best_x is None or best_f >= INFEASIBLE:
        raise DesignError(
            f"no stable design found from {len(x0s)} starts with min_margin={min_margin:g}: "
            "lower --min-margin or change the target"
        )
    params = problem.params(best_x)
    f, values, margins = problem.evaluate(params)
    result_design = replace(
        design,
        params=params,
        name=name or f"{design.name}-{model}-opt",
        description=(
            f"{design.name} optimized for {design.target} under the {model} model "
            f"({objective} = {f:.3g}, min margin {margins[design.resting_mask()].min():.3f})"
        ),
    )
    return OptimizationResult(result_design, f, values, margins, evaluations, len(x0s), feasible)
