"""Core numbers: the paper's formulas, the solid-angle optimizer, evaluation speed.

Run:  python benchmarks/bench_core.py [--quick]

Prints
- the largest |Eq. (1) - numeric centroid| over random gems;
- the paper's statistics (Table 2, the 10-coin substitute) as diefab computes them;
- ``diefab optimize fudge-gem`` timed as a cold process, and the optimum's
  place relative to the stability boundary for several minimum margins;
- one solid-angle model evaluation (centre of mass, solid angles, margins)
  against a straightforward per-face implementation, with the ratio.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
import timeit

import numpy as np

from diefab.dice.design import load_design
from diefab.dice.families import GEM, gem_center_of_mass_y, gem_polyhedron, gem_vertices
from diefab.dice.targets import parse_target
from diefab.made.mass import mass_properties
from diefab.search.optimize import Problem, optimize_design
from diefab.stats.goodness import chi2_power, goodness_of_fit, pearson_divergence, rolls_for_power


def eq1_check(n: int) -> float:
    rng = np.random.default_rng(0)
    worst = 0.0
    for _ in range(n):
        params = {p.name: rng.uniform(p.lower, p.upper) for p in GEM.parameters if not p.optional}
        com = mass_properties(gem_polyhedron(params)).center
        worst = max(worst, abs(com[1] - gem_center_of_mass_y(**params)))
    return worst


def paper_statistics() -> None:
    p = parse_target("4df").probabilities
    fit = goodness_of_fit([0, 20, 48, 80, 89, 83, 66, 17, 2], p)
    print("Paper Table 2 (405 rolls) against 4dF       diefab    paper")
    print(f"  chi2                                      {fit.chi2:8.3f}   12.97")
    print(f"  p                                         {fit.p_value:8.3f}    0.11")
    print(f"  TVD                                       {fit.tvd:8.4f}   0.047")
    print(f"  JSD                                       {fit.jsd:8.4f}  0.0068")
    print(f"  expected TVD sqrt((K-1)/(2 pi N))         {fit.expected_tvd:8.4f}   0.056")
    print(f"  expected TVD, exact for 4dF               {fit.expected_tvd_exact:8.4f}       -")
    print(f"  expected JSD (K-1)/(8N)                   {fit.expected_jsd:8.4f}  0.0025")
    q = parse_target("coins:10").probabilities
    print("Clamped 10 coins against 4dF")
    print(f"  Eq. (2) divergence                        {pearson_divergence(q, p):8.5f} 0.00339")
    print(f"  chi2 power at 1000 rolls, noncentral      {chi2_power(p, q, 1000):8.3f}  < 1/4")
    print(f"  chi2 power at 1000 rolls, Monte-Carlo     {chi2_power(p, q, 1000, method='monte-carlo'):8.3f}  < 1/4")
    print(f"  rolls for 80 % power                      {rolls_for_power(p, q, method='monte-carlo'):8d}")


def cold_optimize() -> None:
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-m", "diefab", "optimize", "fudge-gem", "--out", out, "--json"],
            capture_output=True,
            text=True,
            check=True,
        )
        seconds = time.perf_counter() - start
    data = json.loads(proc.stdout)
    params = " ".join(f"{k}={v:.3f}" for k, v in data["params"].items())
    print(f"diefab optimize fudge-gem (cold process): {seconds:.2f} s, objective {data['objective']:.5f}")
    print(f"  {params}; smallest margin {data['min_margin']:.3f} on {data['binding_face']}")


def margin_sweep(margins: list[float]) -> None:
    design = load_design("fudge-gem")
    print("Optimum against the stability boundary (seed 0)")
    print("  free       min margin  objective  binding face  smallest margin   a      b      c      d      e")
    for names in (("a", "b", "c", "d"), ("a", "b", "c", "d", "e")):
        for m in margins:
            r = optimize_design(design, names=names, min_margin=m, seed=0)
            p = r.design.params
            e = p.get("e", p["a"] * p["b"])
            print(
                f"  {','.join(names):<10} {m:10.3f} {r.objective:10.5f}  {r.binding_face:>12} {r.margins.min():16.4f}"
                f"  {p['a']:.3f}  {p['b']:.3f}  {p['c']:.3f}  {p['d']:.3f}  {e:.3f}"
            )


def baseline_evaluate(params: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """Straightforward per-face loops: centroid by tetrahedra, solid angles and margins face by face."""
    v = gem_vertices(**params)
    faces = [
        [4, 5, 1, 0],
        [5, 6, 2, 1],
        [6, 7, 3, 2],
        [7, 4, 0, 3],
        [7, 6, 5, 4],
        [8, 0, 1],
        [8, 1, 2],
        [8, 2, 3],
        [8, 3, 0],
    ]
    vol, first = 0.0, np.zeros(3)
    for f in faces:
        for k in range(1, len(f) - 1):
            a, b, c = v[f[0]], v[f[k]], v[f[k + 1]]
            det = np.dot(a, np.cross(b, c))
            vol += det / 6
            first += det * (a + b + c) / 24
    com = first / vol
    omega, margins = [], []
    for f in faces:
        total = 0.0
        for k in range(1, len(f) - 1):
            a, b, c = v[f[0]] - com, v[f[k]] - com, v[f[k + 1]] - com
            la, lb, lc = np.linalg.norm(a), np.linalg.norm(b), np.linalg.norm(c)
            num = np.dot(a, np.cross(b, c))
            den = la * lb * lc + np.dot(a, b) * lc + np.dot(a, c) * lb + np.dot(b, c) * la
            total += 2 * np.arctan2(num, den)
        omega.append(total)
        p = v[f]
        n = np.cross(p[1] - p[0], p[2] - p[0])
        n /= np.linalg.norm(n)
        q = com - np.dot(com - p[0], n) * n
        dist = []
        for i in range(len(f)):
            e = p[(i + 1) % len(f)] - p[i]
            inward = np.cross(n, e) / np.linalg.norm(e)
            dist.append(np.dot(q - p[i], inward))
        margins.append(min(dist))
    return np.array(omega) / (4 * np.pi), np.array(margins)


def evaluation_speed(number: int) -> None:
    design = load_design("fudge-gem")
    problem = Problem(design, ("a", "b", "c", "d"))
    params = dict(design.params)
    fast_probs = problem.evaluate(params)[1]
    base_faces, base_margins = baseline_evaluate(params)
    index = problem._value_index
    assert np.allclose(np.bincount(index, weights=base_faces), fast_probs)
    assert np.allclose(base_margins, problem.evaluate(params)[2])  # interior projections: line = edge distance
    fast = timeit.timeit(lambda: problem.evaluate(params), number=number) / number
    base = timeit.timeit(lambda: baseline_evaluate(params), number=number) / number
    print("One solid-angle evaluation of the gem (centre of mass, 9 solid angles, 9 margins)")
    print(f"  per-face loops (baseline)   {base * 1e6:8.1f} us")
    print(f"  diefab (vectorized)         {fast * 1e6:8.1f} us   ratio {base / fast:.1f}x")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer samples, one margin")
    args = parser.parse_args()
    worst = eq1_check(200 if args.quick else 2000)
    print(f"Eq. (1) vs numeric solid centroid, max |difference| over random gems: {worst:.2e}")
    paper_statistics()
    cold_optimize()
    margin_sweep([0.05] if args.quick else [0.0, 0.01, 0.02, 0.05, 0.1])
    evaluation_speed(300 if args.quick else 3000)


if __name__ == "__main__":
    main()
