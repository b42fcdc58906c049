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

Examples
--------
>>> s = PhysicsSettings.from_mapping({"restitution": 0.5, "angular_velocity": [0, 20]})
>>> s.restitution, s.friction, s.angular_velocity
(0.5, 0.8, (0.0, 20.0))
>>> PhysicsSettings(friction=-1)
Traceback (most recent call last):
...
diefab.core.errors.PhysicsError: physics friction=-1.0 must be a finite number >= 0
"""

from __future__ import annotations

import contextlib
import math
import os
import signal
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, fields
from typing import Any

import numpy as np

from diefab.core.errors import DesignError, PhysicsError
from diefab.dice.design import Design
from diefab.made.mass import Fill

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
#: Settings added after the others, with the value that turns them off (the rigid simulation).
OPT_IN = {"capture_energy": 0.0}


def _check(name: str, value, ok: bool, expected: str) -> None:
    if not ok:
        raise PhysicsError(f"physics {name}={value!r} must be {expected}")


def _finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


@dataclass(frozen=True)
class PhysicsSettings:
    """Settings of a simulated drop (model units, seconds, radians; tolerance in degrees).

    Parameters
    ----------
    restitution : float
        Coefficient of restitution of die and ground, in [0, 1] (paper: 0.3).
    friction : float
        Coulomb (lateral) friction of die and ground, >= 0 (paper: 0.8).
    rolling_friction, spinning_friction : float
        Bullet's rolling and spinning friction, >= 0.
    time_step : float
        Simulation step, seconds, in (0, 0.05].
    solver_iterations : int
        Constraint-solver iterations per step, a fixed number (pybullet's
        default is up to 50 with an early exit on a residual, which would
        couple the dice stepped in one world; Bullet's own default is 10).
        For one die on a plane 5 already give the same distribution as
        pybullet's defaults (``benchmarks/bench_validate.py``).
    collision_margin : float
        Bullet's collision margin of the die, model units, in [0, 0.1].
    gravity : float
        Units/s² (the die is simulated in model units).
    drop_height : float
        Initial height of the centre of mass above the ground (paper: about 5).
    height_jitter : float
        The height is uniform in ``drop_height ± height_jitter``.
    angular_velocity : (float, float)
        Range of the initial spin, rad/s; uniform magnitude, uniform direction.
    linear_velocity : (float, float)
        Range of the initial horizontal speed, units/s; uniform heading.
    still_speed, still_spin : float
        A die is still when its speed (units/s) and spin (rad/s) are below these.
    settle_time : float
        Without the energy rule (``energy_fraction`` 0), a die still this
        long (s) on a face it can rest on, within ``face_tolerance`` of
        straight down, has landed on that face.  With it, a die has landed
        when it can no longer leave its face (see ``energy_fraction``) or
        has been still on it for ``cocked_time``: a short still window
        counts a die toppling slowly off a face as resting on it.
    cocked_time : float
        A die still this long (s) with no face down is cocked (a die
        momentarily balanced on an edge can be still for a short while).
    energy_fraction : float
        The landing rule: a die whose orientation lies in face f's basin
        (:class:`diefab.models.basins.RestBasins`) has landed on f once its kinetic
        energy plus potential energy above rest on f is below this fraction
        of the basin's barrier (its lowest saddle): it can no longer leave
        f.  0 turns the rule off (``settle_time`` then decides).  The rest
        is a margin for the engine's energy errors.  In [0, 1).
    capture_energy : float
        Quasi-static capture, in units of ``m g L`` (mass, gravity, the die's
        radius L: the largest distance from its centre of mass to a
        vertex).  A die in face f's basin whose kinetic energy plus
        potential energy above rest on f is below this has landed on f,
        even where that is above f's barrier: a real die loses its energy
        faster than a rigid hull on a rigid plane (plastic impacts, a table
        that gives), so a slow die stays in the basin it is in.  One
        threshold for all faces acts most in wide, shallow basins, which a
        rigid hull rolls out of.  0 (the default)
        turns it off: the rigid simulation.  Very large, every die lands in
        the basin of its orientation at the first check after it nears the
        ground, the quasi-static model.  In [0, 100].
    time_limit : float
        A die still moving after this many seconds is unsettled.
    face_tolerance : float
        Degrees: a settled die lies on a face when that face's outward normal
        is within this angle of straight down, otherwise it is cocked.
    """

    restitution: float = 0.3
    friction: float = 0.8
    rolling_friction: float = 0.0
    spinning_friction: float = 0.0
    time_step: float = 1.0 / 240.0
    solver_iterations: int = 5
    collision_margin: float = 0.001
    gravity: float = 9.81
    drop_height: float = 5.0
    height_jitter: float = 0.5
    angular_velocity: tuple[float, float] = (0.0, 10.0)
    linear_velocity: tuple[float, float] = (0.0, 0.0)
    still_speed: float = 0.02
    still_spin: float = 0.05
    settle_time: float = 0.1
    cocked_time: float = 1.0
    energy_fraction: float = 0.95
    capture_energy: float = 0.0
    time_limit: float = 20.0
    face_tolerance: float = 3.0

    def __post_init__(self) -> None:
        for name in ("angular_velocity", "linear_velocity"):
            value = getattr(self, name)
            if not isinstance(value, tuple):
                try:
                    value = tuple(value)
                except TypeError:
                    raise PhysicsError(f"physics {name}={value!r} must be a [min, max] pair") from None
                object.__setattr__(self, name, value)
            _check(name, list(value), len(value) == 2 and all(map(_finite, value)), "a [min, max] pair of numbers")
            object.__setattr__(self, name, (float(value[0]), float(value[1])))
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "solver_iterations":
                ok = isinstance(value, (int, np.integer)) and not isinstance(value, bool) and 1 <= value <= 1000
                _check(f.name, value, ok, "an integer in [1, 1000]")
                object.__setattr__(self, f.name, int(value))
            elif not isinstance(value, tuple):
                _check(f.name, value, _finite(value), "a finite number")
                object.__setattr__(self, f.name, float(value))
        c = _check
        c("restitution", self.restitution, 0 <= self.restitution <= 1, "in [0, 1]")
        for name in ("friction", "rolling_friction", "spinning_friction"):
            c(name, getattr(self, name), getattr(self, name) >= 0, "a finite number >= 0")
        c("time_step", self.time_step, 0 < self.time_step <= 0.05, "in (0, 0.05] seconds")
        c("collision_margin", self.collision_margin, 0 <= self.collision_margin <= 0.1, "in [0, 0.1] model units")
        c("gravity", self.gravity, 0 < self.gravity <= 1000, "in (0, 1000] units/s²")
        c("drop_height", self.drop_height, 0 < self.drop_height <= 1000, "in (0, 1000] model units")
        c("height_jitter", self.height_jitter, 0 <= self.height_jitter < self.drop_height,
          f"in [0, drop_height={self.drop_height:g})")  # fmt: skip
        for name, top in (("angular_velocity", 1000.0), ("linear_velocity", 100.0)):
            lo, hi = getattr(self, name)
            c(name, [lo, hi], 0 <= lo <= hi <= top, f"a range [min, max] with 0 <= min <= max <= {top:g}")
        c("still_speed", self.still_speed, self.still_speed > 0, "> 0 units/s")
        c("still_spin", self.still_spin, self.still_spin > 0, "> 0 rad/s")
        c("settle_time", self.settle_time, 0 <= self.settle_time <= 10, "in [0, 10] seconds")
        c("cocked_time", self.cocked_time, self.settle_time <= self.cocked_time <= 60,
          f"in [settle_time={self.settle_time:g}, 60] seconds")  # fmt: skip
        c("energy_fraction", self.energy_fraction, 0 <= self.energy_fraction < 1, "in [0, 1)")
        c("capture_energy", self.capture_energy, 0 <= self.capture_energy <= 100, "in [0, 100] (units of m g L)")
        c("time_limit", self.time_limit, self.cocked_time < self.time_limit <= 600,
          f"in (cocked_time={self.cocked_time:g}, 600] seconds")  # fmt: skip
        c("face_tolerance", self.face_tolerance, 0 < self.face_tolerance < 45, "in (0, 45) degrees")

    @classmethod
    def from_mapping(cls, mapping: Mapping[str, Any] | None, **overrides: Any) -> PhysicsSettings:
        """Settings from a design's ``[physics]`` table, then `overrides` (None values are ignored)."""
        if mapping is not None and not isinstance(mapping, Mapping):
            raise PhysicsError(f"physics settings {mapping!r} are not a table of name = value")
        data = dict(mapping or {})
        data.update({k: v for k, v in overrides.items() if v is not None})
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise PhysicsError(f"unknown physics setting {unknown[0]!r} (settings: {', '.join(sorted(known))})")
        return cls(**data)

    def as_dict(self) -> dict[str, Any]:
        """The settings as a plain mapping (ranges as lists), e.g. for JSON.

        An opt-in setting (:data:`OPT_IN`) at its off value is left out, so
        the mapping of settings that do not use it is the same as before it
        existed (stored runs and caches compare these mappings).
        """
        return {
            k: list(v) if isinstance(v, tuple) else v
            for k, v in asdict(self).items()
            if not (k in OPT_IN and v == OPT_IN[k])
        }


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
    """

    faces: tuple[str, ...]
    face_counts: np.ndarray
    cocked: int
    unsettled: int
    outcomes: np.ndarray
    seconds: float
    settings: PhysicsSettings
    seed: int = 0

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
        return self.n / self.seconds if self.seconds > 0 else float("inf")

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
    """Ctrl-C during :func:`simulate`; `done` drops of `total` had finished."""

    def __init__(self, done: int, total: int) -> None:
        super().__init__(f"interrupted after {done} of {total} drops")
        self.done, self.total = done, total


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

_POOL: Any = None
_POOL_SIZE = 0
_ATEXIT: list[bool] = []


def _pool(workers: int):
    """A reused pool of `workers` processes, each keeping one pybullet world."""
    global _POOL, _POOL_SIZE
    if _POOL is None or _POOL_SIZE != workers:
        shutdown_pool()
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        # fork starts a worker in milliseconds and needs no `if __name__ == "__main__"` guard in the
        # caller's script; the parent never holds a pybullet world the children would touch
        method = "fork" if sys.platform == "linux" else "spawn"
        # Start the workers now, with the stop signals held back: an interrupt raised inside a fork
        # hook (logging's lock release) is swallowed by Python, and the run would go on.
        with _signals_held():
            _POOL = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context(method),
                                        initializer=_worker_start, initargs=(os.getpid(),))  # fmt: skip
            _POOL_SIZE = workers
            _POOL.submit(int).result()
        if not _ATEXIT:
            import atexit

            atexit.register(shutdown_pool)  # before the interpreter tears down what the pool needs
            _ATEXIT.append(True)
    return _POOL


#: Seconds the parent waits on its workers at a time before it looks for a stop signal.
SIGNAL_POLL = 0.25
_STOP_SIGNALS = {getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)}


@contextlib.contextmanager
def _signals_held():
    """Hold back Ctrl-C, SIGTERM and SIGHUP in this thread (delivered when the block ends)."""
    import threading

    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, _STOP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _worker_start(parent: int) -> None:
    """Worker initializer: the parent's signal handling, and death with the parent.

    A worker whose parent is killed (SIGKILL, SIGHUP, a crash) must not live
    on, reparented, holding a core: on Linux the kernel sends it SIGKILL when
    the parent dies (``prctl(PR_SET_PDEATHSIG)``); elsewhere a daemon thread
    polls the parent's pid.
    """
    from diefab.physics.world import worker_signals

    worker_signals()  # before the signals held back while the parent forked arrive, not after
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, _STOP_SIGNALS)
    if not _die_with_parent() or os.getppid() != parent:  # no prctl, or the parent is already gone
        import threading

        threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()


def _die_with_parent() -> bool:
    """Ask Linux to SIGKILL this process when its parent dies; False where that is not possible."""
    if not sys.platform.startswith("linux"):
        return False
    import ctypes

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(1, signal.SIGKILL, 0, 0, 0) == 0  # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return False


def _watch_parent(parent: int, interval: float = 0.5) -> None:
    while os.getppid() == parent:
        time.sleep(interval)
    os._exit(1)


def shutdown_pool(kill: bool = False) -> None:
    """Stop the worker processes kept between calls of :func:`simulate`."""
    global _POOL, _POOL_SIZE
    if _POOL is not None:
        if kill:  # the pool then fails its pending futures itself (cancelling them first races with that)
            for proc in list((getattr(_POOL, "_processes", None) or {}).values()):
                proc.terminate()
            _POOL.shutdown(wait=True)
        else:
            _POOL.shutdown(wait=True, cancel_futures=True)
        _POOL, _POOL_SIZE = None, 0


def _batches(n: int, workers: int) -> list[tuple[int, int]]:
    # small enough to balance the workers and move the progress bar, big enough to keep them busy
    size = int(np.clip(n // (workers * 16), 32, 512))
    return [(start, min(start + size, n)) for start in range(0, n, size)]


def dask_client(scheduler, timeout: float = 3.0):
    """``(client, owned)``: a Dask client for `scheduler` (an address or a ``distributed.Client``).

    ``owned`` is True when the client was opened here (the caller closes it).
    An address where no Dask scheduler answers fails within about `timeout`
    seconds (twice that at worst) with a :class:`PhysicsError`: nothing
    listening, a server that stays silent, or one that sends something else.
    """
    try:
        from distributed import Client
    except ImportError as exc:
        raise PhysicsError("--scheduler needs Dask: pip install 'dask[distributed]'") from exc
    if isinstance(scheduler, Client):
        return scheduler, False
    if not isinstance(scheduler, str) or not scheduler.strip():
        raise PhysicsError(f"scheduler address {scheduler!r} is not an address such as tcp://host:8786")
    _probe_scheduler(scheduler, timeout)
    try:
        return Client(scheduler, timeout=f"{timeout}s"), True
    except (OSError, TimeoutError, ValueError, TypeError, MemoryError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise PhysicsError(f"cannot reach Dask scheduler {scheduler!r}: {reason}") from None


#: Largest first message a Dask scheduler sends (its handshake is a few hundred bytes).
_HANDSHAKE_MAX = 1 << 20


def _probe_scheduler(address: str, timeout: float) -> None:
    """Check within `timeout` that a plain TCP `address` greets like a Dask scheduler.

    Dask's TCP comm starts with both ends sending a handshake: an 8-byte
    length, then that many bytes.  distributed waits for it without a time
    limit and allocates whatever length arrives, so a silent server (an HTTP
    server waits for a request) hangs the client and a chatty one makes it
    allocate exabytes.  Other schemes (tls://, ucx://, ...) are left to
    distributed's own timeout.
    """
    import socket
    import struct

    from distributed.comm import parse_address, parse_host_port

    try:
        scheme, location = parse_address(address)
        if scheme != "tcp":
            return
        host, port = parse_host_port(location, default_port=8786)
    except (ValueError, TypeError) as exc:
        raise PhysicsError(f"scheduler address {address!r} is not valid: {exc}") from None

    def fail(reason: str) -> None:
        raise PhysicsError(f"cannot reach Dask scheduler {address!r}: {reason}")

    deadline = time.monotonic() + timeout
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:

            def receive(size: int) -> bytes:
                data = b""
                while len(data) < size:
                    left = deadline - time.monotonic()
                    if left <= 0:
                        raise TimeoutError
                    sock.settimeout(left)
                    chunk = sock.recv(min(size - len(data), 65536))
                    if not chunk:
                        fail("the server closed the connection without a Dask handshake")
                    data += chunk
                return data

            try:
                (size,) = struct.unpack("Q", receive(8))
                if not 0 < size <= _HANDSHAKE_MAX:
                    fail("the server is not a Dask scheduler (it does not speak Dask's protocol)")
                receive(size)
            except TimeoutError:
                fail(f"no Dask handshake within {timeout:g} s (is it a Dask scheduler?)")
    except OSError as exc:
        fail(f"{exc.strerror or exc}")


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

    Raises
    ------
    PhysicsError
        Bad `n`, `seed`, `workers` or settings, an unstable design, a die
        that would start inside the ground, an unreachable scheduler.
    SimulationInterrupted
        On Ctrl-C, with the number of drops that had finished.
    """
    from concurrent.futures.process import BrokenProcessPool

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
    outcomes = np.empty(n, dtype=np.int32)
    batches = _batches(n, 1 if scheduler is None and workers == 1 else workers)
    done = 0
    started = time.perf_counter()

    def finished(start: int, stop: int, codes: np.ndarray) -> None:
        nonlocal done
        outcomes[start:stop] = codes
        done += stop - start
        if progress is not None:
            progress(done, n)

    try:
        if scheduler is not None:
            from distributed import as_completed

            client, own = dask_client(scheduler)
            try:
                futures = client.map(run_batch, [body] * len(batches), [settings] * len(batches), [seed] * len(batches),
                                     [a for a, _ in batches], [b for _, b in batches], pure=False)  # fmt: skip
                where = {f.key: batch for f, batch in zip(futures, batches)}
                try:
                    for future in as_completed(futures):
                        finished(*where[future.key], future.result())
                except BaseException:
                    client.cancel(futures)
                    raise
            finally:
                if own:
                    client.close()
        elif workers == 1:
            for start, stop in batches:
                finished(start, stop, run_batch(body, settings, seed, start, stop))
        else:
            from concurrent.futures import FIRST_COMPLETED, wait

            pool = _pool(workers)
            pending = {pool.submit(run_batch, body, settings, seed, a, b): (a, b) for a, b in batches}
            while pending:
                # a timeout brings the main thread back to Python now and then, to run a signal handler
                # whose signal the kernel gave to another thread (a progress bar's, say)
                ready, _ = wait(pending, timeout=SIGNAL_POLL, return_when=FIRST_COMPLETED)
                for future in ready:
                    finished(*pending.pop(future), future.result())
    except KeyboardInterrupt:
        if scheduler is None and workers > 1:
            shutdown_pool(kill=True)
        raise SimulationInterrupted(done, n) from None
    except BrokenProcessPool as exc:
        shutdown_pool(kill=True)
        raise PhysicsError(f"a simulation worker process died ({exc}); {done} of {n} drops had finished") from None
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
    )


# ----------------------------------------------------------------------
# the chart


def plot_validation(design: Design, result: RollResult, *, fmt: str = "png", alpha: float = 0.05) -> bytes:
    """Bar chart of simulated value probabilities (with simultaneous CIs), target and solid-angle model.

    Returns the image as bytes (`fmt` ``png`` or ``svg``); the caller writes it.
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
    model = value_probabilities(design, "solid-angle")
    x = np.arange(len(values))
    fig = Figure(figsize=(7.5, 4.2), dpi=120)
    ax = fig.add_subplot()
    w = 0.27
    ax.bar(x - w, sim, w, yerr=[sim - ci[:, 0], ci[:, 1] - sim], capsize=3, color="#3b75af",
           label=f"simulated ({result.landed} drops, {1 - alpha:.0%} simultaneous CI)")  # fmt: skip
    ax.bar(x, target, w, color="#9e9e9e", label=f"target {design.target}")
    ax.bar(x + w, model, w, color="#e5a04b", label="solid-angle model")
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
