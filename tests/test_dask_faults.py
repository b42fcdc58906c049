"""A Dask cluster that fails mid-run: the run ends in one line within a stated time, never hangs.

A scheduler and a worker (``dask scheduler``, ``dask worker --no-nanny``) run on 127.0.0.1; the
test kills every worker, or the scheduler, while ``validate --scheduler`` is dropping dice.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed")
pytestmark = [pytest.mark.slow, pytest.mark.skipif(shutil.which("dask") is None, reason="no dask command")]

ROOT = Path(__file__).parent.parent
#: Seconds the run waits for a worker to join (DIEFAB_DASK_STALL), kept short so the test is.
STALL = 5
#: Longest a failed run may take to say so: the stall and a margin for a loaded machine.
LIMIT = 90


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def cluster():
    port = _port()
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    address = f"tcp://127.0.0.1:{port}"
    scheduler = subprocess.Popen(["dask", "scheduler", "--host", "127.0.0.1", "--port", str(port),
                                  "--dashboard-address", ":0"], env=env, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.DEVNULL)  # fmt: skip
    time.sleep(3)
    worker = subprocess.Popen(["dask", "worker", address, "--no-nanny", "--nthreads", "1", "--host", "127.0.0.1",
                               "--dashboard-address", ":0"], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, cwd=ROOT)  # fmt: skip
    time.sleep(4)
    yield address, scheduler, worker
    for proc in (worker, scheduler):
        if proc.poll() is None:
            proc.kill()
        proc.wait()


@pytest.mark.parametrize("victim", ["workers", "scheduler"])
def test_a_cluster_that_dies_mid_run_fails_in_one_line(cluster, victim):
    address, scheduler, worker = cluster
    command = [sys.executable, "-m", "diefab", "validate", "fudge-gem", "--sims", "200000", "--scheduler", address]
    env = dict(os.environ, DIEFAB_DASK_STALL=str(STALL))
    proc = subprocess.Popen(command, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(8)
    assert proc.poll() is None, proc.communicate()
    (worker if victim == "workers" else scheduler).send_signal(signal.SIGKILL)
    started = time.monotonic()
    try:
        _, err = proc.communicate(timeout=LIMIT)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        pytest.fail(f"validate still ran {LIMIT} s after the {victim} died")
    lines = err.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and "Dask" in lines[0], err
    assert "Traceback" not in err
    print(f"{victim} killed: one line after {time.monotonic() - started:.0f} s: {lines[0]}")
