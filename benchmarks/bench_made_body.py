"""The mass model as made: the same figures as a baseline checkout, and how much faster.

Mass, centre of mass and inertia of every template and of 50 random dice of
every family, made in paper and in print, computed by this checkout and by a
baseline checkout (any earlier commit: ``git worktree add BASE COMMIT``), each
in its own process; prints the largest relative differences and the time each
took.  A print's labels are weighed from where they are placed; the paper
die's tabs from the net's layout (the search for its tree and tabs, without the pages).

Run::

    python benchmarks/bench_made_body.py --baseline ../diefab-base

(without ``--baseline`` it prints this checkout's figures and times only).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]

WORKER = r"""
import json, sys, time
import numpy as np
try:
    from diefab.dice.design import list_templates
    from diefab.dice.families.sampling import RANDOM_FAMILIES, random_design
    from diefab.made.fill import Fill
except ImportError:  # a checkout of the flat layout
    from diefab.design import list_templates
    from diefab.families.sampling import RANDOM_FAMILIES, random_design
    from diefab.mass import Fill

per_family, seed = int(sys.argv[1]), int(sys.argv[2])
designs = list(list_templates())
rng = np.random.default_rng(seed)
for name in sorted(RANDOM_FAMILIES):
    for k in range(per_family):
        designs.append(random_design(name, rng, label=f"{name}-{k}"))
out, seconds = {}, {}
for kind in ("paper", "print"):
    fill = Fill(kind)
    start = time.process_time()
    for d in designs:
        try:
            p = d.mass_properties(fill)
        except Exception as exc:  # a die that cannot be made so: the same on both sides
            out[f"{d.name}/{kind}"] = type(exc).__name__
            continue
        out[f"{d.name}/{kind}"] = [p.mass, *p.center.tolist(), *p.inertia.ravel().tolist()]
    seconds[kind] = time.process_time() - start
json.dump({"figures": out, "seconds": seconds, "dice": len(designs)}, sys.stdout)
"""


def measure(checkout: Path, per_family: int, seed: int) -> dict:
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    run = subprocess.run([sys.executable, "-c", WORKER, str(per_family), str(seed)], env=env, cwd=checkout,
                         capture_output=True, text=True, check=True)  # fmt: skip
    return json.loads(run.stdout)


def command_seconds(checkout: Path, args: list[str], runs: int) -> float:
    """Median CPU seconds (user + system, children included) of ``python -m diefab ARGS`` in `checkout`."""
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    times = []
    for _ in range(runs):
        before = os.times()
        subprocess.run([sys.executable, "-m", "diefab", *args], env=env, cwd=checkout, capture_output=True, check=True)
        after = os.times()
        times.append(after.children_user - before.children_user + after.children_system - before.children_system)
    return float(np.median(times))


COMMANDS = [
    ["predict", "fudge-gem", "--fill", "print", "--model", "fast"],
    ["predict", "d20", "--fill", "print", "--model", "fast"],
    ["optimize", "fudge-gem", "--fill", "print", "--model", "fast", "--out", "{tmp}"],
    ["predict", "fudge-gem", "--fill", "paper", "--model", "fast"],
    ["predict", "d20", "--fill", "paper", "--model", "fast"],
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", type=Path, help="a checkout of an earlier commit to compare with")
    parser.add_argument("--per-family", type=int, default=50)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--runs", type=int, default=3, help="runs of each command (median CPU time)")
    args = parser.parse_args()
    start = time.perf_counter()
    now = measure(HERE, args.per_family, args.seed)
    print(f"{now['dice']} dice (templates and {args.per_family} random dice of every family), seed {args.seed}; "
          f"{os.cpu_count()} cores (shared machine)")  # fmt: skip
    if args.baseline is None:
        for kind, s in now["seconds"].items():
            print(f"{kind:6s} {s:8.2f} s CPU")
        return
    base = measure(args.baseline.resolve(), args.per_family, args.seed)
    worst, errors = {"paper": 0.0, "print": 0.0}, 0
    missing = sorted({k.rsplit("/", 1)[0] for k in set(now["figures"]) - set(base["figures"])})
    if missing:  # templates added since the baseline
        print(f"not in the baseline, not compared: {', '.join(missing)}")
    for key, a in now["figures"].items():
        if key not in base["figures"]:
            continue
        b = base["figures"][key]
        if isinstance(a, str) or isinstance(b, str):
            errors += a != b
            continue
        a, b = np.asarray(a), np.asarray(b)
        scale = np.array([abs(b[0])] + [np.abs(b[1:4]).max() + 1e-12] * 3 + [np.abs(b[4:]).max()] * 9)
        kind = key.rsplit("/", 1)[1]
        worst[kind] = max(worst[kind], float(np.max(np.abs(a - b) / scale)))
    print(f"{'fill':6s} {'max rel. diff':>14s} {'this (s CPU)':>13s} {'baseline':>9s} {'speed-up':>9s}")
    for kind in ("paper", "print"):
        t, tb = now["seconds"][kind], base["seconds"][kind]
        print(f"{kind:6s} {worst[kind]:14.2e} {t:13.2f} {tb:9.2f} {tb / t:8.1f}x")
    print(f"dice whose outcome (figures or error) differs: {errors}")
    import tempfile

    print(f"{'command (CPU s, median of ' + str(args.runs) + ')':58s} {'this':>7s} {'baseline':>9s} {'speed-up':>9s}")
    for command in COMMANDS:
        with tempfile.TemporaryDirectory() as tmp:
            argv = [a.format(tmp=tmp) for a in command]
            t = command_seconds(HERE, argv, args.runs)
            tb = command_seconds(args.baseline.resolve(), argv, args.runs)
        shown = " ".join(a for a in command if a not in ("--out", "{tmp}"))
        print(f"diefab {shown:51s} {t:7.2f} {tb:9.2f} {tb / t:8.1f}x")
    print(f"{time.perf_counter() - start:.0f} s in all")


if __name__ == "__main__":
    main()
