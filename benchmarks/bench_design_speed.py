"""Time of ``diefab design`` on the common targets, against an older checkout in the same run.

    git worktree add --detach /tmp/diefab-base REV     # the baseline, e.g. the commit before a change
    nice -n 10 python benchmarks/bench_design_speed.py --baseline /tmp/diefab-base
    nice -n 10 python benchmarks/bench_design_speed.py --baseline /tmp/diefab-base --cases 2d6

Runs each case (``design 2d6``, ``design 3dF --fill print``, at default
options and ``--seed 0``) with this checkout and with the baseline, one
after the other, and prints the wall time, the CPU time of the command and
its worker processes, the drops the search spent, the closing check's TVD
(10,000 drops on the same seed in both), the ratio of the times, and the
machine's cores and load average, which decide the wall times on a shared
machine (the CPU times depend on it far less).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CASES = {"2d6": ["2d6"], "3df-print": ["3dF", "--fill", "print"]}


def run(checkout: Path, args: list[str]) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        load = os.getloadavg()[0]
        t0 = time.monotonic()
        done = subprocess.run([sys.executable, "-m", "diefab", "design", *args, "--seed", "0", "--out", tmp, "--json"],
                              cwd=checkout, capture_output=True, text=True)  # fmt: skip
        seconds = time.monotonic() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)  # the command and the workers it waited for
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    out = {"seconds": seconds, "cpu": cpu, "load": (load + os.getloadavg()[0]) / 2}
    if done.returncode not in (0, 3):
        return {**out, "error": (done.stderr.strip().splitlines() or ["?"])[-1]}
    report = json.loads(done.stdout)
    return {**out, "tvd": report["validated"]["tvd"], "drops": report["drops"], "exit": done.returncode}


def describe(run: dict) -> str:
    """One checkout's figures for one case."""
    text = f"{run['seconds']:.0f} s wall, {run['cpu']:.0f} s CPU, load {run['load']:.1f}"
    if "error" in run:
        return f"{text} ({run['error']})"
    return f"{text}, {run['drops']} search drops, TVD {run['tvd']:.4f} (exit {run['exit']})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--baseline", type=Path, required=True, help="Checkout of the code to compare with")
    parser.add_argument("--cases", nargs="*", default=list(CASES), choices=list(CASES))
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start", flush=True)
    for case in args.cases:
        new = run(ROOT, CASES[case])
        old = run(args.baseline, CASES[case])
        print(f"design {' '.join(CASES[case])}:", flush=True)
        print(f"  this checkout: {describe(new)}", flush=True)
        print(f"  baseline:      {describe(old)}", flush=True)
        print(f"  ratio baseline/this: wall {old['seconds'] / new['seconds']:.2f}, CPU {old['cpu'] / new['cpu']:.2f}",
              flush=True)  # fmt: skip
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
