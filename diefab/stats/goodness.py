"""Statistics of rolls against a target distribution (the paper's Section 3 and beyond).

Examples
--------
The paper's Table 2, 405 real rolls of its final die, against 4dF:

>>> from diefab.dice.targets import parse_target
>>> fit = goodness_of_fit([0, 20, 48, 80, 89, 83, 66, 17, 2], parse_target("4df").probabilities)
>>> round(fit.chi2, 2), round(fit.p_value, 2), round(fit.tvd, 3), round(fit.jsd, 4)
(12.94, 0.11, 0.047, 0.0068)
"""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from diefab.core.errors import StatsError
from diefab.core.tolerances import PROBABILITY_SUM
from diefab.stats.rolllog import MAX_LOG_BYTES as ROLL_LOG_BYTES
from diefab.stats.rolllog import is_roll_log, parse_value, read_log

__all__ = [
    "MAX_COUNT",
    "GoodnessOfFit",
    "check_counts",
    "check_probabilities",
    "chi2_power",
    "counts_from_rolls",
    "expected_jsd",
    "expected_tvd",
    "expected_tvd_exact",
    "goodman_intervals",
    "goodness_of_fit",
    "jsd",
    "noncentrality_for_power",
    "parse_counts",
    "pearson_divergence",
    "read_roll_column",
    "read_rolls",
    "rolls_for_power",
    "tvd",
]


#: Most rolls in one set of counts (multinomial sampling works in 64-bit integers).
MAX_COUNT = 10**15
#: Largest list or sheet of rolls read, bytes (about two million rolls, far beyond any rolled by hand); a roll
#: log of diefab's own format is read up to its own limit, :data:`diefab.stats.rolllog.MAX_LOG_BYTES`.
MAX_LOG_BYTES = 4 << 20
#: Most rolls whose power :func:`rolls_for_power` simulates; beyond, the noncentral answer stands.
MONTE_CARLO_MAX = 10**12


def pearson_divergence(q: np.ndarray, p: np.ndarray) -> float:
    """The paper's Eq. (2): sum (q - p)^2 / p over values with p > 0."""
    q, p = np.asarray(q, float), np.asarray(p, float)
    mask = p > 0
    return float((((q - p) ** 2)[mask] / p[mask]).sum())


def tvd(p: np.ndarray, q: np.ndarray) -> float:
    """Total variation distance, Eq. (3): half the L1 distance."""
    return float(0.5 * np.abs(np.asarray(p, float) - np.asarray(q, float)).sum())


def _kl(p: np.ndarray, m: np.ndarray) -> float:
    mask = p > 0
    return float((p[mask] * np.log(p[mask] / m[mask])).sum())


def jsd(p: np.ndarray, q: np.ndarray) -> float:
    """Jensen--Shannon divergence, Eq. (4), natural logarithm (nats)."""
    p, q = np.asarray(p, float), np.asarray(q, float)
    m = 0.5 * (p + q)
    return 0.5 * _kl(p, m) + 0.5 * _kl(q, m)


def expected_tvd(k: int, n: int) -> float:
    """The paper's asymptotic mean TVD of n samples: sqrt((k-1)/(2 pi n)).

    Exact (asymptotically) for a uniform distribution over k values and an
    upper bound for any other: see :func:`expected_tvd_exact`.
    """
    return float(np.sqrt((k - 1) / (2 * np.pi * n)))


def expected_tvd_exact(p: Sequence[float], n: int) -> float:
    """Asymptotic mean TVD between `p` and the frequencies of n samples of it.

    Each frequency is asymptotically normal with variance p(1-p)/n, and
    E|X| = sigma sqrt(2/pi), so E TVD = sum sqrt(p (1-p) / (2 pi n)).  By
    Cauchy--Schwarz this is at most the paper's sqrt((k-1)/(2 pi n)), with
    equality for the uniform distribution.
    """
    p = np.asarray(p, dtype=float)
    return float(np.sqrt(p * (1 - p) / (2 * np.pi * n)).sum())


def expected_jsd(k: int, n: int) -> float:
    """Asymptotic mean JSD between a distribution and n samples of it: (k-1)/(8n)."""
    return (k - 1) / (8 * n)


#: Draws of n rolls whose mean TVD and JSD stand for the asymptotic figures at small n.
SAMPLED_MEANS = 4000


def sampled_means(p: Sequence[float], n: int, draws: int = SAMPLED_MEANS) -> tuple[float, float]:
    """Mean TVD and JSD between `p` and the frequencies of n samples of it, over `draws` draws (seed 0)."""
    p = np.asarray(p, dtype=float)
    if n <= 0:
        return math.nan, math.nan
    freq = np.random.default_rng(0).multinomial(n, p, size=draws) / n
    m = 0.5 * (freq + p)
    with np.errstate(divide="ignore", invalid="ignore"):
        kl_f = np.where(freq > 0, freq * np.log(freq / m), 0.0).sum(axis=1)
        kl_p = np.where(p > 0, p * np.log(p / m), 0.0).sum(axis=1)
    return float(0.5 * np.abs(freq - p).sum(axis=1).mean()), float((0.5 * kl_f + 0.5 * kl_p).mean())


def goodman_intervals(counts: Sequence[int], alpha: float = 0.05) -> np.ndarray:
    """Goodman's (1965) simultaneous confidence intervals for multinomial proportions.

    Returns
    -------
    (k, 2) float
        Lower and upper bound of each category's probability; all k intervals
        hold together with probability at least ``1 - alpha`` (asymptotically).
    """
    from scipy.stats import chi2

    _check_alpha(alpha)
    x = check_counts(counts).astype(float)
    n, k = x.sum(), len(x)
    a = chi2.ppf(1 - alpha / k, 1)
    half = np.sqrt(a * (a + 4 * x * (n - x) / n))
    return np.column_stack([(a + 2 * x - half), (a + 2 * x + half)]) / (2 * (n + a))


def chi2_power(
    p: Sequence[float],
    q: Sequence[float],
    n: int,
    alpha: float = 0.05,
    *,
    method: str = "noncentral",
    samples: int = 20_000,
    seed: int = 0,
) -> float:
    """Power of Pearson's chi-square test of `p` at `n` rolls when the truth is `q`.

    Parameters
    ----------
    method : {"noncentral", "monte-carlo"}
        ``noncentral``: the asymptotic noncentral chi-square with
        noncentrality ``n * pearson_divergence(q, p)`` and ``k - 1`` degrees
        of freedom (fast; optimistic for small n).  ``monte-carlo``: the
        fraction of `samples` multinomial(n, q) draws the test rejects.
    """
    from scipy.stats import chi2, ncx2

    p, q = np.asarray(p, float), np.asarray(q, float)
    live = p > 0
    df = int(live.sum()) - 1
    crit = chi2.ppf(1 - alpha, df)
    if method == "monte-carlo":
        x = np.random.default_rng(seed).multinomial(n, q, size=samples)
        if np.any(x[:, ~live] > 0):  # a value the null says is impossible: always rejected
            rejected = np.any(x[:, ~live] > 0, axis=1)
        else:
            rejected = np.zeros(samples, dtype=bool)
        rejected |= _chi2_stat(x[:, live], n * p[live]) > crit
        return float(rejected.mean())
    if method != "noncentral":
        raise StatsError(f"unknown power method {method!r} (noncentral, monte-carlo)")
    lam = n * pearson_divergence(q, p)
    return float(chi2.sf(crit, df)) if lam == 0 else float(ncx2.sf(crit, df, lam))


def noncentrality_for_power(df: int, power: float = 0.8, alpha: float = 0.05) -> float:
    """Noncentrality at which a chi-square test with `df` degrees of freedom has this power.

    A die whose Pearson divergence from the target is D gives noncentrality
    n D after n rolls, so it is detected at about ``this / D`` rolls.

    Examples
    --------
    >>> round(noncentrality_for_power(1, 0.5, 0.05), 2)  # 1.96 squared, nearly
    3.84
    """
    from scipy.optimize import brentq
    from scipy.stats import chi2, ncx2

    crit = chi2.ppf(1 - alpha, df)
    hi = 1.0
    while ncx2.sf(crit, df, hi) < power:
        hi *= 2
    return float(brentq(lambda x: ncx2.sf(crit, df, x) - power, 0.0, hi, xtol=1e-10))


def rolls_for_power(
    p: Sequence[float],
    q: Sequence[float],
    power: float = 0.8,
    alpha: float = 0.05,
    *,
    method: str = "noncentral",
    samples: int = 20_000,
    seed: int = 0,
) -> int | None:
    """Fewest rolls at which the chi-square test detects `q` with the given power (None if q == p).

    The noncentral answer is exact for its approximation; the Monte-Carlo
    one bisects on the simulated power with common random numbers, starting
    from the noncentral estimate.
    """
    delta = pearson_divergence(q, p)
    if delta <= 0:
        return None
    df = int(np.count_nonzero(np.asarray(p) > 0)) - 1
    n = int(np.ceil(noncentrality_for_power(df, power, alpha) / delta))
    if method == "noncentral" or n > MONTE_CARLO_MAX:  # that many rolls: the noncentral law is exact enough
        return n

    def enough(m: int) -> bool:
        return chi2_power(p, q, m, alpha, method="monte-carlo", samples=samples, seed=seed) >= power

    lo, hi_n = max(1, n // 2), n
    while not enough(hi_n):
        lo, hi_n = hi_n, hi_n * 2
    while hi_n - lo > 1:
        mid = (lo + hi_n) // 2
        lo, hi_n = (lo, mid) if enough(mid) else (mid, hi_n)
    return hi_n


@dataclass(frozen=True, eq=False)
class GoodnessOfFit:
    """Rolls compared with a target distribution."""

    counts: np.ndarray
    target: np.ndarray
    chi2: float
    df: int
    p_value: float
    p_value_mc: float
    mc_samples: int
    g: float
    g_p_value: float
    tvd: float
    jsd: float
    intervals: np.ndarray
    alpha: float

    @property
    def n(self) -> int:
        return int(self.counts.sum())

    @property
    def expected(self) -> np.ndarray:
        return self.n * self.target

    @property
    def observed(self) -> np.ndarray:
        return self.counts / self.n

    @property
    def expected_tvd(self) -> float:
        """Mean TVD of n rolls of the target: the paper's asymptotic figure, or sampled when n is small.

        With an expected count below 5 (:attr:`small_expected`) the asymptotic figure overstates it (above 1
        at n = 1), so the mean over :data:`SAMPLED_MEANS` draws of n rolls (seed 0) is given instead.
        """
        return self._sampled[0] if self.small_expected else expected_tvd(len(self.counts), self.n)

    @property
    def expected_tvd_exact(self) -> float:
        return self._sampled[0] if self.small_expected else expected_tvd_exact(self.target, self.n)

    @property
    def expected_jsd(self) -> float:
        """Mean JSD of n rolls of the target (asymptotic, or sampled when n is small, as :attr:`expected_tvd`)."""
        return self._sampled[1] if self.small_expected else expected_jsd(len(self.counts), self.n)

    @cached_property
    def _sampled(self) -> tuple[float, float]:
        """:func:`sampled_means` of the target at n, drawn once for the three figures above."""
        return sampled_means(self.target, self.n)

    @property
    def small_expected(self) -> bool:
        """True when some expected count is below 5 and the asymptotic p is doubtful."""
        return bool(np.any(self.expected[self.target > 0] < 5))


def check_counts(counts) -> np.ndarray:
    """(k,) int64 counts: whole, non-negative, at most :data:`MAX_COUNT` in all."""
    try:
        x = np.asarray(counts)
    except (TypeError, ValueError) as exc:
        raise StatsError(f"counts {counts!r} are not a list of numbers") from exc
    if x.ndim != 1 or x.size == 0:
        raise StatsError(f"counts must be a non-empty list of numbers, got shape {x.shape}")
    values = x.tolist()
    for v in values:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v != int(v):
            raise StatsError(f"counts must be whole numbers, got {v!r}")
    values = [int(v) for v in values]
    if any(v < 0 for v in values):
        raise StatsError(f"counts must not be negative, got {values}")
    if sum(values) > MAX_COUNT:
        raise StatsError(f"{sum(values):.3g} rolls in all is more than the {MAX_COUNT:.0e} diefab can count")
    return np.array(values, dtype=np.int64)


def check_probabilities(p, name: str = "probabilities") -> np.ndarray:
    """(k,) float probabilities: finite, non-negative, summing to 1."""
    try:
        q = np.asarray(p, dtype=float)
    except (TypeError, ValueError) as exc:
        raise StatsError(f"{name} {p!r} are not numbers") from exc
    if q.ndim != 1 or q.size == 0:
        raise StatsError(f"{name} must be a non-empty list of numbers, got shape {q.shape}")
    if not np.all(np.isfinite(q)) or np.any(q < 0):
        raise StatsError(f"{name} must be finite and non-negative")
    if abs(q.sum() - 1) > PROBABILITY_SUM:
        raise StatsError(f"{name} sum to {q.sum():.6g}, not 1")
    return q


def _check_alpha(alpha) -> None:
    if isinstance(alpha, bool) or not isinstance(alpha, (int, float, np.floating)) or not 0 < alpha < 1:
        raise StatsError(f"alpha={alpha!r} must be a number in (0, 1)")


def _chi2_stat(counts: np.ndarray, expected: np.ndarray) -> np.ndarray:
    return (((counts - expected) ** 2) / expected).sum(axis=-1)


def goodness_of_fit(
    counts: Sequence[int],
    target: Sequence[float],
    *,
    alpha: float = 0.05,
    mc_samples: int = 100_000,
    seed: int = 0,
) -> GoodnessOfFit:
    """Chi-square and G tests, TVD, JSD and simultaneous intervals of `counts` against `target`.

    Parameters
    ----------
    counts : (k,) int
        Observed count of each value.
    target : (k,) float
        Target probabilities, summing to 1.
    alpha : float
        Significance level of the simultaneous intervals.
    mc_samples : int
        Multinomial samples for the Monte-Carlo p-value of the chi-square
        statistic (exact in the limit, valid for small expected counts).
    seed : int
        Seed of the Monte-Carlo p-value.
    """
    from scipy.stats import chi2

    x = check_counts(counts)
    p = check_probabilities(target, "target")
    if x.shape != p.shape:
        raise StatsError(f"{x.size} counts for {p.size} target values")
    _check_alpha(alpha)
    if isinstance(mc_samples, bool) or not isinstance(mc_samples, (int, np.integer)) or not 1 <= mc_samples <= 10**7:
        raise StatsError(f"mc_samples={mc_samples!r} must be an integer in [1, 10^7]")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise StatsError(f"seed={seed!r} must be an integer >= 0")
    n = int(x.sum())
    if n == 0:
        raise StatsError("no rolls: all counts are zero")
    # a value the target never rolls, rolled: the target is rejected outright (p = 0 exactly)
    impossible = bool(np.any((p == 0) & (x > 0)))
    live = p > 0
    if live.sum() < 2:
        raise StatsError("the target gives only one value a chance: there is nothing to test")
    xs, ps = x[live], p[live]
    expected = n * ps
    stat = float(_chi2_stat(xs, expected))
    df = int(live.sum()) - 1
    sims = np.random.default_rng(seed).multinomial(n, ps, size=mc_samples)
    p_mc = (1 + np.count_nonzero(_chi2_stat(sims, expected) >= stat - 1e-9)) / (1 + mc_samples)
    nz = xs > 0
    g = float(2 * (xs[nz] * np.log(xs[nz] / expected[nz])).sum())
    obs = x / n
    if impossible:
        stat, g, p_mc = np.inf, np.inf, 0.0
    return GoodnessOfFit(
        counts=x,
        target=p,
        chi2=stat,
        df=df,
        p_value=float(chi2.sf(stat, df)),
        p_value_mc=float(p_mc),
        mc_samples=mc_samples,
        g=g,
        g_p_value=float(chi2.sf(g, df)),
        tvd=tvd(obs, p),
        jsd=jsd(p, obs),
        intervals=goodman_intervals(x, alpha),
        alpha=alpha,
    )


# ----------------------------------------------------------------------
# input


def parse_counts(text: str) -> np.ndarray:
    """Counts from text such as ``0,20,48`` or ``0 20 48``; an empty field is an error."""
    if not isinstance(text, str):
        raise StatsError(f"counts {text!r} are not text")
    stripped = text.strip()
    if not stripped:
        raise StatsError("no counts given")
    items = re.split(r"\s*[,;]\s*|\s+", stripped)
    out = []
    for k, s in enumerate(items, start=1):
        if not s:
            raise StatsError(f"count number {k} is empty in {_short(text)!r}")
        number = re.fullmatch(r"[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d{1,4})?", s) if len(s) <= 64 else None
        value = float(s) if number else math.nan
        if not (math.isfinite(value) and value == int(value)):
            raise StatsError(f"count {_short(s)!r} is not a whole number")
        if value < 0:
            raise StatsError(f"count {s!r} is negative")
        if value > MAX_COUNT:
            raise StatsError(f"count {_short(s)!r} is more than the {MAX_COUNT:.0e} rolls diefab can count")
        out.append(int(value))
    return check_counts(out)


def _short(text: str, width: int = 40) -> str:
    return text if len(text) <= width else text[: width - 3] + "..."


#: Column names a roll log's values are read from, in order of preference (exact, case-insensitive).
ROLL_COLUMNS = ("value", "roll", "result", "outcome", "face", "total")


def read_rolls(path: str | Path) -> np.ndarray:
    """Rolled values from a text or CSV log (see :func:`read_roll_column`).

    Returns
    -------
    (n,) int
        The rolls in order.
    """
    return read_roll_column(path)[0]


def read_roll_column(path: str | Path) -> tuple[np.ndarray, str | None]:
    """Rolled values from a text or CSV log, and the name of the column read.

    Accepted: a roll log (:mod:`diefab.stats.rolllog`); values separated by commas,
    spaces, semicolons or newlines, with ``#`` comments; or a CSV file whose
    header names a column ``value``, ``roll``, ``result``, ``outcome``,
    ``face`` or ``total`` (the first of these present, matched exactly and
    case-insensitively; full-line ``#`` comments).  ``+2`` and ``−3`` (true
    minus) are read as numbers.

    Returns
    -------
    rolls : (n,) int
        The rolls in order.
    column : str or None
        The header of the column read (None for a plain list of values).

    Raises
    ------
    StatsError
        Naming the file, line and token of the first bad value.
    """
    path = Path(path)
    if path.exists() and not path.is_file():
        raise StatsError(f"roll log {path} is not a regular file")
    if path.is_file():
        with open(path, "rb") as f:
            head = f.readline(256).decode("utf-8-sig", errors="replace")
        limit = ROLL_LOG_BYTES if is_roll_log(head) else MAX_LOG_BYTES  # a log diefab writes: read as far as written
        if path.stat().st_size > limit:
            raise StatsError(f"roll log {path} is larger than {limit >> 20} MiB")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise StatsError(f"cannot read roll log {path}: {exc}") from exc
    lines = [(i + 1, line) for i, line in enumerate(text.splitlines())]
    lines = [(i, line) for i, line in lines if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise StatsError(f"roll log {path} is empty")
    first = lines[0][1]
    if is_roll_log(first):
        values = read_log(path).values
        column: str | None = "value"
    elif re.search(r"[A-Za-z]", first.split("#", 1)[0]):
        values, column = _read_column(path, lines)
    else:
        column = None
        values = [
            parse_value(t, f"{path}:{i}")
            for i, line in lines
            for t in re.split(r"[,\s;]+", line.split("#", 1)[0].strip())
            if t
        ]
    if len(values) == 0:
        raise StatsError(f"roll log {path} has no rolls")
    return np.asarray(values, dtype=np.int64), column


def _read_column(path: Path, lines: list[tuple[int, str]]) -> tuple[list[int], str]:
    """The values of the preferred column of a CSV file with a header."""
    header = next(csv.reader(io.StringIO(lines[0][1])))
    names = [h.strip().lower() for h in header]
    column = next((names.index(h) for h in ROLL_COLUMNS if h in names), None)
    if column is None:
        raise StatsError(
            f"{path}:{lines[0][0]}: header {_short(lines[0][1].strip())!r} names no column {'/'.join(ROLL_COLUMNS)}"
        )
    name = header[column].strip()
    values = []
    for i, line in lines[1:]:
        row = next(csv.reader(io.StringIO(line)))
        if column >= len(row):
            raise StatsError(f"{path}:{i}: row has no column {name!r}")
        values.append(parse_value(row[column], f"{path}:{i}, column {name!r}"))
    return values, name


def counts_from_rolls(
    rolls: Sequence[int], support: Sequence[int], source: str | Path | None = None, of: str = "the target"
) -> np.ndarray:
    """Count each value of `support` in `rolls`; a roll outside the support is an error.

    The error names the first such roll by its place among the rolls,
    `source` (the file they were read from) when given, and what `support`
    holds the values `of`.
    """
    index = {int(v): i for i, v in enumerate(support)}
    bad = next((k for k, r in enumerate(rolls) if int(r) not in index), None)
    if bad is not None:
        where = f"{source}: " if source is not None else ""
        raise StatsError(
            f"{where}roll {bad + 1} of {len(rolls)} is {int(rolls[bad])}, "
            f"not a value of {of} ({', '.join(map(str, support))})"
        )
    return np.bincount([index[int(r)] for r in rolls], minlength=len(index)).astype(np.int64)
