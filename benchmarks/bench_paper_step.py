"""One step of a slider on a paper die: how long the body takes, here and in a baseline checkout.

A paper die's body needs its net's glue tabs, so every change of shape or
size (one step of a studio slider, one ``predict --fill paper``) runs the
net's search again.  This times the studio's evaluation
(:meth:`diefab.studio.state.Session.evaluation`) of the gem (its ``a``
slider) and of the d20 and d8 (their size) at ``--steps`` positions, in this
checkout and in a baseline checkout (any earlier commit: ``git worktree add
BASE COMMIT``), each in its own process; prints the median CPU time per step,
the speed-up, and the largest relative difference of the bodies' mass,
centre and inertia over all steps.

Run::

    python benchmarks/bench_paper_step.py --baseline ../diefab-base
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]

WORKER = r"""
import json, sys, time
import numpy as np
from diefab import load_design
from diefab.studio.state import Session
steps = int(sys.argv[1])
out = {}
for name in ("fudge-gem", "d20", "d8"):
    session = Session(load_design(name))
    session.edit(fill="paper")
    session.evaluation()
    times, figures = [], []
    for x in np.linspace(0.0, 1.0, steps):
        if name == "fudge-gem":
            session.edit(key=("param", "a"), params={"a": float(1.10 + 0.16 * x)})
        else:
            session.edit(size_mm=float(16.0 + 8.0 * x))
        start = time.process_time()
        session.evaluation()
        times.append(time.process_time() - start)
        p = session.design.mass_properties(session.design.fill)
        figures.append([p.mass, *p.center.tolist(), *p.inertia.ravel().tolist()])
    out[name] = {"seconds": times, "figures": figures}
json.dump(out, sys.stdout)
"""


def measure(checkout: Path, steps: int) -> dict:
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    run = subprocess.run([sys.executable, "-c", WORKER, str(steps)], env=env, cwd=checkout,
                         capture_output=True, text=True, check=True)  # fmt: skip
    return json.loads(run.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", type=Path, required=True, help="a checkout of an earlier commit")
    parser.add_argument("--steps", type=int, default=8)
    args = parser.parse_args()
    now, base = measure(HERE, args.steps), measure(args.baseline.resolve(), args.steps)
    print(f"paper fill, {args.steps} steps per die; {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    print(f"{'die (slider)':18s} {'this ms CPU':>12s} {'baseline':>9s} {'speed-up':>9s} {'max rel. diff':>14s}")
    for name, r in now.items():
        b = base[name]
        a, c = np.asarray(r["figures"]), np.asarray(b["figures"])
        centre = np.abs(c[:, 1:4]).max(axis=1, keepdims=True) + 1e-12
        inertia = np.abs(c[:, 4:]).max(axis=1, keepdims=True)
        scale = np.concatenate([np.abs(c[:, :1]), np.repeat(centre, 3, axis=1), np.repeat(inertia, 9, axis=1)], axis=1)
        t, tb = 1000 * float(np.median(r["seconds"])), 1000 * float(np.median(b["seconds"]))
        label = f"{name} ({'a' if name == 'fudge-gem' else 'size'})"
        print(f"{label:18s} {t:12.0f} {tb:9.0f} {tb / t:8.1f}x {np.max(np.abs(a - c) / scale):14.2e}")


if __name__ == "__main__":
    main()
