"""What the stages of a design search share: the run's state, and what a stage returns.

:class:`SearchRun` holds one search's seed, drop budget, wall-time cap,
workers and reporters, and counts the drops every stage spends;
:class:`Synthesis` is a stage's result, and :func:`~diefab.search.synthesis.synthesize`'s.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from diefab.dice.design import Design
from diefab.search.counting import Counted

__all__ = ["RANK_MODEL", "SearchRun", "Synthesis"]

#: Model used to rank candidates and to start the simulation refinement.
RANK_MODEL = "fast"


@dataclass
class Synthesis:
    """What :func:`synthesize` found."""

    design: Design
    objective: float
    #: (k,) value probabilities under the model the design was optimized for.
    predicted: np.ndarray
    model: str
    #: Every candidate tried: family, faces, objective.
    tried: list[dict] = field(default_factory=list)
    #: Refinement steps: simulated TVD at each.
    steps: list[dict] = field(default_factory=list)
    #: How the die carries the target: "fair", "two-class" or "shaped".
    method: str = "shaped"
    #: True if the wall-time cap ended a stage early: the same seed and options may then give another die.
    capped: bool = False
    #: The fair or two-class die whose face counts come nearest the target (:mod:`diefab.search.counting`), if any.
    nearest: Counted | None = None
    #: Drops the search spent.
    drops: int = 0
    #: The simulated TVD of the die kept (the refinement's or the two-class tuning's), if it was simulated.
    simulated_tvd: float | None = None


@dataclass
class SearchRun:
    """What every stage of one search shares: its seed, drop budget, wall-time cap, workers and reporters."""

    seed: int
    max_drops: int
    deadline: float
    workers: int | None
    scheduler: Any
    settings: Any
    say: Callable[[str], None]
    tick: Callable[[str, int, int], None]
    used: int = 0
    capped: bool = False
    #: Largest TVD of a die that rolls like its target (a tuning stops once its error is well within it).
    tolerance: float = 0.02
    #: Where every drop is kept (a :class:`~diefab.physics.checkpoint.DropStore`), so that a stopped search run
    #: again drops only what it had not; None keeps nothing.
    store: Any = None
    #: The model optimizations kept beside the store's drops (made with the first one).
    memo: Any = None

    def optimize(self, design: Design, **options):
        """:func:`~diefab.search.optimize.optimize_design` of `design` before the search's deadline.

        With a :attr:`store`, each optimization is kept beside the drops
        (:class:`~diefab.search.memo.OptimizationMemo`), so a search run
        again takes the ones it made instead of repeating them.
        """
        if self.store is None:
            from diefab.search.optimize import optimize_design

            return optimize_design(design, deadline=self.deadline, **options)
        if self.memo is None:
            from diefab.search.memo import OptimizationMemo

            self.memo = OptimizationMemo(self.store.folder)
        return self.memo.optimize(design, deadline=self.deadline, **options)

    def note_cap(self) -> None:
        """Record that the wall-time cap has passed (the stage that just ended may have been cut)."""
        self.capped = self.capped or time.monotonic() > self.deadline

    def simulate(self, design: Design, n: int, seed: int, stage: str, settings=None, total: int | None = None):
        """Drop `design` `n` times, counting the drops against the budget and ticking `stage`.

        The stage's progress runs to `total` drops of the whole search
        (default: the budget).
        """
        from diefab.physics.simulate import simulate

        before = self.used
        end = min(self.max_drops if total is None else max(total, before + n), self.max_drops)
        settings = settings if settings is not None else self.settings
        run = {"workers": self.workers, "scheduler": self.scheduler,
               "progress": lambda done, _: self.tick(stage, min(before + done, end), end)}  # fmt: skip
        if self.store is None:
            result = simulate(design, n, seed=seed, settings=settings, **run)
        else:
            result = self.store.run(design, settings, seed, n, **run)
        self.used += n
        self.tick(stage, min(self.used, end), end)
        return result
