"""Time of ``diefab design`` on the common targets, against an older checkout in the same run.

    git worktree add --detach /tmp/diefab-base REV     # the baseline, e.g. the commit before a change
    nice -n 10 python benchmarks/bench_design_speed.py --baseline /tmp/diefab-base
    nice -n 10 python benchmarks/bench_design_speed.py --baseline /tmp/diefab-base --cases 2d6

Runs each case (``design 2d6``, ``design 3dF --fill print``, at default
options and ``--seed 0``) with this checkout and with the baseline, one
after the other, and prints the wall time, the closing check's TVD (the
same 10,000 drops on the same seed in both), the ratio of the times, and
the machine's cores and load average, which decide the times on a shared
machine.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CASES = {"2d6": ["2d6"], "3df-print": ["3dF", "--fill", "print"]}


def run(checkout: Path, args: list[str]) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.monotonic()
        done = subprocess.run([sys.executable, "-m", "diefab", "design", *args, "--seed", "0", "--out", tmp, "--json"],
                              cwd=checkout, capture_output=True, text=True)  # fmt: skip
        seconds = time.monotonic() - t0
    if done.returncode not in (0, 3):
        return {"seconds": seconds, "error": (done.stderr.strip().splitlines() or ["?"])[-1]}
    report = json.loads(done.stdout)
    return {"seconds": seconds, "tvd": report["validated"]["tvd"], "exit": done.returncode}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--baseline", type=Path, required=True, help="Checkout of the code to compare with")
    parser.add_argument("--cases", nargs="*", default=list(CASES), choices=list(CASES))
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start", flush=True)
    for case in args.cases:
        new = run(ROOT, CASES[case])
        old = run(args.baseline, CASES[case])
        line = f"design {' '.join(CASES[case])}: this checkout {new['seconds']:.0f} s"
        line += f" (TVD {new['tvd']:.4f})" if "tvd" in new else f" ({new['error']})"
        line += f", baseline {old['seconds']:.0f} s"
        line += f" (TVD {old['tvd']:.4f})" if "tvd" in old else f" ({old['error']})"
        print(f"{line}; ratio baseline/this {old['seconds'] / new['seconds']:.2f}", flush=True)
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
