"""Tuning one shape parameter by drops until a die's top half takes a given share of the landings.

A two-class die (:mod:`diefab.search.symmetric`) rolls its target once its
top half takes one share ``g`` of the landings.  :func:`tune_share` finds the
parameter value that gives it by simulation, and stops as soon as the share
there is known well enough for the die's tolerance:

* **The model, corrected by the drops.**  A landing model's share ``m(v)``
  gives the curve's shape; the drops measure its offset from the simulated
  share, ``s(v) - m(v)``, taken as linear in ``v`` near the goal (slope
  a priori within :data:`PRIOR_SLOPE` of the model's own slope).  The fit
  is weighted least squares with the binomial variance of each measurement.
* **Every drop counts.**  Each step drops the die on fresh drops (step ``k``
  on seed ``seed + k``), so the fit pools all the measurements near the goal
  and the share's standard error falls as one over the square root of all
  their drops, not of the last step's.
* **A stated error bound.**  The tuning stops once the 95 % interval of the
  fitted share at the chosen value is within ``precision`` of the goal (the
  caller sets it from the tolerance: :data:`SHARE_TVD_FRACTION` of it, in
  TVD), when the drop budget is spent, or when the goal lies beyond the
  steady range by more than that interval.

Examples
--------
A share that grows linearly, measured without noise, is found at once:

>>> found = tune_share(lambda v, n, seed: (0.5 + 0.2 * (v - 1.0), n), 0.8, (0.0, 2.0), 0.6, slope=0.2,
...                    precision=0.01)
>>> round(found.value, 6), found.converged
(1.5, True)
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

__all__ = [
    "CONFIDENCE_Z",
    "LINEAR_SPAN",
    "PRIOR_SLOPE",
    "SHARE_TVD_FRACTION",
    "STEP_DROPS",
    "Tuning",
    "share_precision",
    "tune_share",
]

#: Share of the tolerance (in TVD) the tuned share's error may take: the rest is left to the closing check's noise.
SHARE_TVD_FRACTION = 0.25
#: Two-sided 95 % normal quantile of the stopping rule's interval.
CONFIDENCE_Z = 1.959964
#: Measurements whose share is within this of the goal are fitted together (the offset from the model is
#: taken as linear across them); with fewer than two of them, the two nearest the goal are.
LINEAR_SPAN = 0.05
#: Prior standard deviation of the offset's slope, as a share of the model's slope.
PRIOR_SLOPE = 0.5
#: Drops of the first step, and the fewest and most of any later one.
STEP_DROPS = (1000, 500, 4000)
#: Most steps of one tuning.
MAX_STEPS = 32


def share_precision(per_value: Callable[[float], np.ndarray], tolerance: float) -> float:
    """The share error a two-class die of `tolerance` (TVD) can take: :data:`SHARE_TVD_FRACTION` of it.

    A share off by ``d`` moves the die's value probabilities by
    ``d * D`` in TVD, ``D`` the TVD between the all-top and all-bottom dice
    (`per_value` (share) -> (k,) value probabilities is linear in the share).

    >>> share_precision(lambda s: np.array([s, 1 - s]), 0.02)
    0.005
    """
    spread = 0.5 * float(np.abs(per_value(1.0) - per_value(0.0)).sum())
    return SHARE_TVD_FRACTION * tolerance / max(spread, 1e-12)


@dataclass
class Tuning:
    """What :func:`tune_share` measured, and the parameter value it settled on."""

    value: float
    #: (parameter value, top-half share, landed drops) of each simulation.
    evaluations: list[tuple[float, float, int]]
    #: True if the wall-time cap, not the drop budget or convergence, ended the search.
    capped: bool = False
    #: The fitted share at :attr:`value`.
    share: float = float("nan")
    #: Half-width of its 95 % interval.
    error: float = float("inf")
    #: True once the interval was within the precision asked for.
    converged: bool = False


@dataclass(frozen=True)
class _Fit:
    """The model's share plus a linear offset, fitted to measurements: where it reaches the goal, and how surely."""

    modelled: Callable[[float], float]
    center: float
    coef: np.ndarray  # (2,) offset at `center`, slope
    cov: np.ndarray  # (2, 2)
    #: True if the measurements fitted were all within :data:`LINEAR_SPAN` of the goal.
    local: bool

    def share(self, v: float) -> float:
        return float(self.modelled(v) + self.coef[0] + self.coef[1] * (v - self.center))

    def error(self, v: float) -> float:
        x = np.array([1.0, v - self.center])
        return float(CONFIDENCE_Z * np.sqrt(max(x @ self.cov @ x, 0.0)))


def _fit(points, goal: float, modelled, prior_slope: float) -> _Fit:
    """The offset of the measurements near `goal` from `modelled`, fitted as linear (weighted least squares)."""
    near = [p for p in points if abs(p[1] - goal) <= LINEAR_SPAN]
    local = len(near) >= 2
    if not local:
        near = sorted(points, key=lambda p: abs(p[1] - goal))[:2]
    v = np.array([p[0] for p in near])
    r = np.array([p[1] - modelled(p[0]) for p in near])
    w = np.array([p[2] for p in near], dtype=float) / max(goal * (1 - goal), 1e-6)  # binomial, at the goal
    center = float((w * v).sum() / w.sum())
    x = np.column_stack([np.ones_like(v), v - center])
    info = x.T @ (w[:, None] * x) + np.diag([0.0, 1.0 / max(prior_slope, 1e-9) ** 2])
    cov = np.linalg.inv(info)
    coef = cov @ (x.T @ (w * r))
    dof = len(near) - 2
    if dof > 0:  # scatter beyond the binomial's (a curved offset), shown at the 5 % level, widens the interval
        from scipy.stats import chi2

        scatter = float((w * (r - x @ coef) ** 2).sum())
        if scatter > chi2.ppf(0.95, dof):
            cov = cov * scatter / dof
    return _Fit(modelled, center, coef, cov, local)


def _root(fit: _Fit, goal: float, lo: float, hi: float, near: float) -> float:
    """Where `fit` reaches `goal` in [lo, hi] (the crossing nearest `near`), or the end nearer to it."""
    grid = np.linspace(lo, hi, 65)
    f = np.array([fit.share(v) - goal for v in grid])
    crossings = [i for i in range(len(grid) - 1) if f[i] * f[i + 1] <= 0]
    if not crossings:
        return float(grid[np.argmin(np.abs(f))])
    i = min(crossings, key=lambda j: abs(grid[j] - near))
    if f[i] == f[i + 1]:
        return float(grid[i])
    return float(brentq(lambda v: fit.share(v) - goal, grid[i], grid[i + 1], xtol=1e-7))


def tune_share(
    share_of: Callable[[float, int, int], tuple[float, int]],
    start: float,
    bounds: tuple[float, float],
    goal: float,
    *,
    slope: float,
    precision: float,
    modelled: Callable[[float], float] | None = None,
    max_drops: int = 64_000,
    deadline: float = float("inf"),
    seed: int = 0,
    say: Callable[[str], None] = lambda text: None,
    planned: Callable[[int], None] = lambda drops: None,
) -> Tuning:
    """Find the parameter value at which the top half takes `goal` of the landings, by simulation.

    Each step drops the die at the value where the model, corrected by all
    the measurements so far (see the module's description), reaches the
    goal; step ``k`` uses seed ``seed + k``.  It stops once the fitted
    share there is within `precision` of the goal at 95 % confidence (fitted
    to at least two measurements within :data:`LINEAR_SPAN` of the goal),
    once the goal is that surely out of `bounds`, or when the next step
    would pass `max_drops`.

    Parameters
    ----------
    share_of : callable(value, drops, seed) -> (share, landed)
        Simulates the die with its tuned parameter at `value`.
    start : float
        First value (a model's guess).
    bounds : (float, float)
        The values the tuning may try.
    goal : float
        The top half's share the die must take.
    slope : float
        A model's d(share)/d(value) near `start`.
    precision : float
        Largest error of the share the result may have, at 95 % confidence
        (:func:`share_precision`).
    modelled : callable(value) -> share, optional
        The model's share across `bounds` (default: the line through
        `start` with `slope`).
    max_drops : int
        Most drops in all: no step starts that would exceed it (the first
        always runs).  The result is a function of this budget and `seed`.
    deadline : float, optional
        ``time.monotonic()`` after which no new step starts: a wall-time cap
        (:attr:`Tuning.capped` says it ended the search).
    planned : callable(drops), optional
        Told, before each step, how many drops the tuning now expects to
        spend in all (for a progress bar's ETA).

    Returns
    -------
    Tuning
    """
    lo, hi = bounds
    span = hi - lo
    if modelled is None:
        modelled = lambda v: slope * (v - start)  # noqa: E731 -- only differences from it matter
    prior = PRIOR_SLOPE * max(abs(slope), 1e-3)
    points: list[tuple[float, float, int]] = []
    value, used, capped = float(np.clip(start, lo, hi)), 0, False
    first, least, most = STEP_DROPS
    n = first
    fit: _Fit | None = None
    converged = False
    # the drops the interval is expected to need in all: a binomial share's at the goal, to begin with
    binomial = int(np.ceil(goal * (1 - goal) * (CONFIDENCE_Z / precision) ** 2))
    needed = max(first, binomial)
    for step in range(MAX_STEPS):
        if points:
            n = min(n, max_drops - used)
            if n < least:
                break
        if points and time.monotonic() > deadline:
            capped = True
            break
        planned(max(used + n, needed))
        share, landed = share_of(value, n, seed + step)
        used += n
        points.append((value, share, landed))
        fit = _fit(points, goal, modelled, prior)
        root = _root(fit, goal, lo, hi, value)
        reach = 0.25 * span
        tried = [p[0] for p in points]
        root = float(np.clip(root, max(lo, min(tried) - reach), min(hi, max(tried) + reach)))
        error = fit.error(root)
        say(f"tuning: {value:.4f} gives the top half {share:.4f} of {landed} landings; the fit reaches the goal "
            f"{goal:.4f} at {root:.4f} (± {error:.4f} in share, asked {precision:.4f})")  # fmt: skip
        value = root
        if fit.local and error <= precision and abs(fit.share(root) - goal) <= precision:
            converged = True
            break
        if step >= 1 and root in (lo, hi) and abs(fit.share(root) - goal) > error:
            say(f"tuning: the goal share {goal:.4f} lies beyond the steady shapes (the fit gives "
                f"{fit.share(root):.4f} at {root:.4f})")  # fmt: skip
            break
        # the drops the interval still needs (it narrows as one over the square root of the drops)
        near = sum(p[2] for p in points if abs(p[1] - goal) <= LINEAR_SPAN) or landed
        wanted = min(near * ((error / precision) ** 2 - 1.0), binomial - near)  # no more than a lone share needs
        n = int(np.clip(np.ceil(1.1 * wanted / 250.0) * 250, least, most))
        needed = used + max(n, int(wanted))
    return Tuning(value, points, capped, fit.share(value), fit.error(value), converged)
