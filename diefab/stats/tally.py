"""A hand tally of rolls as a pure state machine: keys in, counts and verdict out.

One key per value, shown on screen; ``backspace`` or ``u`` undoes the last
roll, ``q`` or ``escape`` quits.  The tally never touches a file: each key
returns an :class:`Event` that the caller records (``diefab roll`` appends
it to the roll log), so the same keys always give the same state.

Examples
--------
>>> tally = Tally([-1, 0, 1], [0.25, 0.5, 0.25], delta=0.1)
>>> [tally.key_of(v) for v in (-1, 0, 1)]
['1', '2', '3']
>>> [tally.press(k).kind for k in "12u2x"]
['roll', 'roll', 'undo', 'roll', 'ignored']
>>> tally.counts.tolist(), tally.rolls
([1, 1, 0], [-1, 0])
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from diefab.core.errors import StatsError
from diefab.stats.sequential import SequentialResult, SequentialTest

__all__ = ["QUIT_KEYS", "UNDO_KEYS", "VALUE_KEYS", "Event", "Tally", "value_keys"]

#: Keys that undo the last roll.
UNDO_KEYS = ("backspace", "u")
#: Keys that end the tally.
QUIT_KEYS = ("q", "escape")
#: Keys given to values, in order (digits, then letters other than u and q).
VALUE_KEYS = tuple("1234567890abcdefghijklmnoprstvwxyz")


def value_keys(values: Sequence[int]) -> list[str]:
    """One key per value: the value itself when every value is a digit 0-9, else 1, 2, ... in order.

    >>> value_keys([1, 2, 3, 4, 5, 6])
    ['1', '2', '3', '4', '5', '6']
    >>> value_keys([-2, -1, 0, 1, 2])
    ['1', '2', '3', '4', '5']
    """
    values = [int(v) for v in values]
    if all(0 <= v <= 9 for v in values):
        return [str(v) for v in values]
    if len(values) > len(VALUE_KEYS):
        raise StatsError(f"{len(values)} values are more than the {len(VALUE_KEYS)} keys of a hand tally")
    return list(VALUE_KEYS[: len(values)])


@dataclass(frozen=True)
class Event:
    """What a key did: ``roll`` (of `value`), ``undo`` (of `value`), ``quit`` or ``ignored``."""

    kind: str
    value: int | None = None


class Tally:
    """Counts of a hand tally and their anytime-valid verdict.

    Parameters
    ----------
    values : (k,) int
        The die's values, increasing.
    target : (k,) float
        Target probability of each value.
    delta : float
        Tolerance in TVD of the verdict.
    rolls : sequence of int
        Rolls already made (a resumed log), values in the order rolled.
    alpha : float
        Error rate of the verdict.
    """

    def __init__(
        self, values: Sequence[int], target, delta: float, rolls: Sequence[int] = (), alpha: float = 0.05
    ) -> None:
        self.values = [int(v) for v in values]
        self.keys = value_keys(self.values)
        self._index = {v: i for i, v in enumerate(self.values)}
        self._by_key = dict(zip(self.keys, range(len(self.values))))
        self.test = SequentialTest(target, delta, alpha)
        bad = [r for r in rolls if int(r) not in self._index]
        if bad:
            raise StatsError(f"roll {bad[0]} is not a value of the die ({', '.join(map(str, self.values))})")
        self.test.extend([self._index[int(r)] for r in rolls])
        self._result: SequentialResult | None = None

    @property
    def target(self) -> np.ndarray:
        return self.test.target

    @property
    def counts(self) -> np.ndarray:
        """(k,) int counts of each value."""
        return self.test.counts

    @property
    def n(self) -> int:
        return self.test.n

    @property
    def rolls(self) -> list[int]:
        """The values rolled, in order."""
        return [self.values[i] for i in self.test._rolls]

    def key_of(self, value: int) -> str:
        """The key that records `value`."""
        return self.keys[self._index[int(value)]]

    def add(self, value: int) -> None:
        """Record a roll of `value` (a camera's reading, say) without a key."""
        if int(value) not in self._index:
            raise StatsError(f"roll {value} is not a value of the die ({', '.join(map(str, self.values))})")
        self.test.push(self._index[int(value)])
        self._result = None

    def press(self, key: str) -> Event:
        """Apply one key; returns what it did."""
        if key in self._by_key:
            i = self._by_key[key]
            self.test.push(i)
            self._result = None
            return Event("roll", self.values[i])
        if key in UNDO_KEYS:
            if self.n == 0:
                return Event("ignored")
            value = self.rolls[-1]
            self.test.pop()
            self._result = None
            return Event("undo", value)
        if key in QUIT_KEYS:
            return Event("quit")
        return Event("ignored")

    def revert(self, event: Event) -> None:
        """Undo what `event` did to the state (when recording it failed)."""
        if event.kind == "roll":
            self.test.pop()
        elif event.kind == "undo":
            self.test.push(self._index[event.value])
        self._result = None

    def result(self) -> SequentialResult:
        """The verdict now (cached until the next key that changes the counts)."""
        if self._result is None:
            self._result = self.test.result()
        return self._result
