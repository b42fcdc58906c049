"""Held-out prediction of real dice by a mixture of throws and tables, and the held-out score of choosing the method.

    nice -n 10 python benchmarks/bench_mixture.py [--prior 0.5] [--workers 2]
    nice -n 10 python benchmarks/bench_mixture.py --cuboids     # 3. only

The dice, families and surfaces are those of ``bench_heldout.py``.  A
candidate is one simulated set-up: a throw of vigor 0, 0.5 or 1
(:func:`diefab.physics.throw.throw_settings`), optionally with a table that
takes the energy (quasi-static capture), rolling and spinning friction, a
soft table or rounded edges, alone or in pairs
(:data:`bench_heldout.FEATURES`).  Every die is dropped under every
candidate (``--fit-drops``, seed ``--fit-seed``; the capture grid at the
default throw: its 2000 seed-0 drops of ``bench_calibrate.py --free
capture --grid 11``).  Coordinates (vigor, capture, rolling, softness,
rounding); the prior is normal toward the default (1, 0, 0, 0, 0), sd
``--prior``.

A *method* predicts a held-out die from training dice:

``grid``
    the one candidate of least training deviance plus prior
    (:func:`diefab.search.crossval.pick_candidate`), as ``bench_heldout.py``;
``mix``
    the mixture of candidates of least training deviance plus its prior
    cost (:func:`diefab.search.mixture.fit_weights`): a population of
    throws, some gentle, some vigorous;

over a class of candidates (``throw``: the three throws; ``capture``: the
throws and capture; ``all``: every candidate) and a rule of which dice
train (``loo``: every other die; ``loo-surface``: the other dice on the
held-out die's surface, the default when there is none).

1. Per die: the TVD of the default physics and of every method, held out,
   each held-out die scored on its own fitting drops at its weights (they
   took no part in its choice: only the training dice's drops and counts
   did); ``perfect`` is what a perfect model scores at that many drops.
   Where every candidate a die's weights use is cached at ``--score-drops``
   fresh drops (seed ``--score-seed``), the same weights are also scored
   there (``fresh``), so that the simulation's noise is small beside the
   real rolls'; nothing is simulated for it.
2. **Nested**: which method to use is itself a fit to the dice.  For each
   held-out die the method is chosen by an inner leave-one-out over the
   *other* dice only (:func:`diefab.search.crossval.nested_choices`, inner
   loss the TVD on the fitting drops), then fitted on them and scored on
   the held-out die.  That is the held-out score of the whole procedure,
   selection included; the best single method's score is not.

3. With ``--cuboids``, instead: the published square cuboids
   (:func:`diefab.search.published.square_cuboid_dice`), which nothing was
   fitted on, predicted by the throw (vigor 0.5 and 1, grid or mixture)
   fitted on the eight dice, or on the other cuboids.

Printed: the tables, TVD / noise per die, the means and the goal's checks.
Simulated counts are cached in ``benchmarks/results/calibrate_loo_cache.jsonl``.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from bench_calibrate import Simulations, fingerprint, settings_key  # noqa: E402
from bench_heldout import CACHE, CAPTURE_GRID, FEATURES, REALROLLS, family, perfect_tvd, surface, table  # noqa: E402

from diefab.physics.simulate import PhysicsSettings, shutdown_pool  # noqa: E402
from diefab.physics.throw import throw_settings  # noqa: E402
from diefab.search.crossval import nested_choices, pick_candidate, training_rows  # noqa: E402
from diefab.search.fidelity import load_real_dice, noise_tvd  # noqa: E402
from diefab.search.likelihood import smoothed  # noqa: E402
from diefab.search.mixture import fit_weights, prior_penalty  # noqa: E402

X0 = np.array([1.0, 0.0, 0.0, 0.0, 0.0])
AXES = ("rolling", "soft", "rounded")
#: Weights below this are left out of a held-out die's fresh scoring drops (and the rest renormalized).
MIN_WEIGHT = 1e-3


def candidates(fit_drops: int, fit_seed: int) -> list[tuple[str, str, PhysicsSettings, np.ndarray, int, int]]:
    """(label, class, settings, coordinates, drops, seed) of every candidate; class throw < capture < all."""
    out = []
    for v in (0.0, 0.5, 1.0):
        out.append((f"v{v:g}", "throw", throw_settings(v), np.array([v, 0, 0, 0, 0.0]), fit_drops, fit_seed))
    for c in CAPTURE_GRID[1:]:
        out.append((f"v1 c{c:g}", "capture", PhysicsSettings(capture_energy=c), np.array([1.0, c, 0, 0, 0]), 2000, 0))
    for v in (0.0, 0.5):
        for c in (0.09, 0.25, 0.64):
            out.append((f"v{v:g} c{c:g}", "capture", replace(throw_settings(v), capture_energy=c),
                        np.array([v, c, 0, 0, 0]), fit_drops, fit_seed))  # fmt: skip
    pairs = [(a,) for a in AXES] + [("rolling", "soft"), ("rolling", "rounded"), ("soft", "rounded")]
    for v in (0.0, 0.5, 1.0):
        for pair in pairs:
            extra = {k: x for f in pair for k, x in FEATURES[f].items()}
            x = np.array([v, 0.0, *(float(a in pair) for a in AXES)])
            out.append(
                (f"v{v:g} " + "+".join(pair), "all", replace(throw_settings(v), **extra), x, fit_drops, fit_seed)
            )
    return out


CLASSES = {"throw": ("throw",), "capture": ("throw", "capture"), "all": ("throw", "capture", "all")}
RULES = ("loo", "loo-surface")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fit-drops", type=int, default=1000)
    ap.add_argument("--fit-seed", type=int, default=3)
    ap.add_argument("--score-drops", type=int, default=3000)
    ap.add_argument("--score-seed", type=int, default=4)
    ap.add_argument("--prior", type=float, default=0.5, help="prior sd toward the default, coordinate units")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--data", type=Path, default=REALROLLS)
    ap.add_argument("--cuboids", action="store_true", help="3. only: the published square cuboids (vigor 0.5 and 1)")
    args = ap.parse_args()
    if not args.data.is_dir():
        raise SystemExit(f"no real-rolls folder {args.data}")
    if not args.prior > 0:
        raise SystemExit(f"--prior {args.prior} must be > 0 (inf: none)")
    started = time.perf_counter()
    dice = load_real_dice(args.data)
    names = [d.name for d in dice]
    n = len(dice)
    sims = Simulations(CACHE, args.workers)
    cands = candidates(args.fit_drops, args.fit_seed)
    coords = np.array([c[3] for c in cands])
    penalty = prior_penalty(coords, X0, args.prior)
    freq = np.zeros((n, len(cands)), dtype=object)  # fitting drops: raw frequencies
    probs = np.zeros((n, len(cands)), dtype=object)  # smoothed, symmetrized
    for k, (label, _, s, _, drops, seed) in enumerate(cands):
        for i, d in enumerate(dice):
            c = sims.counts_at(d, s, drops, seed)
            freq[i, k], probs[i, k] = c / c.sum(), d.symmetrized(smoothed(c))
        print(f"  candidate {k + 1}/{len(cands)} {label}: simulated  ({time.perf_counter() - started:.0f} s)",
              flush=True)  # fmt: skip
    default_k = 2
    if args.cuboids:
        cuboids(dice, probs, cands, prior_penalty(coords, X0, args.prior), sims, args)
        shutdown_pool()
        return 0

    def method(members: list[int], how: str, rule: str):
        def fit(rows, target: int) -> np.ndarray:
            train = training_rows(names, target, rule, family, surface, among=rows)
            w = np.zeros(len(cands))
            if not train and rule.endswith("-surface"):
                w[default_k] = 1.0
            elif how == "grid":
                dev = np.array([[float(_dev(dice[j].counts, probs[j, k])) for k in members] for j in train])
                pick = pick_candidate(dev.reshape(len(train), len(members)), range(len(train)), coords[members],
                                      X0, args.prior)  # fmt: skip
                w[members[pick]] = 1.0
            else:
                member_probs = [np.array([probs[j, k] for k in members]) for j in train]
                w[members] = fit_weights([dice[j].counts for j in train], member_probs, penalty[members])
            return w

        return fit

    methods = {}
    for cls, kinds in CLASSES.items():
        members = [k for k, c in enumerate(cands) if c[1] in kinds]
        for how in ("grid", "mix"):
            for rule in RULES:
                methods[f"{how}-{cls} {rule}"] = method(members, how, rule)

    def fresh_tvd(i: int, w: np.ndarray) -> float:
        """TVD on fresh drops of the candidates `w` uses, if every one is cached (else nan: none is simulated)."""
        w = np.where(w >= MIN_WEIGHT, w, 0.0)
        keys = {k: (fingerprint(dice[i]), settings_key(cands[k][2]), args.score_drops, args.score_seed)
                for k in np.flatnonzero(w)}  # fmt: skip
        if any(key not in sims.table for key in keys.values()):
            return float("nan")
        p = sum(w[k] * np.array(sims.table[key], dtype=float) / sum(sims.table[key]) for k, key in keys.items())
        return dice[i].tvd(p / w.sum())

    def own_tvd(j: int, w: np.ndarray) -> float:
        """TVD on the die's own fitting drops at `w` (held out: neither they nor its real counts chose `w`)."""
        return dice[j].tvd(sum(w[k] * freq[j, k] for k in np.flatnonzero(w)))

    noise = [noise_tvd(d, 4000) for d in dice]
    one_hot = np.eye(len(cands))[default_k]
    cols = {
        "perfect": [perfect_tvd(d, args.fit_drops) for d in dice],
        "default": [own_tvd(i, one_hot) for i in range(n)],
    }
    fresh = {"perfect": [perfect_tvd(d, args.score_drops) for d in dice],
             "default": [fresh_tvd(i, one_hot) for i in range(n)]}  # fmt: skip
    weights = {}
    for name, fit in methods.items():
        weights[name] = [fit([j for j in range(n) if j != i], i) for i in range(n)]
        cols[name] = [own_tvd(i, weights[name][i]) for i in range(n)]
        fresh[name] = [fresh_tvd(i, weights[name][i]) for i in range(n)]
    print(f"  every method fitted  ({time.perf_counter() - started:.0f} s)", flush=True)
    table_dice = [i for i, d in enumerate(dice) if surface(d.name) == surface("binom3")]

    print(f"\n0. Each candidate on its fitting drops, in-sample (TVD per die; table: the mean over the "
          f"{len(table_dice)} dice of the source's table)")  # fmt: skip
    print(f"  {'candidate':<24} " + " ".join(f"{d:>13}" for d in names) + f" {'table':>8}")
    for k, c in enumerate(cands):
        t = [d.tvd(freq[i, k]) for i, d in enumerate(dice)]
        print(f"  {c[0]:<24} " + " ".join(f"{x:>13.4f}" for x in t) + f" {np.mean([t[i] for i in table_dice]):>8.4f}")
    print(f"\n1. Held out, each die scored on its own {args.fit_drops} fitting drops (seed {args.fit_seed}; capture "
          f"at the default throw: 2000, seed 0), which took no part in its choice; {len(cands)} candidates, "
          f"prior sd {args.prior:g}; perfect: a perfect model at {args.fit_drops} drops")  # fmt: skip
    for rule in RULES:
        print(f"\n  rule {rule}:")
        table(dice, {"perfect": cols["perfect"], "default": cols["default"],
                     **{m.split()[0]: cols[m] for m in methods if m.endswith(" " + rule)}}, noise)  # fmt: skip
    print(f"\n  held-out mean TVD / mean noise per method; fresh: the same weights on {args.score_drops} fresh drops "
          f"(seed {args.score_seed}) where every candidate used is cached there")  # fmt: skip
    for m in ["perfect", "default", *methods]:
        f = np.mean(fresh[m])
        tail = f"{f:.4f} {f / np.mean(noise):.2f}x" if np.isfinite(f) else "(not every candidate cached)"
        print(f"  {m:<26} own drops {np.mean(cols[m]):.4f} {np.mean(cols[m]) / np.mean(noise):.2f}x   fresh {tail}")
    best = min(methods, key=lambda m: np.mean(cols[m]))
    print(f"  best single method (chosen on these same dice, so optimistic): {best}")
    for m in ("mix-throw loo-surface", best):
        used = [np.flatnonzero(weights[m][i] >= 0.01) for i in range(n)]
        parts = [", ".join(f"{cands[k][0]} {weights[m][i][k]:.2f}" for k in used[i]) for i in range(n)]
        print(f"  {m} weights per die: " + "; ".join(f"{names[i]} {parts[i]}" for i in range(n)))
    sys.stdout.flush()
    nested = nested_choices(n, methods, own_tvd)
    cols["nested"] = [own_tvd(i, w) for i, (_, w, _) in enumerate(nested)]
    fresh["nested"] = [fresh_tvd(i, w) for i, (_, w, _) in enumerate(nested)]
    f = np.mean(fresh["nested"])
    print(f"\n  nested: own drops {np.mean(cols['nested']):.4f} {np.mean(cols['nested']) / np.mean(noise):.2f}x; fresh "
          + (f"{f:.4f} {f / np.mean(noise):.2f}x" if np.isfinite(f) else "(not every candidate cached)"))  # fmt: skip
    print("\n2. Nested: the method chosen without the held-out die (inner leave-one-out), then fitted and scored")
    table(
        dice,
        {"perfect": cols["perfect"], "default": cols["default"], best: cols[best], "nested": cols["nested"]},
        noise,
    )
    for i, (chosen, _, inner) in enumerate(nested):
        ratio = cols["nested"][i] / noise[i]
        print(f"  {names[i]:<13} chose {chosen:<26} (inner {inner[chosen]:.4f}); TVD/noise {ratio:.2f}")
    print(f"\n  per die TVD / noise ({best}): "
          + ", ".join(f"{names[i]} {cols[best][i] / noise[i]:.2f}" for i in range(n)))  # fmt: skip
    for m in (best, "nested"):
        goal(dice, cols[m], cols["default"], noise, f"{m}, own drops")
        if np.all(np.isfinite(fresh[m])):
            goal(dice, fresh[m], fresh["default"], noise, f"{m}, fresh drops")
    print(f"\n{time.perf_counter() - started:.0f} s in all; {sims.dropped} drops simulated now ({sims.seconds:.0f} s), "
          f"the rest cached in {CACHE.name}")  # fmt: skip
    shutdown_pool()
    return 0


def cuboids(dice, probs, cands, penalty, sims, args) -> None:
    """3. The published square cuboids, held out: the throw fitted on the other dice, or on the other cuboids.

    Nothing was ever fitted to them.  Only the throws of vigor 0.5 and 1,
    ``--fit-drops`` drops each (the gentle release, 1.6 units up, is below the
    radius of the longest cuboid, 1.601, and the simulation refuses it); a
    cuboid is scored on its own drops at its weights, which took no part in
    them (its real counts neither).
    """
    from diefab.search.published import square_cuboid_dice

    throws = [k for k, c in enumerate(cands) if c[0] in ("v0.5", "v1")]
    cub = square_cuboid_dice()
    freq, pr = [], []
    for d in cub:
        cs = [sims.counts_at(d, cands[k][2], args.fit_drops, args.fit_seed) for k in throws]
        freq.append(np.array([c / c.sum() for c in cs]))
        pr.append(np.array([d.symmetrized(smoothed(c)) for c in cs]))
    eight = ([d.counts for d in dice], [np.array([probs[i, k] for k in throws]) for i in range(len(dice))])
    pen = penalty[throws]
    m = len(cub)
    cols: dict[str, list[float]] = {"perfect": [perfect_tvd(d, args.fit_drops) for d in cub],
                                    "default": [d.tvd(freq[i][-1]) for i, d in enumerate(cub)]}  # fmt: skip

    def grid(counts, ps) -> np.ndarray:
        dev = np.array([[_dev(c, p[k]) for k in range(len(throws))] for c, p in zip(counts, ps)])
        return np.eye(len(throws))[pick_candidate(dev, range(len(counts)), np.array([cands[k][3] for k in throws]),
                                                  X0, args.prior)]  # fmt: skip

    for how, fit in (("grid", grid), ("mix", lambda c, p: fit_weights(c, p, pen))):
        w8 = fit(*eight)
        cols[f"{how} from the 8"] = [d.tvd(w8 @ freq[i]) for i, d in enumerate(cub)]
        ws = [fit([cub[j].counts for j in range(m) if j != i], [pr[j] for j in range(m) if j != i]) for i in range(m)]
        cols[f"{how} loo-cuboids"] = [d.tvd(ws[i] @ freq[i]) for i, d in enumerate(cub)]
        print(f"  {how}: weights (v0.5, v1) fitted on the 8 dice {np.round(w8, 2)}; on the other cuboids "
              + ", ".join(f"{cub[i].name} {np.round(ws[i], 2)}" for i in range(m)))  # fmt: skip
    noise = [noise_tvd(d, 4000) for d in cub]
    print(f"\n3. The published square cuboids (hand-rolled, surface not stated), held out; scored on their own "
          f"{args.fit_drops} drops (seed {args.fit_seed}), perfect at that many drops")  # fmt: skip
    table(cub, cols, noise)
    for c in cols:
        print(f"  {c:<20} mean {np.mean(cols[c]):.4f} = {np.mean(cols[c]) / np.mean(noise):.2f}x the noise")


def _dev(counts, p) -> float:
    from diefab.search.likelihood import deviance

    return deviance(counts, p)


def goal(dice, held, default, noise, label: str) -> None:
    """The goal's checks for one column of held-out scores."""
    ref_dice = [i for i, d in enumerate(dice) if "ours" in d.reference and "bullet" in d.reference]
    best_source = min(np.mean([dice[i].tvd(dice[i].reference[k]) for i in ref_dice]) for k in ("ours", "bullet"))
    worse = [dice[i].name for i in range(len(dice)) if held[i] > default[i] + noise[i]]
    stone = [held[i] for i, d in enumerate(dice) if d.name == "binom3_stone"]
    print(f"  goal, {label}: mean {np.mean(held):.4f} = {np.mean(held) / np.mean(noise):.2f}x the noise "
          f"{np.mean(noise):.4f} (goal <= 1.3); on the {len(ref_dice)} dice with the source's columns "
          f"{np.mean([held[i] for i in ref_dice]):.4f} vs {best_source:.4f}; worse than the default by more than "
          f"the noise: {', '.join(worse) or 'none'}"
          + (f"; binom3_stone {stone[0]:.4f} (<= 0.06)" if stone else ""))  # fmt: skip


if __name__ == "__main__":
    sys.exit(main())
