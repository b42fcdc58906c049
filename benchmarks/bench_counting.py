"""The nearest counted dice of a target, against asking for every fair shape from six faces up.

Run:  python benchmarks/bench_counting.py [--targets 2d6,3d6,4df,uniform:30] [--repeat 3]

:func:`diefab.search.counting.nearest_dice` needs the steadiest fair shape
of each face count it offers (:func:`~diefab.search.symmetric.fair_shapes`,
about a hundred solids built from planes per face count).  A die needs a
face for every value, so it asks only for face counts from the target's
number of values up.  The baseline is the same search that first asks
for every even face count from six up to that number, as a search that
does not skip them would.  Each run starts with no shape cached, as a new
``diefab design`` process does; both give the same dice, which is checked.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from diefab.dice.targets import parse_target  # noqa: E402
from diefab.search import symmetric  # noqa: E402
from diefab.search.counting import nearest_dice  # noqa: E402


def skipping(target):
    return nearest_dice(target)


def every_face_count(target):
    for m in range(6, len(target.values), 2):
        symmetric.fair_shapes(m)
    return nearest_dice(target)


def timed(search, target) -> tuple[float, list]:
    symmetric._fair_shapes.cache_clear()
    start = time.perf_counter()
    found = search(target)
    return time.perf_counter() - start, found


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--targets", default="2d6,3d6,4df,uniform:30")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    print(f"{'target':<12} {'values':>6} {'every count':>16} {'skipping':>13} {'ratio':>6}  dice")
    for name in args.targets.split(","):
        target = parse_target(name)
        base, new = [], []
        for _ in range(args.repeat):  # interleaved, so that the machine's load falls on both alike
            t, expected = timed(every_face_count, target)
            base.append(t)
            t, found = timed(skipping, target)
            new.append(t)
            assert found == expected, name
        b, n = float(np.median(base)), float(np.median(new))
        print(f"{name:<12} {len(target.values):>6} {b:>14.2f} s {n:>11.2f} s {b / n:>5.2f}x  {len(found)}, the same")
    runs = f"{args.repeat} cold run{'s' if args.repeat != 1 else ''}"
    print(f"\nmedian of {runs} each, interleaved; every count: the fair shapes of 6, 8, ... faces "
          "below the target's number of values asked for first")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
