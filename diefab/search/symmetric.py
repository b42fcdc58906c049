"""Symmetric dice that roll like a target because of how many faces carry each value.

A die whose symmetry maps every face onto every other (an isohedral die: the
cube, the octahedron, the bipyramids and trapezohedra) lands on each face
equally often under any physics, any table and any throw that does not
favour an orientation.  When a target's probabilities are all multiples of
``1 / m``, such a die with ``m`` faces rolls it exactly: ``p * m`` faces carry
each value.  binomial:4 is a 16-faced die, a d6 loaded to 1:3,2:3,3:3,4:3,5:3,6:5
a 20-faced one.

Only dice with a face parallel to each face are used, so the value is read on
the face that points up: bipyramids with an even number of sides and
trapezohedra with an odd number of kites.  Of each, the shape that topples
least easily (largest smallest tipping angle over any edge), no longer than
:data:`MAX_ASPECT` times its width, is chosen.  Opposite faces carry values
that sum to the same total when the target is symmetric, as on a d6.  Dice
whose smallest tipping angle is below :data:`MIN_TIPPING` roll on like a
ball, on the table as in the simulator, and are not offered.

When no fair die is steady enough, a **two-class** die may be: make the top
half of a bipyramid or trapezohedron steeper or flatter than the bottom and
its ``n`` top faces stay equally likely among themselves (probability ``a``
each), as do its ``n`` bottom faces (``b`` each), by the die's rotation and
mirror symmetry.  A target whose weights are ``alpha_v * x + beta_v * y``
over ``D`` with ``n * (x + y) = D`` is then rolled exactly once
``a / b = x / y``, that is once the top half takes ``x / (x + y)`` of the
landings.  2d6 is 24 faces, 12 at 2/36 and 12 at 1/36, and 3dF 18 faces, 9 at 2/27 and 9
at 1/27.  One number, the
top half's share, is left to tune, and every drop of a simulation measures
it (:func:`tune_share`).

Examples
--------
>>> from diefab.dice.targets import parse_target
>>> face_counts(parse_target("binomial:4"), 16).tolist()
[1, 4, 6, 4, 1]
>>> fair_faces(parse_target("2d6")), fair_shapes(36)  # 36 faces: it would tip too easily
(36, [])
>>> plan = two_class_plans(parse_target("2d6"))[0]
>>> plan.family, plan.faces, plan.share, plan.alpha, plan.beta
('bipyramid', 24, 0.6666666666666666, (0, 1, 1, 1, 2, 2, 2, 1, 1, 1, 0), (1, 0, 1, 2, 1, 2, 1, 2, 1, 0, 1))
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import cache
from math import gcd, lcm

import numpy as np
from scipy.optimize import minimize_scalar

from diefab.dice.families import family as get_family
from diefab.dice.targets import Target
from diefab.geometry.polyhedron import Polyhedron, face_margins
from diefab.search.tuning import Tuning, tune_share

__all__ = [
    "MAX_ASPECT",
    "MAX_FACES",
    "MIN_TIPPING",
    "Tuning",
    "TwoClass",
    "denominator",
    "face_counts",
    "fair_faces",
    "fair_shapes",
    "fair_values",
    "tipping_angle",
    "tune_share",
    "two_class_plans",
    "two_class_values",
]

#: Most faces of a fair die offered for a target.
MAX_FACES = 60
#: Longest extent over shortest of a fair die's shape.
MAX_ASPECT = 2.0
#: A probability is a multiple of 1/m when it is within this of one.
RATIONAL_TOLERANCE = 1e-9
#: Smallest tipping angle (degrees) of a die offered: below it, dice roll on and on.
MIN_TIPPING = 12.0
#: Shares of the top half a two-class die is asked for (further from 1/2 are hard to reach).
SHARE_RANGE = (0.3, 0.7)


def face_counts(target: Target, faces: int) -> np.ndarray | None:
    """(k,) int: how many of `faces` equally likely faces carry each value, or None if no count fits."""
    counts = target.probabilities * faces
    rounded = np.round(counts)
    if np.any(rounded < 1) or np.max(np.abs(counts - rounded)) > RATIONAL_TOLERANCE * faces:
        return None
    return rounded.astype(int)


def denominator(target: Target, largest: int = 10_000) -> int | None:
    """The least common denominator of `target`'s probabilities (up to `largest`), or None."""
    m = lcm(*[Fraction(float(p)).limit_denominator(largest).denominator for p in target.probabilities])
    return m if m <= largest and face_counts(target, m) is not None else None


def fair_faces(target: Target, max_faces: int = MAX_FACES) -> int | None:
    """The fewest faces of a fair die (an even number, at least 6) that rolls `target` exactly, or None."""
    m = denominator(target)
    if m is None:
        return None
    m *= -(-6 // m) if m < 6 else 1
    if m % 2:
        m *= 2
    return m if m <= max_faces else None


def tipping_angle(poly: Polyhedron, center: np.ndarray) -> float:
    """Smallest angle, degrees, by which the die resting on any face tips over an edge of it."""
    height = poly.offsets - poly.normals @ center
    return float(np.degrees(np.arctan2(face_margins(poly, center), height)).min())


def _aspect(poly: Polyhedron) -> float:
    extent = np.ptp(poly.vertices, axis=0)
    return float(extent.max() / extent.min())


def fair_shapes(faces: int) -> list[tuple[str, dict[str, float]]]:
    """Fair dice with `faces` faces, each with a parallel face: (family, params), steadiest shape of each.

    Dice whose tipping angle is below :data:`MIN_TIPPING` are left out.
    """
    return [(name, dict(params)) for name, params in _fair_shapes(faces)]


@cache
def _fair_shapes(faces: int) -> tuple[tuple[str, tuple[tuple[str, float], ...]], ...]:
    n = faces // 2
    if faces % 2 or n < 3:
        return ()
    name, key = ("bipyramid", "h") if n % 2 == 0 else ("trapezohedron", "t")
    fam = get_family(name)
    known = {p.name: p for p in fam.parameters}
    if not known["n"].lower <= n <= known["n"].upper:
        return ()
    bound = known[key]

    @cache  # the grid's points and the bounded search's are each built once
    def shape(x: float) -> Polyhedron:
        return fam.polyhedron({"n": n, key: float(x)})

    grid = np.linspace(bound.lower, bound.upper, 97)
    ok = [float(x) for x in grid if _aspect(shape(float(x))) <= MAX_ASPECT]
    if not ok:
        return ()
    score = [tipping_angle(p, p.centroid) for p in map(shape, ok)]
    i = int(np.argmax(score))
    lo, hi = ok[max(i - 1, 0)], ok[min(i + 1, len(ok) - 1)]
    if hi > lo:
        best = minimize_scalar(
            lambda x: -tipping_angle(shape(float(x)), shape(float(x)).centroid), bounds=(lo, hi), method="bounded",
            options={"xatol": 1e-6},
        )  # fmt: skip
        x, angle = (float(best.x), -best.fun) if -best.fun >= score[i] else (float(ok[i]), score[i])
    else:
        x, angle = float(ok[i]), score[i]
    return ((name, (("n", n), (key, round(x, 6)))),) if angle >= MIN_TIPPING else ()


def _spread(kinds: list, counts: list[int]) -> list:
    """`kinds[j]` repeated `counts[j]` times, each kind's copies as evenly spaced as they can be."""
    total = sum(counts)
    keyed = [((i + 0.5) / c, j, kind) for j, (kind, c) in enumerate(zip(kinds, counts)) for i in range(c)]
    order = sorted(keyed, key=lambda item: (item[0], item[1]))
    assert len(order) == total
    return [kind for _, _, kind in order]


def fair_values(poly: Polyhedron, target: Target, counts: np.ndarray) -> dict[str, int]:
    """Face name -> value: ``counts[j]`` faces carry ``target.values[j]``, spread round the die.

    Faces are taken in order of their direction's azimuth about the die's
    longest axis.  When every face has a parallel opposite face and the
    target is symmetric, each opposite pair sums to ``min + max`` of the
    values.
    """
    normals = poly.normals
    axis = np.argmax(np.ptp(poly.vertices, axis=0))
    a, b = [i for i in range(3) if i != axis]
    turn = np.arctan2(normals[:, b], normals[:, a])
    order = np.lexsort((normals[:, axis], np.round(turn, 9)))
    opposite = np.argmin(normals @ normals.T, axis=1)
    paired = bool(np.allclose(normals[opposite], -normals, atol=1e-9))
    values, q = target.values, counts
    symmetric = bool(np.array_equal(q, q[::-1]) and np.allclose(np.diff(values), np.diff(values)[0]))
    mid = len(values) // 2
    if paired and symmetric and (len(values) % 2 == 0 or q[mid] % 2 == 0):
        pair_kinds = [(int(values[j]), int(values[-1 - j])) for j in range((len(values) + 1) // 2)]
        pair_counts = [int(q[j]) for j in range(len(values) // 2)]
        if len(values) % 2:
            pair_counts.append(int(q[mid]) // 2)
        firsts, seen = [], set()
        for f in order:  # one face of each opposite pair, in azimuth order
            if f not in seen:
                firsts.append(int(f))
                seen.update((int(f), int(opposite[f])))
        out = {}
        for f, (v, w) in zip(firsts, _spread(pair_kinds, pair_counts)):
            out[poly.names[f]], out[poly.names[opposite[f]]] = v, w
        return out
    kinds = _spread([int(v) for v in values], [int(c) for c in q])
    return {poly.names[f]: v for f, v in zip(order, kinds)}


@dataclass(frozen=True)
class TwoClass:
    """A two-class die for a target: its shape's family and fair parameters, and the faces counted out.

    ``alpha[j]`` top faces and ``beta[j]`` bottom faces carry the target's
    ``j``-th value; the top half must take :attr:`share` of the landings.
    """

    family: str
    #: The fair shape; :attr:`other` (the bottom half's parameter) is tuned.
    params: dict[str, float]
    other: str
    n: int
    x: int
    y: int
    alpha: tuple[int, ...]
    beta: tuple[int, ...]
    #: Faces of the bottom class when it has not as many as the top (the icosahedral die: 12 and 30).
    m: int | None = None

    @property
    def bottom(self) -> int:
        """Faces of the bottom class (the top's :attr:`n` on a bipyramid or trapezohedron)."""
        return self.n if self.m is None else self.m

    @property
    def faces(self) -> int:
        return self.n + self.bottom

    def per_value(self, share: float) -> np.ndarray:
        """(k,) value probabilities when the top class takes `share` of the landings."""
        return np.array(self.alpha) * share / self.n + np.array(self.beta) * (1 - share) / self.bottom

    @property
    def share(self) -> float:
        """The top half's share of the landings that rolls the target exactly."""
        return self.x / (self.x + self.y)


def _split_counts(weights: np.ndarray, x: int, y: int, n: int) -> tuple[tuple[int, ...], tuple[int, ...]] | None:
    """alpha, beta >= 0 with alpha * x + beta * y = weights, alpha and beta each summing to n, or None.

    Among the solutions, the one whose values are most evenly split between
    the halves (least sum of |alpha - beta|, which also makes the die least
    sensitive to an error in the share).
    """
    # dynamic programme over values; state: top faces used so far
    best: dict[int, tuple[int, tuple[int, ...], tuple[int, ...]]] = {0: (0, (), ())}
    for w in weights:
        step: dict[int, tuple[int, tuple[int, ...], tuple[int, ...]]] = {}
        for used, (cost, alpha, beta) in best.items():
            for a in range(0, int(w) // x + 1):
                rest = int(w) - a * x
                if rest % y or used + a > n:
                    continue
                b = rest // y
                key = used + a
                entry = (cost + abs(a - b), (*alpha, a), (*beta, b))
                if key not in step or entry < step[key]:
                    step[key] = entry
        best = step
    if n not in best:
        return None
    _, alpha, beta = best[n]
    return (alpha, beta) if sum(beta) == n else None


def two_class_plans(target: Target, max_faces: int = MAX_FACES, enough: int | None = None) -> list[TwoClass]:
    """Two-class dice that roll `target` exactly at the right share, fewest faces first, then share nearest 1/2.

    With `enough`, the search stops after the first face count at which
    that many plans have been found (the list then starts as it would
    without it).
    """
    d = denominator(target)
    if d is None:
        return []
    plans = []
    for faces in range(6, max_faces + 1, 2):
        if enough is not None and len(plans) >= enough:
            break
        n = faces // 2
        for scale in range(1, 4):
            total, rest = divmod(scale * d, n)  # x + y
            if rest or total < 3:
                continue
            weights = np.round(target.probabilities * scale * d).astype(int)
            for x in range(1, total):
                y = total - x
                if x == y or gcd(x, y) != 1 or not SHARE_RANGE[0] <= x / total <= SHARE_RANGE[1]:
                    continue
                split = _split_counts(weights, x, y, n)
                if split is None or split[0] == split[1]:  # equal halves: the fair die already rolls it
                    continue
                for family, params in fair_shapes(faces):
                    other = "g" if family == "bipyramid" else "u"
                    plans.append(TwoClass(family, params, other, n, x, y, *split))
    return sorted(plans, key=lambda p: (p.faces, abs(p.share - 0.5)))


def two_class_values(poly: Polyhedron, target: Target, plan: TwoClass) -> dict[str, int]:
    """Face name -> value: ``plan.alpha`` counted out on the top class (the first faces), ``plan.beta`` on the rest."""
    values = [int(v) for v in target.values]
    top = _spread(values, list(plan.alpha))
    bottom = _spread(values[::-1], list(plan.beta)[::-1])  # high values below low ones: spread round the die
    names = poly.names
    return {**dict(zip(names[: plan.n], top)), **dict(zip(names[plan.n :], bottom))}
