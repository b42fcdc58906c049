"""A design stopped again and again and continued from its checkpoint: does it write the uninterrupted die?

Runs ``diefab design TARGET --json`` once without a checkpoint, then with
``--checkpoint DIR`` stopped by SIGINT (to the process), SIGTERM and SIGHUP
(to its group) at the given seconds after each start, each run continuing
from DIR; then once to the end, and once more on the full DIR.  Prints the
drops DIR held after each stop, and every field of the continued runs'
reports that differs from the uninterrupted one's (the design file's path
and the time always do).

Run:  python benchmarks/resume_design.py [TARGET] [--at 30 20 15] [--workers 2]
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from diefab.physics.dropfile import DropFile

ROOT = Path(__file__).resolve().parent.parent
#: Fields of a design report that change from run to run whatever the drops.
VOLATILE = {"design_file", "seconds", "checkpoint"}


def _defaults() -> None:
    """In the child: the stop signals at their defaults, as a terminal starts a command."""
    for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, signal.SIG_DFL)


def _command(args: list[str], out: Path) -> list[str]:
    return [sys.executable, "-m", "diefab", "design", *args, "--out", str(out), "--json"]


def _design(args: list[str], out: Path) -> tuple[dict, float]:
    start = time.monotonic()
    done = subprocess.run(_command(args, out), cwd=ROOT, capture_output=True, text=True, preexec_fn=_defaults)
    if done.returncode not in (0, 3):
        sys.exit(f"resume_design: design ended with status {done.returncode}: {done.stderr.strip()[-300:]}")
    return json.loads(done.stdout), time.monotonic() - start


def _kept(folder: Path) -> int:
    """The drops the drop files of `folder` hold."""
    return sum(DropFile(path).count() for path in sorted(folder.glob("*.npz")))


def _differs(whole: dict, other: dict) -> list[str]:
    return sorted(k for k in whole.keys() - VOLATILE if whole[k] != other.get(k))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("target", nargs="?", default="3d6")
    parser.add_argument("--at", type=float, nargs=3, default=(30.0, 20.0, 15.0), metavar=("INT", "TERM", "HUP"),
                        help="seconds after each start at which SIGINT, SIGTERM and SIGHUP are sent")  # fmt: skip
    parser.add_argument("--workers", default="2")
    opts = parser.parse_args()
    base = [opts.target, "--workers", opts.workers]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        whole, seconds = _design(base, tmp / "whole")
        print(f"uninterrupted: diefab design {' '.join(base)}, {seconds:.0f} s, {whole['drops']:,} search drops")
        kept = [*base, "--checkpoint", str(tmp / "drops")]
        stops = [(signal.SIGINT, False), (signal.SIGTERM, True), (signal.SIGHUP, True)]
        for (signum, to_group), at in zip(stops, opts.at):
            proc = subprocess.Popen(_command(kept, tmp / "kept"), cwd=ROOT, stdout=subprocess.DEVNULL,
                                    stderr=subprocess.PIPE, text=True, start_new_session=True,
                                    preexec_fn=_defaults)  # fmt: skip
            time.sleep(at)
            (os.killpg if to_group else os.kill)(proc.pid, signum)
            _, err = proc.communicate()
            last = err.strip().splitlines()[-1].replace(str(tmp / "drops"), "DIR") if err.strip() else ""
            print(f"{signal.Signals(signum).name} to the {'group' if to_group else 'process'} at {at:g} s: "
                  f"exit {proc.returncode}, {_kept(tmp / 'drops'):,} drops kept; {last}")  # fmt: skip
        for what in ("continued to the end", "again on the full folder"):
            report, seconds = _design(kept, tmp / "kept")
            c = report["checkpoint"]
            print(f"{what}: {seconds:.0f} s, {c['resumed']:,} of {c['drops']:,} drops from the folder; fields that "
                  f"differ from the uninterrupted run: {', '.join(_differs(whole, report)) or 'none'}")  # fmt: skip
        left = [p.name for p in tmp.rglob("*") if p.name.endswith((".tmp", ".lock"))]
        print(f"temporary or lock files left: {', '.join(left) or 'none'}")


if __name__ == "__main__":
    main()
