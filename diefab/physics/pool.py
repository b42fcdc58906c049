"""The pool of worker processes that drop dice, and how it handles stop signals.

Workers are forked once and kept between calls of
:func:`~diefab.physics.simulate.simulate`, each holding one pybullet world.
They ignore the terminal's stop signals (the parent decides when to stop) and
die with their parent, so a killed run leaves no orphan holding a core.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import time
from typing import Any

from diefab.core import files

__all__ = ["SIGNAL_POLL", "shutdown_pool", "signals_held", "worker_pool"]

_POOL: Any = None
_POOL_SIZE = 0
_ATEXIT: list[bool] = []


def worker_pool(workers: int):
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
        with signals_held():
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


@contextlib.contextmanager
def signals_held():
    """Hold back Ctrl-C, SIGTERM and SIGHUP in this thread (delivered when the block ends)."""
    import threading

    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, set(files.STOP_SIGNALS))  # the stops files defers
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
        signal.pthread_sigmask(signal.SIG_UNBLOCK, set(files.STOP_SIGNALS))
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
