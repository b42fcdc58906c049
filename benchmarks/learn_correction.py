"""Simulate random dice of every family and learn the fast model's per-face correction from them.

Two steps, each resumable:

``--collect``  draws ``--designs`` random dice (:func:`diefab.dice.families.sampling.random_design`,
    ``--families`` (default all) in turn, die *i* from ``default_rng([seed, i])``), drops each
    ``--drops`` times in pybullet (physics seed ``seed * 1000 + i``, default
    settings, solid fill) and appends its face counts to
    ``diefab/data/correction-training.jsonl`` (one line per die, written as
    soon as it is simulated: an interrupted run loses at most the die in
    flight, and a rerun simulates only what is missing);
``--fit``      chooses the correction's feature set and ridge penalty by
    grouped cross-validation over those dice and writes the fitted table,
    ``diefab/data/correction.json``.

Usage::

    nice -n 10 python benchmarks/learn_correction.py --collect --designs 180 --drops 600 --workers 1
    nice -n 10 python benchmarks/learn_correction.py --collect --seed 1202 --designs 24 --drops 1200 \
        --families ngem,prism,bipyramid,freeform,convex --workers 1
    nice -n 10 python benchmarks/learn_correction.py --collect --seed 1203 --designs 70 --drops 1200 \
        --families ngem,prism,bipyramid,trapezohedron,cuboid,freeform,convex --workers 1
    python benchmarks/learn_correction.py --fit                # refit the constants, cross-validate, write
    python benchmarks/learn_correction.py --fit --keep-chain   # the same on the packaged constants (quicker)
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1] / "diefab" / "data"
TRAINING = DATA / "correction-training.jsonl"
TRAIN_SEED = 1201


def training_design(seed: int, i: int, families: list[str] | None = None):
    """Die `i` of the training set drawn with `seed` (`families`, default all, in turn)."""
    from diefab.dice.families.sampling import RANDOM_FAMILIES, random_design

    names = list(families or RANDOM_FAMILIES)
    return random_design(names[i % len(names)], np.random.default_rng([seed, i]), label=f"train-{i}")


def read_runs(path: Path = TRAINING) -> list[dict]:
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def collect(
    designs: int, drops: int, seed: int, workers: int | None, families: list[str] | None = None, path: Path = TRAINING
) -> None:
    from diefab.dice.families.sampling import design_record
    from diefab.physics.simulate import simulate
    from diefab.physics.world import OUTCOME_VERSION

    done = {(r["seed"], r["index"]) for r in read_runs(path) if r["drops"] >= drops}
    path.parent.mkdir(parents=True, exist_ok=True)
    for i in range(designs):
        if (seed, i) in done:
            continue
        d = training_design(seed, i, families)
        t = time.perf_counter()
        r = simulate(d, drops, seed=seed * 1000 + i, workers=workers)
        row = {"seed": seed, "index": i, **design_record(d), "drops": drops, "physics": f"outcomes-{OUTCOME_VERSION}",
               "face_counts": r.face_counts.tolist(), "cocked": int(r.cocked)}  # fmt: skip
        with path.open("a") as fh:  # one complete line per die
            fh.write(json.dumps(row, separators=(",", ":")) + "\n")
        print(f"  {i + 1}/{designs} {d.family:13s} {len(d.values):2d} faces: {drops} drops in "
              f"{time.perf_counter() - t:.1f} s", file=sys.stderr, flush=True)  # fmt: skip


#: What the cross-validation chooses from.
CHOICES = (
    *(("small", p, 1.0) for p in (1e-3, 1e-1)),
    *(("linear", p, 1.0) for p in (1e-3, 1e-2, 1e-1, 1.0)),
    *(("quadratic", p, 1.0) for p in (3e-3, 1e-2, 3e-2, 1e-1, 1.0)),
    *(("rbf", p, w) for p in (1e-3, 1e-2, 1e-1) for w in (0.5, 1.0)),
)
FOLDS = 5


class TrainingSet:
    """The simulated training dice with their features, chain probabilities and frequencies (resting faces)."""

    def __init__(self, runs: list[dict], constants: dict):
        from diefab.dice.families.sampling import record_design
        from diefab.models.correction import face_features
        from diefab.models.fast import landing_probabilities

        self.runs, self.features, self.chains, self.q, self.families = runs, [], [], [], []
        self.constants = constants
        for r in runs:
            d = record_design(r)
            poly, center = d.polyhedron, d.mass_properties().center
            chain = landing_probabilities(poly, center, **constants)
            x, resting = face_features(poly, center, chain)
            counts = np.array(r["face_counts"], dtype=float)
            self.features.append(x[resting])
            self.chains.append(chain[resting] / chain[resting].sum())
            self.q.append(counts[resting] / counts[resting].sum())
            self.families.append(r["family"])

    def tvd(self, fit, i: int) -> float:
        p = fit.correct(self.chains[i], self.features[i], np.ones(len(self.chains[i]), bool))
        return 0.5 * float(np.abs(p - self.q[i]).sum())

    def fit(self, which, **kw):
        from diefab.models.correction import Correction

        return Correction.fit([self.features[i] for i in which], [self.chains[i] for i in which],
                              [self.q[i] for i in which], chain=self.constants, **kw)  # fmt: skip

    def cross_validate(self, **kw) -> np.ndarray:
        """(n,) held-out TVD of every die, 5-fold grouped by die (fixed folds)."""
        n = len(self.runs)
        folds = np.random.default_rng(0).permutation(n) % FOLDS
        err = np.empty(n)
        for k in range(FOLDS):
            fit = self.fit(np.flatnonzero(folds != k), **kw)
            for i in np.flatnonzero(folds == k):
                err[i] = self.tvd(fit, i)
        return err


def fit(path: Path = TRAINING, maxfev: int = 600, keep_chain: bool = False) -> None:
    """Refit the chain's constants, choose expansion and penalty by cross-validation, write the table.

    The chain's five constants are refitted (:func:`diefab.models.fast.calibrate`,
    least mean TVD, at most `maxfev` evaluations) to every training die, then
    the correction on top of that chain is cross-validated: the folds hold
    dice out of the correction's fit, not of the constants' (5 numbers fitted
    to all the dice).  With `keep_chain`, the packaged correction's constants
    are kept instead.
    """
    from diefab.core.files import atomic_write
    from diefab.dice.families.sampling import record_design
    from diefab.models.probabilities import correction
    from diefab.models import fast as fastmodel

    runs = read_runs(path)
    t = time.perf_counter()
    if keep_chain:  # the packaged table's constants, whatever features it was fitted on
        constants = dict(json.loads((DATA / correction.CORRECTION_FILE).read_text())["chain"])
    else:
        constants = fastmodel.calibrate([record_design(r) for r in runs], [np.array(r["face_counts"]) for r in runs],
                                        maxfev=maxfev)  # fmt: skip
        print(f"chain constants refitted to {len(runs)} dice in {time.perf_counter() - t:.0f} s: "
              + ", ".join(f"{k} {v:.4g}" for k, v in constants.items()), flush=True)  # fmt: skip
        constants.pop("mean_tvd")
    old = TrainingSet(runs, {})
    data = TrainingSet(runs, constants)
    before = np.array([0.5 * np.abs(c - q).sum() for c, q in zip(old.chains, old.q)])
    chain = np.array([0.5 * np.abs(c - q).sum() for c, q in zip(data.chains, data.q)])
    fams = np.array(data.families)
    print(f"{len(runs)} training dice; the chain with the gem constants: median TVD {np.median(before):.4f}, "
          f"mean {before.mean():.4f}; refitted: median {np.median(chain):.4f}, mean {chain.mean():.4f}")  # fmt: skip
    scores = {}
    for expansion, penalty, width in CHOICES:
        err = data.cross_validate(expansion=expansion, penalty=penalty, width=width)
        scores[(expansion, penalty, width)] = err
        per = " ".join(f"{f} {np.median(err[fams == f]):.3f}" for f in dict.fromkeys(data.families))
        print(f"  {expansion:9s} penalty {penalty:<6g} width {width:<4g}: {FOLDS}-fold CV TVD median "
              f"{np.median(err):.4f} mean {err.mean():.4f}  ({per})", flush=True)  # fmt: skip
    best = min(scores, key=lambda k: scores[k].mean())
    print(f"chosen: {best[0]}, penalty {best[1]:g}, width {best[2]:g}")
    info = {
        "dice": len(runs),
        "families": {f: int((fams == f).sum()) for f in dict.fromkeys(data.families)},
        "drops": sorted({r["drops"] for r in runs}),
        "design_seed": sorted({r["seed"] for r in runs}),
        "physics": sorted({r["physics"] for r in runs}),
        "cv": {
            f"{e} {p:g} {w:g}": {"median_tvd": round(float(np.median(v)), 5), "mean_tvd": round(float(v.mean()), 5)}
            for (e, p, w), v in scores.items()
        },  # fmt: skip
        "chain_tvd": {"median": round(float(np.median(chain)), 5), "mean": round(float(chain.mean()), 5)},
        "gem_chain_tvd": {"median": round(float(np.median(before)), 5), "mean": round(float(before.mean()), 5)},
    }
    table = data.fit(np.arange(len(runs)), expansion=best[0], penalty=best[1], width=best[2], info=info)
    atomic_write(DATA / correction.CORRECTION_FILE, table.to_json())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--collect", action="store_true")
    ap.add_argument("--fit", action="store_true")
    ap.add_argument("--designs", type=int, default=216)
    ap.add_argument("--drops", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=TRAIN_SEED)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--families", default="", help="--collect: comma-separated families to draw in turn (default: all)")
    ap.add_argument("--keep-chain", action="store_true", help="--fit: keep the packaged chain constants")
    args = ap.parse_args(argv)
    if not (args.collect or args.fit):
        ap.error("nothing to do: give --collect, --fit or both")
    if args.designs < 1 or args.drops < 1:
        ap.error("--designs and --drops must be positive")
    if args.collect:
        from diefab.dice.families.sampling import RANDOM_FAMILIES

        families = [f.strip() for f in args.families.split(",") if f.strip()]
        unknown = [f for f in families if f not in RANDOM_FAMILIES]
        if unknown:
            ap.error(f"unknown family {unknown[0]!r} (known: {', '.join(RANDOM_FAMILIES)})")
        collect(args.designs, args.drops, args.seed, args.workers, families or None)
    if args.fit:
        if len(read_runs()) < 2 * FOLDS:
            ap.error(f"--fit needs at least {2 * FOLDS} simulated dice in {TRAINING}; run --collect first")
        fit(keep_chain=args.keep_chain)
    return 0


if __name__ == "__main__":
    sys.exit(main())
