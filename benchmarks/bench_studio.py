"""How long does the studio's server take per slider step, by fill?

One slider step evaluates the die once (:meth:`diefab.studio.state.Session.evaluation`:
the fast model, every face's margin, stability and readings).  This times a
sweep of ``--steps`` positions of the gem's ``a`` slider for the solid, print
and paper fills, first uncached, then swept back over the same positions
(from the cache), beside the straightforward baseline: the fast model's value
probabilities alone (``value_probabilities(design, "fast")``).

The browser's part (transport and redraw) is measured by
``tests/test_studio.py``, which prints the slider-to-chart latency.

Usage::

    python benchmarks/bench_studio.py             # 20 steps per fill
    python benchmarks/bench_studio.py --steps 5   # quick look
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from diefab import load_design, value_probabilities
from diefab.studio.state import Session, made_body_is_slow


def sweep(fill: str, steps: int) -> dict[str, float]:
    base = load_design("fudge-gem")
    session = Session(base)
    session.edit(fill=fill)
    positions = np.linspace(1.10, 1.26, steps)
    times = {"baseline": [], "uncached": [], "cached": [], "first": []}
    session.evaluation()  # warm caches that are not per position (the model's tables)
    for a in positions:
        d = session.design.with_params(a=float(a))
        t = time.perf_counter()
        value_probabilities(d, "fast")
        times["baseline"].append(time.perf_counter() - t)
    for kind in ("uncached", "cached"):
        for a in positions:
            session.edit(key=("param", "a"), params={"a": float(a)})
            t = time.perf_counter()
            session.evaluation()
            times[kind].append(time.perf_counter() - t)
    for a in positions + 1e-4:  # positions not seen yet: what the page draws first on a slider step
        session.edit(key=("param", "a"), params={"a": float(a)})
        t = time.perf_counter()
        session.provisional() if made_body_is_slow(session.design) else session.evaluation()
        times["first"].append(time.perf_counter() - t)
    return {k: 1000 * float(np.median(v)) for k, v in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=20)
    args = parser.parse_args()
    print(f"fudge-gem, slider a over {args.steps} positions; {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f}")  # fmt: skip
    print(f"{'fill':<8}{'baseline ms':>14}{'studio ms':>12}{'cached ms':>12}{'studio/baseline':>17}"
          f"{'first drawn ms':>16}{'first/baseline':>16}")  # fmt: skip
    for fill in ("solid", "print", "paper"):
        r = sweep(fill, args.steps)
        ratio, first = r["uncached"] / r["baseline"], r["first"] / r["baseline"]
        print(f"{fill:<8}{r['baseline']:>14.2f}{r['uncached']:>12.2f}{r['cached']:>12.4f}{ratio:>17.2f}"
              f"{r['first']:>16.2f}{first:>16.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
