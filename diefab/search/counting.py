"""The nearest a counted die comes to a target: fair and two-class dice whose face counts only approximate it.

A fair die with ``m`` faces rolls value ``v`` with probability ``c_v / m``,
where ``c_v >= 1`` faces carry it; a two-class die with ``n`` faces on each
half rolls it with ``(a_v s + b_v (1 - s)) / n``, where ``a_v`` top and
``b_v`` bottom faces carry it and the top half takes a tunable share ``s``
of the landings (:mod:`diefab.search.symmetric`).  When the target's probabilities
are not such numbers (3d6 needs 1/216 on 16 values), the best such die is
the one whose counts come closest in total variation distance (TVD).

:func:`nearest_counts` finds a fair die's counts exactly: the TVD is a
separable convex function of the counts, so moving one face at a time to
the value that gains most is optimal.  :func:`nearest_two_class` finds a
two-class die's counts by dynamic programming over the values on a grid of
shares, then the best share for those counts exactly (the TVD is convex and
piecewise linear in the share, so it is least at a breakpoint).

Only face counts of dice that stay steady (:func:`~diefab.search.symmetric.fair_shapes`)
are offered, so :func:`nearest_dice` is also the limit of what a counted die
can do for a target.

Examples
--------
>>> from diefab.dice.targets import parse_target
>>> counts, distance = nearest_counts(parse_target("2d6"), 12)
>>> counts.tolist(), distance
([1, 1, 1, 1, 1, 2, 1, 1, 1, 1, 1], Fraction(1, 6))
>>> counts, distance = nearest_counts(parse_target("uniform:3"), 6)
>>> counts.tolist(), distance
([2, 2, 2], Fraction(0, 1))
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import cache

import numpy as np

from diefab.dice.targets import Target
from diefab.search.symmetric import MAX_FACES, SHARE_RANGE, TwoClass, fair_shapes

__all__ = [
    "Counted",
    "exact_probabilities",
    "nearest_counts",
    "nearest_dice",
    "nearest_icosahedral",
    "nearest_two_class",
]

#: Largest denominator used to read a target's probabilities as fractions.
MAX_DENOMINATOR = 1_000_000
#: The pentagons' share of the landings an icosahedral die (12 pentagons, 30 hexagons) is asked for: the drops
#: give it this share while it tips by at least 12 degrees.
ICOSAHEDRAL_SHARES = (0.1, 0.3)


def _share_grid(lo: float, hi: float) -> np.ndarray:
    """Shares searched for a two-class die's counts (refined exactly afterwards): a grid on [lo, hi], and the
    fractions x / t with t up to 16 in it, where targets with small denominators are carried exactly."""
    return np.array(sorted({*np.round(np.linspace(lo, hi, 41), 12).tolist(),
                            *(x / t for t in range(2, 17) for x in range(1, t) if lo <= x / t <= hi)}))  # fmt: skip


SHARE_GRID = _share_grid(*SHARE_RANGE)


def exact_probabilities(target: Target) -> list[Fraction]:
    """The target's probabilities as fractions summing to exactly 1 (nearest with denominator up to 10**6)."""
    q = [Fraction(float(p)).limit_denominator(MAX_DENOMINATOR) for p in target.probabilities]
    total = sum(q)
    return [p / total for p in q]


def _tvd(probabilities: list[Fraction], goal: list[Fraction]) -> Fraction:
    return sum((abs(p - g) for p, g in zip(probabilities, goal)), Fraction(0)) / 2


def nearest_counts(target: Target, faces: int) -> tuple[np.ndarray, Fraction | None]:
    """Face counts of a fair die with `faces` faces nearest `target`, and their exact TVD.

    Every value gets at least one face; the counts minimize
    ``sum |c_v / faces - p_v| / 2``.  Returns ``(counts, None)`` (a
    zero-padded count) when there are fewer faces than values.

    Returns
    -------
    counts : (k,) int
    tvd : Fraction or None
    """
    goal = exact_probabilities(target)
    k = len(goal)
    if faces < k:
        return np.array([1] * faces + [0] * (k - faces)), None
    counts = [max(1, int(p * faces)) for p in goal]  # floor, at least one

    def cost(j: int, c: int) -> Fraction:
        return abs(Fraction(c, faces) - goal[j])

    while sum(counts) < faces:  # add the face that lowers the distance most
        j = min(range(k), key=lambda i: (cost(i, counts[i] + 1) - cost(i, counts[i]), i))
        counts[j] += 1
    while sum(counts) > faces:  # take away the face whose loss raises it least
        j = min((i for i in range(k) if counts[i] > 1), key=lambda i: (cost(i, counts[i] - 1) - cost(i, counts[i]), i))
        counts[j] -= 1
    return np.array(counts), _tvd([Fraction(c, faces) for c in counts], goal)


@dataclass(frozen=True)
class Counted:
    """A fair or two-class die whose face counts come nearest a target, and how near (exact TVD)."""

    #: "fair" or "two-class".
    kind: str
    faces: int
    tvd: Fraction
    #: (k,) faces per value of a fair die.
    counts: tuple[int, ...] = ()
    #: The two-class die, its share the one that comes nearest.
    plan: TwoClass | None = None

    def probabilities(self) -> np.ndarray:
        """(k,) the value probabilities the die rolls (at its best share, for a two-class die)."""
        if self.plan is None:
            return np.array(self.counts, dtype=float) / self.faces
        return self.plan.per_value(self.plan.share)


def _split(goal: np.ndarray, n: int, s: float, m: int | None = None) -> tuple[float, np.ndarray, np.ndarray] | None:
    """Top and bottom counts (summing to `n` and `m`, every value at least one face) nearest `goal` at share `s`.

    A top face lands with probability ``s / n``, a bottom face with
    ``(1 - s) / m`` (`m` defaults to `n`).  Dynamic programme over the
    values; state: (top faces, bottom faces) used.
    """
    m = n if m is None else m
    k = len(goal)
    inf = np.inf
    top, bottom = s, (1 - s) * n / m  # a face's probability, times n
    cost = np.full((n + 1, m + 1), inf)
    cost[0, 0] = 0.0
    choice = np.zeros((k, n + 1, m + 1, 2), dtype=np.int16)
    for j, w in enumerate(goal * n):
        new = np.full((n + 1, m + 1), inf)
        pick = np.zeros((n + 1, m + 1, 2), dtype=np.int16)
        for a in range(0, min(n, int(w / top) + 2) + 1):
            rest = (w - a * top) / bottom
            for b in {max(0, int(np.floor(rest))), max(0, int(np.ceil(rest)))} | ({1} if a == 0 else set()):
                if a + b < 1 or b > m:
                    continue
                err = abs(a * top + b * bottom - w)
                shifted = np.full((n + 1, m + 1), inf)
                shifted[a:, b:] = cost[: n + 1 - a, : m + 1 - b] + err
                better = shifted < new
                new[better] = shifted[better]
                pick[better] = (a, b)
        cost = new
        choice[j] = pick
    if not np.isfinite(cost[n, m]):
        return None
    alpha, beta = np.zeros(k, dtype=int), np.zeros(k, dtype=int)
    i, jb = n, m
    for j in range(k - 1, -1, -1):
        a, b = choice[j, i, jb]
        alpha[j], beta[j] = a, b
        i, jb = i - a, jb - b
    return float(cost[n, m]), alpha, beta


def _best_share(
    alpha, beta, n: int, goal: list[Fraction], m: int | None = None, shares: tuple[float, float] = SHARE_RANGE
) -> tuple[Fraction, Fraction]:
    """The share in `shares` at which counts `alpha`, `beta` (`n` and `m` faces) come nearest `goal`, and that TVD."""
    m = n if m is None else m
    lo, hi = (Fraction(x).limit_denominator(100) for x in shares)
    points = {lo, hi}
    for a, b, g in zip(alpha, beta, goal):
        slope = Fraction(a, n) - Fraction(b, m)
        if slope:
            s = (g - Fraction(b, m)) / slope
            if lo <= s <= hi:
                points.add(s)

    def distance(s: Fraction) -> Fraction:
        return _tvd([a * s / n + b * (1 - s) / m for a, b in zip(alpha, beta)], goal)

    best = min(sorted(points), key=distance)
    return best, distance(best)


def _nearest_split(
    goal: list[Fraction], n: int, m: int, shares: tuple[float, float], grid: np.ndarray
) -> tuple[Fraction, Fraction, np.ndarray, np.ndarray] | None:
    """(TVD, share, alpha, beta) of the two-class counts nearest `goal`, over `grid`, refined exactly; or None."""
    g = np.array([float(p) for p in goal])
    found = [r for r in (_split(g, n, float(s), m) for s in grid) if r is not None]
    best = None
    for _, alpha, beta in sorted(found, key=lambda r: r[0])[:3]:
        if n == m and np.array_equal(alpha, beta):
            continue
        share, distance = _best_share(alpha.tolist(), beta.tolist(), n, goal, m, shares)
        if best is None or distance < best[0]:
            best = (distance, share, alpha, beta)
    return best


def nearest_two_class(target: Target, faces: int) -> Counted | None:
    """The two-class die with `faces` faces (a steady fair shape's) nearest `target`, or None."""
    shapes = fair_shapes(faces)
    n = faces // 2
    if not shapes or 2 * n < len(target.values):
        return None
    best = _nearest_split(exact_probabilities(target), n, n, SHARE_RANGE, SHARE_GRID)
    if best is None:
        return None
    distance, share, alpha, beta = best
    family, params = shapes[0]
    x, y = share.numerator, share.denominator - share.numerator
    plan = TwoClass(family, params, "g" if family == "bipyramid" else "u", n, x, y,
                    tuple(int(a) for a in alpha), tuple(int(b) for b in beta))  # fmt: skip
    return Counted("two-class", faces, distance, plan=plan)


def nearest_icosahedral(target: Target) -> Counted | None:
    """The icosahedral die (12 pentagons, 30 hexagons; :mod:`diefab.dice.families.icosahedral`) nearest `target`.

    Its pentagons' share of the landings is kept in :data:`ICOSAHEDRAL_SHARES`.
    None when the target has more than 42 values.
    """
    n, m = 12, 30
    if n + m < len(target.values):
        return None
    best = _nearest_split(exact_probabilities(target), n, m, ICOSAHEDRAL_SHARES, _icosahedral_grid())
    if best is None:
        return None
    distance, share, alpha, beta = best
    x, y = share.numerator, share.denominator - share.numerator
    plan = TwoClass("icosahedral", {"d": 1.0}, "d", n, x, y, tuple(int(a) for a in alpha),
                    tuple(int(b) for b in beta), m=m)  # fmt: skip
    return Counted("two-class", n + m, distance, plan=plan)


@cache
def _icosahedral_grid() -> np.ndarray:
    return _share_grid(*ICOSAHEDRAL_SHARES)


def nearest_dice(target: Target, max_faces: int = MAX_FACES, faces: int | None = None) -> list[Counted]:
    """Fair and two-class dice of steady shapes with at most `max_faces` faces, nearest `target` first.

    Parameters
    ----------
    faces : int, optional
        Only dice with this many faces.

    Returns
    -------
    list of Counted
        Sorted by TVD, then by face count (fair before two-class at a tie).
    """
    found = []
    sizes = [faces] if faces is not None else range(6, max_faces + 1, 2)
    unsteady = 0
    for m in sizes:
        if m < len(target.values):  # every value needs a face: the shapes of fewer faces are not asked for
            continue
        steady = m % 2 == 0 and bool(fair_shapes(m))
        # the steadiest fair shape tips more easily the more faces it has: once both families (bipyramids for
        # an even half, trapezohedra for an odd one) have failed in a row, every larger die fails too
        unsteady = 0 if steady else unsteady + 1
        if unsteady >= 2 and m > 6:
            break
        if not steady:
            continue
        counts, distance = nearest_counts(target, m)
        if distance is not None:
            found.append(Counted("fair", m, distance, counts=tuple(int(c) for c in counts)))
        two = nearest_two_class(target, m)
        if two is not None:
            found.append(two)
    if (faces is None and max_faces >= 42) or faces == 42:
        ico = nearest_icosahedral(target)
        if ico is not None:
            found.append(ico)
    return sorted(found, key=lambda c: (c.tvd, c.faces, c.kind != "fair"))
