"""Stop signals at the edges of a command: while the interpreter tears down, and while handlers are swapped.

A command that has finished keeps its exit status: a stop signal that arrives while the interpreter
tears itself down (after it has reset every handler to the default) must not kill the process, which
would report a finished command as killed.  A stop that lands while the handlers are being swapped
around a write must not leave a swapped handler behind.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: A module that `site` imports at start-up: an object whose finalizer runs in the interpreter's teardown, after
#: the signal handlers are reset, says so on stderr and holds the teardown open long enough to be signalled.
SLOW_TEARDOWN = textwrap.dedent(
    """
    import os
    import time


    class _SlowTeardown:
        def __del__(self, write=os.write, sleep=time.sleep):
            write(2, b"tearing down\\n")
            sleep(3)


    _keep = _SlowTeardown()
    """
)


def _hangups_heard() -> None:
    """In the child: hang-ups at their default, as in a terminal (under nohup they arrive ignored, and stay so)."""
    signal.signal(signal.SIGHUP, signal.SIG_DFL)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="process groups")
@pytest.mark.parametrize("signum", [signal.SIGHUP, signal.SIGTERM, signal.SIGINT])
def test_a_stop_during_the_interpreters_teardown_leaves_the_exit_status(tmp_path, signum):
    (tmp_path / "sitecustomize.py").write_text(SLOW_TEARDOWN)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT)])}
    proc = subprocess.Popen([sys.executable, "-m", "diefab", "templates"], cwd=tmp_path, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
                            preexec_fn=_hangups_heard)  # fmt: skip
    try:
        assert proc.stderr.readline() == "tearing down\n"  # the command has finished; the handlers are reset
        os.killpg(proc.pid, signum)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, (proc.returncode, err)  # not -signum: the finished command's own status
    assert "fudge-gem" in out and err == ""


def test_a_stop_while_the_handlers_are_swapped_leaves_none_swapped(monkeypatch):
    """A pending stop runs its handler inside ``signal.signal``: the handlers swapped so far are put back."""
    from diefab.core import files

    signums = (signal.SIGUSR1, signal.SIGUSR2)
    monkeypatch.setattr(files, "STOP_SIGNALS", signums)
    originals = {s: signal.signal(s, lambda *_: None) for s in signums}
    before = {s: signal.getsignal(s) for s in signums}
    real = signal.signal
    calls = []

    def pending_stop_on_second_swap(signum, handler):
        calls.append(signum)
        if len(calls) == 2:
            raise KeyboardInterrupt  # the handler of a signal that arrived just before
        return real(signum, handler)

    monkeypatch.setattr(files.signal, "signal", pending_stop_on_second_swap)
    try:
        with pytest.raises(KeyboardInterrupt), files.signals_deferred():
            pass
    finally:
        monkeypatch.setattr(files.signal, "signal", real)
        after = {s: signal.getsignal(s) for s in signums}
        for s, handler in originals.items():
            signal.signal(s, handler)
    assert after == before


def test_a_stop_while_a_lock_is_taken_or_released_leaves_no_lock_file(tmp_path, interrupt_at_random):
    from diefab.core import files

    def take_and_release_until_stopped():
        try:
            while True:  # the stop lands anywhere in the cycle of taking and releasing the lock
                files.hold_lock(tmp_path / "r", "run r")
                files.release_locks()
        finally:
            files.release_locks()  # what the command line does on its way out
            assert not list(tmp_path.iterdir())

    assert interrupt_at_random(take_and_release_until_stopped, 200, 0.001, seed=1) == 200


#: Start-up code that sends the process a hang-up just as it lets go of a lock (the command's last steps).
HANG_UP_ON_RELEASE = textwrap.dedent(
    """
    import os
    import signal

    from diefab.core import files

    _release = files.ExclusiveLock.release


    def release(self):
        os.kill(os.getpid(), signal.SIGHUP)
        _release(self)


    files.ExclusiveLock.release = release
    """
)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="process groups")
def test_a_stop_as_the_command_lets_go_of_its_locks_is_one_line_and_no_lock_file(tmp_path):
    pytest.importorskip("textual")
    (tmp_path / "sitecustomize.py").write_text(HANG_UP_ON_RELEASE)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT)])}
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "diefab", "roll", "d6", "--out", str(out)], env=env, text=True,
                          stdin=subprocess.DEVNULL, capture_output=True, timeout=120,
                          preexec_fn=_hangups_heard)  # fmt: skip
    lines = proc.stderr.splitlines()
    assert proc.returncode == 130 and lines[-1] == "diefab: interrupted" and "Traceback" not in proc.stderr, lines
    assert "needs a terminal" in lines[0]  # the command's own end came first: it took its lock, then refused
    assert not list(out.iterdir())  # the lock file went with the lock


#: Start-up code that makes a stop land in code run by ``exec`` (as the methods a dataclass generates are).
STOP_INSIDE_EXEC = textwrap.dedent(
    """
    import diefab.dice.design as _design

    _list = _design.list_templates


    def list_templates():
        exec("import os, signal\\nos.kill(os.getpid(), signal.SIGTERM)\\nfor _ in range(100_000):\\n    pass\\n")
        return _list()


    _design.list_templates = list_templates
    """
)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="signals")
def test_a_stop_that_lands_in_executed_code_ends_in_exit_130(tmp_path):
    # the interpreter remembers a KeyboardInterrupt that ended a string given to exec, caught or not, and a
    # ``python -m`` run that ends with it remembered dies by SIGINT instead of exiting with its status
    (tmp_path / "sitecustomize.py").write_text(STOP_INSIDE_EXEC)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT)])}
    proc = subprocess.run([sys.executable, "-m", "diefab", "templates"], env=env, text=True, capture_output=True,
                          timeout=120)  # fmt: skip
    lines = [line for line in proc.stderr.splitlines() if line]  # click starts the line after a ^C on a new one
    assert proc.returncode == 130 and lines == ["diefab: interrupted"], (proc.returncode, proc.stderr)
