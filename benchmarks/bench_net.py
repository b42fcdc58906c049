"""Net layout search vs the first valid spanning tree, and whole-process time of `diefab net`.

Run: python benchmarks/bench_net.py
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from diefab import Polyhedron, load_design
from diefab.made.unfold import unfold


def footprint(net) -> float:
    """Area (mm^2) of the bounding box of all pieces as placed (faces and tabs)."""
    total = 0.0
    for piece in range(net.n_pieces):
        members = np.flatnonzero(net.face_piece == piece)
        pts = np.concatenate([net.faces[k] for k in members] + [t.polygon for t in net.tabs if t.face in members])
        total += float(np.prod(np.ptp(pts, axis=0)))
    return total


def timed(fn, repeat=3):
    """Best wall time of `fn` over `repeat` calls, each on a cold layout cache, and its result."""
    from diefab.made.unfold import _layout_cached

    best, out = np.inf, None
    for _ in range(repeat):
        _layout_cached.cache_clear()
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def main() -> None:
    rng = np.random.default_rng(7)
    x = rng.normal(size=(12, 3))
    cases = {name: (load_design(name).polyhedron, load_design(name).mm_per_unit) for name in ("fudge-gem", "d6", "d8")}
    cases["random-20"] = (Polyhedron.from_points(x / np.linalg.norm(x, axis=1)[:, None]), 20.0)
    head = ("die", "faces", "search s", "first s", "time x", "area mm2", "first mm2", "area ratio")
    print(f"{head[0]:<10} " + " ".join(f"{h:>9}" for h in head[1:]))
    for name, (poly, scale) in cases.items():
        t_search, best = timed(lambda p=poly, s=scale: unfold(p, s))
        t_first, first = timed(lambda p=poly, s=scale: unfold(p, s, search=False))
        a, b = footprint(best), footprint(first)
        print(
            f"{name:<10} {len(poly.faces):>9} {t_search:>9.3f} {t_first:>9.3f} {t_search / t_first:>9.2f} "
            f"{a:>9.0f} {b:>9.0f} {a / b:>10.3f}"
        )
    exe = Path(sys.executable).with_name("diefab")
    with tempfile.TemporaryDirectory() as tmp:
        times = []
        for _ in range(3):
            t = time.perf_counter()
            subprocess.run([str(exe), "net", "fudge-gem", "--out", tmp], check=True, capture_output=True)
            times.append(time.perf_counter() - t)
    print(f"whole process `diefab net fudge-gem` (svg+pdf): best {min(times):.2f} s, median {np.median(times):.2f} s")


if __name__ == "__main__":
    main()
