"""How well do the landing models track the physics on every die family?

Draws random dice of each family (structural parameters fixed per family,
the others uniform in the family's box, rejection-sampled until every face
holds the die by --min-margin), drops each --drops times in pybullet
(default settings, solid fill) and compares the ``fast`` model (for
non-gem dice: its physics chain, the gem correction does not apply) and the
``solid-angle`` model with the simulated face frequencies by TVD.  The
baseline in the same run is the solid-angle model.  Prints one row per
family (median and worst TVD of each model) and writes
benchmarks/results/families.json.

Run:  python benchmarks/bench_families.py [--designs 4] [--drops 5000] [--seed 505] [--workers 2]
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
    "ngem": {"n": 5},
    "prism": {"n": 5},
    "bipyramid": {"n": 4},
    "trapezohedron": {"n": 5},
    "cuboid": {},
    "freeform": {"n": 10},
}


def random_dice(name: str, fixed: dict, k: int, rng: np.random.Generator, min_margin: float):
    """`k` random designs of family `name`, every face a resting face with its own value."""
    from diefab.design import Design
    from diefab.errors import DesignError
    from diefab.families import family

    fam = family(name)
    free = fam.free_names(fam.complete(fixed | _required(fam, fixed)))
    lo, hi = fam.bounds(free).T
    out = []
    while len(out) < k:
        params = {**fixed, **dict(zip(free, (lo + rng.random(len(free)) * (hi - lo)).tolist()))}
        try:
            poly = fam.polyhedron(params)
            m = len(poly.faces)
            d = Design(f"{name}-{len(out)}", name, params, values={n: i + 1 for i, n in enumerate(poly.names)},
                       target=f"uniform:{m}")  # fmt: skip
            if d.margins().min() > min_margin:
                out.append(d)
        except DesignError:
            continue
    return out


def _required(fam, fixed: dict) -> dict:
    """Mid-box values of the required parameters not in `fixed` (to learn which are free)."""
    return {p.name: (p.lower + p.upper) / 2 for p in fam.parameters if not p.optional and p.name not in fixed}


def main() -> int:
    from diefab.geometry import solid_angles
    from diefab.models import MODELS
    from diefab.physics import simulate
    from diefab.stats import tvd

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--designs", type=int, default=4, help="random dice per family")
    parser.add_argument("--drops", type=int, default=5000)
    parser.add_argument("--seed", type=int, default=505, help="seed of the random dice and their drops")
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--min-margin", type=float, default=0.05)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    print(f"{args.designs} random dice per family, {args.drops} drops each (seed {args.seed}), solid fill")
    print(
        f"{'family':14s} {'fast median':>11s} {'fast worst':>10s} {'solid-angle median':>18s} {'worst':>7s} {'s':>6s}"
    )
    rows = []
    for name, fixed in FAMILIES.items():
        t0 = time.perf_counter()
        fast, solid = [], []
        for d in random_dice(name, fixed, args.designs, rng, args.min_margin):
            sim = simulate(d, args.drops, seed=args.seed, workers=args.workers)
            center = d.mass_properties().center
            fast.append(tvd(MODELS["fast"](d.polyhedron, center), sim.face_probabilities))
            omega = solid_angles(d.polyhedron, center)
            solid.append(tvd(omega / omega.sum(), sim.face_probabilities))
        row = {"family": name, "fixed": fixed, "fast": fast, "solid_angle": solid, "drops": args.drops,
               "seconds": time.perf_counter() - t0}  # fmt: skip
        rows.append(row)
        print(f"{name:14s} {np.median(fast):11.4f} {max(fast):10.4f} {np.median(solid):18.4f} {max(solid):7.4f} "
              f"{row['seconds']:6.0f}", flush=True)  # fmt: skip
    every_fast = [x for r in rows for x in r["fast"]]
    every_solid = [x for r in rows for x in r["solid_angle"]]
    print(f"{'all':14s} {np.median(every_fast):11.4f} {max(every_fast):10.4f} {np.median(every_solid):18.4f} "
          f"{max(every_solid):7.4f}")  # fmt: skip
    out = Path(__file__).with_name("results") / "families.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(rows, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
