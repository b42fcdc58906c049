"""Shared fixtures: a CLI runner that returns (exit status, stdout, stderr)."""

from __future__ import annotations

import pytest

from diefab.cli import main

try:  # property tests draw the same examples on every run, so that a red run is one anyone can repeat;
    # ``--hypothesis-profile explore`` draws new ones
    from hypothesis import settings
except ImportError:  # pragma: no cover - hypothesis comes with the test extra
    pass
else:
    settings.register_profile("fixed", derandomize=True)
    settings.register_profile("explore", derandomize=False)
    settings.load_profile("fixed")


@pytest.fixture
def run(capsys):
    """Run ``diefab ARGS...`` in-process; returns (status, stdout, stderr)."""

    def _run(*args: str) -> tuple[int, str, str]:
        try:
            main([str(a) for a in args])
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        else:  # pragma: no cover - main always exits
            code = 0
        out, err = capsys.readouterr()
        return code, out, err

    return _run


@pytest.fixture
def bad(run):
    """Assert ``diefab ARGS...`` fails with exit 2 and one line on stderr; return that line."""

    def _bad(*args: str) -> str:
        code, _, err = run(*args)
        assert code == 2, err
        lines = err.strip().splitlines()
        assert len(lines) == 1, err
        assert "Traceback" not in err
        return lines[0]

    return _bad


@pytest.fixture
def interrupt_at_random(monkeypatch):
    """``interrupt_at_random(step, n, high, seed)``: run ``step()`` `n` times, each cut short by a stop signal.

    The stop is a stand-in for Ctrl-C that a timer sends after a random 0 to `high` seconds: SIGALRM,
    whose handler raises ``KeyboardInterrupt`` and which the file helpers defer as they defer the stop
    signals.  ``step`` must run until interrupted.  Returns how many interrupts arrived.
    """
    import signal

    import numpy as np

    from diefab.core import files

    if not hasattr(signal, "setitimer"):
        pytest.skip("needs interval timers")

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    monkeypatch.setattr(files, "STOP_SIGNALS", (*files.STOP_SIGNALS, signal.SIGALRM))

    def run(step, n: int, high: float, seed: int = 0) -> int:
        rng = np.random.default_rng(seed)
        interrupted = 0
        previous = signal.signal(signal.SIGALRM, interrupt)
        try:
            for _ in range(n):
                try:
                    signal.setitimer(signal.ITIMER_REAL, rng.uniform(0, high))
                    step()
                except KeyboardInterrupt:
                    interrupted += 1
                finally:
                    signal.setitimer(signal.ITIMER_REAL, 0)
        finally:
            signal.signal(signal.SIGALRM, previous)
        return interrupted

    return run
