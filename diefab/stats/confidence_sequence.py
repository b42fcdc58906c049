"""The confidence sequence behind the anytime-valid test: a set of distributions valid at every roll.

A fixed-N p-value is only valid if the number of rolls was fixed in advance;
looking at it after every roll and stopping when it looks good inflates the
error rate without bound.  This module builds a *confidence sequence* for the
die's true distribution ``p`` over the target's k values, valid at every
number of rolls at once, and reads two verdicts off it:

- **within** δ: every distribution in the confidence set lies within total
  variation distance δ of the target (strictly);
- **off** by at least δ: every distribution in the set lies at TVD >= δ.

Method
------
For any fixed ``p``, the mixture likelihood ratio

.. math:: M_n(p) = \\frac{\\int \\prod_i q(x_i)\\, \\pi(dq)}{\\prod_i p(x_i)}

is a nonnegative martingale with mean 1 when the rolls are drawn from ``p``,
for any mixing prior :math:`\\pi` fixed before the first roll.  diefab mixes,
in equal shares, the Krichevsky--Trofimov Dirichlet(1/2, ..., 1/2) and
Dirichlet priors centered on the target, ``Dir(beta t + 0.05)`` for beta in
:data:`CONCENTRATIONS`; each is a ratio of Beta functions of the counts ``c``.
By Ville's inequality, :math:`P(\\exists n: M_n(p) \\ge 1/\\alpha) \\le \\alpha`,
so the sets :math:`C_n = \\{p : M_n(p) < 1/\\alpha\\}` all hold the true
``p`` at once with probability at least 1 - α.  :math:`C_n` is a
log-likelihood ball: ``sum c_j log(p̂_j / p_j) < r_n`` with the radius
``r_n = log(1/α) + regret_n``, where the regret (the log of the best
likelihood over the mixture's) grows like ``(k-1)/2 log n`` for an arbitrary
die and much more slowly for a die near its target.

The TVD bounds over :math:`C_n` are computed exactly:

- the largest TVD is ``max_S max_{p in C_n} p(S) - t(S)`` over subsets S of
  values; the inner maximum is a binomial problem, ``n kl(c(S)/n, s) <= r_n``
  (the same radius for every S), solved in closed form up to a bisection.
  Subsets are enumerated up to :data:`EXACT_VALUES` values; above that a
  conservative (wider) bound ``sum_j (u_j - t_j)^+`` over single values is
  used, which keeps the guarantee.
- the smallest TVD is the smallest δ at which the TVD ball around the target
  reaches the log-likelihood threshold; the most likely distribution in a
  TVD ball is ``p_j = clip(t_j, a c_j, b c_j)`` for two scalars a <= b.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.special import gammaln, logsumexp, xlogy

from diefab.stats.goodness import tvd

__all__ = [
    "CONCENTRATIONS",
    "EXACT_VALUES",
    "FLOOR",
    "PRIOR",
    "ball_max_loglik",
    "confidence_radius",
    "log_mixture_likelihood",
    "off_reached",
    "tvd_bounds",
    "within_reached",
]

#: Dirichlet prior weight per value of the uncentered component (Krichevsky--Trofimov: near-minimax regret).
PRIOR = 0.5
#: Concentrations of the Dirichlet components centered on the target (prior sample sizes, rolls).
CONCENTRATIONS = (30.0, 300.0, 3_000.0, 30_000.0)
#: Prior weight added to every value in the centered components (so a value the target excludes may occur).
FLOOR = 0.05
#: Most values (of nonzero count or target weight) for which the largest TVD is found exactly.
EXACT_VALUES = 16
#: Bisection steps (each halves an interval of at most 1: 2^-60 is below float precision).
_STEPS = 60
#: Subset-sum table entries evaluated at once (bounds memory to tens of MB).
_CHUNK = 1 << 18


def _rows(counts) -> np.ndarray:
    c = np.asarray(counts, dtype=float)
    return c[None, :] if c.ndim == 1 else c


def _log_dirichlet(c: np.ndarray, a: np.ndarray) -> np.ndarray:
    """(m,) log probability of a sequence with counts c (m, k) under the Dirichlet(a) mixture."""
    n = c.sum(axis=1)
    return (gammaln(c + a) - gammaln(a)).sum(axis=1) + gammaln(a.sum()) - gammaln(n + a.sum())


def log_mixture_likelihood(counts, target=None) -> np.ndarray | float:
    """Log of the mixture probability of a sequence with these counts.

    The mixing prior is fixed in advance: the Krichevsky--Trofimov
    Dirichlet(1/2, ..., 1/2) and, given a target, Dirichlet priors centered
    on it with concentrations :data:`CONCENTRATIONS`, in equal shares.  The
    centered ones cost little when the die is near its target, as made
    dice are; KT keeps the cost for any die near (k-1)/2 log n.

    Parameters
    ----------
    counts : (k,) or (m, k) float
        Counts per value (real counts are allowed: projections use them).
    target : (k,) float, optional

    Returns
    -------
    float or (m,) float, nats

    Examples
    --------
    One roll of a two-valued die has mixture probability 1/2:

    >>> round(float(np.exp(log_mixture_likelihood([1, 0]))), 6)
    0.5
    """
    c = _rows(counts)
    k = c.shape[1]
    parts = [_log_dirichlet(c, np.full(k, PRIOR))]
    if target is not None:
        t = np.asarray(target, float)
        parts += [_log_dirichlet(c, beta * t + FLOOR) for beta in CONCENTRATIONS]
    out = logsumexp(np.stack(parts), axis=0) - np.log(len(parts))
    return float(out[0]) if np.ndim(counts) == 1 else out


def _max_loglik(c: np.ndarray) -> np.ndarray:
    n = c.sum(axis=1, keepdims=True)
    return (xlogy(c, c) - xlogy(c, n)).sum(axis=1)


def confidence_radius(counts, alpha: float = 0.05, target=None) -> np.ndarray | float:
    """Radius r_n (nats) of the log-likelihood confidence set after these counts.

    The confidence set is ``{p : sum_j c_j log(p̂_j / p_j) < r_n}``; it holds
    the die's distribution at every n at once with probability >= 1 - alpha.

    Examples
    --------
    Before any roll the radius is log(1/alpha):

    >>> round(confidence_radius([0, 0, 0], alpha=0.05), 4) == round(float(np.log(20)), 4)
    True
    """
    c = _rows(counts)
    out = _max_loglik(c) - _rows_mix(c, target) + np.log(1 / alpha)
    return float(out[0]) if np.ndim(counts) == 1 else out


def _rows_mix(c: np.ndarray, target) -> np.ndarray:
    return np.atleast_1d(log_mixture_likelihood(c, target))


def _kl(x: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Bernoulli KL divergence kl(x || s), nats; +inf where s excludes what x has."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return xlogy(x, x) - xlogy(x, s) + xlogy(1 - x, 1 - x) - xlogy(1 - x, 1 - s)


def _solve_increasing(f, lo: np.ndarray, hi: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """Vectorized bisection: the smallest x in [lo, hi] with f(x) >= goal (f nondecreasing)."""
    lo, hi = lo.astype(float).copy(), hi.astype(float).copy()
    for _ in range(_STEPS):
        mid = 0.5 * (lo + hi)
        up = f(mid) >= goal
        hi = np.where(up, mid, hi)
        lo = np.where(up, lo, mid)
    return hi


def _raise_scale(c: np.ndarray, t: np.ndarray, knee: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(m,) the a > 0 with sum_j (a c_j - t_j)^+ = d, exactly (the sum is piecewise linear in a)."""
    order = np.argsort(knee, axis=1)
    ks = np.take_along_axis(knee, order, axis=1)
    cs = np.cumsum(np.take_along_axis(c, order, axis=1), axis=1)
    ts = np.cumsum(np.take_along_axis(t, order, axis=1), axis=1)
    nxt = np.concatenate([ks[:, 1:], np.full((len(ks), 1), np.inf)], axis=1)
    with np.errstate(invalid="ignore"):
        reach = np.where(cs > 0, nxt * cs - ts, -np.inf) >= d[:, None]  # the sum at the next knee
    m = np.argmax(reach, axis=1)[:, None]
    return ((d[:, None] + np.take_along_axis(ts, m, axis=1)) / np.take_along_axis(cs, m, axis=1))[:, 0]


def _lower_scale(c: np.ndarray, t: np.ndarray, knee: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(m,) the b with sum_j (t_j - b c_j)^+ = d, exactly; inf when the unrolled values hold d."""
    order = np.argsort(-knee, axis=1)  # unrolled values (knee inf) first: always lowered
    ks = np.take_along_axis(knee, order, axis=1)
    cs = np.cumsum(np.take_along_axis(c, order, axis=1), axis=1)
    ts = np.cumsum(np.take_along_axis(t, order, axis=1), axis=1)
    nxt = np.concatenate([ks[:, 1:], np.zeros((len(ks), 1))], axis=1)
    with np.errstate(invalid="ignore"):
        reach = np.where(cs > 0, ts - nxt * cs, ts) >= d[:, None]  # the sum at the next knee down
    m = np.argmax(reach, axis=1)[:, None]
    cm, tm = np.take_along_axis(cs, m, axis=1)[:, 0], np.take_along_axis(ts, m, axis=1)[:, 0]
    with np.errstate(divide="ignore"):
        return np.where(cm > 0, (tm - d) / np.where(cm > 0, cm, 1), np.inf)


def ball_max_loglik(counts, target, delta) -> np.ndarray | float:
    """Largest log-likelihood ``sum c_j log p_j`` over distributions within TVD `delta` of `target`.

    The maximizer is ``p_j = clip(t_j, a c_j, b c_j)``: values rolled more
    often than the target are raised, the others lowered, by `delta` in all,
    each in proportion to its count.

    Parameters
    ----------
    counts : (k,) or (m, k) float
    target : (k,) float
    delta : float or (m,) float, TVD in [0, 1]

    Returns
    -------
    float or (m,) float, nats (``-inf`` if every such distribution excludes a rolled value)

    Examples
    --------
    Within TVD 0.1 of a fair coin, 7 heads in 10 are best explained by 0.6:

    >>> v = ball_max_loglik([3, 7], [0.5, 0.5], 0.1)
    >>> bool(np.isclose(v, 3 * np.log(0.4) + 7 * np.log(0.6)))
    True
    """
    c = _rows(counts)
    t = np.broadcast_to(np.asarray(target, float), c.shape)
    n = c.sum(axis=1)
    best = _max_loglik(c)
    with np.errstate(divide="ignore"):
        at_target = (xlogy(c, t)).sum(axis=1)
        at_target = np.where(np.any((c > 0) & (t <= 0), axis=1), -np.inf, at_target)
    phat = c / np.where(n > 0, n, 1)[:, None]
    dist = 0.5 * np.abs(phat - t).sum(axis=1)
    d = np.broadcast_to(np.asarray(delta, float), n.shape)
    out = np.where(dist <= d, best, at_target)
    todo = (dist > d) & (d > 0) & (n > 0)
    if np.any(todo):
        cc, tt, dd = c[todo], t[todo], d[todo]
        with np.errstate(divide="ignore"):
            knee = np.where(cc > 0, tt / np.where(cc > 0, cc, 1), np.inf)  # a c_j passes t_j beyond a = knee_j
        a = _raise_scale(cc, tt, knee, dd)
        b = _lower_scale(cc, tt, knee, dd)
        with np.errstate(invalid="ignore"):
            p = np.maximum(a[:, None] * cc, np.minimum(tt, b[:, None] * cc))
        out[todo] = xlogy(cc, np.where(cc > 0, p, 1)).sum(axis=1)
    return float(out[0]) if np.ndim(counts) == 1 else out


def _threshold(c: np.ndarray, alpha: float, target) -> np.ndarray:
    """Log-likelihood a distribution must exceed to stay in the confidence set."""
    return _rows_mix(c, target) - np.log(1 / alpha)


def off_reached(counts, target, delta: float, alpha: float = 0.05) -> np.ndarray:
    """Whether every distribution in the confidence set is at TVD >= `delta` from `target`.

    Parameters
    ----------
    counts : (m, k) or (k,) float

    Returns
    -------
    (m,) bool
    """
    c = _rows(counts)
    return np.atleast_1d(ball_max_loglik(c, target, delta)) <= _threshold(c, alpha, target)


def _live(c: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Values that matter: rolled at least once or of positive target weight."""
    return np.any(c > 0, axis=0) | (t > 0)


def _subset_sums(v: np.ndarray) -> np.ndarray:
    """(m, 2^k) sums of the columns of v (m, k) over every subset (bit j of the index = value j)."""
    m, k = v.shape
    out = np.zeros((m, 1 << k))
    for j in range(k):
        out[:, 1 << j : 2 << j] = out[:, : 1 << j] + v[:, j : j + 1]
    return out


def within_reached(counts, target, delta: float, alpha: float = 0.05) -> np.ndarray:
    """Whether every distribution in the confidence set is within TVD `delta` (strictly) of `target`.

    Exact over all subsets of values up to :data:`EXACT_VALUES` live values;
    above, a sufficient condition (the per-value bound), so a "within" is
    never claimed that the exact set would not support.

    Returns
    -------
    (m,) bool
    """
    c = _rows(counts)
    t = np.asarray(target, float)
    r = np.atleast_1d(confidence_radius(c, alpha, t))
    live = _live(c, t)
    c, t = c[:, live], t[live]
    n = c.sum(axis=1)
    out = np.zeros(len(c), dtype=bool)
    ok = n > 0
    if not np.any(ok):
        return out
    x = c[ok] / n[ok, None]
    # singletons and their complements: necessary, cheap, and enough beyond EXACT_VALUES
    need = np.all(_beyond(x, t, delta, n[ok], r[ok]) & _beyond(1 - x, 1 - t, delta, n[ok], r[ok]), axis=1)
    if c.shape[1] > EXACT_VALUES:
        u = _upper(x, n[ok], r[ok])
        out[np.flatnonzero(ok)] = np.clip(u - t, 0, None).sum(axis=1) < delta
        return out
    rows = np.flatnonzero(ok)[need]
    k = c.shape[1]
    ts = _subset_sums(t[None, :])[0]
    # Subsets that refuted earlier rows refute most later ones too: test those first (a
    # necessary condition, cheap), and enumerate all subsets only for the rows they pass.
    witnesses = np.zeros((k, 0))
    step = max(1, _CHUNK >> k)
    while len(rows):
        if witnesses.shape[1]:
            xw = (c[rows] / n[rows, None]) @ witnesses
            keep = np.all(_beyond(xw, (t @ witnesses)[None, :], delta, n[rows], r[rows]), axis=1)
            rows = rows[keep]
        idx, rows = rows[:step], rows[step:]
        if not len(idx):
            break
        xs = _subset_sums(c[idx] / n[idx, None])
        fine = _beyond(xs, ts[None, :], delta, n[idx], r[idx])
        out[idx] = np.all(fine, axis=1)
        refuting = np.unique(np.argmin(fine, axis=1)[~out[idx]])
        bits = (refuting[None, :] >> np.arange(k)[:, None]) & 1
        witnesses = np.concatenate([witnesses, bits.astype(float)], axis=1)
    return out


def _beyond(x: np.ndarray, t: np.ndarray, delta: float, n: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Whether probability t + delta of a set with frequency x is outside the confidence set."""
    s = t + delta
    with np.errstate(invalid="ignore"):
        far = n[:, None] * _kl(x, np.minimum(s, 1.0)) > r[:, None]
    return (s > 1) | ((x < s) & far)


def _upper(x: np.ndarray, n: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Largest s with n kl(x, s) <= r, elementwise (x (m, j); n, r (m,))."""
    nn, rr = np.broadcast_to(n[:, None], x.shape), np.broadcast_to(r[:, None], x.shape)

    def excess(s):
        return nn * _kl(x, s) - rr

    s = _solve_increasing(excess, x.copy(), np.ones_like(x), np.zeros_like(x))
    return np.where(nn * _kl(x, np.ones_like(x)) <= rr, 1.0, s)


def tvd_bounds(counts: Sequence[int], target, alpha: float = 0.05) -> tuple[float, float]:
    """Smallest and largest TVD to `target` over the confidence set after `counts`.

    Parameters
    ----------
    counts : (k,) int
    target : (k,) float

    Returns
    -------
    (low, high) : float
        A time-uniform confidence interval for the TVD between the die and
        the target: it holds at every n at once with probability >= 1 - alpha.

    Examples
    --------
    Before any roll nothing is known: anything from 0 to 1 - min(t):

    >>> tvd_bounds([0, 0], [0.5, 0.5])
    (0.0, 0.5)
    """
    c = np.asarray(counts, float)
    t = np.asarray(target, float)
    n = c.sum()
    if n == 0:
        return 0.0, float(1 - t.min())
    r = float(confidence_radius(c, alpha, t))
    threshold = float(_threshold(c[None, :], alpha, t)[0])
    live = _live(c[None, :], t)
    c, t = c[live], t[live]
    x = c / n
    if len(c) > EXACT_VALUES:
        high = float(np.clip(_upper(x[None, :], np.array([n]), np.array([r]))[0] - t, 0, None).sum())
    else:
        gap = (_subset_sums(x[None, :]) - _subset_sums(t[None, :]))[0]
        xs = _subset_sums(x[None, :])[0]
        # Pinsker: u(x) - x <= sqrt(r / 2n), so only subsets within that of the best gap can win
        best = int(np.argmax(gap))
        floor = float(_upper(xs[None, [best]], np.array([n]), np.array([r]))[0, 0] - xs[best] + gap[best])
        keep = np.flatnonzero(gap + np.sqrt(r / (2 * n)) >= floor)
        high = float((_upper(xs[None, keep], np.array([n]), np.array([r]))[0] - xs[keep] + gap[keep]).max())
    high = min(high, float(1 - t.min()))
    point = tvd(x, t)
    if ball_max_loglik(c, t, 0.0) > threshold:
        return 0.0, high
    # the smallest delta whose ball reaches the threshold: ball_max_loglik increases with delta;
    # four rounds of 64 evaluations at once narrow [0, point] to 64^-4 of it
    low, up = 0.0, point
    rows = np.broadcast_to(c, (65, len(c)))
    for _ in range(4):
        grid = np.linspace(low, up, 65)
        inside = ball_max_loglik(rows, t, grid) > threshold
        first = int(np.argmax(inside)) if inside.any() else 64
        low, up = grid[max(first - 1, 0)], grid[first]
    return float(low), float(max(high, low))
