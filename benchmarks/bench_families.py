"""How well do the landing models track the physics on every die family?

Draws random dice of each family (structural parameters fixed per family,
the others uniform in the family's box, rejection-sampled until every face
holds the die by --min-margin; :func:`diefab.dice.families.sampling.random_design`)
with a seed the fast model's correction was not trained on, drops each
--drops times in pybullet (default settings, solid fill) and compares four
models with the simulated face frequencies by TVD:

* ``fast``: the model ``--model fast`` uses (the chain with its learned
  correction; for the gem family the route :func:`diefab.models.fast.fast_model`
  takes);
* ``general``: the general correction (:func:`diefab.models.correction.corrected`),
  which is ``fast`` except on gems;
* ``chain``: its physics chain alone, with the constants fitted to gems
  (:func:`diefab.models.fast.landing_probabilities`);
* ``solid-angle``, the paper's model, the baseline;
* ``basins``, the quasi-static basins of attraction.

Prints one table per family (every die: faces, smallest margin, the
sampling-noise floor -- the expected TVD of that many drops sampled from the
fast model's own prediction -- and the TVD of each model), a summary (median
and worst TVD per family and model, the median over every die and of the
family medians), the fast model's measured TVD beside its noise floor, and
the time per evaluation of each model.  The simulated counts are cached in
``benchmarks/results/families.jsonl`` (one line per range of drops), so a
rerun, or a run with more drops, only simulates what is missing.

Run:  nice -n 10 python benchmarks/bench_families.py [--designs 6] [--drops 6000] [--seed 505]
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
    from diefab.dice.families.sampling import random_design

    index = list(FAMILIES).index(name)
    return [
        random_design(
            name, np.random.default_rng([seed, index, i]), FAMILIES[name], min_margin=min_margin, label=f"{name}-{i}"
        )  # fmt: skip
        for i in range(k)
    ]


def _key(record: dict, seed: int, physics: str) -> str:
    return json.dumps([record, seed, physics], sort_keys=True)


def _drop_range(design, seed: int, start: int, stop: int) -> tuple[np.ndarray, int]:
    """Face counts and cocked drops of drops ``start .. stop - 1`` at `seed` (as :func:`diefab.physics.simulate.simulate`).

    Drop *i* of a run depends on the seed and *i* alone, so counts of
    consecutive ranges add up to those of one longer run.
    """
    from diefab.physics.simulate import PhysicsSettings, _body
    from diefab.physics.world import COCKED, run_batch

    codes = run_batch(_body(design), PhysicsSettings.from_mapping(design.physics), seed, start, stop)
    counts = np.bincount(codes[codes >= 0], minlength=len(design.polyhedron.faces))
    return counts, int(np.count_nonzero(codes == COCKED))


def simulated(dice: dict[str, list], drops: int, seed: int) -> dict[str, list[np.ndarray]]:
    """Face counts of the first `drops` drops of every die, from the cache or simulated now (and cached at once).

    The cache holds ranges of drops (``start``, ``drops``) per die and seed;
    a longer run simulates only the drops the cache lacks.  Dice are visited
    round-robin over the families (die 0 of each, then die 1, ...), so an
    interrupted run leaves every family about equally far.
    """
    from diefab.dice.families.sampling import design_record
    from diefab.physics.world import OUTCOME_VERSION

    physics = f"outcomes-{OUTCOME_VERSION}"
    ranges: dict[str, dict[int, dict]] = {}
    if RESULTS.exists():
        for line in RESULTS.read_text().splitlines():
            r = json.loads(line)
            ranges.setdefault(_key(r["design"], r["seed"], r["physics"]), {})[r.get("start", 0)] = r
    out = {name: [None] * len(ds) for name, ds in dice.items()}
    for i in range(max(map(len, dice.values()), default=0)):
        for name, ds in dice.items():
            if i >= len(ds):
                continue
            d = ds[i]
            record = design_record(d)
            have = ranges.setdefault(_key(record, seed, physics), {})
            total, done = np.zeros(len(d.polyhedron.faces), dtype=np.int64), 0
            while done in have and done < drops:  # consecutive cached ranges from drop 0
                r = have[done]
                if done + r["drops"] > drops:
                    break
                total += np.array(r["face_counts"])
                done += r["drops"]
            if done < drops:
                t = time.perf_counter()
                counts, cocked = _drop_range(d, seed, done, drops)
                row = {"design": record, "start": done, "drops": drops - done, "seed": seed, "physics": physics,
                       "face_counts": counts.tolist(), "cocked": cocked}  # fmt: skip
                have[done] = row
                RESULTS.parent.mkdir(exist_ok=True)
                with RESULTS.open("a") as fh:  # one complete line per range
                    fh.write(json.dumps(row, separators=(",", ":")) + "\n")
                print(f"  simulated {d.name}: drops {done}..{drops - 1} in {time.perf_counter() - t:.1f} s",
                      file=sys.stderr, flush=True)  # fmt: skip
                total += counts
            out[name][i] = total
    return out


def noise_floor(p: np.ndarray, drops: int, rng: np.random.Generator, samples: int = 2000) -> float:
    """Expected TVD between `p` and the frequencies of `drops` drops drawn from it (sampling noise alone)."""
    freq = rng.multinomial(drops, p, size=samples) / drops
    return float(0.5 * np.abs(freq - p).sum(axis=1).mean())


def models() -> dict:
    from diefab.models.correction import corrected
    from diefab.models.fast import landing_probabilities
    from diefab.models.probabilities import MODELS

    return {"fast": MODELS["fast"], "general": corrected, "chain": landing_probabilities,
            "solid-angle": MODELS["solid-angle"], "basins": MODELS["basins"]}  # fmt: skip


def main(argv=None) -> int:
    from diefab.core.files import atomic_write
    from diefab.stats.goodness import tvd

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--designs", type=int, default=6, help="random dice per family")
    parser.add_argument("--drops", type=int, default=6000)
    parser.add_argument("--seed", type=int, default=505, help="seed of the random dice and their drops")
    parser.add_argument("--min-margin", type=float, default=0.05)
    parser.add_argument("--families", default=",".join(FAMILIES), help="comma-separated (default: all)")
    parser.add_argument("--collect-only", action="store_true", help="simulate (fill the cache) and stop")
    args = parser.parse_args(argv)
    if args.designs < 1 or args.drops < 1:
        parser.error("--designs and --drops must be positive")
    names = [f.strip() for f in args.families.split(",") if f.strip()]
    unknown = [f for f in names if f not in FAMILIES]
    if unknown:
        parser.error(f"unknown family {unknown[0]!r} (known: {', '.join(FAMILIES)})")
    dice = {name: test_dice(name, args.designs, args.seed, args.min_margin) for name in names}
    counts = simulated(dice, args.drops, args.seed)
    if args.collect_only:
        return 0

    fns = models()
    print(f"{args.designs} random dice per family (seed {args.seed}, not trained on), {args.drops} drops each, "
          f"solid fill; TVD to the simulated frequencies")  # fmt: skip
    print("floor: expected TVD of that many drops sampled from the fast model's own prediction (sampling noise)")
    summary, every, seconds = {}, {m: [] for m in fns}, {m: [] for m in fns}
    floors, rng = {}, np.random.default_rng(args.seed)
    for name in names:
        print(f"\n{name} {FAMILIES[name] or ''}")
        print(f"{'#':>3} {'faces':>5} {'margin':>7} {'floor':>6}  " + " ".join(f"{m:>11}" for m in fns))
        rows, floors[name] = [], []
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
            floors[name].append(noise_floor(fns["fast"](poly, center), int(c.sum()), rng))
            print(f"{i:3d} {len(poly.faces):5d} {d.margins().min():7.3f} {floors[name][-1]:6.4f}  "
                  + " ".join(f"{x:11.4f}" for x in row))  # fmt: skip
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
    # the fast model beside its noise floor; 'beyond noise' ~ sqrt(TVD^2 - floor^2) per die (a rough split)
    print("\nfast model: measured TVD, sampling-noise floor, and roughly what is beyond the noise (medians)")
    print(f"{'family':14s} {'TVD':>7} {'floor':>7} {'beyond':>7}")
    split, start = {}, 0
    for name in summary:
        k = len(floors[name])
        measured = np.array(every["fast"][start : start + k])
        start += k
        beyond = np.sqrt(np.clip(measured**2 - np.array(floors[name]) ** 2, 0, None))
        split[name] = (np.median(measured), np.median(floors[name]), np.median(beyond))
        print(f"{name:14s} {split[name][0]:7.4f} {split[name][1]:7.4f} {split[name][2]:7.4f}")
    all_floors = np.concatenate([floors[n] for n in summary])
    all_beyond = np.sqrt(np.clip(np.array(every["fast"]) ** 2 - all_floors**2, 0, None))
    print(
        f"{'every die':14s} {np.median(every['fast']):7.4f} {np.median(all_floors):7.4f} {np.median(all_beyond):7.4f}"
    )
    print(f"{'family medians':14s} " + " ".join(f"{np.median([v[j] for v in split.values()]):7.4f}" for j in range(3)))
    print("mean time per evaluation (ms, these dice): "
          + ", ".join(f"{m} {np.mean(s) * 1e3:.2f}" for m, s in seconds.items()))  # fmt: skip
    out = Path(__file__).with_name("results") / "families.json"
    rows = [{"family": name, "median": dict(zip(fns, map(float, med))), "worst": dict(zip(fns, map(float, worst)))}
            for name, (med, worst) in summary.items()]  # fmt: skip
    for row in rows:
        row["fast_floor"], row["fast_beyond_noise"] = map(float, split[row["family"]][1:])
    atomic_write(out, json.dumps({"designs": args.designs, "drops": args.drops, "seed": args.seed, "families": rows},
                              indent=1) + "\n")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
