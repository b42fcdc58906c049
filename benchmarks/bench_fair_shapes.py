"""Do the faces a fair die's symmetry makes alike land alike in the simulator?  One hull against flat faces.

    nice -n 10 python benchmarks/bench_fair_shapes.py
    nice -n 10 python benchmarks/bench_fair_shapes.py --faces 18 22 26

Every fair die diefab offers for a face count (``fair_shapes(m)``: the
steadiest bipyramid or trapezohedron, m = 6 ... 60) and the d6, d8 and d20
templates are dropped ``--sims`` times on seed ``--seed`` with ``python -m
diefab validate DIE --json``, each face its own value: as the engine holds
it by default (one hull) and with ``--flat-faces``, in the same run.  Such a die lands on every face alike
under any physics, so the counts are tested against the uniform
distribution: chi-squared on faces - 1 degrees of freedom and its p-value,
the fewest and most landings on one face, and the drops per second.  The
``folds`` column says whether the engine's hull folds a face the die rests
on (``diefab.physics.shapes``; without folds both runs are the same
simulation).  Results go to ``benchmarks/results/fair_shapes.json`` as each
die finishes.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.stats import chisquare

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
RESULTS = ROOT / "benchmarks" / "results" / "fair_shapes.json"


def dice(faces: list[int] | None):
    """(label, Design) of every fair die measured."""
    from diefab.dice.design import Design, load_design
    from diefab.search.symmetric import fair_shapes

    out = []
    for name in ("d6", "d8", "d20"):
        d = load_design(name)
        if faces is None or len(d.polyhedron.faces) in faces:
            out.append((name, d))
    for m in range(6, 61, 2) if faces is None else faces:
        for family, params in fair_shapes(m):
            d = Design(f"fair-{m}", family, params, values={f"f{k + 1}": k + 1 for k in range(m)},
                       target=f"uniform:{m}")  # fmt: skip
            out.append((f"{family} {m}", d))
    return out


def drop(toml: Path, sims: int, seed: int, workers: int, *options: str) -> dict:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-m", "diefab", "validate", str(toml), "--sims", str(sims), "--seed",
                           str(seed), "--workers", str(workers), "--json", *options], cwd=ROOT, env=env,
                          capture_output=True, text=True)  # fmt: skip
    if done.returncode != 0:
        return {"error": (done.stderr.strip().splitlines() or ["?"])[-1]}
    report = json.loads(done.stdout)
    counts = np.array(list(report["face_counts"].values()))
    test = chisquare(counts)
    return {"counts": counts.tolist(), "chi2": float(test.statistic), "df": len(counts) - 1,
            "p_value": float(test.pvalue), "drops_per_second": report["drops_per_second"]}  # fmt: skip


def describe(run: dict) -> str:
    if "error" in run:
        return run["error"]
    c = run["counts"]
    return (f"chi2 {run['chi2']:7.1f} (df {run['df']:2d}) p {run['p_value']:8.2g}  faces {min(c)}-{max(c)}  "
            f"{run['drops_per_second']:5.0f} drops/s")  # fmt: skip


def main() -> None:
    from diefab.dice.design import design_to_toml
    from diefab.physics.shapes import folded_resting_faces
    from diefab.physics.world import die_body, import_pybullet
    from diefab.search.symmetric import tipping_angle

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sims", type=int, default=4000)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--faces", type=int, nargs="*", default=None, help="Only dice of these face counts.")
    args = parser.parse_args()
    results = json.loads(RESULTS.read_text()) if RESULTS.is_file() else {}
    print(f"{args.sims} drops each, seed {args.seed}, {args.workers} workers, load {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as tmp:
        for label, d in dices if (dices := dice(args.faces)) else []:
            toml = Path(tmp) / f"{d.name}.toml"
            toml.write_text(design_to_toml(d))
            poly = d.polyhedron
            body = die_body(poly, d.mass_properties())
            folds = bool(folded_resting_faces(import_pybullet(), body).any())
            tipping = tipping_angle(poly, poly.centroid)
            print(f"{label:18s} tipping {tipping:5.1f} deg, folds {'yes' if folds else 'no'}", flush=True)
            hull = drop(toml, args.sims, args.seed, args.workers)
            print(f"  one hull:    {describe(hull)}", flush=True)
            row = {"sims": args.sims, "seed": args.seed, "folds": folds, "tipping": tipping, "hull": hull}
            if folds:
                flat = drop(toml, args.sims, args.seed, args.workers, "--flat-faces")
                print(f"  flat faces:  {describe(flat)}", flush=True)
                if "error" not in flat and "error" not in hull:
                    print(f"  drops/s flat/hull {flat['drops_per_second'] / hull['drops_per_second']:.2f}", flush=True)
                row["flat"] = flat
            results[label] = row
            RESULTS.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
