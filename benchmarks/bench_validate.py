"""Physics validator: the fast path against a straightforward paper-style loop.

    python benchmarks/bench_validate.py            # the full run (a few minutes)
    python benchmarks/bench_validate.py --n 3000   # a quick one

Prints, measured in this run on the ``fudge-gem`` template with default settings:

1. drops/s of the plain loop (one process, pybullet's own engine defaults,
   one ``stepSimulation`` call per 1/240 s step, velocities polled after
   every step, settled after 0.1 s still);
2. drops/s of ``diefab.physics.simulate.simulate`` (what ``diefab validate`` runs) on
   all cores over the N drops of (4), its ratio to (1), and the resident
   memory of each worker;
3. the early stop checked drop by drop: the fast path against itself with
   the energy rule off (every die runs until still), at a common seed;
4. the same-physics check: N fast-path drops against N plain-loop drops at
   independent seeds (TVD, two-sample chi2 p), and the share of identical
   outcomes drop by drop at a common seed;
5. the fast path's distribution of values against 4dF and against the
   paper's 405 real rolls (Table 2).
"""

from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np
from scipy.stats import chi2_contingency

from diefab.dice.design import load_design
from diefab.physics.simulate import PhysicsSettings, _body, shutdown_pool, simulate
from diefab.physics.world import run_batch
from diefab.stats.goodness import goodness_of_fit, tvd

TABLE_2 = np.array([0, 20, 48, 80, 89, 83, 66, 17, 2])  # the paper's real rolls, values -4..4


def plain_outcomes(design, settings, seed: int, n: int, workers: int) -> np.ndarray:
    """The plain loop over `workers` processes (only to get its distribution sooner)."""
    body = _body(design)
    chunk = -(-n // (workers * 8))
    starts = list(range(0, n, chunk))
    with ProcessPoolExecutor(workers) as pool:
        parts = pool.map(run_batch, *zip(*[(body, settings, seed, a, min(a + chunk, n), True) for a in starts]))
        return np.concatenate(list(parts))


def worker_rss_mb() -> list[float]:
    from diefab.physics import pool

    out = []
    for proc in getattr(pool._POOL, "_processes", {}).values():
        with open(f"/proc/{proc.pid}/status", encoding="ascii") as fh:
            out += [int(line.split()[1]) / 1024 for line in fh if line.startswith("VmRSS:")]
    return out


def two_sample(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    keep = (a + b) > 0
    return tvd(a / a.sum(), b / b.sum()), float(chi2_contingency(np.array([a[keep], b[keep]]))[1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=30_000, help="drops of each distribution (default 30000)")
    parser.add_argument("--n-plain-speed", type=int, default=1500, help="drops timing the plain loop")
    parser.add_argument("--n-early", type=int, default=6000, help="drops of the early-stop check")
    parser.add_argument("--workers", type=int, default=os.cpu_count(), help="fast-path workers (default all)")
    args = parser.parse_args()
    design = load_design("fudge-gem")
    settings = PhysicsSettings.from_mapping(design.physics)
    body = _body(design)
    faces = design.polyhedron.names
    print(f"fudge-gem, default settings, {os.cpu_count()} cores, fast path on {args.workers} workers")

    # 1. plain loop speed, one process
    t = time.perf_counter()
    run_batch(body, settings, 10_000, 0, args.n_plain_speed, True)
    plain_rate = args.n_plain_speed / (time.perf_counter() - t)
    print(f"plain loop:  {plain_rate:8.0f} drops/s  (1 process, pybullet defaults, {args.n_plain_speed} drops)")

    # 2. fast path, all cores (the pool is started once, as an optimizer reuses it)
    t = time.perf_counter()
    simulate(design, 64 * args.workers, seed=99, workers=args.workers, settings=settings)
    print(f"worker pool start-up and first batch: {time.perf_counter() - t:.1f} s")
    fast = simulate(design, args.n, seed=1, workers=args.workers, settings=settings)
    rss = worker_rss_mb()
    print(f"fast path:   {fast.drops_per_second:8.0f} drops/s  ({args.n} drops in {fast.seconds:.1f} s)")
    print(f"ratio:       {fast.drops_per_second / plain_rate:8.1f} x the plain loop")
    print("memory:      " + ", ".join(f"{r:.0f} MB" for r in rss) + " resident per worker")

    # 3. the early stop changes no outcome
    k = args.n_early
    settled = simulate(design, k, seed=3, workers=args.workers, settings=replace(settings, energy_fraction=0.0))
    early = simulate(design, k, seed=3, workers=args.workers, settings=settings)
    same = int((early.outcomes == settled.outcomes).sum())
    print(f"early stop (energy fraction {settings.energy_fraction}) against none, drop by drop: "
          f"{same} of {k} identical; {settled.drops_per_second:.0f} drops/s without it")  # fmt: skip
    shutdown_pool()

    # 4. same physics
    t = time.perf_counter()
    plain = plain_outcomes(design, settings, 2, args.n, args.workers)
    print(f"plain loop distribution: {args.n} drops in {time.perf_counter() - t:.0f} s on {args.workers} processes")
    paired = simulate(design, args.n, seed=2, workers=args.workers, settings=settings)
    shutdown_pool()
    plain_faces = np.bincount(plain[plain >= 0], minlength=len(faces))
    d_face, p_face = two_sample(fast.face_counts, plain_faces)
    print("face counts  " + " ".join(f"{n:>6}" for n in faces) + "  cocked unsettled")
    print("  fast       " + " ".join(f"{c:6d}" for c in fast.face_counts) + f"  {fast.cocked:6d} {fast.unsettled:9d}")
    cocked, unsettled = int((plain == -1).sum()), int((plain == -2).sum())
    print("  plain      " + " ".join(f"{c:6d}" for c in plain_faces) + f"  {cocked:6d} {unsettled:9d}")
    print(f"same physics (faces, independent seeds): TVD {d_face:.4f}, two-sample chi2 p = {p_face:.3f}")
    from diefab.physics.simulate import RollResult

    plain_result = RollResult(tuple(faces), plain_faces, cocked, unsettled, plain, 1.0, settings, 2)
    d_val, p_val = two_sample(fast.value_counts(design), plain_result.value_counts(design))
    print(f"same physics (values):                   TVD {d_val:.4f}, two-sample chi2 p = {p_val:.3f}")
    print(f"same seed, drop by drop: {np.mean(paired.outcomes == plain):.1%} of drops end alike")

    # 5. against 4dF and the paper's real rolls
    counts = fast.value_counts(design)
    goal = design.target_distribution.aligned(design.support)
    fit = goodness_of_fit(counts, goal)
    print("value        " + " ".join(f"{v:>7d}" for v in design.support))
    print("  simulated  " + " ".join(f"{q:7.4f}" for q in fit.observed))
    print("  4dF        " + " ".join(f"{q:7.4f}" for q in goal))
    print("  Table 2    " + " ".join(f"{q:7.4f}" for q in TABLE_2 / TABLE_2.sum()))
    print(f"vs 4dF: chi2 {fit.chi2:.1f} (df {fit.df}), p = {fit.p_value:.3g}, TVD {fit.tvd:.4f}, JSD {fit.jsd:.5f}")
    d_real, p_real = two_sample(counts, TABLE_2)
    print(f"vs the paper's 405 rolls: TVD {d_real:.4f}, two-sample chi2 p = {p_real:.3g}")
    ones = fit.observed[[3, 5]]
    print(f"P(-1), P(+1) = {ones[0]:.4f}, {ones[1]:.4f} against 16/81 = {16 / 81:.4f} each")


if __name__ == "__main__":
    main()
