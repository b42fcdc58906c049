"""Drops kept as they finish: one run's in a drop file, a whole search's in a folder of them.

A :class:`Checkpoint` runs only the drops its
:class:`~diefab.physics.dropfile.DropFile` does not hold and writes the file as
drops finish, at the end, and when the run is stopped or fails; a
:class:`DropStore` is a folder of drop files, one for each die body, physics
and seed a search drops, so that a stopped search run again drops only what
it had not.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from diefab.core.errors import PhysicsError
from diefab.physics.dropfile import UNKNOWN, DropFile, drops_identity
from diefab.physics.simulate import PhysicsSettings, SimulationInterrupted, simulate

__all__ = ["Checkpoint", "DropStore"]


class Checkpoint:
    """One run's drops kept in a drop file: those it already holds, and new ones as they finish.

    :meth:`run` simulates only the drops the file does not hold and writes
    the file while drops run (every :attr:`EVERY` seconds at least, and at
    least :attr:`SHARE` times the last write's own time apart, so that writing
    takes at most a twentieth of the run), at the end, and when the run is
    stopped or a worker dies.
    """

    #: Seconds between two writes while drops run, at least.
    EVERY = 10.0
    #: Times the last write's own time between two writes, at least.
    SHARE = 20.0

    def __init__(self, file: DropFile, design, settings, seed: int, n: int, *, identity: str | None = None) -> None:
        self.file, self.design, self.settings, self.seed, self.n = file, design, settings, int(seed), int(n)
        self.identity = identity or drops_identity(design, settings, seed)
        self.all = file.load(self.identity, self.n, faces=len(design.polyhedron.faces))  # n or more drops
        self.known = self.all[: self.n]
        self.held = int(np.count_nonzero(self.known != UNKNOWN))
        self.last, self.latest, self.wait = time.monotonic(), None, self.EVERY

    def keep(self, outcomes: np.ndarray) -> None:
        """Note the run's outcomes so far; write them if the last write is long enough ago."""
        self.latest = outcomes  # the run's own array: what has finished, should the run fail
        if time.monotonic() - self.last >= self.wait:
            self.store(outcomes)

    def store(self, outcomes: np.ndarray) -> None:
        """Write `outcomes` (the run's first n drops) and whatever more drops the file held."""
        start = time.monotonic()
        self.all[: self.n] = outcomes
        self.file.save(self.identity, self.all)
        self.last = time.monotonic()
        self.wait = max(self.EVERY, self.SHARE * (self.last - start))

    def run(self, **options):
        """Drop the design n times on this checkpoint's seed and settings, keeping every drop.

        `options` are the other arguments of
        :func:`~diefab.physics.simulate.simulate` (`workers`, `scheduler`,
        `progress`).  A stop
        (:class:`~diefab.physics.simulate.SimulationInterrupted`) or a dead
        worker (:class:`~diefab.core.errors.PhysicsError`) is raised after the
        drops that finished are written.
        """
        try:
            result = simulate(self.design, self.n, seed=self.seed, settings=self.settings, known=self.known,
                              keep=self.keep, **options)  # fmt: skip
        except SimulationInterrupted as exc:
            if exc.outcomes is not None:
                self.store(exc.outcomes)
            raise
        except PhysicsError:
            if self.latest is not None:
                self.store(self.latest)
            raise
        self.store(result.outcomes)
        return result


class DropStore:
    """A folder of drop files, one for each die body, physics and seed dropped: every drop of a long search.

    :meth:`run` drops a die as :meth:`Checkpoint.run` does, in the file named
    by the run's :func:`~diefab.physics.dropfile.drops_identity` (`settings`
    None: the design's ``[physics]`` table, as for
    :func:`~diefab.physics.simulate.simulate`), so a search run again with the same
    folder finds the drops it made before and drops only the others;
    :attr:`drops` and :attr:`resumed` count the drops asked for and those
    found.  Other runs (another target's search, say) may share the folder:
    their files are left alone and :meth:`held` does not count them.
    """

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.drops = self.resumed = 0
        self.files: dict[Path, None] = {}  # the drop files this store ran, in order

    def run(self, design, settings, seed: int, n: int, **options):
        """Drop `design` `n` times under `settings` on `seed`, keeping every drop, as :meth:`Checkpoint.run` does."""
        settings = settings if settings is not None else PhysicsSettings.from_mapping(design.physics)
        identity = drops_identity(design, settings, seed)
        path = self.folder / f"{identity[:32]}.npz"
        self.files[path] = None
        file = DropFile(path)
        result = Checkpoint(file, design, settings, seed, n, identity=identity).run(**options)
        self.drops += result.n
        self.resumed += result.resumed
        return result

    def held(self) -> int:
        """The drops held now by the files this store ran: those the same search run again finds.

        A file that is missing or not a drop file counts none.
        """
        held = 0
        for path in self.files:
            try:
                held += DropFile(path).count()
            except PhysicsError:
                continue
        return held
