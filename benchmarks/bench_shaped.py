"""Shaped dice: ``diefab design TARGET --family ngem`` on several targets and seeds, against a baseline if asked.

    nice -n 10 python benchmarks/bench_shaped.py [--seeds 0,1,2] [--targets "2d6;3df"]
    git worktree add --detach /tmp/diefab-base REV     # a baseline, e.g. the commit before a change
    nice -n 10 python benchmarks/bench_shaped.py --baseline /tmp/diefab-base

A shaped die is optimized under the fast model and then refined against
simulated drops (``--model simulation``, the default, with its default
``--max-drops``).  For each target and seed this prints the simulated TVD of
every refinement step, the die's closing check (10,000 drops on a seed the
search never used) and its exit status; with ``--baseline``, the same run
of the other checkout beside it, and the mean closing TVD of each.  A
perfect die scores about 0.01 at 10,000 drops (0.013 for the 11 values of
2d6), so only differences well above that mean anything.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGETS = ["2d6", "3df", "binomial:4", "1:3,2:3,3:3,4:3,5:3,6:5"]


def run(checkout: Path, target: str, seed: int) -> dict:
    """One ``design`` of `target` by the code in `checkout`: its refinement steps and closing check."""
    with tempfile.TemporaryDirectory() as tmp:
        command = ["design", target, "--family", "ngem", "--seed", str(seed), "--out", tmp, "--json"]
        done = subprocess.run([sys.executable, "-m", "diefab", *command], cwd=checkout, capture_output=True, text=True)
    if done.returncode not in (0, 3):
        return {"error": (done.stderr.strip().splitlines() or ["?"])[-1]}
    report = json.loads(done.stdout)
    steps = [s["simulated_tvd"] for s in report.get("refinement") or []]
    return {"steps": steps, "tvd": report["validated"]["tvd"], "exit": done.returncode}


def describe(result: dict) -> str:
    if "error" in result:
        return result["error"]
    steps = " ".join(f"{s:.3f}" for s in result["steps"])
    return f"closing TVD {result['tvd']:.4f} (exit {result['exit']}); steps {steps}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--targets", default=";".join(TARGETS), help="targets separated by ;")
    parser.add_argument("--seeds", default="0,1,2", help="design seeds, comma-separated")
    parser.add_argument("--baseline", type=Path, default=None, help="checkout of the code to compare with")
    args = parser.parse_args()
    try:
        seeds = [int(s) for s in args.seeds.split(",")]
    except ValueError:
        parser.error(f"--seeds {args.seeds!r}: give whole numbers separated by commas")
    if args.baseline is not None and not (args.baseline / "diefab").is_dir():
        parser.error(f"--baseline {args.baseline}: not a diefab checkout")
    targets = [t for t in args.targets.split(";") if t]
    checkouts = {"this checkout": ROOT, **({"baseline": args.baseline} if args.baseline else {})}
    print(f"design TARGET --family ngem --seed SEED (default options); {os.cpu_count()} cores", flush=True)
    closing: dict[str, list[float]] = {name: [] for name in checkouts}
    for target in targets:
        for seed in seeds:
            print(f"{target}, seed {seed}:", flush=True)
            for name, checkout in checkouts.items():
                result = run(checkout, target, seed)
                print(f"  {name + ':':15s} {describe(result)}", flush=True)
                if "tvd" in result:
                    closing[name].append(result["tvd"])
    for name, values in closing.items():
        if values:
            print(f"mean closing TVD, {name}: {sum(values) / len(values):.4f} over {len(values)} dice")
    return 0


if __name__ == "__main__":
    sys.exit(main())
