"""Leave-one-die-out prediction of real dice: default physics, calibrated physics, models, the source's own.

    nice -n 10 python benchmarks/bench_calibrate.py --workers 1    # the full run (about 10 minutes, 2 busy cores)
    python benchmarks/bench_calibrate.py --drops 200 --candidates 3 --slow-drops 60 --predict-drops 200  # a quick one
    python benchmarks/bench_calibrate.py --free capture --grid 11 --drops 2000 --slow-drops 2000 \
        --predict-drops 10000 --prior inf --workers 2    # capture alone on a grid (7 minutes on 2 cores)

The dice: the paper's die as made (the gem a=1.18 b=0.52 c=0.72 d=1.41 as
a paper model, i.e. a shell fill) with its 405 real rolls (Table 2), and
every die of ``/work/shared/realrolls`` (or ``--realrolls FOLDER``): the
printed prisms and the figurine d3s, read by
:func:`diefab.search.calibrate.realrolls_die` (hull, stated centre of mass and
inertia).

Calibration, affordable on a shared 2-core machine:

1. Every die is dropped at the same candidate settings: the defaults and
   ``--candidates`` scrambled Sobol points in the box of the settings
   ``--free`` names (default restitution, friction, rolling friction, spin,
   drop height and the quasi-static capture, over the ranges and scales
   ``diefab calibrate`` searches), with
   common random numbers (one seed; ``--drops`` drops per die and candidate,
   ``--slow-drops`` for dice of more than 50 hull faces, whose drops cost
   several times more).
2. Per die, a response surface (:func:`diefab.search.surface.fit_surface`, a
   multinomial logistic regression quadratic in the settings) pools all
   candidates' counts into smooth value probabilities over the whole box.
3. For each held-out die the calibrated setting minimizes the deviance of
   the *other* dice's real counts under their surfaces plus a normal prior
   toward the default physics (``--prior`` standard deviations, in units of
   each parameter's range; fixed before any result was seen)
   (:func:`diefab.search.surface.fit_settings`).  Pooled, the fit uses every
   other die; *by material* only the other dice of the held-out die's
   material (:data:`MATERIAL`: what it is made of and what it was rolled
   on), and a die whose material no other die shares gets the defaults:
   a calibration carries over to a die of the same material, not across.
   With ``--refine R`` each fit is then refined in R rounds: its training
   dice are dropped at the fitted setting (``--refine-drops``, the
   candidates' seed), that point joins their surfaces (the fit's own copies,
   so the folds stay independent) and the fit is repeated: a quadratic
   surface is least accurate where the response is sharp, and the fit lands
   just there.  The held-out die is never dropped in fitting.
   With ``--grid N`` (one free setting, e.g. ``--free capture``) the
   candidates are instead N evenly spaced points of the setting's search
   scale and each fit is the candidate of least training deviance (plus the
   prior, none with ``--prior inf``): no surface, as ``diefab calibrate
   --method grid`` fits.
4. The held-out die is then dropped afresh at its calibrated setting
   (``--predict-drops`` drops, seed ``--predict-seed``, never used in
   fitting), and so is every die at the default physics.

Printed per die, as TVD to the real frequencies (mirror-image outcomes
compared up to relabelling): default physics; leave-one-out calibrated
physics, pooled and by material (fresh drops), the pooled fit's surface
value; the same without the prior and the best single candidate (surface
values, for comparison); the in-sample fit (all dice, the optimistic
bound); the solid-angle, fast and basins models; the source's own
quasi-static model (``ours``) and Bullet and IPC simulations; and the TVD
sampling noise alone gives at the die's number of rolls (Monte-Carlo at
the observed frequencies).  Then, for a surface design, how far the
surfaces are from fresh drops where the fit on the printed dice lands, and
which parameters the fit leans on.

Simulated counts are cached in ``--cache`` (one JSON line per design,
setting, drop count and seed), so an interrupted run continues where it
stopped; the table is also written as JSON (``--json``).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import time
from pathlib import Path

import numpy as np

from diefab.core.errors import DiefabError
from diefab.dice.design import design_to_toml
from diefab.physics.simulate import shutdown_pool
from diefab.search.calibrate import RealDie, deviance, make_spec, realrolls_die, simulate_die, smoothed
from diefab.search.fidelity import noise_tvd, paper_die
from diefab.search.surface import fit_settings, fit_surface, prior_penalty

HERE = Path(__file__).parent
FREE = ("restitution", "friction", "rolling_friction", "spin", "drop_height", "capture")
#: What each die is made of and what it was rolled on: a calibration carries over only within one material.
MATERIAL = {"paper-gem": "paper model on the paper's table", "binom3_stone": "printed, on stone"}
PRINTED = "printed, on the source's table"
SLOW_FACES = 50  # dice with more hull faces than this drop --slow-drops times per candidate


def load_dice(folder: Path) -> list[RealDie]:
    dice = [paper_die()]
    for path in sorted(folder.glob("*.json")):
        try:
            dice.append(realrolls_die(path))
        except DiefabError as exc:
            print(f"skipped {path.name}: {exc}")
    return dice


def fingerprint(die: RealDie) -> str:
    """A short hash of the die's design: the same design shares its simulations, a changed one is simulated anew."""
    return hashlib.sha256(design_to_toml(die.design).encode()).hexdigest()[:16]


def model_probabilities(die: RealDie, model: str) -> np.ndarray | None:
    from diefab.models.probabilities import MODELS, value_probabilities

    if model not in MODELS:
        return None
    try:
        return value_probabilities(die.design, model)
    except (DiefabError, ValueError):
        return None


#: The free settings whose values a cache line without "settings" holds, by their number.
UNNAMED_VALUES = {4: ("restitution", "friction", "spin", "drop_height"), 5: FREE[:5]}


def settings_key(settings) -> str:
    """The physics settings of a simulation as canonical JSON (settings at their off value left out)."""
    return json.dumps(settings.as_dict(), sort_keys=True)


class Simulations:
    """Simulated value counts of the dice, cached by design, physics settings, drop count and seed."""

    def __init__(self, path: Path, workers: int) -> None:
        from diefab.physics.simulate import PhysicsSettings
        from diefab.search.calibrate import settings_at

        self.path, self.workers, self.table, self.dropped, self.seconds = path, workers, {}, 0, 0.0
        if path.is_file():
            for line in path.read_text().splitlines():
                try:
                    r = json.loads(line)
                    if "settings" in r:
                        key = settings_key(PhysicsSettings.from_mapping(r["settings"]))
                    else:
                        key = settings_key(settings_at(PhysicsSettings(), UNNAMED_VALUES[len(r["values"])],
                                                       r["values"]))  # fmt: skip
                    self.table[(r["design"], key, r["drops"], r["seed"])] = r["counts"]
                except (ValueError, KeyError, DiefabError):
                    continue
        path.parent.mkdir(parents=True, exist_ok=True)

    def counts(self, die: RealDie, spec, x: np.ndarray, drops: int, seed: int) -> np.ndarray:
        from diefab.search.calibrate import settings_at

        values = [round(float(v), 9) for v in spec.values(x)]
        return self.counts_at(die, settings_at(spec.base, spec.names, values), drops, seed, values)

    def counts_at(self, die: RealDie, settings, drops: int, seed: int, values=()) -> np.ndarray:
        """(k,) float: value counts of `die` simulated at `settings` (cached)."""
        key = (fingerprint(die), settings_key(settings), int(drops), int(seed))
        if key not in self.table:
            r = simulate_die(die, settings, int(drops), int(seed), self.workers)
            self.table[key] = r["counts"]
            self.dropped += int(drops)
            self.seconds += r["seconds"]
            with self.path.open("a") as log:
                log.write(json.dumps({"die": die.name, "design": key[0], "values": list(values), "drops": key[2],
                                      "seed": key[3], "settings": settings.as_dict(), "counts": r["counts"]})
                          + "\n")  # fmt: skip
        return np.array(self.table[key], dtype=float)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drops", type=int, default=100, help="drops per die and candidate")
    parser.add_argument("--slow-drops", type=int, default=60, help=f"the same, dice of more than {SLOW_FACES} faces")
    parser.add_argument("--candidates", type=int, default=64, help="Sobol candidates besides the defaults")
    parser.add_argument("--grid", type=int, default=0,
                        help="instead: this many evenly spaced candidates of the one free setting (unit scale), "
                             "and each fit is the candidate of least training deviance, no surface")  # fmt: skip
    parser.add_argument("--prior", type=float, default=0.25,
                        help="prior sd toward the defaults, in parameter ranges (inf: none)")  # fmt: skip
    parser.add_argument(
        "--refine",
        type=int,
        default=0,
        help="refinement rounds: drop the training dice at each fit and refit their surfaces",
    )
    parser.add_argument(
        "--refine-drops",
        type=int,
        default=400,
        help="drops of a training die per refinement round (fewer for slow dice, as --slow-drops)",
    )
    parser.add_argument("--predict-drops", type=int, default=2000, help="fresh drops of each prediction")
    parser.add_argument("--seed", type=int, default=0, help="physics seed of the candidates (common random numbers)")
    parser.add_argument("--predict-seed", type=int, default=1, help="physics seed of the predictions")
    parser.add_argument("--free", default=",".join(FREE), help="the settings fitted (comma-separated)")
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--realrolls", type=Path, default=Path("/work/shared/realrolls"))
    parser.add_argument("--cache", type=Path, default=HERE / "results" / "calibrate_loo_cache.jsonl")
    parser.add_argument("--json", type=Path, default=None, help="also write the table as JSON to this file")
    args = parser.parse_args()
    from scipy.stats import qmc

    dice = load_dice(args.realrolls)
    free = tuple(n.strip() for n in args.free.split(",") if n.strip())
    spec = make_spec(dice, free=free)
    materials = [MATERIAL.get(d.name, PRINTED) for d in dice]
    x0 = np.array(spec.x0)
    if args.grid:
        if len(free) != 1 or args.grid < 2:
            parser.error("--grid needs one free setting and at least 2 points")
        points = np.linspace(0.0, 1.0, args.grid)[:, None]
        xs = np.unique(np.vstack([x0, points]).round(12), axis=0)
    else:
        m = max(int(np.ceil(np.log2(max(args.candidates, 1)))), 0)  # whole powers of 2 keep Sobol's balance
        points = qmc.Sobol(len(free), scramble=True, seed=args.seed).random_base2(m)[: args.candidates]
        xs = np.vstack([x0, points])
    faces = [len(d.design.polyhedron.names) for d in dice]
    drops = [args.slow_drops if f > SLOW_FACES else args.drops for f in faces]
    refine_drops = [args.refine_drops * d // args.drops for d in drops]  # the same ratio for slow dice
    kind = f"a grid of {len(xs)} points" if args.grid else f"defaults + {args.candidates} Sobol points"
    print(f"{len(dice)} dice, {len(xs)} candidates ({kind} in "
          f"{', '.join(f'{n} [{lo:g}, {hi:g}]' for n, (lo, hi) in zip(free, spec.bounds))}); "
          f"{args.drops} drops per die and candidate ({args.slow_drops} for dice of more than {SLOW_FACES} faces), "
          f"seed {args.seed}; {args.refine} refinement rounds of {args.refine_drops} drops; "
          f"predictions {args.predict_drops} drops, seed {args.predict_seed}; prior sd "
          f"{args.prior:g} of each range; {args.workers} workers", flush=True)  # fmt: skip

    sims = Simulations(args.cache, args.workers)
    started = time.perf_counter()
    counts = []
    for i, die in enumerate(dice):
        counts.append(np.array([sims.counts(die, spec, x, drops[i], args.seed) for x in xs]))
        print(f"  {die.name}: {len(xs)} candidates x {drops[i]} drops  ({time.perf_counter() - started:.0f} s)",
              flush=True)  # fmt: skip
    surfaces = [fit_surface(xs, c) for c in counts]

    def surface_tvd(i: int, x: np.ndarray) -> float:
        return dice[i].tvd(dice[i].symmetrized(surfaces[i].probabilities(x)))

    # how closely each surface follows its own candidates, against the simulation noise of one candidate
    fit_rows = []
    for i, die in enumerate(dice):
        sim = counts[i] / counts[i].sum(axis=1, keepdims=True)
        emu = surfaces[i].probabilities(xs)
        gaps = 0.5 * np.abs(sim - emu).sum(axis=1)
        expected = np.mean([np.sum(np.sqrt(p * (1 - p) / (2 * np.pi * drops[i]))) for p in emu])
        fit_rows.append((die.name, float(np.mean(gaps)), float(expected)))

    dev = np.array([[deviance(d.counts, d.symmetrized(smoothed(counts[i][j]))) for j in range(len(xs))]
                    for i, d in enumerate(dice)])  # fmt: skip

    def calibrate(train: list[int], sigma: float, rounds: int = 0) -> np.ndarray:
        """The fit on the `train` dice; each refinement round drops them at the fit and refits their surfaces.

        On a grid the fit is the candidate of least training deviance (plus the prior), its simulated counts as
        they are: no surface, no refinement.
        """
        if args.grid:
            penalty = [prior_penalty(x, x0, sigma) for x in xs]
            return xs[int(np.argmin(dev[train].sum(axis=0) + penalty))]  # ties: the lowest setting
        order = np.argsort(dev[train].sum(axis=0))[:3]
        starts = [xs[j] for j in order]
        local = {i: (xs, counts[i], surfaces[i]) for i in train}  # this fit's own copies: folds stay independent
        x, _ = fit_settings([dice[i] for i in train], [surfaces[i] for i in train], x0, sigma=sigma, starts=starts)
        for _ in range(rounds):
            for i in train:
                pts, c, _s = local[i]
                more = sims.counts(dice[i], spec, x, refine_drops[i], args.seed)
                pts, c = np.vstack([pts, x]), np.vstack([c, more])
                local[i] = (pts, c, fit_surface(pts, c, cross=surfaces[i].cross))
            x, _ = fit_settings([dice[i] for i in train], [local[i][2] for i in train], x0, sigma=sigma,
                                starts=[x, *starts])  # fmt: skip
        return x

    def fresh(i: int, x: np.ndarray) -> np.ndarray:
        """Die `i`'s value frequencies on fresh drops at `x` (the predictions' drops and seed), symmetrized."""
        c = sims.counts(dice[i], spec, x, args.predict_drops, args.predict_seed)
        return dice[i].symmetrized(c / max(c.sum(), 1))

    everyone = list(range(len(dice)))
    x_all = calibrate(everyone, args.prior, args.refine)
    printed = [i for i in everyone if materials[i] == PRINTED]
    x_printed = calibrate(printed, args.prior, args.refine) if printed and not args.grid else None
    rows, fitted = [], []
    for i, die in enumerate(dice):
        train = [j for j in everyone if j != i]
        x_loo = calibrate(train, args.prior, args.refine)
        x_noprior = calibrate(train, np.inf)
        same = [j for j in train if materials[j] == materials[i]]
        # no die of its material: nothing to carry over
        x_mat = calibrate(same, args.prior, args.refine) if same else x0
        pick = int(np.argmin(dev[train].sum(axis=0)))
        fitted.append(x_loo)

        row = {
            "die": die.name,
            "rolls": die.n,
            "noise": noise_tvd(die, 4000),
            "default": die.tvd(fresh(i, x0)),
            "loo": die.tvd(fresh(i, x_loo)),
            "material": die.tvd(fresh(i, x_mat)),
            "loo-surface": surface_tvd(i, x_loo),
            "no-prior": surface_tvd(i, x_noprior),
            "candidate": die.tvd(die.symmetrized(counts[i][pick] / counts[i][pick].sum())),
            "in-sample": surface_tvd(i, x_all),
        }
        for model in ("solid-angle", "fast", "basins"):
            p = model_probabilities(die, model)
            row[model] = None if p is None else die.tvd(p)
        for ref in ("ours", "bullet", "ipc"):
            row[ref] = die.tvd(die.reference[ref]) if ref in die.reference else None
        row["settings"] = dict(zip(free, spec.values(x_loo).round(4).tolist()))
        row["material_settings"] = dict(zip(free, spec.values(x_mat).round(4).tolist()))
        row["material_dice"] = [dice[j].name for j in same]
        rows.append(row)
        print(f"  held out {die.name}: " + " ".join(f"{n}={v:.3g}" for n, v in row["settings"].items())
              + f"; by material ({materials[i]}, {len(same)} dice): "
              + (" ".join(f"{n}={v:.3g}" for n, v in row["material_settings"].items()) if same else "the defaults")
              + f"  ({time.perf_counter() - started:.0f} s)", flush=True)  # fmt: skip
    # where the fit lands, is the surface still the simulation? The printed dice's own fit, on fresh drops
    surface_check = []
    if x_printed is not None:
        for i in printed:
            surface_check.append((dice[i].name, surface_tvd(i, x_printed), dice[i].tvd(fresh(i, x_printed))))
    shutdown_pool()
    seconds = time.perf_counter() - started

    cols = ["noise", "default", "loo", "material", "loo-surface", "no-prior", "candidate", "in-sample", "solid-angle",
            "fast", "basins", "ours", "bullet", "ipc"]  # fmt: skip
    print(f"\nTVD to the real frequencies ({sims.dropped:,} drops simulated in {sims.seconds:.0f} s of simulation, "
          f"{seconds:.0f} s in all, on a shared machine)")  # fmt: skip
    print(f"{'die':<22}{'rolls':>6}" + "".join(f"{c:>12}" for c in cols))
    for row in rows:
        cells = "".join(f"{'-':>12}" if row[c] is None else f"{row[c]:12.4f}" for c in cols)
        print(f"{row['die']:<22}{row['rolls']:>6}{cells}")

    def mean(c: str, which) -> float | None:
        vals = [r[c] for r in which if r[c] is not None]
        return float(np.mean(vals)) if vals else None

    groups = {
        "mean, all dice": rows,
        "mean, the real-rolls dice": [r for r in rows if r["ours"] is not None],
        "mean, real-rolls w/o kitten": [r for r in rows if r["ours"] is not None and r["die"] != "kitten_d3"],
    }
    means = {}
    for label, which in groups.items():
        means[label] = {c: mean(c, which) for c in cols}
        print(f"{label:<28}" + "".join(f"{'-':>12}" if v is None else f"{v:12.4f}" for v in means[label].values()))
    for col in ("loo", "material"):
        wins = {ref: sum(r[col] < r[ref] for r in rows if r[ref] is not None) for ref in ("default", "ours", "bullet")}
        print(
            f"\n{col}: beats default physics on {wins['default']} of {len(rows)} dice, `ours` on "
            f"{wins['ours']} of {len(groups['mean, the real-rolls dice'])}, `bullet` on {wins['bullet']}; "
            f"within 1.5x sampling noise on {sum(r[col] <= 1.5 * r['noise'] for r in rows)} of {len(rows)}"
        )

    print("\nresponse surfaces: mean TVD to their own candidates' frequencies (the simulation noise of one candidate)")
    for name, gap, expected in fit_rows:
        print(f"  {name:<14}{gap:.4f} ({expected:.4f})")

    if surface_check:
        print(
            f"\nthe surfaces where the fit lands: the fit on the {len(printed)} printed dice (in-sample: "
            + " ".join(f"{n}={v:.3g}" for n, v in zip(free, spec.values(x_printed)))
            + f"), TVD to the real rolls by the surface and by {args.predict_drops} fresh drops (seed "
            f"{args.predict_seed})"
        )
        for name, by_surface, by_drops in surface_check:
            print(f"  {name:<14}surface {by_surface:.4f}   drops {by_drops:.4f}")

    # which settings the fit leans on: the rise of the total deviance when one setting sweeps its range
    total = lambda x: sum(deviance(d.counts, d.symmetrized(s.smoothed(x))) for d, s in zip(dice, surfaces))  # noqa: E731
    base = total(x_all)
    print(
        f"\nin-sample fit over all {len(dice)} dice: "
        + " ".join(f"{n}={v:.3g}" for n, v in zip(free, spec.values(x_all)))
        + f"; total deviance {base:.1f} (defaults {total(x0):.1f}), prior {prior_penalty(x_all, x0, args.prior):.1f}"
    )
    print("rise of the total deviance as one setting sweeps its range (others at the in-sample fit):")
    leans = {}
    for k, name in enumerate(free):
        grid = np.linspace(0, 1, 21)
        vals = [total(np.where(np.arange(len(free)) == k, g, x_all)) for g in grid]
        leans[name] = float(max(vals) - base)
        least = spec.values(np.where(np.arange(len(free)) == k, grid[int(np.argmin(vals))], x_all))[k]
        print(f"  {name:<12} up to +{leans[name]:.1f} (least at {least:.3g})")
    if args.json is not None:
        summary = {"args": {k: str(v) for k, v in vars(args).items()}, "rows": rows, "means": means,
                   "in_sample": dict(zip(free, spec.values(x_all).tolist())), "leans": leans, "seconds": seconds,
                   "drops": sims.dropped}  # fmt: skip
        args.json.write_text(json.dumps(summary, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
