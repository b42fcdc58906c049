"""Physics validation: drop the die many times in pybullet and count the faces.

The paper (§2 end, §3) checks its die by rigid-body simulation: the die starts
about 5 units above the ground in a random orientation with a random spin,
restitution 0.3, friction 0.8, and the face it comes to rest on is counted.
:func:`simulate` does that in parallel worker processes (or on a Dask
cluster), reproducibly: drop *i* draws its initial conditions from
``SeedSequence(seed, spawn_key=(i,))``, so the same seed gives the same
counts whatever the number of workers or batches.

A drop ends on a face, **cocked** (at rest with no face within
``face_tolerance`` degrees of straight down) or **unsettled** (still moving at
``time_limit``); cocked and unsettled drops are reported, never assigned to a
face.  The engine itself lives in :mod:`diefab.physics.world`; see there for units
(model units, gravity 9.81 units/s², unit density) and for the fast path's
stopping rule.

The settings of a drop are :class:`~diefab.dice.drop.PhysicsSettings`
(re-exported here).
"""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from diefab.core.errors import DesignError, PhysicsError
from diefab.core.files import signals_deferred
from diefab.dice.design import Design
from diefab.dice.drop import PhysicsSettings
from diefab.made.fill import Fill
from diefab.physics.cluster import dask_client, gather
from diefab.physics.dropfile import UNKNOWN
from diefab.physics.pool import SIGNAL_POLL, shutdown_pool, worker_pool

__all__ = [
    "MAX_DROPS",
    "DropOutcome",
    "PhysicsSettings",
    "RollResult",
    "SimulationInterrupted",
    "classify_pose",
    "dask_client",
    "drop",
    "plot_validation",
    "shutdown_pool",
    "simulate",
]

#: More drops than this in one call is taken as a typo.
MAX_DROPS = 100_000_000

# ----------------------------------------------------------------------
# results


@dataclass(frozen=True, eq=False)
class RollResult:
    """Outcome of `n` simulated drops.

    Attributes
    ----------
    faces : tuple of str
        Face names, polyhedron order.
    face_counts : (m,) int
        Drops that came to rest on each face.
    cocked, unsettled : int
        Drops at rest on no face / still moving at the time limit.
    outcomes : (n,) int32
        Per drop: the face index, -1 cocked or -2 unsettled (drop *i* is
        the same for the same seed whatever the workers).
    seconds : float
        Wall-clock time of the simulation.
    settings : PhysicsSettings
    seed : int
    resumed : int
        Drops whose outcomes were given (``known``), not run.
    """

    faces: tuple[str, ...]
    face_counts: np.ndarray
    cocked: int
    unsettled: int
    outcomes: np.ndarray
    seconds: float
    settings: PhysicsSettings
    seed: int = 0
    resumed: int = 0

    @property
    def n(self) -> int:
        """Drops simulated."""
        return len(self.outcomes)

    @property
    def landed(self) -> int:
        """Drops that came to rest on a face."""
        return int(self.face_counts.sum())

    @property
    def drops_per_second(self) -> float:
        return (self.n - self.resumed) / self.seconds if self.seconds > 0 else float("inf")

    @property
    def face_probabilities(self) -> np.ndarray:
        """(m,) float: share of the landed drops on each face."""
        return self.face_counts / max(self.landed, 1)

    def value_counts(self, design: Design) -> np.ndarray:
        """(k,) int: landed drops per value of ``design.support`` (increasing)."""
        if tuple(design.polyhedron.names) != self.faces:
            raise PhysicsError(f"design {design.name!r} has faces {design.polyhedron.names}, the result {self.faces}")
        from diefab.models.probabilities import to_values

        if tuple(design.polyhedron.names) != self.faces:
            raise PhysicsError(f"design {design.name!r} has faces {design.polyhedron.names}, the result {self.faces}")
        return to_values(design, self.face_counts).astype(np.int64)

    def value_probabilities(self, design: Design) -> np.ndarray:
        """(k,) float: share of the landed drops on each value."""
        return self.value_counts(design) / max(self.landed, 1)


class SimulationInterrupted(KeyboardInterrupt):
    """Ctrl-C during :func:`simulate`; `done` drops of `total` had finished, their outcomes in `outcomes`.

    `outcomes` is (total,) int32, :data:`~diefab.physics.dropfile.UNKNOWN`
    for each drop that had not finished (None when not known).
    """

    def __init__(self, done: int, total: int, outcomes: np.ndarray | None = None) -> None:
        super().__init__(f"interrupted after {done} of {total} drops")
        self.done, self.total, self.outcomes = done, total, outcomes


# ----------------------------------------------------------------------
# single drops, for tests and inspection


@dataclass(frozen=True)
class DropOutcome:
    """One drop: ``face`` (name, or None when cocked/unsettled) and ``status``."""

    face: str | None
    status: str  # "face", "cocked" or "unsettled"


def _body(design: Design, fill: Fill | None = None):
    from diefab.physics.world import die_body

    return die_body(design.polyhedron, design.mass_properties(fill))


def _outcome(design: Design, code: int) -> DropOutcome:
    from diefab.physics.world import COCKED

    if code >= 0:
        return DropOutcome(design.polyhedron.names[code], "face")
    return DropOutcome(None, "cocked" if code == COCKED else "unsettled")


def classify_pose(design: Design, rotation, *, tolerance: float = 3.0) -> str | None:
    """The face lying on the ground when the die has orientation `rotation`, or None (cocked).

    Parameters
    ----------
    rotation : (3, 3) float
        Model coordinates -> world (z up).
    tolerance : float
        Degrees between the face's outward normal and straight down.
    """
    r = np.asarray(rotation, dtype=float)
    if r.shape != (3, 3) or not np.allclose(r @ r.T, np.eye(3), atol=1e-9) or np.linalg.det(r) < 0:
        raise PhysicsError(f"rotation must be a (3, 3) rotation matrix, got shape {r.shape}")
    down = r.T @ np.array([0.0, 0.0, -1.0])
    cos = design.polyhedron.normals @ down
    k = int(np.argmax(cos))
    return design.polyhedron.names[k] if cos[k] >= np.cos(np.radians(tolerance)) else None


def drop(
    design: Design,
    rotation,
    height: float,
    *,
    linear_velocity=(0.0, 0.0, 0.0),
    angular_velocity=(0.0, 0.0, 0.0),
    settings: PhysicsSettings | None = None,
    plain: bool = False,
) -> DropOutcome:
    """Drop `design` once from explicit initial conditions.

    Parameters
    ----------
    rotation : (3, 3) float
        Initial orientation, model coordinates -> world (z up).
    height : float
        Initial height of the centre of mass, model units.
    linear_velocity, angular_velocity : (3,) float
        World frame, units/s and rad/s.
    plain : bool
        Use the straightforward reference loop instead of the fast path.
    """
    from scipy.spatial.transform import Rotation

    from diefab.physics.world import World

    settings = settings or PhysicsSettings.from_mapping(design.physics)
    body = _body(design)
    r = np.asarray(rotation, dtype=float)
    if r.shape != (3, 3) or not np.allclose(r @ r.T, np.eye(3), atol=1e-9) or np.linalg.det(r) < 0:
        raise PhysicsError(f"rotation must be a (3, 3) rotation matrix, got shape {r.shape}")
    quat = Rotation.from_matrix(r @ body.rotation).as_quat()  # body (principal) frame -> world
    state = np.array([0.0, 0.0, float(height), *quat, *linear_velocity, *angular_velocity], dtype=float)
    world = World(body, settings, slots=1, engine_defaults=plain)
    try:
        code = world.run_plain(state[None])[0] if plain else world.run(state[None])[0]
    finally:
        world.close()
    return _outcome(design, int(code))


# ----------------------------------------------------------------------
# the parallel run


#: Fewest drops of a batch sent to a worker (five worlds' worth of slots: a batch's last drops run in a world
#: left mostly idle, and its free falls are integrated together, so a small batch costs more per drop).
MIN_BATCH = 120


def _batches(todo: np.ndarray, workers: int) -> list[tuple[int, int]]:
    """Index ranges covering the drops of mask `todo`, run by run of consecutive drops."""
    # small enough to balance the workers and move the progress bar, big enough to keep them busy
    size = int(np.clip(int(todo.sum()) // (workers * 16), MIN_BATCH, 512))
    flips = np.flatnonzero(np.diff(np.concatenate([[0], todo.astype(np.int8), [0]])))
    out = []
    for start, stop in zip(flips[::2], flips[1::2]):
        edges = np.linspace(start, stop, -(-(stop - start) // size) + 1).round().astype(int)  # equal sizes
        out.extend((int(a), int(b)) for a, b in zip(edges[:-1], edges[1:]))
    return out


def _check_run(design: Design, n, seed, workers, settings: PhysicsSettings) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= MAX_DROPS:
        raise PhysicsError(f"n={n!r} drops must be an integer in [1, {MAX_DROPS}]")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise PhysicsError(f"seed={seed!r} must be an integer >= 0")
    if workers is None:
        workers = os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or not 1 <= workers <= 1024:
        raise PhysicsError(f"workers={workers!r} must be an integer in [1, 1024]")
    try:
        design.check_stable(0.0)
    except DesignError as exc:
        raise PhysicsError(str(exc)) from None
    return int(workers)


def simulate(
    design: Design,
    n: int,
    *,
    seed: int = 0,
    workers: int | None = None,
    settings: PhysicsSettings | None = None,
    scheduler=None,
    progress: Callable[[int, int], None] | None = None,
    known: np.ndarray | None = None,
    keep: Callable[[np.ndarray], None] | None = None,
) -> RollResult:
    """Drop `design` `n` times and count the faces it comes to rest on.

    Parameters
    ----------
    design : Design
        Simulated with its fill's mass properties, in model units.
    n : int
        Number of drops.
    seed : int
        Drop *i* uses ``SeedSequence(seed, spawn_key=(i,))``: the same seed gives
        the same outcomes whatever `workers`, `scheduler` or batching
        (common random numbers for comparing designs).
    workers : int, optional
        Worker processes (default: all cores); 1 runs in this process.  The
        pool is kept for the next call.
    settings : PhysicsSettings, optional
        Default: the design's ``[physics]`` table over the paper's defaults.
    scheduler : str or distributed.Client, optional
        Run the batches on this Dask cluster instead of local processes.
    progress : callable(done, total), optional
        Called as batches finish.
    known : (n,) int array, optional
        Outcomes of drops already run (a stopped run's, from a
        :class:`~diefab.physics.dropfile.DropFile`), with
        :data:`~diefab.physics.dropfile.UNKNOWN` for each drop still to run;
        only those are run.
    keep : callable(outcomes), optional
        Called with the (n,) outcomes so far (``UNKNOWN`` for drops not yet
        finished) after each batch, to keep them.

    Raises
    ------
    PhysicsError
        Bad `n`, `seed`, `workers` or settings, an unstable design, a die
        that would start inside the ground, an unreachable scheduler.
    SimulationInterrupted
        On Ctrl-C, with the number of drops that had finished.
    """
    from concurrent.futures.process import BrokenProcessPool

    from diefab.core.stopping import check_stop
    from diefab.physics.world import COCKED, UNSETTLED, run_batch

    settings = settings or PhysicsSettings.from_mapping(design.physics)
    workers = _check_run(design, n, seed, workers, settings)
    body = _body(design)
    if settings.drop_height - settings.height_jitter <= body.radius:
        raise PhysicsError(
            f"physics drop_height={settings.drop_height:g} - height_jitter={settings.height_jitter:g} "
            f"must exceed the die's radius {body.radius:.3f} so that it starts above the ground"
        )
    n, seed = int(n), int(seed)
    outcomes = _known(known, n, len(design.polyhedron.faces))
    resumed = done = int(np.count_nonzero(outcomes != UNKNOWN))
    started = time.perf_counter()

    def finished(start: int, stop: int, codes: np.ndarray) -> None:
        nonlocal done
        outcomes[start:stop] = codes
        done += stop - start
        if progress is not None:
            progress(done, n)
        if keep is not None:
            keep(outcomes)

    try:
        batches = _batches(outcomes == UNKNOWN, 1 if scheduler is None and workers == 1 else workers)
        if scheduler is not None:
            client, own = dask_client(scheduler)  # first: a missing Dask is one line naming the extra
            try:
                futures = client.map(run_batch, [body] * len(batches), [settings] * len(batches), [seed] * len(batches),
                                     [a for a, _ in batches], [b for _, b in batches], pure=False)  # fmt: skip
                where = {f.key: batch for f, batch in zip(futures, batches)}
                try:
                    gather(client, futures, lambda f: finished(*where[f.key], f.result()), check_stop)
                except BaseException:
                    with contextlib.suppress(Exception):
                        client.cancel(futures)
                    raise
            finally:
                if own:
                    with contextlib.suppress(Exception):
                        client.close(timeout=2)
        elif workers == 1:
            for start, stop in batches:
                finished(start, stop, run_batch(body, settings, seed, start, stop))
                check_stop()
        else:
            from concurrent.futures import FIRST_COMPLETED, wait

            pool = worker_pool(workers)
            # A stop raised inside the pool's calls can leave a future's lock held, and the pool's own
            # thread then waits on it for ever when the run is stopped: stops are noted there, and raised
            # between the calls.
            with signals_deferred():
                pending = {pool.submit(run_batch, body, settings, seed, a, b): (a, b) for a, b in batches}
            while pending:
                # the timeout brings the main thread back now and then, to raise a stop noted meanwhile
                with signals_deferred():  # a result is read under its future's lock too
                    ready, _ = wait(pending, timeout=SIGNAL_POLL, return_when=FIRST_COMPLETED)
                    results = [(pending.pop(future), future.result()) for future in ready]
                for batch, codes in results:
                    finished(*batch, codes)
                check_stop()  # an interrupt that landed where it was swallowed (inside the pool's machinery)
    except KeyboardInterrupt:
        if scheduler is None and workers > 1:
            shutdown_pool(kill=True)
        raise SimulationInterrupted(done, n, outcomes.copy()) from None
    except BrokenProcessPool as exc:
        shutdown_pool(kill=True)
        raise PhysicsError(f"a simulation worker process died ({exc}); {done} of {n} drops had finished") from None
    except BaseException:  # a batch's own error, or a callback's (a full disk under `keep`): no batch runs on
        if scheduler is None and workers > 1:
            shutdown_pool(kill=True)
        raise
    seconds = time.perf_counter() - started
    face_counts = np.bincount(outcomes[outcomes >= 0], minlength=len(design.polyhedron.faces))
    return RollResult(
        faces=tuple(design.polyhedron.names),
        face_counts=face_counts.astype(np.int64),
        cocked=int(np.count_nonzero(outcomes == COCKED)),
        unsettled=int(np.count_nonzero(outcomes == UNSETTLED)),
        outcomes=outcomes,
        seconds=seconds,
        settings=settings,
        seed=seed,
        resumed=resumed,
    )


def _known(known: np.ndarray | None, n: int, faces: int) -> np.ndarray:
    """(n,) int32 outcomes to start from: `known`'s, or every drop still to run."""
    from diefab.physics.world import UNSETTLED

    if known is None:
        return np.full(n, UNKNOWN, dtype=np.int32)
    known = np.asarray(known)
    if known.shape != (n,) or known.dtype.kind not in "iu":
        raise PhysicsError(f"known outcomes of shape {known.shape} must be {n} integers")
    ran = known[known != UNKNOWN]
    if ran.size and not (ran.min() >= UNSETTLED and ran.max() < faces):
        raise PhysicsError(f"known outcomes must be face indices below {faces}, cocked or unsettled")
    return known.astype(np.int32)


# ----------------------------------------------------------------------
# the chart


def plot_validation(design: Design, result: RollResult, *, fmt: str = "png", alpha: float = 0.05,
                    model: str | None = None) -> bytes:  # fmt: skip
    """Bar chart of simulated value probabilities (with simultaneous CIs), target and a landing model.

    Returns the image as bytes (`fmt` ``png`` or ``svg``); the caller writes it.
    `model` is a key of :data:`diefab.models.MODELS` (default: the one to trust
    for the die, :func:`diefab.models.choice.best_model`).
    """
    import io

    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from diefab.models.probabilities import value_probabilities
    from diefab.stats.goodness import goodman_intervals

    if fmt not in ("png", "svg"):
        raise PhysicsError(f"plot format {fmt!r} must be png or svg")
    values = design.support
    counts = result.value_counts(design)
    sim = counts / max(counts.sum(), 1)
    ci = goodman_intervals(counts, alpha) if counts.sum() else np.zeros((len(values), 2))
    target = design.target_distribution.aligned(values)
    from diefab.models.choice import best_model

    name = model or best_model(design).name
    model = value_probabilities(design, name)
    x = np.arange(len(values))
    fig = Figure(figsize=(7.5, 4.2), dpi=120)
    ax = fig.add_subplot()
    w = 0.27
    ax.bar(x - w, sim, w, yerr=[sim - ci[:, 0], ci[:, 1] - sim], capsize=3, color="#3b75af",
           label=f"simulated ({result.landed} drops, {1 - alpha:.0%} simultaneous CI)")  # fmt: skip
    ax.bar(x, target, w, color="#9e9e9e", label=f"target {design.target}")
    ax.bar(x + w, model, w, color="#e5a04b", label=f"{name} model")
    from diefab.dice.design import format_value

    ax.set_xticks(x, [format_value(int(v), min(values) < 0) for v in values])
    ax.set_xlabel("value")
    ax.set_ylabel("probability")
    extra = f", {result.cocked} cocked, {result.unsettled} unsettled" if result.cocked or result.unsettled else ""
    ax.set_title(f"{design.name}: {result.n} pybullet drops{extra}", fontsize=10)
    ax.legend(fontsize=8, frameon=False)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt)
    return buf.getvalue()
