"""Simulate random gems made in a fill (paper, print or shell) and learn that fill's correction of the fast model.

One command per fill.  It draws ``--designs`` random stable gems with design
seed ``--seed`` (:func:`bench_fastmodel.iter_random_designs`: uniform in the
family box, at the fill's default settings: 160 g/m² card with the glue tabs
of the net ``diefab net`` lays out, or the default print), drops each
``--drops`` times in pybullet (default physics, physics seed
``--physics-seed``) and keeps the counts, with the body each gem was
simulated with, in ``benchmarks/results/fastmodel.json`` (written atomically
after every gem: an interrupted run loses at most the gem in flight, and a
rerun simulates only what is missing).  ``--extra-set NAME`` adds gems
already simulated in that fill at its current default settings under that
set name (for example the shell gems of ``bench_fastmodel.py --fill shell
--test-seed 404``).

It then learns :class:`diefab.models.fills.FillCorrection` from them: the
simulated frequencies minus the fast model without the fill's layer, as a
ridge-regularized linear function of the coordinates plus, where it helps, a
Gaussian kernel ridge term, proportional to the body's inertia excess.  The
coordinates, the penalties and the kernel term are chosen by 5-fold
cross-validation over gems (the least mean held-out TVD; within 1 % of it,
the simpler coordinates, the larger penalties, no kernel term), and the
result is written to ``diefab/data/gem-discrepancy-FILL.json`` with the
training sets, their gems, drops and physics seed in ``info["sets"]``.  The
design seed of the held-out test gems (707) is refused.

Before learning, the bodies of a few training gems are rebuilt with the
current code and compared with the recorded ones: if the body model has
changed since the gems were simulated (a new net layout moves the glue
tabs), the counts no longer describe these dice and the script stops.

Usage (the packaged corrections)::

    nice -n 10 python benchmarks/learn_fill_correction.py --fill paper --seed 608 --designs 150 --drops 2000 \\
        --workers 2 --collect-only
    nice -n 10 python benchmarks/learn_fill_correction.py --fill print --seed 608 --designs 200 --drops 2000 \\
        --workers 2 --collect-only
    python benchmarks/learn_fill_correction.py --fill paper --designs 0 --extra-set train-paper-608 \\
        --extra-set train-paper-607 --extra-set train-paper-606
    python benchmarks/learn_fill_correction.py --fill print --designs 0 --extra-set train-print-608 \\
        --extra-set train-print-606 --extra-set train-print
    python benchmarks/learn_fill_correction.py --fill shell --designs 0 --extra-set test-404-shell

(``train-paper-606`` holds 61 paper gems simulated with the former,
asymmetric tab layout, ``train-paper-607`` 30 and ``train-print-606`` 27 at
1,000 drops, ``train-print`` 26 printed gems of design seed 404 at
2,000-5,000 drops).  A larger ``--designs`` with the same seed simulates
only the gems not yet in the cache.

Measure the result on gems of another seed with ``bench_fastmodel.py --fill FILL --test-seed 707``.

``--learning-curve 42,84,112`` learns nothing and writes nothing: it scores
the packaged correction's choice (its linear part alone, then with its kernel
term, if it has one) by the same 5-fold cross-validation on the first 42, 84
and 112 of the given gems, in the order of their sets, then, on the largest
n, how each held-out TVD follows the gem's d (the apex height: Pearson's r and
where the worst tenth lie)::

    python benchmarks/learn_fill_correction.py --fill paper --designs 0 --extra-set train-paper-608 \\
        --learning-curve 28,42,56,84,112,150
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from itertools import islice
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_fastmodel import (  # noqa: E402
    DISCREPANCY,
    FOLDS,
    MIN_MARGIN,
    iter_random_designs,
    load_cache,
    noise_floor,
    physics_version,
    simulated,
)

from diefab.models import fills  # noqa: E402
from diefab.stats.goodness import tvd  # noqa: E402

#: Ridge penalties the cross-validation chooses from (per training gem, on standardized coordinates).
PENALTIES = (1e-3, 1e-2, 3e-2, 1e-1, 0.3, 1.0, 10.0)
#: The kernel term's lengths and penalties (per training gem), tried on top of the chosen linear part.
KERNEL_LENGTHS = (0.3, 0.6, 1.0)
KERNEL_PENALTIES = (1e-3, 3e-3, 1e-2, 3e-2)
#: Linear penalties tried together with a kernel term.
KERNEL_LINEAR_PENALTIES = (0.1, 0.3, 1.0)
#: Design seeds of the held-out test gems (``bench_fastmodel.py --fill FILL --test-seed 707``): never learned from.
HELD_OUT_SEEDS = (707,)
#: Recorded bodies rebuilt to check that the body model has not changed since they were simulated.
BODY_CHECKS = 3
#: How far a rebuilt body may lie from the recorded one (model units, and model units² for the inertia).
BODY_TOLERANCE = 1e-6


def fail(message: str) -> None:
    """One line on stderr and exit status 2."""
    print(message, file=sys.stderr)
    raise SystemExit(2)


class FillData:
    """Training gems of one fill: what the correction is learned from."""

    def __init__(self, kind: str, designs: list, runs: list[dict]):
        from diefab.geometry.polyhedron import face_margins
        from diefab.models.fills import DISCREPANCY_AT, body_excess, made_gem_base

        self.kind, self.designs, self.runs = kind, designs, runs
        self.points = np.array([[d.params[n] for n in "abcde"] for d in designs])
        counts = np.array([r["face_counts"] for r in runs], dtype=float)
        self.q = counts / counts.sum(axis=1, keepdims=True)
        self.drops = counts.sum(axis=1)
        margins, excess = [], []
        self.base = {at: [] for at in DISCREPANCY_AT}  # the base model, by where it takes the solid discrepancy
        for d, r in zip(designs, runs):
            center, inertia = np.array(r["body"]["center"]), np.array(r["body"]["inertia"])
            margins.append(face_margins(d.polyhedron, center))
            excess.append(body_excess(d.polyhedron, inertia))
            for at, out in self.base.items():
                out.append(made_gem_base(d.polyhedron, center, inertia, d.params, margins[-1], at))
        self.base = {at: np.array(v) for at, v in self.base.items()}
        self.margins, self.excess = np.array(margins), np.array(excess)

    def learn(self, discrepancy_at: str = "body", **kw):
        from diefab.models.fills import FillCorrection

        base = self.base[discrepancy_at]
        return FillCorrection.learn(self.kind, self.points, self.margins, base, self.excess, self.q,
                                    discrepancy_at=discrepancy_at, **kw)  # fmt: skip

    def cross_validate(self, discrepancy_at: str = "body", **kw) -> np.ndarray:
        """(n,) held-out TVD of every gem, 5-fold (fixed folds), each fold learned from the others with `kw`."""
        from diefab.models.fills import FillCorrection

        n = len(self.designs)
        base = self.base[discrepancy_at]
        folds = np.random.default_rng(0).permutation(n) % FOLDS
        err = np.empty(n)
        for k in range(FOLDS):
            train = folds != k
            fit = FillCorrection.learn(self.kind, self.points[train], self.margins[train], base[train],
                                       self.excess[train], self.q[train], **kw)  # fmt: skip
            for i in np.flatnonzero(~train):
                params = dict(zip("abcde", self.points[i]))
                err[i] = tvd(fit.correct(base[i], params, self.margins[i], self.excess[i]), self.q[i])
        return err


def check_bodies(designs: list, runs: list[dict], k: int = BODY_CHECKS) -> None:
    """Stop when the current code builds other bodies than the recorded ones (the counts would be stale)."""
    for d, r in list(zip(designs, runs))[:k]:
        body = d.mass_properties()
        center, inertia = np.array(r["body"]["center"]), np.array(r["body"]["inertia"])
        moved = max(np.abs(body.center - center).max(), np.abs(body.inertia / body.mass - inertia).max())
        if moved > BODY_TOLERANCE:
            fail(f"learn_fill_correction: the {d.fill.kind} body of gem {dict(d.params)} is not the one it "
                     f"was simulated with (off by {moved:.2g}): the body model has changed; simulate again "
                     "(a new --seed) before learning")  # fmt: skip


def cached_set(name: str, kind: str, cache: dict) -> tuple[list, list[dict]]:
    """The gems of set `name` simulated in fill `kind` at its current default settings, with their bodies."""
    from bench_fastmodel import MADE, body_record

    from diefab.dice.design import load_design
    from diefab.geometry.polyhedron import face_margins
    from diefab.made.fill import Fill

    fill = Fill(kind=kind)
    label = json.dumps(fill.to_mapping(), sort_keys=True) if kind in MADE else kind
    base = replace(load_design("fudge-gem"), fill=fill)
    designs, runs = [], []
    for r in sorted(cache.values(), key=lambda r: r["index"]):
        if r["set"] != name or r.get("fill", "solid") != label or r["physics"] != physics_version():
            continue
        d = base.with_params(**r["params"])
        if "body" not in r:  # simulated before bodies were recorded: this one (the check below compares others)
            r = {**r, "body": body_record(d)}
        if face_margins(d.polyhedron, np.array(r["body"]["center"])).min() <= 0:
            continue
        designs.append(d)
        runs.append(r)
    if not designs:
        fail(f"learn_fill_correction: no {kind} gems of set {name!r} in the cache")
    return designs, runs


def choose(data: FillData) -> tuple[dict, dict]:
    """Base, coordinates, penalty and kernel term by cross-validation; returns the choice and every score.

    First the linear correction (where the solid discrepancy is taken, the
    coordinates, the penalty), then a kernel term on top of it (its length
    and penalty, with the linear penalty again).  In each stage the least
    mean held-out TVD wins, and within 1 % of it the simpler choice (simpler
    coordinates, larger penalties, no kernel term).
    """
    from diefab.models.fills import DISCREPANCY_AT, FILL_COORDINATES

    def score(label: str, **kw) -> tuple[float, float]:
        err = data.cross_validate(**kw)
        scores[label] = out = (float(np.median(err)), float(err.mean()))
        print(f"  {label:<40} {FOLDS}-fold CV TVD median {out[0]:.4f} mean {out[1]:.4f}", file=sys.stderr, flush=True)
        return out

    scores, linear = {}, {}
    for at in DISCREPANCY_AT:
        for coordinates in FILL_COORDINATES:
            for penalty in PENALTIES:
                kw = {"discrepancy_at": at, "coordinates": coordinates, "penalty": penalty}
                linear[at, coordinates, penalty] = score(label(kw), **kw)
    least = min(v[1] for v in linear.values())
    simple = {c: i for i, c in enumerate(FILL_COORDINATES)}
    at, coordinates, penalty = min((k for k, v in linear.items() if v[1] <= 1.01 * least),
                                   key=lambda k: (simple[k[1]], -k[2], k[0] != "body"))  # fmt: skip
    choice = {"discrepancy_at": at, "coordinates": coordinates, "penalty": penalty}
    if coordinates == "constant":
        return choice, scores
    kernel = {}
    for length in KERNEL_LENGTHS:
        for kernel_penalty in KERNEL_PENALTIES:
            for lin in KERNEL_LINEAR_PENALTIES:
                kw = choice | {"penalty": lin, "kernel_length": length, "kernel_penalty": kernel_penalty}
                kernel[lin, length, kernel_penalty] = score(label(kw), **kw)
    best = min(v[1] for v in kernel.values())
    if best < linear[at, coordinates, penalty][1] / 1.01:
        lin, length, kernel_penalty = min((k for k, v in kernel.items() if v[1] <= 1.01 * best),
                                          key=lambda k: (-k[2], -k[0], -k[1]))  # fmt: skip
        choice |= {"penalty": lin, "kernel_length": length, "kernel_penalty": kernel_penalty}
    return choice, scores


def learning_curve(kind: str, designs: list, runs: list[dict], sizes: list[int]) -> None:
    """Print the packaged correction's cross-validated TVD on the first n gems, for each n in `sizes`."""
    packaged = fills.fill_discrepancy(kind)
    if packaged is None:
        fail(f"learn_fill_correction: no packaged {kind} correction to score")
    linear = {"discrepancy_at": packaged.discrepancy_at, "coordinates": packaged.coordinates,
              "penalty": packaged.penalty}  # fmt: skip
    choices = {"linear": linear}
    if packaged.kernel_length:
        choices["with kernel"] = linear | {"kernel_length": packaged.kernel_length,
                                           "kernel_penalty": packaged.kernel_penalty}  # fmt: skip
    print(f"the packaged {kind} correction's choice ({label(choices.get('with kernel', linear))}) by {FOLDS}-fold "
          f"CV on the first n of {len(designs)} gems")  # fmt: skip
    print(f"{'gems':>5}" + "".join(f"  {name + ' median':>18} {'mean':>7}" for name in choices))
    for n in sizes:
        data = FillData(kind, designs[:n], runs[:n])
        row = [data.cross_validate(**kw) for kw in choices.values()]
        print(f"{n:5d}" + "".join(f"  {np.median(err):18.4f} {err.mean():7.4f}" for err in row), flush=True)
    d = data.points[:, 3]
    for name, err in zip(choices, row):
        worst = np.argsort(err)[-max(1, len(err) // 10) :]
        print(f"{name} on the {len(err)} gems: held-out TVD against d, Pearson r {np.corrcoef(d, err)[0, 1]:+.2f}; "
              f"the worst tenth have d {d[worst].min():.2f}-{d[worst].max():.2f} (median {np.median(d[worst]):.2f}) "
              f"of {d.min():.2f}-{d.max():.2f}")  # fmt: skip


def label(choice: dict) -> str:
    """How a choice is named in the cross-validation scores (``info["cv"]``)."""
    text = f"{choice['discrepancy_at']} {choice['coordinates']} {choice['penalty']:g}"
    if choice.get("kernel_length"):
        text += f" kernel {choice['kernel_length']:g} {choice['kernel_penalty']:g}"
    return text


def main(argv=None) -> None:
    from diefab.core.files import atomic_write
    from diefab.made.fill import Fill
    from diefab.physics.simulate import PhysicsSettings

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fill", choices=fills.FILL_LAYERS, required=True)
    ap.add_argument("--seed", type=int, default=606, help="design seed of the training gems")
    ap.add_argument("--designs", type=int, default=120, help="training gems to draw and simulate")
    ap.add_argument("--drops", type=int, default=1000, help="drops per training gem")
    ap.add_argument("--physics-seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--extra-set", action="append", default=[], metavar="NAME",
                    help="also learn from the gems cached under this set name (same fill and settings, "
                         "with the bodies they were simulated with)")  # fmt: skip
    ap.add_argument("--collect-only", action="store_true", help="simulate and stop")
    ap.add_argument(
        "--learning-curve",
        default=None,
        metavar="N,N,...",
        help="score the packaged correction's choice on the first N gems, for each N; learn nothing",
    )
    ap.add_argument("--cache", type=Path, default=None, help="counts file (default benchmarks/results/fastmodel.json)")
    args = ap.parse_args(argv)
    if args.cache is not None:
        import bench_fastmodel

        bench_fastmodel.RESULTS = args.cache
    if args.designs < 0 or args.drops < 1:
        ap.error("--designs must be >= 0 and --drops >= 1")
    sizes = None
    if args.learning_curve is not None:
        try:
            sizes = [int(n) for n in args.learning_curve.split(",")]
        except ValueError:
            ap.error(f"--learning-curve {args.learning_curve!r}: give whole numbers separated by commas")
        if min(sizes) < 2 * FOLDS:
            ap.error(f"--learning-curve: every size must be at least {2 * FOLDS} gems")

    held_out = [s for s in HELD_OUT_SEEDS if (args.designs and args.seed == s) or
                any(str(s) in extra.split("-") for extra in args.extra_set)]  # fmt: skip
    if held_out:
        fail(f"learn_fill_correction: design seed {held_out[0]} holds the held-out test gems; train on another")

    cache = load_cache()
    name = f"train-{args.fill}-{args.seed}"
    drawn = islice(iter_random_designs(args.seed, args.fill), args.designs)
    designs, runs = simulated(drawn, args.drops, args.physics_seed, name, cache, args.workers, args.designs)
    checked = len(designs) or None  # the drawn gems come first
    for extra in args.extra_set:
        d, r = cached_set(extra, args.fill, cache)
        designs, runs = designs + d, runs + r
    if args.collect_only:
        return
    if len(designs) < 2 * FOLDS:
        fail(f"learn_fill_correction: {len(designs)} gems are too few to cross-validate; give --designs or "
                 "--extra-set")  # fmt: skip
    # the gems this command draws (or the first extra set) must still be what the code builds; extra sets
    # are taken with the bodies they were simulated with, which the correction takes as inputs
    check_bodies(designs[:checked], runs[:checked])
    if sizes is not None:
        if max(sizes) > len(designs):
            fail(f"learn_fill_correction: --learning-curve asks for {max(sizes)} gems; there are {len(designs)}")
        learning_curve(args.fill, designs, runs, sizes)
        return

    data = FillData(args.fill, designs, runs)
    sets = {}
    for r in runs:
        # the set's name holds its design seed (train-FILL-SEED)
        entry = sets.setdefault(r["set"], {"set": r["set"], "physics_seed": r["seed"], "gems": 0, "drops": 0,
                                           "drops_per_gem": set()})  # fmt: skip
        entry["gems"] += 1
        entry["drops"] += int(r["drops"])
        entry["drops_per_gem"].add(int(r["drops"]))
    print(f"{len(designs)} {args.fill} gems, {int(data.drops.sum())} drops (median {int(np.median(data.drops))} "
          f"per gem; sampling noise alone ~{np.median(noise_floor(data.q, data.drops)):.4f} TVD per gem)")  # fmt: skip
    choice, scores = choose(data)
    before = np.array([tvd(p, q) for p, q in zip(data.base[choice["discrepancy_at"]], data.q)])
    info = {
        "fill": Fill(kind=args.fill).to_mapping(),
        "designs": len(designs),
        "design_seed": args.seed if args.designs else None,
        "extra_sets": args.extra_set,
        "min_margin": MIN_MARGIN,
        "drops": int(np.median(data.drops)),
        "total_drops": int(data.drops.sum()),
        "sets": [v | {"drops_per_gem": sorted(v["drops_per_gem"])} for v in sets.values()],
        "seed": args.physics_seed,
        "physics": physics_version(),
        "settings": PhysicsSettings().as_dict(),
        "bodies": [{"params": dict(d.params), **r["body"]} for d, r in list(zip(designs, runs))[:BODY_CHECKS]],
        "on_top_of": "fast model without this layer (chain with the body's inertia + gem discrepancy)",
        "before_median_tvd": round(float(np.median(before)), 5),
        "cv": {k: {"median_tvd": round(v[0], 5), "mean_tvd": round(v[1], 5)} for k, v in scores.items()},
    }
    fit = data.learn(**choice, info=info)
    out = DISCREPANCY / fills.fill_discrepancy_file(args.fill)
    atomic_write(out, fit.to_json())
    median, mean = scores[label(choice)]
    print(f"learned the {args.fill} correction: {label(choice)} (solid discrepancy at, coordinates, penalty"
          f"{', kernel length and penalty' if choice.get('kernel_length') else ''}); "
          f"{FOLDS}-fold CV TVD median {median:.4f} mean {mean:.4f} (without it {np.median(before):.4f} "
          f"mean {before.mean():.4f}); wrote {out.relative_to(DISCREPANCY.parents[1])}")  # fmt: skip


if __name__ == "__main__":
    main()
