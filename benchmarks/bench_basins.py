"""The basins model: spherical polygons (exact) against the adaptive cube map (the baseline), per evaluation.

For each die: the time of one basins evaluation (RestBasins built and its
shares measured) by each method, best of a few repeats, the largest share
difference and each method's stated bound; then one evaluation of the
optimizer's objective (``Problem.evaluate``, the inner loop of
``diefab optimize --model basins``) with each method, and a whole
``diefab optimize fudge-gem --model basins`` run through the CLI.

Run: nice -n 10 python benchmarks/bench_basins.py
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from diefab.dice.design import load_design
from diefab.models.basins import RestBasins
from diefab.models.probabilities import probabilities as models
from diefab.search.optimize import Problem

DICE = ("fudge-gem", "fudge-gem-paper", "d6", "d20")


def best_of(fn, repeat: int = 3) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def main() -> None:
    print(f"{'die':<16} {'faces':>5} {'cube map s':>10} {'exact s':>8} {'speed-up':>8} {'max diff':>9} "
          f"{'map bound':>9} {'exact bound':>11}")  # fmt: skip
    for name in DICE:
        d = load_design(name)
        poly, center = d.polyhedron, d.mass_properties().center
        t_grid, (grid, grid_bound) = best_of(lambda p=poly, c=center: RestBasins.of(p, c).shares())
        t_exact, (exact, bound) = best_of(lambda p=poly, c=center: RestBasins.of(p, c).exact_shares())
        print(f"{name:<16} {len(poly.faces):>5} {t_grid:>10.3f} {t_exact:>8.3f} {t_grid / t_exact:>8.1f} "
              f"{np.abs(grid - exact).max():>9.1e} {grid_bound:>9.1e} {bound:>11.1e}")  # fmt: skip

    gem = load_design("fudge-gem")
    problem = Problem(gem, ("a", "b", "c", "d", "e"), model="basins")
    params = dict(gem.params)
    t_exact, _ = best_of(lambda: problem.evaluate(params))
    exact_model = models.MODELS["basins"]
    models.MODELS["basins"] = lambda poly, center: RestBasins.of(poly, center).shares()[0]
    try:
        t_grid, _ = best_of(lambda: problem.evaluate(params))
    finally:
        models.MODELS["basins"] = exact_model
    print(f"\noptimizer objective, fudge-gem (Problem.evaluate): cube map {t_grid:.3f} s, exact {t_exact:.3f} s "
          f"per evaluation ({t_grid / t_exact:.1f}x)")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-m", "diefab", "optimize", "fudge-gem", "--model", "basins", "--out", tmp, "--json"],
            capture_output=True, text=True,
        )  # fmt: skip
        seconds = time.perf_counter() - t
    if proc.returncode != 0:
        raise SystemExit(f"diefab optimize failed: {proc.stderr.strip()}")
    import json

    data = json.loads(proc.stdout)
    evaluations = data.get("evaluations")
    per = f", {seconds / evaluations * 1000:.0f} ms per evaluation" if evaluations else ""
    print(f"diefab optimize fudge-gem --model basins: {seconds:.1f} s wall, {evaluations} evaluations{per}, "
          f"objective {data.get('objective')}")  # fmt: skip
    print(f"best of 3 repeats per timing; {os.cpu_count()} cores (shared machine)")


if __name__ == "__main__":
    main()
