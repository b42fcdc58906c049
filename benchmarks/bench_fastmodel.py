"""How well do the landing models track the physics?

Draws random stable gems in the family's whole box (a, b, c, d and e free),
drops each in pybullet (:func:`diefab.physics.simulate.simulate`, default settings)
and compares the ``fast`` model, its physics chain alone and the
``solid-angle`` model with the simulated frequencies by TVD.  Two disjoint
sets of designs:

* a **training** set (``--train-designs`` designs, ``--train-drops`` drops
  each).  ``--calibrate`` fits the chain's five constants on its first
  ``--chain-designs``; ``--learn`` learns the gem discrepancy (what the chain
  misses) from all of it, with the RBF smoothing chosen by 5-fold
  cross-validation, and writes ``diefab/data/gem-discrepancy.json``;
* a **test** set (``--designs`` designs, ``--drops`` drops each, 30,000 by
  default) on which the table and the median TVD are reported, beside the
  sampling noise floor (the median TVD a perfect model would score at
  those drops).

**Fill mode** (``--fill paper|print|shell``): the test gems are made in that
fill at its default settings (160 g/m² card with the net's glue tabs; the
default print) and simulated with their bodies; the table adds the fast
model without the fill's own correction (``no-layer``) and as it was before
it knew the fill (``fast-solid``: solid-trained, solid inertia).  The fill's
correction is learned by ``learn_fill_correction.py`` from gems of another
design seed.

Simulated counts are cached in ``benchmarks/results/fastmodel.json`` (about
600 bytes per design), keyed by parameters, drops, seed, physics settings
and fill settings (a made gem's body, centre and inertia, is kept beside
its counts), so a rerun only simulates what is missing and an interrupted
run loses at most the design in flight.

Usage::

    python benchmarks/bench_fastmodel.py                  # full: 20 x 30,000 drops (~3 min on 2 cores)
    python benchmarks/bench_fastmodel.py --drops 2000     # quick look
    python benchmarks/bench_fastmodel.py --test-seed 303  # the second, never-fitted test set
    python benchmarks/bench_fastmodel.py --calibrate      # refit the chain's constants (paste them into fastmodel.py)
    python benchmarks/bench_fastmodel.py --learn          # relearn the gem discrepancy (~20 min to simulate)
    python benchmarks/bench_fastmodel.py --ablation       # its coordinates and training size, cross-validated
    python benchmarks/bench_fastmodel.py --optima         # the 4dF optima of fast and chain, validated (30k drops)
    python benchmarks/bench_fastmodel.py --fill paper --test-seed 707 --designs 12 --drops 10000  # fill mode
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from diefab.core.files import atomic_write
from diefab.dice.design import load_design
from diefab.geometry.polyhedron import face_margins
from diefab.models import discrepancy, fills
from diefab.stats.goodness import jsd, pearson_divergence, tvd

RESULTS = Path(__file__).with_name("results") / "fastmodel.json"
DISCREPANCY = Path(__file__).resolve().parents[1] / "diefab" / "data"
TRAIN_SEED, TEST_SEED = 101, 202
#: RBF smoothing values the cross-validation of ``--learn`` chooses from.
SMOOTHING = (1e-4, 1e-3, 1e-2, 1e-1, 1.0)
FOLDS = 5
#: Random designs must rest on every face with at least this margin (model units).
MIN_MARGIN = 0.02
#: Fills whose bodies are made (the net's tabs, the print's walls and labels) and recorded beside their counts.
MADE = ("paper", "print")


def iter_random_designs(seed: int, fill: str = "solid"):
    """Random stable gems, uniform in the family box (e included), rejection-sampled, one at a time.

    A solid or shell gem is kept when it rests on every face with a margin of
    at least :data:`MIN_MARGIN`.  A paper or printed gem's body takes seconds
    to build (the net's glue tabs, the print's labels), so it is built only
    for a gem whose shell rests so, and the gem is kept when its own body
    rests on every face with at least half that margin.
    """
    from dataclasses import replace

    from diefab.core.errors import DesignError
    from diefab.dice.families import GEM
    from diefab.made.fill import Fill

    base = replace(load_design("fudge-gem"), fill=Fill(kind=fill))
    bounds = GEM.bounds(["a", "b", "c", "d", "e"])
    rng = np.random.default_rng(seed)
    made = fill not in ("solid", "shell")
    while True:
        x = bounds[:, 0] + rng.random(5) * (bounds[:, 1] - bounds[:, 0])
        params = dict(zip("abcde", np.round(x, 4).tolist()))
        try:
            d = base.with_params(**params)
            if made:
                if d.margins(Fill(kind="shell")).min() < MIN_MARGIN or d.margins().min() < MIN_MARGIN / 2:
                    continue
            elif d.margins().min() < MIN_MARGIN:
                continue
        except DesignError:
            continue
        yield d


def random_designs(k: int, seed: int, fill: str = "solid"):
    """`k` random stable gems (:func:`iter_random_designs`)."""
    from itertools import islice

    return list(islice(iter_random_designs(seed, fill), k))


def physics_version() -> str:
    """The validator's outcome version: counts simulated by other physics code are not reused."""
    from diefab.physics.world import OUTCOME_VERSION

    return f"outcomes-{OUTCOME_VERSION}"


def _key(params, drops, seed, settings, physics, fill="solid") -> str:
    # solid gems keep the key they had before fills were benchmarked
    return json.dumps([params, drops, seed, settings, physics] + ([fill] if fill != "solid" else []), sort_keys=True)


def load_cache() -> dict:
    if RESULTS.exists():
        data = json.loads(RESULTS.read_text())
        return {
            _key(r["params"], r["drops"], r["seed"], r["settings"], r["physics"], r.get("fill", "solid")): r
            for r in data["runs"]
        }
    return {}


def save_cache(cache: dict) -> None:
    """Write the counts simulated by the current physics (older ones are dropped), one run per line."""
    version = physics_version()
    runs = sorted((r for r in cache.values() if r["physics"] == version), key=lambda r: (r["set"], r["index"]))
    lines = ",\n".join(json.dumps(r, sort_keys=True) for r in runs)
    atomic_write(RESULTS, '{"runs": [\n' + lines + "\n]}\n")


def body_record(d) -> dict:
    """The mass properties a gem was simulated with: centre and inertia over mass, model units (rounded)."""
    body = d.mass_properties()
    return {"center": np.round(body.center, 10).tolist(), "inertia": np.round(body.inertia / body.mass, 10).tolist()}


def simulated(designs, drops: int, seed: int, which: str, cache: dict, workers: int | None,
              total: int | None = None) -> tuple[list, list[dict]]:  # fmt: skip
    """Every design with its counts, from the cache or simulated now (and cached at once).

    `designs` may be a lazy iterable of `total` designs: a made gem is then
    simulated right after it is drawn, while its body is still cached.  The
    body a paper or printed gem was simulated with is kept beside its counts
    (:func:`body_record`), so learning need not rebuild it and can tell when
    the body model has changed since.
    """
    from diefab.physics.simulate import PhysicsSettings, simulate

    settings = PhysicsSettings().as_dict()
    total = len(designs) if total is None else total
    out, drawn = [], []
    for i, d in enumerate(designs):
        # a made fill's settings are part of what was simulated (the print model has changed before)
        fill = d.fill.kind if d.fill.kind in ("solid", "shell") else json.dumps(d.fill.to_mapping(), sort_keys=True)
        key = _key(dict(d.params), drops, seed, settings, physics_version(), fill)
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
                **({"fill": fill} if fill != "solid" else {}),
                "face_counts": r.face_counts.tolist(),
                "cocked": r.cocked,
                "unsettled": r.unsettled,
                "seconds": r.seconds,
            }
            if d.fill.kind in MADE:
                cache[key]["body"] = body_record(d)
            save_cache(cache)
            print(f"  simulated {which} {i + 1}/{total}: {drops} drops in {time.perf_counter() - t:.1f} s",
                  file=sys.stderr, flush=True)  # fmt: skip
        elif d.fill.kind in MADE and "body" not in cache[key]:
            cache[key]["body"] = body_record(d)
        out.append(cache[key])
        drawn.append(d)
    return drawn, out


def noise_floor(q: np.ndarray, drops: np.ndarray) -> np.ndarray:
    """(n,) expected TVD between a sample of `drops` landings and its own distribution `q` (n, m).

    ``sum_i sqrt(q_i (1 - q_i) / (2 pi N))``, the normal approximation of
    ``E|f_i - q_i| / 2`` summed over faces: what a perfect model would score.
    """
    return np.sqrt(q * (1 - q) / (2 * np.pi * np.asarray(drops, dtype=float)[:, None])).sum(axis=1)


def frequencies(runs) -> np.ndarray:
    """(n, m) simulated landing frequencies per face (cocked drops excluded)."""
    counts = np.array([r["face_counts"] for r in runs], dtype=float)
    return counts / counts.sum(axis=1, keepdims=True)


def chain_probabilities(designs) -> np.ndarray:
    """(n, m) the chain model (no discrepancy) at each design."""
    from diefab.models.chain import landing_probabilities

    return np.array([landing_probabilities(d.polyhedron, d.mass_properties().center) for d in designs])


class TrainingSet:
    """The solid training gems with what the gem discrepancy is learned from (the chain's probabilities)."""

    def __init__(self, designs, runs):
        self.designs = designs
        self.points = np.array([[d.params[n] for n in "abcde"] for d in designs])
        self.q = frequencies(runs)
        self.p = chain_probabilities(designs)
        self.margins = np.array([d.margins() for d in designs])

    def cross_validate(self, n: int | None = None, distances: bool = False, **kw):
        """(n,) held-out TVD of each of the first `n` designs, 5-fold (fixed folds), learning with `kw`.

        With `distances`, also each design's distance to the nearest design of the other folds.
        """
        from diefab.models.discrepancy import Discrepancy

        n = len(self.designs) if n is None else n
        folds = np.random.default_rng(0).permutation(n) % FOLDS
        err, near = np.empty(n), np.empty(n)
        for k in range(FOLDS):
            train = np.flatnonzero(folds != k)
            fit = Discrepancy.learn(self.points[train], self.margins[train], self.p[train], self.q[train], **kw)
            for i in np.flatnonzero(folds == k):
                params = dict(zip("abcde", self.points[i]))
                err[i] = tvd(fit.correct(self.p[i], params, self.margins[i]), self.q[i])
                near[i] = fit.distance(params, self.margins[i], self.p[i]) if distances else np.nan
        return (err, near) if distances else err

    def learn(self, **kw):
        from diefab.models.discrepancy import Discrepancy

        return Discrepancy.learn(self.points, self.margins, self.p, self.q, **kw)


def learn(training: TrainingSet, drops: int, seed: int, design_seed: int = TRAIN_SEED) -> dict:
    """Learn the gem discrepancy from the solid training set and write it into the package.

    The smoothing is chosen from :data:`SMOOTHING` by 5-fold cross-validation
    (fixed folds, each fold learning from the others): the largest whose mean
    held-out TVD is within 1 % of the least (more smoothing, same accuracy).
    A fill's correction is learned by ``learn_fill_correction.py``.
    """
    from diefab.models import chain
    from diefab.physics.simulate import PhysicsSettings

    scores = {}
    for smoothing in SMOOTHING:
        err = training.cross_validate(smoothing=smoothing)
        scores[smoothing] = (float(np.median(err)), float(np.mean(err)))
        print(f"  smoothing {smoothing:g}: {FOLDS}-fold CV TVD median {scores[smoothing][0]:.4f} "
              f"mean {scores[smoothing][1]:.4f}", file=sys.stderr, flush=True)  # fmt: skip
    least = min(v[1] for v in scores.values())
    best = max(k for k, v in scores.items() if v[1] <= 1.01 * least)
    before = np.array([tvd(p, q) for p, q in zip(training.p, training.q)])
    names = ("temperature", "tau", "area_power", "roll_power", "height_weight")
    info = {
        "designs": len(training.designs),
        "design_seed": design_seed,
        "min_margin": MIN_MARGIN,
        "drops": drops,
        "seed": seed,
        "physics": physics_version(),
        "settings": PhysicsSettings().as_dict(),
        "chain": {k: getattr(chain, k.upper()) for k in names},
        "cv": {f"{k:g}": {"median_tvd": round(v[0], 5), "mean_tvd": round(v[1], 5)} for k, v in scores.items()},
    }
    name = discrepancy.DISCREPANCY_FILE
    fit = training.learn(smoothing=best, info=info)
    atomic_write(DISCREPANCY / name, fit.to_json())
    discrepancy.gem_discrepancy.cache_clear()
    score = scores[best]
    out = {"file": name, "smoothing": best}
    return out | {"cv_median_tvd": score[0], "cv_mean_tvd": score[1], "median_tvd_without": float(np.median(before))}


def ablation(training: TrainingSet, test, test_q) -> None:
    """Cross-validated TVD by coordinates and training-set size; the test set with the parameters alone."""
    from diefab.models import chain

    smoothing = discrepancy.gem_discrepancy().smoothing
    print(f"\nablation ({FOLDS}-fold CV on the training set at its drops, noise included; smoothing {smoothing:g})")
    print(f"{'coordinates':<28} {'designs':>7} {'median':>7} {'mean':>7}")
    for physics, label in ((False, "parameters"), (True, "parameters + margins, chain")):
        for n in (200, 400, len(training.designs)):
            err = training.cross_validate(n, smoothing=smoothing, physics_coordinates=physics)
            print(f"{label:<28} {n:7d} {np.median(err):7.4f} {err.mean():7.4f}")
    err, near = training.cross_validate(smoothing=smoothing, distances=True)
    chain_tvd = np.array([tvd(p, q) for p, q in zip(training.p, training.q)])
    lo, hi = np.quantile(near, [1 / 8, 7 / 8])
    print(f"held-out gems by distance to their nearest training gem: nearest eighth (<= {lo:.3f}) median TVD "
          f"{np.median(err[near <= lo]):.4f}; farthest eighth (>= {hi:.3f}) {np.median(err[near >= hi]):.4f}, "
          f"chain alone there {np.median(chain_tvd[near >= hi]):.4f}")  # fmt: skip
    shape = training.learn(smoothing=smoothing, physics_coordinates=False)
    err = []
    for d, q in zip(test, test_q):
        c = d.mass_properties().center
        p = chain.landing_probabilities(d.polyhedron, c)
        err.append(tvd(shape.correct(p, d.params, d.margins()), q))
    print(f"test set with the parameters alone as coordinates: median TVD {np.median(err):.4f}, max {max(err):.4f}")


def optima(drops: int, seeds=(1, 2), workers: int | None = None) -> None:
    """The 4dF optimum of the fast model and of its chain alone, each validated by simulation."""
    from diefab.models import chain
    from diefab.models.probabilities import MODELS
    from diefab.physics.simulate import simulate
    from diefab.search.optimize import optimize_design

    MODELS.setdefault("chain", chain.landing_probabilities)  # for this benchmark only
    base = load_design("fudge-gem")
    goal = base.target_distribution.aligned(base.support)
    print(f"\n4dF optima (diefab optimize fudge-gem --model M, seed 0), validated with {drops} drops per seed")
    for model in ("fast", "chain"):
        t = time.perf_counter()
        d = optimize_design(base, model=model, seed=0).design
        seconds = time.perf_counter() - t
        params = " ".join(f"{k}={v:.4f}" for k, v in d.params.items())
        q = [simulate(d, drops, seed=s, workers=workers).value_probabilities(d) for s in seeds]
        print(f"{model:>6}: {params}  ({seconds:.1f} s); TVD to 4dF at seeds {' / '.join(map(str, seeds))}: "
              f"{' / '.join(f'{tvd(v, goal):.4f}' for v in q)}; at seed {seeds[0]} Eq. (2) "
              f"{pearson_divergence(q[0], goal):.5f}, JSD {jsd(q[0], goal):.5f}")  # fmt: skip


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", type=int, default=20, help="test designs")
    ap.add_argument("--drops", type=int, default=30_000, help="drops per test design")
    ap.add_argument("--test-seed", type=int, default=TEST_SEED, help="design seed of the test set")
    ap.add_argument("--fill", choices=("solid", "shell", "paper", "print"), default="solid",
                    help="fill of the test gems, at its default settings (fill mode: the fast model with that "
                         "fill's correction, learned by learn_fill_correction.py)")  # fmt: skip
    ap.add_argument("--train-designs", type=int, default=800)
    ap.add_argument("--train-seed", type=int, default=TRAIN_SEED, help="design seed of the training set")
    ap.add_argument("--train-drops", type=int, default=4_000)
    ap.add_argument("--chain-designs", type=int, default=20, help="training designs --calibrate fits the chain on")
    ap.add_argument("--seed", type=int, default=0, help="physics seed of the drops")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--calibrate", action="store_true", help="refit the chain's five constants (prints them)")
    ap.add_argument("--learn", action="store_true", help="relearn the gem discrepancy from the training set")
    ap.add_argument("--ablation", action="store_true", help="cross-validate the discrepancy's coordinates and size")
    ap.add_argument("--optima", action="store_true", help="validate the 4dF optima of the fast model and its chain")
    ap.add_argument("--collect-only", action="store_true", help="simulate (fill the cache) and stop")
    args = ap.parse_args(argv)
    if args.calibrate and (args.learn or args.ablation):
        ap.error("--calibrate prints constants to paste into fastmodel.py; --learn afterwards, in a second run")

    from itertools import islice

    cache = load_cache()
    # the training set is simulated only when it is used
    if args.learn or args.ablation or args.collect_only:
        k, train = args.train_designs, islice(iter_random_designs(args.train_seed), args.train_designs)
    else:
        k = args.chain_designs if args.calibrate else 0
        train = random_designs(k, TRAIN_SEED)
    train, train_runs = simulated(train, args.train_drops, args.seed, "train", cache, args.workers, k)
    which = "test" if args.test_seed == TEST_SEED else f"test-{args.test_seed}"
    which += "" if args.fill == "solid" else f"-{args.fill}"
    test = islice(iter_random_designs(args.test_seed, args.fill), args.designs)
    test, test_runs = simulated(test, args.drops, args.seed, which, cache, args.workers, args.designs)
    if args.collect_only:
        return

    from diefab.models import chain
    from diefab.models.probabilities import MODELS

    constants = {}
    if args.calibrate:
        fit = chain.calibrate(train, [np.array(r["face_counts"]) for r in train_runs])
        print(f"calibrated the chain on {len(train)} training designs x {args.train_drops} drops: {fit}")
        constants = {k: v for k, v in fit.items() if k != "mean_tvd"}
    training = TrainingSet(train, train_runs) if (args.learn or args.ablation) else None
    if args.learn:
        fit = learn(training, args.train_drops, args.seed, args.train_seed)
        print(f"learned from {len(train)} training designs x {args.train_drops} drops: {fit}")

    if not test:  # --designs 0: learning (or calibrating) only
        return

    def chain_alone(poly, center, *, fill=None, inertia=None):
        return chain.landing_probabilities(poly, center, inertia=inertia, **constants)

    def solid_trained(poly, center, *, fill=None, inertia=None):
        return MODELS["fast"](poly, center)

    def no_layer(poly, center, *, fill=None, inertia=None):
        from diefab.dice.families import gem_parameters

        at = fills.fill_discrepancy(args.fill).discrepancy_at
        return fills.made_gem_base(poly, center, inertia, gem_parameters(poly), face_margins(poly, center), at)

    # with new chain constants the packaged discrepancy (learned against the old chain) does not apply
    models = {"fast": MODELS["fast"], "chain": chain_alone, "solid": MODELS["solid-angle"]}
    if args.fill != "solid":  # the fast model without the fill's correction, and as it was before it knew the fill
        models |= {"no-layer": no_layer, "fast-solid": solid_trained}
    if args.calibrate:
        del models["fast"]
    found = discrepancy.gem_discrepancy()
    rows, near = [], []
    margins = []
    for d, r, q in zip(test, test_runs, frequencies(test_runs)):
        poly = d.polyhedron
        if "body" in r:  # a made gem: the body it was simulated with (rebuilding a net's tabs takes seconds)
            center, inertia = np.array(r["body"]["center"]), np.array(r["body"]["inertia"])
        else:
            body = d.mass_properties()
            center, inertia = body.center, body.inertia / body.mass
        margins.append(face_margins(poly, center).min())
        kw = {"fill": d.fill, "inertia": inertia}
        rows.append([tvd(fn(poly, center, **kw) if name != "solid" else fn(poly, center), q)
                     for name, fn in models.items()])  # fmt: skip
        near.append(found.distance(d.params, face_margins(poly, center), chain.landing_probabilities(poly, center)))
    rows = np.array(rows)

    info = found.info
    print(f"\n{', '.join(models)} against {args.drops}-drop simulations "
          f"({len(test)} random stable {args.fill} gems, design seed {args.test_seed}, physics seed {args.seed}; "
          f"discrepancy learned from {info['designs']} other gems x {info['drops']} drops)")  # fmt: skip
    print(f"{'#':>3} {'a':>6} {'b':>6} {'c':>6} {'d':>6} {'e':>6} {'margin':>7} {'cocked':>7} {'nearest':>7}  "
          + " ".join(f"{'TVD ' + m if i == 0 else m:>9}" for i, m in enumerate(models)))  # fmt: skip
    for i, (d, r, row) in enumerate(zip(test, test_runs, rows)):
        p = d.params
        print(f"{i:3d} {p['a']:6.3f} {p['b']:6.3f} {p['c']:6.3f} {p['d']:6.3f} {p['e']:6.3f} "
              f"{margins[i]:7.3f} {r['cocked'] / r['drops']:7.2%} {near[i]:7.3f}  "
              + " ".join(f"{t:9.4f}" for t in row))  # fmt: skip
    med, worst = np.median(rows, axis=0), rows.max(axis=0)
    counts = np.array([r["face_counts"] for r in test_runs], dtype=float)
    noise = float(np.median(noise_floor(frequencies(test_runs), counts.sum(axis=1))))
    print("median TVD: " + ", ".join(f"{m} {v:.4f}" for m, v in zip(models, med))
          + f" (sampling noise floor {noise:.4f}: the median TVD a perfect model would score at these drops)"
          + "; max: " + ", ".join(f"{m} {v:.4f}" for m, v in zip(models, worst)))  # fmt: skip
    if not args.calibrate:
        print(f"solid angles / fast {med[2] / med[0]:.1f}x, chain alone / fast {med[1] / med[0]:.1f}x (medians); "
              f"'nearest': distance to the nearest training gem in the discrepancy's coordinates")  # fmt: skip
        cv = info.get("cv", {}).get(f"{found.smoothing:g}")
        if cv:
            print(f"gem discrepancy: smoothing {found.smoothing:g}, {FOLDS}-fold CV on the training set: "
                  f"median TVD {cv['median_tvd']:.4f}, mean {cv['mean_tvd']:.4f} "
                  f"(at {info['drops']} drops, noise included)")  # fmt: skip
        layer = fills.fill_discrepancy(args.fill)
        if layer is not None:
            li = layer.info
            chosen = f"{layer.discrepancy_at} {layer.coordinates} {layer.penalty:g}"
            if layer.kernel_length:
                chosen += f" kernel {layer.kernel_length:g} {layer.kernel_penalty:g}"
            cv = li["cv"][chosen]
            kernel = ""
            if layer.kernel_length:
                kernel = f", kernel length {layer.kernel_length:g} penalty {layer.kernel_penalty:g}"
            print(f"{args.fill} fill: its correction learned from {li['designs']} other {li['fill']['kind']} gems "
                  f"(median {li['drops']} drops; solid discrepancy at the {layer.discrepancy_at}, "
                  f"{layer.coordinates} coordinates, penalty {layer.penalty:g}{kernel}), "
                  f"{FOLDS}-fold CV median TVD {cv['median_tvd']:.4f} (without it {li['before_median_tvd']:.4f}; "
                  "noise included)")  # fmt: skip
    if args.ablation:
        ablation(training, test, frequencies(test_runs))
    if args.optima:
        optima(args.drops, workers=args.workers)

    # speed, against the solid-angle model in the same run
    d = load_design("fudge-gem")
    poly, center = d.polyhedron, d.mass_properties().center
    for name, fn in models.items():
        fn(poly, center)
        reps = 300
        t = time.perf_counter()
        for _ in range(reps):
            fn(poly, center)
        print(f"{name:>11}: {(time.perf_counter() - t) / reps * 1e3:.3f} ms per evaluation")


if __name__ == "__main__":
    main()
