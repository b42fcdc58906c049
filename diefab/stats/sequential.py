"""Anytime-valid tests of a die against a target: may be checked after every roll.

:func:`sequential_test` reads two verdicts off a confidence sequence for
the die's distribution, valid at every number of rolls at once: **within**
δ of the target in total variation distance, or **off** by at least δ.

The confidence sequence itself (its method and exact TVD bounds) is in
:mod:`diefab.stats.confidence_sequence`; the estimate of rolls still
needed in :mod:`diefab.stats.projection`.

Decisions are checked after every roll and are final once reached (the
running intersection of the confidence sets), so a verdict is wrong with
probability at most α however long one keeps rolling.

Examples
--------
A fair coin, checked after every flip, is shown within 0.05 of fair at flip 1,092:

>>> flips = np.random.default_rng(1).integers(0, 2, 3000)
>>> res = sequential_test(flips, [0.5, 0.5], delta=0.05)
>>> res.decision, res.decided_at
('within', 1092)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from diefab.core.errors import StatsError
from diefab.stats.confidence_sequence import (
    CONCENTRATIONS,
    EXACT_VALUES,
    FLOOR,
    PRIOR,
    ball_max_loglik,
    confidence_radius,
    log_mixture_likelihood,
    off_reached,
    tvd_bounds,
    within_reached,
)
from diefab.stats.goodness import check_counts, tvd
from diefab.stats.projection import HORIZON, denoised_tvd, rolls_needed, rolls_to_decision
from diefab.stats.projection import check_test as _check

__all__ = [
    "CONCENTRATIONS",
    "EXACT_VALUES",
    "FLOOR",
    "HORIZON",
    "PRIOR",
    "SequentialResult",
    "SequentialTest",
    "ball_max_loglik",
    "confidence_radius",
    "log_mixture_likelihood",
    "off_reached",
    "rolls_needed",
    "sequential_counts",
    "sequential_test",
    "tvd_bounds",
    "within_reached",
]


@dataclass(frozen=True)
class SequentialResult:
    """The anytime-valid verdict after n rolls.

    Attributes
    ----------
    n : int
        Rolls so far.
    delta, alpha : float
        Tolerance (TVD) and error rate of the verdict.
    decision : {"within", "off", "undecided"}
        ``within``: the die is within TVD `delta` of the target;
        ``off``: it is off by at least `delta`; each wrong with probability
        at most `alpha` however the rolls were monitored.
    decided_at : int or None
        The roll at which the decision was first reached.
    tvd : float
        TVD between the observed frequencies and the target (biased upward by noise).
    tvd_low, tvd_high : float
        Time-uniform (1 - alpha) confidence interval for the die's TVD to the target.
    more_rolls : int or None
        Estimated further rolls to a decision if the die rolls as observed so
        far (0 once decided; None beyond :data:`HORIZON`).
    tvd_denoised : float
        TVD to the target once the noise of n rolls is taken out of the
        frequencies: the die the estimate of `more_rolls` assumes.  Near
        `delta` that estimate grows without bound.
    """

    n: int
    delta: float
    alpha: float
    decision: str
    decided_at: int | None
    tvd: float
    tvd_low: float
    tvd_high: float
    more_rolls: int | None
    tvd_denoised: float

    def as_dict(self) -> dict:
        return {f: getattr(self, f) for f in self.__dataclass_fields__}


def _grid(n: int) -> list[int]:
    """Roll counts at which the TVD interval is computed and intersected: about 13 per decade, and n."""
    g = np.unique(np.round(1.2 ** np.arange(0, int(np.log(max(n, 1)) / np.log(1.2)) + 2)).astype(int))
    return [int(m) for m in g if m < n] + [n]


class SequentialTest:
    """A sequential test fed one roll at a time, with undo.

    Parameters
    ----------
    target : (k,) float
        Target probabilities of the k values.
    delta : float
        Tolerance in TVD.
    alpha : float
        Error rate of each verdict.

    Examples
    --------
    >>> test = SequentialTest([0.5, 0.5], delta=0.2)
    >>> for _ in range(60):
    ...     test.push(1)
    >>> test.result().decision, test.result().decided_at
    ('off', 19)
    >>> test.pop(); test.n
    59
    """

    def __init__(self, target, delta: float, alpha: float = 0.05) -> None:
        self.target = _check(target, delta, alpha)
        self.delta, self.alpha = float(delta), float(alpha)
        self._rolls: list[int] = []
        self._counts = np.zeros(len(self.target), dtype=np.int64)
        self._decided: tuple[str, int] | None = None
        self._bounds: dict[int, tuple[float, float]] = {}
        self._ordered = True  # False: counts without order, one look at their total

    @property
    def n(self) -> int:
        return int(self._counts.sum())

    @property
    def counts(self) -> np.ndarray:
        return self._counts.copy()

    @property
    def decision(self) -> str:
        """``within``, ``off`` or ``undecided`` (final once reached)."""
        return self._decided[0] if self._decided else "undecided"

    @property
    def decided_at(self) -> int | None:
        """The roll at which the decision was reached."""
        return self._decided[1] if self._decided else None

    def push(self, index: int) -> None:
        """Add a roll of the value with this index (0 <= index < k)."""
        if not 0 <= int(index) < len(self.target):
            raise StatsError(f"value index {index!r} is not in 0..{len(self.target) - 1}")
        self._rolls.append(int(index))
        self._counts[int(index)] += 1
        self._check_now()

    def _check_now(self) -> None:
        """Decide on the counts now, unless decided already."""
        if self._decided is None:
            self._decided = _first_decision(self._counts[None, :], self.target, self.delta, self.alpha, self.n - 1)

    def extend(self, indices: Sequence[int]) -> None:
        """Add many rolls at once (checked after every one, vectorized)."""
        indices = np.asarray(indices, dtype=np.int64)
        if indices.size and (indices.min() < 0 or indices.max() >= len(self.target)):
            raise StatsError(f"value indices must be in 0..{len(self.target) - 1}")
        start = self.n
        prefix = self._counts + np.cumsum(np.eye(len(self.target), dtype=np.int64)[indices], axis=0)
        self._rolls.extend(indices.tolist())
        if len(indices):
            self._counts = prefix[-1].copy()
        if self._decided is None and len(indices):
            self._decided = _first_decision(prefix, self.target, self.delta, self.alpha, start)

    def pop(self) -> None:
        """Undo the last roll."""
        if not self._ordered:
            raise StatsError("counts without order: no roll to undo")
        if not self._rolls:
            raise StatsError("no roll to undo")
        self._counts[self._rolls.pop()] -= 1
        if self._decided is not None and self._decided[1] > self.n:
            self._decided = None
        self._bounds = {m: b for m, b in self._bounds.items() if m <= self.n}

    def _counts_at(self, m: int) -> np.ndarray:
        if m == self.n:
            return self._counts.copy()
        return np.bincount(np.asarray(self._rolls[:m], dtype=np.int64), minlength=len(self.target))

    def result(self, *, estimate: bool = True) -> SequentialResult:
        """The verdict now: decision, TVD interval, and rolls likely still needed."""
        n = self.n
        low, high = 0.0, 1.0
        for m in _grid(n) if self._ordered else [n]:
            if m not in self._bounds or m == n:
                self._bounds[m] = tvd_bounds(self._counts_at(m), self.target, self.alpha)
            lo_m, hi_m = self._bounds[m]
            low, high = max(low, lo_m), min(high, hi_m)
        decision, at = self._decided if self._decided else ("undecided", None)
        if decision == "within":
            high = min(high, self.delta)
        elif decision == "off":
            low = max(low, self.delta)
        low = min(low, high)
        c = self._counts.astype(float)
        observed = tvd(c / n, self.target) if n else float("nan")
        more = 0 if at is not None else None
        if at is None and estimate:
            total = rolls_to_decision(c, self.target, self.delta, self.alpha)
            more = None if total is None else max(total - n, 1)
        denoised = denoised_tvd(c, self.target) if n else float("nan")
        return SequentialResult(n, self.delta, self.alpha, decision, at, observed, low, high, more, denoised)


def _first_decision(prefix: np.ndarray, t, delta, alpha, start: int) -> tuple[str, int] | None:
    """First (decision, roll number) over the prefix counts (m, k), rows numbered from start + 1."""
    step = 4096
    for s in range(0, len(prefix), step):
        rows = prefix[s : s + step].astype(float)
        off = off_reached(rows, t, delta, alpha)
        within = within_reached(rows, t, delta, alpha)
        hit = np.flatnonzero(off | within)
        if len(hit):
            i = hit[0]
            return ("off" if off[i] else "within", start + s + int(i) + 1)
    return None


def sequential_test(
    rolls: Sequence[int],
    target,
    delta: float = 0.03,
    alpha: float = 0.05,
    *,
    estimate: bool = True,
) -> SequentialResult:
    """The anytime-valid verdict on rolls in the order rolled, checked after every one.

    Parameters
    ----------
    rolls : (n,) int
        Index of each rolled value in 0..k-1 (the target's value order), in order.
    target : (k,) float
    delta : float
        Tolerance in TVD, e.g. 0.03.
    alpha : float
        Error rate of each verdict (0.05: 95 % confidence).
    estimate : bool
        Estimate the rolls still needed (a few more likelihood evaluations).

    Returns
    -------
    SequentialResult
    """
    t = _check(target, delta, alpha)
    test = SequentialTest(t, delta, alpha)
    test.extend(np.asarray(rolls, dtype=np.int64).reshape(-1))
    return test.result(estimate=estimate)


def sequential_counts(
    counts: Sequence[int],
    target,
    delta: float = 0.03,
    alpha: float = 0.05,
    *,
    estimate: bool = True,
) -> SequentialResult:
    """The verdict on counts whose order is unknown: one look, at their total.

    One look is a special case of monitoring, so the verdict keeps its error
    rate; it cannot say at which roll it was first reached.

    Examples
    --------
    The paper's Table 2: 405 rolls are too few to tell within 0.03 of 4dF:

    >>> from diefab.dice.targets import parse_target
    >>> res = sequential_counts([0, 20, 48, 80, 89, 83, 66, 17, 2], parse_target("4df").probabilities)
    >>> res.decision, res.n
    ('undecided', 405)
    >>> bool(res.tvd_low <= res.tvd <= res.tvd_high)
    True

    A coin that came up heads 90 times in 100 is off a fair coin by at least 0.2:

    >>> sequential_counts([10, 90], [0.5, 0.5], delta=0.2).decision
    'off'
    """
    t = _check(target, delta, alpha)
    c = check_counts(counts)
    if len(c) != len(t):
        raise StatsError(f"{len(c)} counts for the {len(t)} values of the target")
    test = SequentialTest(t, delta, alpha)
    test._counts = np.asarray(c, dtype=np.int64).copy()  # no roll list: counts can be far too many to list
    test._ordered = False
    test._check_now()
    return test.result(estimate=estimate)
