"""Stop signals at random moments in every long command (the CI-sized run of benchmarks/signal_suite.py).

Every signalled run ends in exit 130 with one line, no traceback, no temporary file and no process
left; no signal is lost.  A signal that lands before the interpreter has run diefab's first line
(its own start-up, the first tenth of a second or more) is outside what the program can handle: the
suite reads from the kernel whether diefab's handlers were in place, and does not count those.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

pytestmark = [pytest.mark.slow, pytest.mark.skipif(not sys.platform.startswith("linux"), reason="process groups")]

_SPEC = importlib.util.spec_from_file_location("signal_suite", Path(__file__).parent.parent / "benchmarks" /
                                               "signal_suite.py")  # fmt: skip
suite = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(suite)


def test_stop_signals_end_every_long_command_cleanly():
    counts = suite.run_trials(15, seed=3, earliest=0.3, latest=4.0)  # about two minutes
    signalled = 15 - counts["finished"] - counts["early"]
    assert counts["clean"] == signalled, counts  # none lost, none with a traceback, none killed by the signal
