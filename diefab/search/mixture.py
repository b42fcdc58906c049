"""A mixture of simulated set-ups: real throws are neither all gentle nor all vigorous.

A real thrower does not throw every time the same way.  If a die is
simulated under a few set-ups (candidates: throws of different vigor, a
table that takes the energy...), a population of throws that uses set-up
``k`` a fraction ``w[k]`` of the time lands on value ``v`` with probability

    p(v) = sum_k w[k] * p_k(v),

linear in the weights, so once every die is simulated under every candidate,
fitting the weights to real counts costs no simulation.  :func:`fit_weights`
finds the weights of least total deviance of the training dice's real counts,
plus a linear prior ``penalty @ w`` (the expected prior cost of a set-up drawn
from the mixture, :func:`prior_penalty`), on the simplex.  The objective is
convex in ``w`` (deviance is minus a log of a linear function, plus a linear
term), so its minimum is unique in value.

Examples
--------
Two candidates; the real die rolled half of each; the mixture recovers it:

>>> import numpy as np
>>> probs = np.array([[0.9, 0.1], [0.1, 0.9]])
>>> w = fit_weights([np.array([50.0, 50.0])], [probs], np.zeros(2))
>>> np.round(w, 3)
array([0.5, 0.5])
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from diefab.core.errors import StatsError

__all__ = ["fit_weights", "mix", "mixture_deviance", "prior_penalty"]

#: Convergence tolerance of the weights' objective (deviance units).
FIT_TOLERANCE = 1e-10


def mix(probs: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(k,) float: the value probabilities of the mixture, ``weights @ probs``.

    Parameters
    ----------
    probs : (K, k) float
        Each candidate's value probabilities.
    weights : (K,) float
        Non-negative, summing to 1.
    """
    return np.asarray(weights, dtype=float) @ np.asarray(probs, dtype=float)


def prior_penalty(coords: np.ndarray, x0: np.ndarray, prior_sd: float) -> np.ndarray:
    """(K,) float: each candidate's prior cost ``sum(((x - x0) / prior_sd)**2)`` (0 when `prior_sd` is inf).

    A mixture costs ``penalty @ w``: the expected cost of a set-up drawn from
    it, so a pure candidate costs what :func:`diefab.search.crossval.pick_candidate`
    charges it.
    """
    if not prior_sd > 0:
        raise StatsError(f"prior_sd={prior_sd!r} must be > 0 (inf: no prior)")
    coords = np.asarray(coords, dtype=float)
    if not np.isfinite(prior_sd):
        return np.zeros(len(coords))
    return (((coords - np.asarray(x0, dtype=float)) / prior_sd) ** 2).sum(axis=1)


def mixture_deviance(counts: Sequence[np.ndarray], probs: Sequence[np.ndarray], weights: np.ndarray) -> float:
    """Total deviance ``G²`` of each die's real `counts` under the mixture of its `probs` (K, k_j) by `weights`."""
    total = 0.0
    for c, p in zip(counts, probs):
        c = np.asarray(c, dtype=float)
        q = mix(p, weights)
        m = c > 0
        total += 2.0 * float(np.sum(c[m] * np.log(c[m] / (c.sum() * q[m]))))
    return total


def _check(counts, probs, penalty) -> int:
    penalty = np.asarray(penalty, dtype=float)
    if penalty.ndim != 1 or not np.all(np.isfinite(penalty)):
        raise StatsError(f"penalty of shape {penalty.shape} must be a finite (K,) vector")
    if len(counts) != len(probs):
        raise StatsError(f"{len(counts)} dice' counts for {len(probs)} dice' probabilities")
    for j, (c, p) in enumerate(zip(counts, probs)):
        p = np.asarray(p, dtype=float)
        if p.shape != (len(penalty), len(c)):
            raise StatsError(f"die {j}: probabilities of shape {p.shape}, expected ({len(penalty)}, {len(c)})")
        if np.any(p <= 0) or not np.allclose(p.sum(axis=1), 1.0, atol=1e-6):
            raise StatsError(f"die {j}: probabilities must be > 0 (smoothed) and sum to 1 per candidate")
    return len(penalty)


def fit_weights(counts: Sequence[np.ndarray], probs: Sequence[np.ndarray], penalty: np.ndarray) -> np.ndarray:
    """(K,) float: the mixture weights of least total deviance plus ``penalty @ w``, on the simplex.

    Parameters
    ----------
    counts : sequence of (k_j,) float
        Real counts of each training die.
    probs : sequence of (K, k_j) float
        Each training die's simulated value probabilities per candidate,
        smoothed (none 0) and already symmetrized within its groups.
    penalty : (K,) float
        The prior cost of each candidate (:func:`prior_penalty`).

    Returns
    -------
    (K,) float
        Non-negative weights summing to 1.  With no training die, the
        candidate of least penalty (the default) alone.

    Raises
    ------
    StatsError
        Shapes disagree, or a probability is 0 or a row does not sum to 1.
    """
    from scipy.optimize import minimize

    k = _check(counts, probs, penalty)
    penalty = np.asarray(penalty, dtype=float)
    alone = np.eye(k)[int(np.argmin(penalty))]
    if not len(counts) or k == 1:
        return alone
    # every die's observed values side by side: columns of (K, M) probabilities and (M,) counts
    cs = [np.asarray(c, dtype=float) for c in counts]
    seen = [c > 0 for c in cs]
    p_all = np.concatenate([np.asarray(p, dtype=float)[:, m] for p, m in zip(probs, seen)], axis=1)
    c_all = np.concatenate([c[m] for c, m in zip(cs, seen)])
    saturated = float(
        np.sum(c_all * np.log(c_all / np.concatenate([np.full(m.sum(), c.sum()) for c, m in zip(cs, seen)])))
    )

    def objective(w: np.ndarray) -> tuple[float, np.ndarray]:
        q = np.maximum(w @ p_all, 1e-300)
        value = float(penalty @ w) + 2.0 * (saturated - float(c_all @ np.log(q)))
        return value, penalty - 2.0 * p_all @ (c_all / q)

    # a convex objective: one start reaches the minimum; the default alone is kept if SLSQP stops short of it
    res = minimize(objective, np.full(k, 1.0 / k), jac=True, method="SLSQP", bounds=[(0.0, 1.0)] * k,
                   constraints=[{"type": "eq", "fun": lambda w: w.sum() - 1.0, "jac": lambda w: np.ones(k)}],
                   options={"ftol": FIT_TOLERANCE, "maxiter": 500})  # fmt: skip
    w = np.clip(res.x, 0.0, None)
    w = w / w.sum()
    return w if objective(w)[0] < objective(alone)[0] - FIT_TOLERANCE else alone
