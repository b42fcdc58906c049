"""How well do the landing models track the physics?  (issue 6)

Draws random stable gems in the family's whole box (a, b, c, d and e free),
drops each in pybullet (:func:`diefab.physics.simulate`, default settings)
and compares the ``fast`` and ``solid-angle`` models with the simulated
frequencies by TVD.  Two disjoint sets of designs:

* a **training** set (``--train-designs`` designs, ``--train-drops`` drops
  each) that ``--calibrate`` fits the fast model's constants on;
* a **test** set (``--designs`` designs, ``--drops`` drops each, 30,000 by
  default) on which the table and the median TVD are reported.

Simulated counts are cached in ``benchmarks/results/fastmodel.json`` (a few
kilobytes: nine counts per design), keyed by parameters, drops, seed and
physics settings, so a rerun only simulates what is missing and an
interrupted run loses at most the design in flight.

Usage::

    python benchmarks/bench_fastmodel.py                  # full: 20 x 30,000 drops (~10 min on 2 cores)
    python benchmarks/bench_fastmodel.py --drops 2000     # quick look
    python benchmarks/bench_fastmodel.py --calibrate      # refit the constants on the training set
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from diefab.design import load_design
from diefab.files import atomic_write
from diefab.stats import tvd

RESULTS = Path(__file__).with_name("results") / "fastmodel.json"
TRAIN_SEED, TEST_SEED = 101, 202
#: Random designs must rest on every face with at least this margin (model units).
MIN_MARGIN = 0.02


def random_designs(k: int, seed: int):
    """`k` random stable gems, uniform in the family box (e included), rejection-sampled."""
    from diefab.errors import DesignError
    from diefab.families import GEM

    base = load_design("fudge-gem")
    bounds = GEM.bounds(["a", "b", "c", "d", "e"])
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < k:
        x = bounds[:, 0] + rng.random(5) * (bounds[:, 1] - bounds[:, 0])
        params = dict(zip("abcde", np.round(x, 4).tolist()))
        try:
            d = base.with_params(**params)
            if d.margins().min() < MIN_MARGIN:
                continue
        except DesignError:
            continue
        out.append(d)
    return out


def physics_version() -> str:
    """The validator's outcome version: counts simulated by other physics code are not reused."""
    from diefab.world import OUTCOME_VERSION

    return f"outcomes-{OUTCOME_VERSION}"


def _key(params, drops, seed, settings) -> str:
    return json.dumps([params, drops, seed, settings, physics_version()], sort_keys=True)


def load_cache() -> dict:
    if RESULTS.exists():
        data = json.loads(RESULTS.read_text())
        return {
            json.dumps([r["params"], r["drops"], r["seed"], r["settings"], r["physics"]], sort_keys=True): r
            for r in data["runs"]
        }
    return {}


def save_cache(cache: dict) -> None:
    """Write the counts simulated by the current physics (older ones are dropped), one run per line."""
    version = physics_version()
    runs = sorted((r for r in cache.values() if r["physics"] == version), key=lambda r: (r["set"], r["index"]))
    lines = ",\n".join(json.dumps(r, sort_keys=True) for r in runs)
    atomic_write(RESULTS, '{"runs": [\n' + lines + "\n]}\n")


def simulated(designs, drops: int, seed: int, which: str, cache: dict, workers: int | None) -> list[dict]:
    """Counts of every design, from the cache or simulated now (and cached at once)."""
    from diefab.physics import PhysicsSettings, simulate

    settings = PhysicsSettings().as_dict()
    out = []
    for i, d in enumerate(designs):
        key = _key(dict(d.params), drops, seed, settings)
        if key not in cache:
            t = time.perf_counter()
            r = simulate(d, drops, seed=seed, workers=workers)
            cache[key] = {
                "set": which,
                "index": i,
                "params": dict(d.params),
                "drops": drops,
                "seed": seed,
                "settings": settings,
                "physics": physics_version(),
                "face_counts": r.face_counts.tolist(),
                "cocked": r.cocked,
                "unsettled": r.unsettled,
                "seconds": r.seconds,
            }
            save_cache(cache)
            print(f"  simulated {which} {i + 1}/{len(designs)}: {drops} drops in {time.perf_counter() - t:.1f} s",
                  file=sys.stderr, flush=True)  # fmt: skip
        out.append(cache[key])
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", type=int, default=20, help="test designs")
    ap.add_argument("--drops", type=int, default=30_000, help="drops per test design")
    ap.add_argument("--train-designs", type=int, default=20)
    ap.add_argument("--train-drops", type=int, default=4_000)
    ap.add_argument("--seed", type=int, default=0, help="physics seed of the drops")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--calibrate", action="store_true", help="refit the fast model's constants on the training set")
    ap.add_argument("--collect-only", action="store_true", help="simulate (fill the cache) and stop")
    args = ap.parse_args(argv)

    cache = load_cache()
    train = random_designs(args.train_designs, TRAIN_SEED)
    test = random_designs(args.designs, TEST_SEED)
    train_runs = simulated(train, args.train_drops, args.seed, "train", cache, args.workers)
    test_runs = simulated(test, args.drops, args.seed, "test", cache, args.workers)
    save_cache(cache)
    if args.collect_only:
        return

    from diefab import fastmodel
    from diefab.models import MODELS

    if args.calibrate:
        fit = fastmodel.calibrate(train, [np.array(r["face_counts"]) for r in train_runs])
        print(f"calibrated on {len(train)} training designs x {args.train_drops} drops: {fit}")
        constants = {k: v for k, v in fit.items() if k != "mean_tvd"}
    else:
        constants = None

    def fast(poly, center):
        return (
            fastmodel.fast_model(poly, center)
            if constants is None
            else fastmodel.landing_probabilities(poly, center, **constants)
        )

    rows = []
    for d, r in zip(test, test_runs):
        counts = np.array(r["face_counts"], dtype=float)
        q = counts / counts.sum()
        poly, center = d.polyhedron, d.mass_properties().center
        rows.append((d, r, tvd(fast(poly, center), q), tvd(MODELS["solid-angle"](poly, center), q)))

    print(f"\nfast model vs solid angles against {args.drops}-drop simulations ({len(test)} random stable gems, "
          f"physics seed {args.seed}; training set: {len(train)} other gems x {args.train_drops} drops)")  # fmt: skip
    print(f"{'#':>3} {'a':>6} {'b':>6} {'c':>6} {'d':>6} {'e':>6} {'margin':>7} {'cocked':>7}  {'TVD fast':>9} "
          f"{'TVD solid':>9}")  # fmt: skip
    for i, (d, r, tf, ts) in enumerate(rows):
        p = d.params
        print(f"{i:3d} {p['a']:6.3f} {p['b']:6.3f} {p['c']:6.3f} {p['d']:6.3f} {p['e']:6.3f} "
              f"{d.margins().min():7.3f} {r['cocked'] / r['drops']:7.2%}  {tf:9.4f} {ts:9.4f}")  # fmt: skip
    tf = np.array([x[2] for x in rows])
    ts = np.array([x[3] for x in rows])
    noise = np.sqrt((9 - 1) / (2 * np.pi * args.drops))
    ratio = np.median(ts) / np.median(tf)
    print(f"median TVD: fast {np.median(tf):.4f}, solid-angle {np.median(ts):.4f} (ratio {ratio:.1f}x); "
          f"max: fast {tf.max():.4f}, solid-angle {ts.max():.4f}; sampling noise alone ~{noise:.4f}")  # fmt: skip
    # training-set fit, for comparison
    tr = [tvd(fast(d.polyhedron, d.mass_properties().center), np.array(r["face_counts"]) / sum(r["face_counts"]))
          for d, r in zip(train, train_runs)]  # fmt: skip
    print(f"training set median TVD (fast): {np.median(tr):.4f}")

    # speed, against the solid-angle model in the same run
    d = load_design("fudge-gem")
    poly, center = d.polyhedron, d.mass_properties().center
    for name, fn in (("fast", fast), ("solid-angle", MODELS["solid-angle"])):
        fn(poly, center)
        reps = 300
        t = time.perf_counter()
        for _ in range(reps):
            fn(poly, center)
        print(f"{name:>11}: {(time.perf_counter() - t) / reps * 1e3:.3f} ms per evaluation")


if __name__ == "__main__":
    main()
