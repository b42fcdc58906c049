"""Stop signals of the command line: Ctrl-C, SIGTERM and SIGHUP end a command cleanly.

A stop signal raises :class:`Stopped` (a :class:`KeyboardInterrupt`) in the
main thread, and is also *noted*.  The note is what makes a stop impossible
to lose: Python code that catches ``BaseException`` (an optional import
guarded that way, a callback whose errors are ignored) can swallow the
exception, but not the note, and :func:`check_stop` raises again at the
next safe point (before a file is written, between batches of drops, before
the command reports success).

Before the package's heavy imports run, :func:`install_early` makes a stop
end the process at once with one line and exit status 130: nothing has been
written yet, and an exception raised inside a half-imported module would
print a traceback or be swallowed by it.

Once the command has finished, its exit status stands.  The interpreter
resets every signal handler to the default before it tears down its modules
(a tenth of a second and more with NumPy, SciPy and trimesh loaded), and a
stop signal then would kill the process, reporting a finished command as
killed.  The command's last exit hook therefore ignores the stop signals,
after it has handled one already received.

This module imports nothing but the standard library and calls
:func:`install_early` when imported: the package imports it first.
"""

from __future__ import annotations

import atexit
import os
import signal
import sys
import threading

__all__ = ["STOP_SIGNALS", "Stopped", "check_stop", "install", "install_early", "reset", "restore", "stop_requested"]

#: The signals that stop a command.
STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))
#: Exit status of a stopped command (128 + SIGINT, as a shell reports Ctrl-C).
STOPPED = 130

_noted: list[int] = []


class Stopped(KeyboardInterrupt):
    """A stop signal, raised in the main thread; caught as the :class:`KeyboardInterrupt` it is.

    A subclass, not ``KeyboardInterrupt`` itself: CPython remembers a
    ``KeyboardInterrupt`` of exactly that type that ends code run by ``exec``
    on a string (the methods a dataclass or named tuple generates), even when
    it is caught, and a ``python -m`` program that ends with one remembered
    dies by SIGINT instead of exiting with its own status.
    """


def stop_requested() -> int | None:
    """The first stop signal received since :func:`reset`, or None."""
    return _noted[0] if _noted else None


def reset() -> None:
    """Forget the stop signals received (a new command starts)."""
    _noted.clear()


def check_stop() -> None:
    """Raise :class:`Stopped` if a stop signal was received (and perhaps swallowed)."""
    if _noted:
        raise Stopped


def _interrupt(signum, frame) -> None:
    _noted.append(signum)
    raise Stopped


def _exit_now(signum, frame) -> None:
    try:
        os.write(2, b"diefab: interrupted\n")
    finally:
        os._exit(STOPPED)


def _ours(handler) -> bool:
    return handler in (signal.SIG_DFL, signal.default_int_handler, _exit_now, _interrupt)


def install() -> dict[int, object]:
    """Make each stop signal note itself and raise :class:`Stopped`; return the previous handlers.

    A signal whose handler was set by someone else (ignored by ``nohup``,
    say) is left alone.  Only in the main thread.
    """
    return _install(_interrupt)


def restore(previous: dict[int, object], pending: list[int] | tuple[int, ...] = ()) -> None:
    """Put back the handlers :func:`install` replaced; deliver to them the stops `pending` and those received meanwhile.

    ``signal.signal`` first runs the handler of a signal already received:
    its ``KeyboardInterrupt`` is caught here, the swap finished, and the
    signal raised again once the handlers are back (for the command line,
    one line and exit status 130 at once).
    """
    noted = list(pending)
    for signum, handler in previous.items():
        while True:
            try:
                signal.signal(signum, handler)
                break
            except KeyboardInterrupt:
                noted.append(stop_requested() or signal.SIGINT)
    for signum in dict.fromkeys(noted):
        signal.raise_signal(signum)


def install_early() -> None:
    """When this process is the ``diefab`` command, make a stop signal exit at once (status 130, one line)."""
    if _is_command():
        _install(_exit_now)
        # registered before any of the package's and its libraries' hooks, so it runs after them
        atexit.register(_ignore_at_exit)


def _ignore_at_exit() -> None:
    """Ignore the stop signals from here to the end of the process (the interpreter's teardown).

    ``signal.signal`` first runs the handler of a stop signal already
    received, so a stop that came before this point still ends the command
    with its one line and status 130.
    """
    try:
        _install(signal.SIG_IGN)
    except KeyboardInterrupt:  # a stop received, whose handler was the command's
        _exit_now(None, None)


def _install(handler) -> dict[int, object]:
    previous: dict[int, object] = {}
    if threading.current_thread() is not threading.main_thread():
        return previous
    for signum in STOP_SIGNALS:
        current = signal.getsignal(signum)
        if _ours(current):
            previous[signum] = signal.signal(signum, handler)
    return previous


def _is_command() -> bool:
    """True for ``diefab ...`` (the console script) and ``python -m diefab ...``."""
    argv = list(getattr(sys, "orig_argv", ()) or ())
    if sys.argv and os.path.basename(sys.argv[0]) in ("diefab", "diefab.exe"):
        return True
    i = 1
    while i < len(argv):
        arg = argv[i]
        if arg == "-m":
            return i + 1 < len(argv) and argv[i + 1] in ("diefab", "diefab.cli")
        if arg.startswith("-m"):
            return arg[2:] in ("diefab", "diefab.cli")
        if arg == "-c" or not arg.startswith("-"):
            return False
        i += 2 if arg in ("-X", "-W") else 1
    return False


install_early()
