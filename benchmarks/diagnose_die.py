"""Why a simulation misses a real die: its body, each resting face's basin and barrier, the drops and the rolls.

    python benchmarks/diagnose_die.py kitten_d3 [--drops 600] [--seed 0] [--workers 1]
        [--shift-mm 0.5 --toward f133]

For one die with real rolls (the shared data, the paper's gem or a
published die, by name) it prints:

- the body as simulated: its centre of mass and how far it sits from the
  hull's centroid (mm), and the principal moments of its inertia per unit
  mass (model units squared);
- per resting face: the value it shows, its quasi-static basin share
  (:meth:`diefab.models.basins.RestBasins.exact_shares`), its barrier, the
  rise of the centre of mass that leaves the basin (model units and mm), and
  its share of ``--drops`` drops at the default physics (seed ``--seed``);
- per value: the basins model, the drops and the real frequencies;
- with ``--shift-mm D --toward FACE``: the barriers again with the centre of
  mass moved D mm toward that face's plane (along its outward normal): how
  fragile the quasi-static prediction is to the body.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from diefab.core.errors import DiefabError  # noqa: E402
from diefab.models.basins import RestBasins  # noqa: E402
from diefab.models.probabilities import to_values  # noqa: E402
from diefab.physics.simulate import shutdown_pool, simulate  # noqa: E402
from diefab.search.fidelity import load_real_dice  # noqa: E402

REALROLLS = ROOT / ".." / "shared" / "realrolls"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("die", help="a die with real rolls, by name (e.g. kitten_d3)")
    ap.add_argument("--drops", type=int, default=600, help="drops at the default physics (0: none)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--shift-mm", type=float, default=0.0, help="move the centre of mass this far (mm)")
    ap.add_argument("--toward", default="", help="... toward this face's plane (a face name, e.g. f133)")
    ap.add_argument("--data", type=Path, default=REALROLLS)
    args = ap.parse_args()
    if args.drops < 0:
        raise SystemExit(f"--drops {args.drops} must be >= 0")
    dice = {d.name: d for d in load_real_dice(args.data, published=True)}
    if args.die not in dice:
        raise SystemExit(f"no die {args.die!r} with real rolls (the dice: {', '.join(dice)})")
    die = dice[args.die]
    design = die.design
    poly, body = design.polyhedron, design.mass_properties()
    mm = design.mm_per_unit
    center, inertia = np.asarray(body.center, dtype=float), body.inertia / body.mass
    names = list(poly.names)
    if args.shift_mm and args.toward not in names:
        raise SystemExit(f"--toward {args.toward!r}: name a face of {die.name} (f0 ... f{len(names) - 1})")

    print(f"{die.name}: {len(poly.faces)} hull faces, {die.n} real rolls, {mm:.3g} mm per model unit")
    offset = np.linalg.norm(center - poly.centroid) * mm
    moments = np.linalg.eigvalsh(inertia)
    print(f"  centre of mass {np.round(center, 4).tolist()} (model units), {offset:.2f} mm from the hull's centroid")
    print("  principal moments of inertia per unit mass: " + ", ".join(f"{x:.3f}" for x in moments) + " units^2")

    basins = RestBasins.of(poly, center)
    shares, bound = basins.exact_shares()
    sim = None
    if args.drops:
        result = simulate(design, args.drops, seed=args.seed, workers=args.workers)
        shutdown_pool()
        sim = result.face_counts / max(result.landed, 1)
        lost = result.cocked + result.unsettled
    resting = np.flatnonzero(basins.resting)
    drops_text = f", share of {args.drops} drops (seed {args.seed})" if sim is not None else ""
    print(f"\n  per resting face ({len(resting)}): value, basin share (quasi-static), barrier (the rise of the "
          f"centre of mass that leaves the basin){drops_text}")  # fmt: skip
    for f in sorted(resting, key=lambda f: -shares[f]):
        value = design.values.get(names[f], "-")
        barrier = basins.barriers[f]
        text = f"{barrier:.4f} units = {barrier * mm:.2f} mm" if np.isfinite(barrier) else "none"
        print(f"  {names[f]:>6}  value {value!s:>4}  basin {shares[f]:.3f}  barrier {text:<22}"
              + (f"  drops {sim[f]:.3f}" if sim is not None else ""))  # fmt: skip

    values = design.support
    basins_v = to_values(design, shares)
    sim_v = to_values(design, sim) if sim is not None else None
    print("\n  per value: basins model, drops at the default physics, real frequencies")
    for k, v in enumerate(values):
        drops_v = f"{sim_v[k]:.3f}" if sim_v is not None else "-"
        print(f"  value {v!s:>4}  basins {basins_v[k]:.3f}  drops {drops_v:>5}  real {die.frequencies[k]:.3f}")
    print(f"  TVD to the real rolls (up to relabelling within mirror-image groups): basins {die.tvd(basins_v):.4f}"
          + (f", drops {die.tvd(sim_v):.4f} ({lost} of {args.drops} cocked or unsettled)"
             if sim_v is not None else ""))  # fmt: skip
    print(f"  (basin shares exact to {bound:.1e})")

    if args.shift_mm:
        f = names.index(args.toward)
        moved = center + poly.normals[f] * (args.shift_mm / mm)
        try:
            shifted = RestBasins.of(poly, moved)
        except DiefabError as exc:
            raise SystemExit(f"the centre of mass moved {args.shift_mm:g} mm toward {args.toward}: {exc}") from None
        print(f"\n  the centre of mass moved {args.shift_mm:g} mm toward {args.toward} (along its outward normal): "
              "barriers of the faces resting before")  # fmt: skip
        for g in sorted(resting, key=lambda g: -shares[g]):
            before, after = basins.barriers[g], shifted.barriers[g]
            state = f"{after:.4f}" if shifted.resting[g] else "no longer a resting face"
            print(f"  {names[g]:>6}  {before:.4f} -> {state}")
    return 0


if __name__ == "__main__":
    try:
        raise SystemExit(main())
    except DiefabError as exc:
        raise SystemExit(f"diagnose_die: {exc}") from None
