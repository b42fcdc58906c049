"""One plain sentence on how a die rolls against its target.

Two questions are easily confused:

- **identical?** Is the die's distribution exactly the target?  A fixed-N
  chi-square test answers it.  With enough rolls every real die is
  *distinguishable*: no made object is exact.
- **close?** Is it within a tolerance δ in total variation distance?  The
  anytime-valid confidence sequence of :mod:`diefab.stats.sequential` answers it,
  and says so at 95 % confidence however often one looked.

A die can be distinguishable and still close; what matters to a player is
how many rolls it takes to notice the difference, set against
:data:`LIFETIME_ROLLS`.

Examples
--------
>>> from diefab.dice.targets import parse_target
>>> from diefab.stats.sequential import sequential_counts
>>> t = parse_target("4df").probabilities
>>> counts = [0, 20, 48, 80, 89, 83, 66, 17, 2]
>>> v = verdict(counts, t, "4dF", p_value=0.114, sequential=sequential_counts(counts, t, 0.03))
>>> print(v.text)  # doctest: +ELLIPSIS
indistinguishable from 4dF at 405 rolls (p = 0.11), but not yet shown within or off by TVD 0.03 ...
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from diefab.stats.goodness import noncentrality_for_power, pearson_divergence
from diefab.stats.sequential import SequentialResult

__all__ = ["LIFETIME_ROLLS", "NOTICE_POWER", "Verdict", "notice_rolls", "sequential_line", "target_label", "verdict"]

#: Rolls of one die in a player's lifetime: some 40 rolls a week, every week, for 50 years.
LIFETIME_ROLLS = 100_000
#: Power at which "a player would notice": a 5 % chi-square test detects the difference 4 times in 5.
NOTICE_POWER = 0.8


@dataclass(frozen=True)
class Verdict:
    """A plain verdict and the figures behind it.

    Attributes
    ----------
    text : str
        One line, e.g. "rolls like 4dF within TVD 0.03 ...".
    distinguishable : bool
        The fixed-N chi-square test rejects the target at level alpha.
    decision : {"within", "off", "undecided"}
        The anytime-valid decision at tolerance delta.
    notice_rolls : int or None
        Rolls after which a player's chi-square test would notice the
        difference (80 % power); None when no difference is shown.
    """

    text: str
    distinguishable: bool
    decision: str
    notice_rolls: int | None


def target_label(spec: str) -> str:
    """How a target is named in prose: ``4df`` -> ``4dF``.

    >>> target_label("4df"), target_label("2d6")
    ('4dF', '2d6')
    """
    return re.sub(r"^(\d*)d[fF]$", r"\1dF", spec.strip())


def notice_rolls(counts: Sequence[int], target, power: float = NOTICE_POWER, alpha: float = 0.05) -> int | None:
    """Rolls at which a chi-square test would detect the die as observed, debiased for noise.

    The observed Pearson divergence D of n rolls exceeds the true one by
    about (k - 1)/n (its mean under the target); the true one is taken as
    ``D - (k - 1)/n``, and the rolls as the noncentrality giving `power`
    divided by it.

    Returns
    -------
    int or None
        None when the observed divergence is within noise.

    Examples
    --------
    A coin showing heads 60 % of the time over 10,000 flips: D = 0.04, so a
    5 % test at 80 % power notices it after 7.85 / 0.04 = 197 flips:

    >>> notice_rolls([4000, 6000], [0.5, 0.5])
    197
    """
    c = np.asarray(counts, float)
    t = np.asarray(target, float)
    n = c.sum()
    if n == 0:
        return None
    live = t > 0
    if np.any(c[~live] > 0):
        return 1
    df = int(live.sum()) - 1
    excess = pearson_divergence(c / n, t) - df / n
    if excess <= 0 or df < 1:
        return None
    return math.ceil(noncentrality_for_power(df, power, alpha) / excess)


def _about(n: int) -> str:
    """A count to two significant figures, for estimates: 48,195 -> "48,000"."""
    digits = max(len(str(int(n))) - 2, 0)
    return f"{round(int(n), -digits):,}"


def _still_needed(seq: SequentialResult, label: str, needed: str) -> str:
    """The rolls still `needed`, and why when the die looks to sit on the tolerance."""
    more = "many more rolls" if seq.more_rolls is None else f"about {_about(seq.more_rolls)} more rolls"
    more += f" {needed}"
    huge = seq.more_rolls is None or seq.more_rolls > 100 * max(seq.n, 100)
    if huge and abs(seq.tvd_denoised - seq.delta) < 0.5 * seq.delta:
        more += (
            f" (without the noise of {seq.n:,} rolls the die looks TVD {seq.tvd_denoised:.3f} from {label},"
            f" on the tolerance {seq.delta:g}: a looser tolerance decides far sooner)"
        )
    return more


def _p(p: float) -> str:
    return "p < 0.001" if p < 0.001 else f"p = {p:.2g}"


def verdict(
    counts: Sequence[int],
    target,
    label: str,
    *,
    p_value: float,
    sequential: SequentialResult,
    alpha: float = 0.05,
) -> Verdict:
    """The plain verdict on a die's counts: close or not, identical or not, and whether a player would notice.

    Parameters
    ----------
    counts : (k,) int
        Rolls of each value.
    target : (k,) float
        Target probabilities.
    label : str
        The target's name in prose (see :func:`target_label`).
    p_value : float
        Fixed-N chi-square p-value of the counts against the target.
    sequential : SequentialResult
        The anytime-valid result on the same rolls.
    alpha : float
        Level of the chi-square test.

    Returns
    -------
    Verdict
    """
    s = sequential
    n = int(np.sum(counts))
    level = f"{100 * (1 - s.alpha):.10g} %"
    ci = f"TVD {s.tvd:.3f}, {level} CI {s.tvd_low:.3f}\u2013{s.tvd_high:.3f}"
    distinguishable = bool(p_value < alpha)
    noticed = notice_rolls(counts, target, alpha=alpha) if distinguishable else None
    if noticed is None or noticed > LIFETIME_ROLLS:
        notice = "no player will notice in a lifetime of rolls"
    else:
        notice = f"a player would notice after about {_about(noticed)} rolls"
    more = _still_needed(s, label, "needed")
    seen = f"at {n:,} rolls ({_p(p_value)})"
    if s.decision == "within":
        text = f"rolls like {label} within TVD {s.delta:g} ({ci}): " + (
            f"distinguishable from {label} {seen}, but {notice}"
            if distinguishable
            else f"indistinguishable from {label} {seen}"
        )
    elif s.decision == "off":
        text = f"does not roll like {label}: off by at least TVD {s.delta:g} ({ci}); " + (
            f"distinguishable {seen}; {notice}" if distinguishable else f"chi-square test {seen}"
        )
    elif distinguishable:
        text = (
            f"distinguishable from {label} {seen}; {ci}; not yet shown within or off by TVD {s.delta:g}: "
            f"{more}; {notice}"
        )
    else:
        text = (
            f"indistinguishable from {label} {seen}, but not yet shown within or off by TVD {s.delta:g} ({ci}): {more}"
        )
    return Verdict(text, distinguishable, s.decision, noticed)


def sequential_line(seq: SequentialResult, label: str) -> str:
    """One line for an anytime-valid result: rolls, TVD, its interval, the decision or the rolls to go.

    Examples
    --------
    >>> from diefab.stats.sequential import sequential_counts
    >>> print(sequential_line(sequential_counts([10, 90], [0.5, 0.5], 0.2), "a fair coin"))
    100 rolls: TVD 0.400 to a fair coin, 95 % anytime CI 0.251–0.476: off a fair coin by at least TVD 0.2
    """
    level = f"{100 * (1 - seq.alpha):.10g} %"
    if seq.n == 0:
        return f"no rolls yet: {_still_needed(seq, label, 'likely needed')}"
    head = (
        f"{seq.n:,} rolls: TVD {seq.tvd:.3f} to {label}, {level} anytime CI {seq.tvd_low:.3f}\u2013{seq.tvd_high:.3f}"
    )
    at = "" if seq.decided_at is None or seq.decided_at == seq.n else f" (decided at roll {seq.decided_at:,})"
    if seq.decision == "within":
        return f"{head}: rolls like {label} within TVD {seq.delta:g}{at}"
    if seq.decision == "off":
        return f"{head}: off {label} by at least TVD {seq.delta:g}{at}"
    return f"{head}: not yet within or off by TVD {seq.delta:g}; {_still_needed(seq, label, 'likely needed')}"
