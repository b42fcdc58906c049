"""How well do the landing models track the physics on every die family?

Draws random dice of each family (structural parameters fixed per family,
the others uniform in the family's box, rejection-sampled until every face
holds the die by --min-margin; :func:`diefab.families.sampling.random_design`)
with a seed the fast model's correction was not trained on, drops each
--drops times in pybullet (default settings, solid fill) and compares four
models with the simulated face frequencies by TVD:

* ``fast``: the model ``--model fast`` uses (the chain with its learned
  correction; for the gem family the route :func:`diefab.fastmodel.fast_model`
  takes);
* ``general``: the general correction (:func:`diefab.correction.corrected`),
  which is ``fast`` except on gems;
* ``chain``: its physics chain alone, with the constants fitted to gems
  (:func:`diefab.fastmodel.landing_probabilities`);
* ``solid-angle``, the paper's model, the baseline;
* ``basins``, the quasi-static basins of attraction.

Prints one table per family (every die: faces, smallest margin, TVD of each
model), a summary (median and worst TVD per family and model, the median
over every die) and the time per evaluation of each model.  The simulated
counts are cached in ``benchmarks/results/families.jsonl`` (one line per
die), so a rerun only simulates what is missing.

Run:  nice -n 10 python benchmarks/bench_families.py [--designs 6] [--drops 8000] [--seed 505] [--workers 1]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

#: family -> structural parameters of the random dice drawn from it
FAMILIES = {
    "gem": {},
    "ngem": {"n": 5},
    "prism": {"n": 5},
    "bipyramid": {"n": 4},
    "trapezohedron": {"n": 5},
    "cuboid": {},
    "freeform": {"n": 10},
    "convex": {"n": 10},
}
RESULTS = Path(__file__).with_name("results") / "families.jsonl"


def test_dice(name: str, k: int, seed: int, min_margin: float) -> list:
    """The `k` random test dice of family `name` for `seed` (die i from ``default_rng([seed, family, i])``)."""
    from diefab.families.sampling import random_design

    index = list(FAMILIES).index(name)
    return [
        random_design(
            name, np.random.default_rng([seed, index, i]), FAMILIES[name], min_margin=min_margin, label=f"{name}-{i}"
        )  # fmt: skip
        for i in range(k)
    ]


def _key(record: dict, drops: int, seed: int, physics: str) -> str:
    return json.dumps([record, drops, seed, physics], sort_keys=True)


def simulated(designs, drops: int, seed: int, workers: int | None) -> list[np.ndarray]:
    """Face counts of every design, from the cache or simulated now (and cached at once)."""
    from diefab.families.sampling import design_record
    from diefab.physics import simulate
    from diefab.world import OUTCOME_VERSION

    physics = f"outcomes-{OUTCOME_VERSION}"
    cache = {}
    if RESULTS.exists():
        for line in RESULTS.read_text().splitlines():
            r = json.loads(line)
            cache[_key(r["design"], r["drops"], r["seed"], r["physics"])] = r
    out = []
    for d in designs:
        record = design_record(d)
        key = _key(record, drops, seed, physics)
        if key not in cache:
            t = time.perf_counter()
            r = simulate(d, drops, seed=seed, workers=workers)
            cache[key] = {"design": record, "drops": drops, "seed": seed, "physics": physics,
                          "face_counts": r.face_counts.tolist(), "cocked": int(r.cocked)}  # fmt: skip
            RESULTS.parent.mkdir(exist_ok=True)
            with RESULTS.open("a") as fh:  # one complete line per die
                fh.write(json.dumps(cache[key], separators=(",", ":")) + "\n")
            print(f"  simulated {d.name}: {drops} drops in {time.perf_counter() - t:.1f} s", file=sys.stderr,
                  flush=True)  # fmt: skip
        out.append(np.array(cache[key]["face_counts"]))
    return out


def models() -> dict:
    from diefab.correction import corrected
    from diefab.fastmodel import landing_probabilities
    from diefab.models import MODELS

    return {"fast": MODELS["fast"], "general": corrected, "chain": landing_probabilities,
            "solid-angle": MODELS["solid-angle"], "basins": MODELS["basins"]}  # fmt: skip


def main(argv=None) -> int:
    from diefab.files import atomic_write
    from diefab.stats import tvd

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--designs", type=int, default=6, help="random dice per family")
    parser.add_argument("--drops", type=int, default=8000)
    parser.add_argument("--seed", type=int, default=505, help="seed of the random dice and their drops")
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--min-margin", type=float, default=0.05)
    parser.add_argument("--families", default=",".join(FAMILIES), help="comma-separated (default: all)")
    parser.add_argument("--collect-only", action="store_true", help="simulate (fill the cache) and stop")
    args = parser.parse_args(argv)
    names = [f.strip() for f in args.families.split(",") if f.strip()]
    unknown = [f for f in names if f not in FAMILIES]
    if unknown:
        parser.error(f"unknown family {unknown[0]!r} (known: {', '.join(FAMILIES)})")
    dice = {name: test_dice(name, args.designs, args.seed, args.min_margin) for name in names}
    counts = {name: simulated(ds, args.drops, args.seed, args.workers) for name, ds in dice.items()}
    if args.collect_only:
        return 0

    fns = models()
    print(f"{args.designs} random dice per family (seed {args.seed}, not trained on), {args.drops} drops each, "
          f"solid fill; TVD to the simulated frequencies")  # fmt: skip
    summary, every, seconds = {}, {m: [] for m in fns}, {m: [] for m in fns}
    for name in names:
        print(f"\n{name} {FAMILIES[name] or ''}")
        print(f"{'#':>3} {'faces':>5} {'margin':>7} {'noise':>6}  " + " ".join(f"{m:>11}" for m in fns))
        rows = []
        for i, (d, c) in enumerate(zip(dice[name], counts[name])):
            q = c / c.sum()
            poly, center = d.polyhedron, d.mass_properties().center
            row = []
            for m, fn in fns.items():
                t = time.perf_counter()
                p = fn(poly, center)
                seconds[m].append(time.perf_counter() - t)
                row.append(tvd(p, q))
            rows.append(row)
            faces = len(poly.faces)
            noise = np.sqrt((faces - 1) / (2 * np.pi * c.sum()))
            print(f"{i:3d} {faces:5d} {d.margins().min():7.3f} {noise:6.4f}  " + " ".join(f"{x:11.4f}" for x in row))
        rows = np.array(rows)
        summary[name] = (np.median(rows, axis=0), rows.max(axis=0))
        for j, m in enumerate(fns):
            every[m] += rows[:, j].tolist()

    print(f"\nmedian TVD per family (worst in brackets), {args.designs} dice x {args.drops} drops each")
    print(f"{'family':14s} " + " ".join(f"{m:>16}" for m in fns))
    for name, (med, worst) in summary.items():
        print(f"{name:14s} " + " ".join(f"{a:8.4f} ({b:.3f})" for a, b in zip(med, worst)))
    print(f"{'every die':14s} " + " ".join(f"{np.median(v):8.4f} ({max(v):.3f})" for v in every.values()))
    medians = np.median([med for med, _ in summary.values()], axis=0)
    print(f"{'family medians':14s} " + " ".join(f"{v:8.4f} {'':7s}" for v in medians))
    print("mean time per evaluation (ms, these dice): "
          + ", ".join(f"{m} {np.mean(s) * 1e3:.2f}" for m, s in seconds.items()))  # fmt: skip
    out = Path(__file__).with_name("results") / "families.json"
    rows = [{"family": name, "median": dict(zip(fns, map(float, med))), "worst": dict(zip(fns, map(float, worst)))}
            for name, (med, worst) in summary.items()]  # fmt: skip
    atomic_write(out, json.dumps({"designs": args.designs, "drops": args.drops, "seed": args.seed, "families": rows},
                              indent=1) + "\n")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
