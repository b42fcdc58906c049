"""Target distributions over die values.

A target is given by name or by explicit weights:

``4df``, ``NdF``
    the sum of N Fudge dice (faces -1, 0, +1): 4dF is 1 4 10 16 19 16 10 4 1 / 81;
``2d6``, ``3d6``, ``NdM``
    the sum of N fair M-sided dice;
``binomial:N`` or ``binomial:N:P``
    heads in N coin flips (P = 1/2 by default), values 0..N;
``uniform:N``
    values 1..N, equally likely;
``coins:N``
    the paper's substitute: N fair coins, heads - N/2, clamped into [-4, 4];
``1,4,10,...``
    weights for the design's values in increasing order;
``-1:1,0:2,1:1``
    explicit value:weight pairs.

Examples
--------
>>> t = parse_target("4df")
>>> t.values.tolist(), (t.probabilities * 81).round().astype(int).tolist()
([-4, -3, -2, -1, 0, 1, 2, 3, 4], [1, 4, 10, 16, 19, 16, 10, 4, 1])
"""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Sequence
from dataclasses import dataclass
from math import comb

import numpy as np

from diefab.core.errors import TargetError

__all__ = ["MAX_VALUE", "Target", "parse_target"]

#: Largest magnitude of a die value.
MAX_VALUE = 1e9


@dataclass(frozen=True, eq=False)
class Target:
    """A distribution over integer values.

    Parameters
    ----------
    spec : str
        What the user wrote.
    values : (k,) int, increasing
    probabilities : (k,) float, sums to 1
    """

    spec: str
    values: np.ndarray
    probabilities: np.ndarray

    def as_dict(self) -> dict[str, float]:
        """Value (as a string, e.g. ``"-4"``) -> probability."""
        return {str(int(v)): float(p) for v, p in zip(self.values, self.probabilities)}

    def aligned(self, values: Sequence[int]) -> np.ndarray:
        """Probabilities for `values` (which must be exactly this target's support)."""
        values = [int(v) for v in values]
        if sorted(values) != self.values.tolist():
            raise TargetError(
                f"target {self.spec!r} is over values {self.values.tolist()}, the design's values are {sorted(values)}"
            )
        lookup = dict(zip(self.values.tolist(), self.probabilities))
        return np.array([lookup[v] for v in values])


def _dice_sum(n: int, faces: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
    dist = np.array([1.0])
    for _ in range(n):
        dist = np.convolve(dist, np.ones(len(faces)))
    lo = n * min(faces)
    return np.arange(lo, lo + len(dist)), dist


def _normalized(spec: str, values, weights) -> Target:
    weights = np.asarray(weights, dtype=float)
    values = np.asarray(values, dtype=int)
    if weights.ndim != 1 or len(weights) == 0:
        raise TargetError(f"target {spec!r} has no weights")
    if not np.all(np.isfinite(weights)):
        raise TargetError(f"target {spec!r} has a weight that is not finite")
    if np.any(weights < 0):
        raise TargetError(f"target {spec!r} has a negative weight")
    if weights.max() <= 0:
        raise TargetError(f"target {spec!r} has all weights zero")
    if len(set(values.tolist())) != len(values):
        raise TargetError(f"target {spec!r} lists a value twice")
    order = np.argsort(values)
    weights = weights / weights.max()  # weights near the largest float would overflow their sum
    return Target(spec, values[order], weights[order] / weights.sum())


def _number(text: str, spec: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise TargetError(f"target {spec!r}: {text!r} is not a number") from None


def _integer(v) -> int:
    if isinstance(v, (bool, str)) or int(v) != v:
        raise ValueError(v)
    return int(v)


def parse_target(spec: str, values: Sequence[int] | None = None) -> Target:
    """Parse a target specification.

    Parameters
    ----------
    spec : str
        A name or weights, see the module documentation.
    values : sequence of int, optional
        The design's values, needed for a bare weight list (matched in
        increasing order) and checked against the support of any target.

    Raises
    ------
    TargetError
        If the specification is unknown, malformed, not a distribution, or
        does not fit `values`.
    """
    if not isinstance(spec, str):
        raise TargetError(f"target {spec!r} is not a string (a name such as 4df, or weights such as 1,4,10)")
    if values is not None:
        try:
            values = [_integer(v) for v in values]
        except (TypeError, ValueError):
            raise TargetError(f"the design's values {values!r} are not a sequence of integers") from None
    text = unicodedata.normalize("NFKC", spec).strip().lower().replace("\u2212", "-")  # fullwidth 2d6: 2d6
    if not text.isascii():
        raise TargetError(f"target {spec!r}: write it with ASCII letters and digits (4df, 2d6, 1,4,10)")
    target = _parse(text, spec, values)
    if values is not None:
        target.aligned(values)  # raises if the supports differ
    return target


def _parse(text: str, spec: str, values: Sequence[int] | None) -> Target:
    if m := re.fullmatch(r"(\d{1,9})d(f|\d{1,9})", text):
        n = int(m[1])
        if not 1 <= n <= 100:
            raise TargetError(f"target {spec!r}: number of dice must be 1..100")
        if m[2] == "f":
            return _normalized(spec, *_dice_sum(n, (-1, 0, 1)))
        sides = int(m[2])
        if not 2 <= sides <= 1000:
            raise TargetError(f"target {spec!r}: dice need 2..1000 sides")
        return _normalized(spec, *_dice_sum(n, range(1, sides + 1)))
    if m := re.fullmatch(r"binomial:(\d{1,9})(?::([0-9.eE+-]+))?", text):
        n, p = int(m[1]), _number(m[2], spec) if m[2] else 0.5
        if not (1 <= n <= 1000 and 0 < p < 1):
            raise TargetError(f"target {spec!r}: need 1 <= N <= 1000 and 0 < P < 1")
        k = np.arange(n + 1)
        return _normalized(spec, k, [comb(n, int(i)) * p**i * (1 - p) ** (n - i) for i in k])
    if m := re.fullmatch(r"uniform:(\d{1,9})", text):
        n = int(m[1])
        if not 2 <= n <= 1000:
            raise TargetError(f"target {spec!r}: need 2 <= N <= 1000")
        return _normalized(spec, np.arange(1, n + 1), np.ones(n))
    if m := re.fullmatch(r"coins:(\d{1,9})", text):
        n = int(m[1])
        if n % 2 or not 8 <= n <= 1000:
            raise TargetError(f"target {spec!r}: need an even number of coins, at least 8")
        heads = np.arange(n + 1)
        weights = np.array([comb(n, int(h)) for h in heads], dtype=float)
        clamped = np.clip(heads - n // 2, -4, 4)
        return _normalized(spec, np.arange(-4, 5), np.bincount(clamped + 4, weights=weights, minlength=9))
    if re.fullmatch(r"[-+0-9.eE]+(:[-+0-9.eE]+)?(\s*,\s*[-+0-9.eE]+(:[-+0-9.eE]+)?)*", text):
        items = [s.strip() for s in text.split(",")]
        if all(":" in s for s in items):
            pairs = [s.split(":") for s in items]
            keys = [_number(v, spec) for v, _ in pairs]
            if any(not (abs(k) <= MAX_VALUE and k == int(k)) for k in keys):
                raise TargetError(f"target {spec!r}: values must be integers of magnitude at most {MAX_VALUE:g}")
            return _normalized(spec, [int(k) for k in keys], [_number(w, spec) for _, w in pairs])
        if any(":" in s for s in items):
            raise TargetError(f"target {spec!r} mixes value:weight pairs and bare weights")
        weights = [_number(s, spec) for s in items]
        if values is None:
            support = list(range(len(weights)))
        else:
            support = sorted({int(v) for v in values})
            if len(support) != len(weights):
                raise TargetError(
                    f"target {spec!r} has {len(weights)} weights, the design has {len(support)} values {support}"
                )
        return _normalized(spec, support, weights)
    raise TargetError(f"unknown target {spec!r} (use 4df, NdM, binomial:N, uniform:N, coins:N, or weights like 1,4,10)")
