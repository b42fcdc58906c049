"""The likelihood of real counts under simulated frequencies: smoothing, deviance, one die's fit.

* each die's value probabilities under a candidate setting are its simulated
  frequencies, smoothed by half a count per value (a Jeffreys prior), so that
  a value that was rolled but never simulated costs a finite amount;
* the deviance ``G² = 2 Σ c log(c / (n p))`` of the real counts is twice the
  log-likelihood ratio to the saturated model: its minimum over settings is
  their maximum-likelihood fit.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from diefab.search.realdie import RealDie

__all__ = ["SMOOTHING", "deviance", "die_report", "predict_report", "simulate_die", "smoothed"]

#: Pseudo-count added to each value's simulated count (Jeffreys prior).
SMOOTHING = 0.5


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
    >>> deviance([1, 1], [1.0, 0.0])  # a count where p is 0
    inf
    """
    c = np.asarray(counts, dtype=float)
    p = np.asarray(p, dtype=float)
    n = c.sum()
    m = c > 0
    with np.errstate(divide="ignore"):  # a count where p is 0: infinite deviance, not a warning
        return float(2.0 * np.sum(c[m] * np.log(c[m] / (n * p[m]))))


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
    (:meth:`RealDie.tvd`: up to relabelling within the die's groups, as
    every real-roll figure is compared); ``noise_tvd`` is the TVD that
    sampling alone gives at the die's number of rolls
    (:func:`diefab.stats.goodness.expected_tvd_exact`); ``p_value`` is the chi-squared
    tail of the deviance with k - 1 degrees of freedom (the simulation's own
    noise and the fit are not counted).
    """
    from scipy.stats import chi2

    from diefab.stats.goodness import expected_tvd_exact

    counts = np.asarray(sim_counts, dtype=float)
    p = counts / max(counts.sum(), 1)
    ps = die.symmetrized(smoothed(counts))
    g2 = deviance(die.counts, ps)
    df = len(die.counts) - 1
    return {
        "name": die.name,
        "rolls": die.n,
        "real": die.frequencies.tolist(),
        "simulated": p.tolist(),
        "tvd": die.tvd(p),
        "noise_tvd": expected_tvd_exact(die.frequencies, die.n),
        "deviance": g2,
        "df": df,
        "p_value": float(chi2.sf(g2, df)),
    }


def predict_report(die: RealDie) -> dict[str, Any]:
    """What ``diefab predict`` scores on `die`'s real rolls, fitted on no real die.

    ``model`` is its landing model to trust (:func:`diefab.models.choice.best_model`)
    and ``tvd`` that model's TVD to the real frequencies, compared as
    :func:`die_report` compares a simulation (:meth:`RealDie.tvd`); None,
    with the ``error``, where the model cannot predict the die.
    """
    from diefab.core.errors import DiefabError
    from diefab.models.choice import best_model
    from diefab.models.probabilities import value_probabilities

    model = best_model(die.design).name
    try:
        p = value_probabilities(die.design, model)
    except DiefabError as exc:
        return {"model": model, "tvd": None, "error": str(exc)}
    return {"model": model, "tvd": die.tvd(p)}
