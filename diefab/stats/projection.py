"""How many more rolls a die is likely to need before the sequential test decides.

A plug-in estimate: the frequencies seen so far, shrunk towards the target by
their expected noise, are taken as the truth and scaled up until the verdict
of :mod:`diefab.stats.sequential` would be reached.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from diefab.core.errors import StatsError
from diefab.stats.confidence_sequence import off_reached, within_reached
from diefab.stats.goodness import check_counts, check_probabilities, expected_tvd_exact, tvd

__all__ = ["HORIZON", "check_test", "denoised_tvd", "rolls_needed", "rolls_to_decision"]

#: Most rolls the estimate of rolls still needed looks ahead to.
HORIZON = 10**8


def check_test(target, delta: float, alpha: float) -> np.ndarray:
    """The target as probabilities, after checking `delta` and `alpha` (a :class:`StatsError` names the bad one)."""
    t = check_probabilities(target, "target")
    if not 0 < delta < 1:
        raise StatsError(f"delta={delta!r} must be a TVD in (0, 1)")
    if not 0 < alpha < 1:
        raise StatsError(f"alpha={alpha!r} must be in (0, 1)")
    return t


def rolls_to_decision(c: np.ndarray, t: np.ndarray, delta: float, alpha: float) -> int | None:
    """Fewest total rolls at which a die like the one observed reaches a decision (None: beyond HORIZON)."""
    p = _debiased(c, t)
    aim_within = tvd(p, t) < delta

    def decided(m: float) -> bool:
        row = (m * p)[None, :]
        if not aim_within:
            return bool(off_reached(row, t, delta, alpha)[0])
        # real frequencies wander from p by about the mean TVD of m rolls, which the
        # noiseless counts m p do not: ask for that much margin inside delta
        margin = delta - expected_tvd_exact(p, m)
        return margin > 0 and bool(within_reached(row, t, margin, alpha)[0])

    lo = max(int(c.sum()), 1)
    hi = lo
    while not decided(hi):
        if hi >= HORIZON:
            return None
        lo, hi = hi, min(2 * hi, HORIZON)
    while hi - lo > max(1, lo // 100):
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if decided(mid) else (mid, hi)
    return hi


def _debiased(c: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The observed frequencies shrunk towards the target by the part of their spread that is noise.

    Under the target, n times the Pearson divergence of the frequencies has
    mean k - 1; the deviation p̂ - t is scaled by sqrt(max(D - (k-1)/n, 0) / D)
    so that the divergence kept is the excess over noise.  No roll: the target.
    """
    n = c.sum()
    if n == 0:
        return t.copy()
    phat = c / n
    live = t > 0
    if np.any(c[~live] > 0):
        return phat
    d = float((((phat - t) ** 2)[live] / t[live]).sum())
    excess = d - (live.sum() - 1) / n
    scale = np.sqrt(excess / d) if excess > 0 else 0.0
    return t + scale * (phat - t)


def denoised_tvd(counts: np.ndarray, target: np.ndarray) -> float:
    """TVD to the target of the frequencies with their expected noise taken out: the die the estimate assumes.

    Examples
    --------
    Counts exactly at the target's proportions, and counts whose spread is all noise:

    >>> denoised_tvd(np.array([50.0, 50.0]), np.array([0.5, 0.5]))
    0.0
    >>> denoised_tvd(np.array([52.0, 48.0]), np.array([0.5, 0.5]))
    0.0
    """
    c = np.asarray(counts, float)
    return float(tvd(_debiased(c, target), target))


def rolls_needed(counts: Sequence[int], target, delta: float, alpha: float = 0.05) -> int | None:
    """Estimated further rolls to a decision, if the die rolls as it has so far.

    The counts' frequencies, shrunk towards the target by their expected
    noise (the target itself before any roll), are taken as the truth and
    scaled up until the verdict would be reached; a "within" is asked to hold
    with a margin of the frequencies' own expected wander (mean TVD).  A plug-in estimate: a die
    close to the boundary `delta` needs many more.

    Examples
    --------
    A coin exactly fair needs about a thousand flips to be shown within 0.05 of fair:

    >>> 1_000 < rolls_needed([0, 0], [0.5, 0.5], 0.05) < 2_000
    True
    """
    c = np.asarray(check_counts(counts), float)
    t = check_test(target, delta, alpha)
    total = rolls_to_decision(c, t, delta, alpha)
    return None if total is None else max(total - int(c.sum()), 1)
