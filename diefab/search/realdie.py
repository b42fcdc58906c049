"""Dice with real rolls: a design as made and how often each of its values was rolled.

A :class:`RealDie` is what calibration fits the physics to and what the
fidelity benchmarks score a model on: the die's design (its fill gives the
mass properties), its real counts per value, the outcomes the data name only
up to relabelling (mirror images, :attr:`RealDie.groups`) and the source's
own predictions if any.  :func:`real_die` reads counts or a roll log,
:func:`realrolls_die` a file of the real-rolls data.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from diefab.core.errors import DiefabError, StatsError
from diefab.dice.design import Design

__all__ = ["CalibrationError", "RealDie", "real_die", "realrolls_die"]


class CalibrationError(DiefabError, ValueError):
    """Real dice or calibration settings that cannot be used."""


@dataclass(frozen=True, eq=False)
class RealDie:
    """A die with real rolls.

    Parameters
    ----------
    name : str
    design : Design
        The die as made (its fill gives the mass properties).
    counts : (k,) int
        Real rolls of each value of ``design.support`` (increasing values).
    groups : tuple of tuple of int
        Indices into ``design.support`` of values the data name only up to
        relabelling (mirror-image faces); each group has two or more.
    reference : mapping str -> (k,) float
        Other predictions of the die to compare with (e.g. a source's own
        model), keyed by name.
    """

    name: str
    design: Design
    counts: np.ndarray
    groups: tuple[tuple[int, ...], ...] = ()
    reference: Mapping[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from diefab.stats.goodness import MAX_COUNT

        if not isinstance(self.name, str) or not self.name:
            raise CalibrationError(f"die name {self.name!r} must be a non-empty string")
        k = len(self.design.support)
        try:
            counts = np.asarray(self.counts, dtype=float)
        except (TypeError, ValueError):
            raise CalibrationError(f"die {self.name!r}: counts {self.counts!r} must be numbers") from None
        if counts.shape != (k,):
            raise CalibrationError(
                f"die {self.name!r}: {counts.size} counts for the {k} values {self.design.support} of "
                f"{self.design.name!r}"
            )
        if not np.all(np.isfinite(counts)) or np.any(counts < 0) or np.any(counts != np.round(counts)):
            raise CalibrationError(f"die {self.name!r}: counts {counts.tolist()} must be whole numbers >= 0")
        if counts.sum() > MAX_COUNT:
            raise CalibrationError(f"die {self.name!r}: {counts.sum():.3g} rolls in all is more than the "
                                   f"{MAX_COUNT:.0e} diefab can count")  # fmt: skip
        if counts.sum() <= 0:
            raise CalibrationError(f"die {self.name!r}: no real rolls")
        object.__setattr__(self, "counts", counts.astype(np.int64))
        seen: set[int] = set()
        for g in self.groups:
            if len(g) < 2 or any(not 0 <= i < k for i in g) or seen & set(g):
                raise CalibrationError(f"die {self.name!r}: group {list(g)} must name two or more distinct values")
            seen |= set(g)
        object.__setattr__(self, "groups", tuple(tuple(int(i) for i in g) for g in self.groups))
        ref = {}
        for key, p in self.reference.items():
            p = np.asarray(p, dtype=float)
            if p.shape != (k,) or not np.all(np.isfinite(p)) or np.any(p < 0) or p.sum() <= 0:
                raise CalibrationError(f"die {self.name!r}: reference {key!r} is not a distribution over {k} values")
            ref[key] = p / p.sum()
        object.__setattr__(self, "reference", ref)

    @property
    def n(self) -> int:
        """Real rolls."""
        return int(self.counts.sum())

    @property
    def frequencies(self) -> np.ndarray:
        return self.counts / self.n

    def tvd(self, p: np.ndarray, q: np.ndarray | None = None) -> float:
        """TVD of value probabilities `p` (over ``design.support``) to `q` (default: the real frequencies).

        Compared up to relabelling within :attr:`groups`, the least over
        relabellings: the data do not say which outcome of a group is which
        face.  Mass missing from `p` counts as on no value.
        """
        from diefab.physics.realrolls import grouped_tvd

        p = np.asarray(p, dtype=float)
        q = self.frequencies if q is None else np.asarray(q, dtype=float)
        return grouped_tvd(p, q, tuple(range(len(p))), self.groups) + 0.5 * max(0.0, 1.0 - float(p.sum()))

    def symmetrized(self, p: np.ndarray) -> np.ndarray:
        """`p` with each group's probabilities replaced by their mean."""
        p = np.array(p, dtype=float)
        for g in self.groups:
            p[list(g)] = p[list(g)].mean()
        return p

    def to_json(self) -> dict[str, Any]:
        from diefab.search.runid import pinned_toml

        return {
            "name": self.name,
            "design_toml": pinned_toml(self.design),
            "counts": self.counts.tolist(),
            "groups": [list(g) for g in self.groups],
            "reference": {k: v.tolist() for k, v in self.reference.items()},
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RealDie:
        from diefab.dice.design import parse_design

        design = parse_design(data["design_toml"], source=f"die {data['name']!r}")
        return cls(data["name"], design, np.array(data["counts"]), tuple(tuple(g) for g in data.get("groups", ())),
                   {k: np.array(v) for k, v in data.get("reference", {}).items()})  # fmt: skip


def real_die(name: str, design: Design, counts: Sequence[int] | str, **kwargs: Any) -> RealDie:
    """A :class:`RealDie` from counts per value or a roll-log path (see :func:`diefab.stats.goodness.read_rolls`)."""
    from pathlib import Path

    from diefab.stats.goodness import counts_from_rolls, parse_counts, read_rolls

    try:
        if isinstance(counts, str):
            path = Path(counts)
            if path.exists():  # a roll log; one that is no regular file (a folder, a pipe) is named as such
                counts = counts_from_rolls(read_rolls(path), design.support, path, of="the die")
            else:
                counts = parse_counts(counts)
    except StatsError as exc:
        raise CalibrationError(f"die {name!r}: {exc}") from None
    return RealDie(name, design, np.asarray(counts), **kwargs)


def realrolls_die(path) -> RealDie:
    """A :class:`RealDie` from a file of the real-rolls data (:func:`diefab.physics.realrolls.load_real_rolls`).

    Its design is the data's hull with the printed body's centre of mass and
    inertia; mirror-image outcomes become :attr:`RealDie.groups` and the
    source's own predictions its :attr:`RealDie.reference`.
    """
    from diefab.dice.design import parse_design

    try:
        from diefab.physics.realrolls import load_real_rolls
    except ImportError:
        raise CalibrationError(f"{path}: reading the real-rolls format needs diefab.physics.realrolls, which this "
                               "installation lacks") from None  # fmt: skip
    rolls = load_real_rolls(path)
    (text,) = rolls.design_files().values()
    design = parse_design(text, source=str(path))
    index = {v: i for i, v in enumerate(design.support)}
    missing = [o for o in rolls.outcomes if o not in index]
    if missing or len(index) != len(rolls.outcomes):
        raise CalibrationError(f"{path}: outcome {missing[0] if missing else '?'} has no face the die rests on")
    order = [index[o] for o in rolls.outcomes]

    def aligned(values) -> np.ndarray:
        out = np.zeros(len(index))
        out[order] = values
        return out

    groups = tuple(tuple(index[o] for o in g) for g in rolls.groups)
    reference = {k: aligned(v) for k, v in rolls.reference.items()}
    return RealDie(rolls.name, design, aligned(rolls.counts).astype(np.int64), groups, reference)
