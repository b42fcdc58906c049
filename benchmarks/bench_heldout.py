"""Held-out prediction of real dice: every shipped physics profile, and a throw fitted by cross-validation.

    nice -n 10 python benchmarks/bench_heldout.py [--drops 400] [--seed 1] [--workers 2] [--prior 0.5]
        [--physics-drops 1000] [--score-drops 3000]

The dice: the paper's die as made (Table 2) and every die of
``../shared/realrolls`` (:func:`diefab.search.fidelity.load_real_dice`), in four
families: the paper's gem (a paper model on the paper's table), the
printed prisms (binom2, binom3, binom4), the printed figurines (armadillo,
dragon, kitten), all on the source's table, and the binom3 prism rolled on
stone (its own surface).

1. **Shipped profiles.**  Every die is dropped ``--drops`` times (seed
   ``--seed``) under the default physics and under each shipped profile
   (:func:`diefab.profiles.list_profiles`), and the TVD to its real rolls
   is printed.  A profile fitted to real dice (its ``[calibration]`` table
   names them) is in-sample on those; the others were never fitted to any
   die, and every score is held out.  For ``printed-table`` (a grid fit of
   the quasi-static capture on its six dice) the fit is also redone
   leaving each of its dice out, and each of its families out, on the
   capture grid ``bench_calibrate.py --free capture --grid 11`` cached
   (fitted on seed-0 drops, the held-out die scored on seed-2 drops).
   Then where the error comes from: what a perfect model scores at
   ``--drops`` and ``--score-drops`` simulated drops, beside the default
   physics at ``--drops`` and at 20,000 drops (its own simulation noise
   small).
2. **A throw fitted across dice.**  The throw's vigor
   (:func:`diefab.physics.throw.throw_settings`: 0 a die released at rest just
   above the table with low friction and no bounce, the source's own
   Bullet set-up; 1 diefab's default throw) on a grid of ``--vigor``
   points; each die dropped at each.  For each held-out die the vigor is
   the grid point of least deviance of the *other* dice's real counts
   (leave one die out), or of the dice of the other families (leave one
   family out), plus a normal prior toward the default (``--prior``
   standard deviations of vigor; ``inf``: none).  The held-out die's own
   drops at the chosen point score it: they played no part in the choice.
3. **Throw or table.**  The same over the union of the vigor grid and the
   capture grid (vigor 1), and once more with the fit restricted to dice
   rolled on the held-out die's own surface (:data:`SURFACE`; no other die
   on it: the default physics), the columns ``loo-surface`` and
   ``lofo-surface``; then (3') the same choices, each held-out die and the
   default scored on ``--score-drops`` fresh drops (seed ``--score-seed``),
   so that the simulation's own noise is small beside the real rolls'.
4. **Throw, table and rounded edges** (:func:`table_physics`): the throws
   0, 0.5 and 1, each alone and with rolling friction, a soft table or
   rounded edges, and the capture grid, cross-validated the same way
   (:mod:`diefab.search.crossval`) and scored on fresh drops, beside what a
   perfect model scores at that many drops (``perfect``).

Printed: TVD to the real frequencies per die (mirror-image outcomes up to
relabelling), the sampling noise of the real counts (the TVD a perfect
model scores on average), the source's ``ours`` and ``bullet``; the means;
and the goal's checks (held-out mean no worse than the best of the
source's columns and within 1.3x the noise; no held-out die worse than the
default by more than its noise; binom3 on stone at TVD <= 0.06).

Simulated counts are cached in ``benchmarks/results/calibrate_loo_cache.jsonl``
(shared with ``bench_calibrate.py``), so a rerun only prints.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from bench_calibrate import Simulations, fingerprint, settings_key  # noqa: E402

from diefab.physics.profiles import list_profiles, load_profile, read_profile  # noqa: E402
from diefab.physics.simulate import PhysicsSettings, shutdown_pool  # noqa: E402
from diefab.physics.throw import throw_settings  # noqa: E402
from diefab.search.calibrate import deviance, smoothed  # noqa: E402
from diefab.search.fidelity import load_real_dice, noise_tvd  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
REALROLLS = ROOT / ".." / "shared" / "realrolls"
CACHE = ROOT / "benchmarks" / "results" / "calibrate_loo_cache.jsonl"
#: Family of each die: leave-one-family-out holds a whole family out of the fit.
FAMILY = {"paper-gem": "gem", "binom2": "prisms", "binom3": "prisms", "binom4": "prisms",
          "armadilo_d3": "figurines", "dragon_d3": "figurines", "kitten_d3": "figurines",
          "binom3_stone": "stone"}  # fmt: skip
#: The capture grid bench_calibrate.py --free capture --grid 11 caches (2000 drops, seeds 0 and 2).
CAPTURE_GRID = tuple(round((i / 10) ** 2, 9) for i in range(11))


#: What each die was rolled on: a fitted throw and table carry over only to dice on the same surface.
SURFACE = {"paper-gem": "the paper's table", "binom3_stone": "stone"}


def family(name: str) -> str:
    return FAMILY.get(name, name)


def surface(name: str) -> str:
    return SURFACE.get(name, "the source's table")


def fit_index(dice, probs, train: list[int], prior_sd: float, x: np.ndarray, x0: float) -> int:
    """Grid index of least total deviance of the `train` dice's real counts (plus the normal prior toward `x0`)."""
    total = np.zeros(len(x))
    for j in train:
        d = dice[j]
        total += [deviance(d.counts, d.symmetrized(p)) for p in probs[j]]
    if math.isfinite(prior_sd):
        total += ((x - x0) / prior_sd) ** 2
    return int(np.argmin(total))


def cross_validate(dice, probs, x: np.ndarray, x0: float, prior_sd: float) -> dict[str, list]:
    """Held-out grid index per die: leave one die out, and leave its family out."""
    n = len(dice)
    loo = [fit_index(dice, probs, [j for j in range(n) if j != i], prior_sd, x, x0) for i in range(n)]
    lofo = [fit_index(dice, probs, [j for j in range(n) if family(dice[j].name) != family(dice[i].name)],
                      prior_sd, x, x0) for i in range(n)]  # fmt: skip
    return {"loo": loo, "lofo": lofo}


def table(dice, columns: dict[str, list[float]], noise: list[float]) -> None:
    names = list(columns)
    print(f"{'die':<13} {'rolls':>5} {'noise':>7} " + " ".join(f"{c:>12}" for c in names))
    for i, d in enumerate(dice):
        print(f"{d.name:<13} {d.n:>5} {noise[i]:>7.4f} " + " ".join(f"{columns[c][i]:>12.4f}" for c in names))
    print(f"{'mean':<13} {'':>5} {np.mean(noise):>7.4f} " + " ".join(f"{np.nanmean(columns[c]):>12.4f}" for c in names))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drops", type=int, default=400)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--vigor", default="0,0.25,0.5,0.75,1", help="Grid of throw vigor (comma-separated).")
    ap.add_argument("--prior", type=float, default=0.5, help="Prior sd of vigor toward 1 (the default; inf: none).")
    ap.add_argument("--data", type=Path, default=REALROLLS)
    ap.add_argument(
        "--physics-drops",
        type=int,
        default=1000,
        help="4.: drops per die and candidate of the fuller physics (0: skip section 4)",
    )
    ap.add_argument("--physics-seed", type=int, default=3)
    ap.add_argument(
        "--score-drops",
        type=int,
        default=3000,
        help="4.: fresh drops that score each held-out die at its chosen candidate, and the default",
    )
    ap.add_argument("--score-seed", type=int, default=4)
    args = ap.parse_args()
    if not args.data.is_dir():
        raise SystemExit(f"no real-rolls folder {args.data}")
    started = time.perf_counter()
    dice = load_real_dice(args.data)
    sims = Simulations(CACHE, args.workers)
    noise = [noise_tvd(d, 4000) for d in dice]
    ref = {k: [d.tvd(d.reference[k]) if k in d.reference else np.nan for d in dice] for k in ("ours", "bullet")}

    def tvds(settings) -> list[float]:
        out = []
        for d in dice:
            c = sims.counts_at(d, settings, args.drops, args.seed)
            out.append(d.tvd(c / max(c.sum(), 1)))
        return out

    # 2. the throw (simulated first: the profiles' table reuses the default)
    vigor = np.array([float(v) for v in args.vigor.split(",")])
    probs, grid_tvd = [[None] * len(vigor) for _ in dice], np.zeros((len(dice), len(vigor)))
    for k, v in enumerate(vigor):
        settings = throw_settings(v)
        for i, d in enumerate(dice):
            c = sims.counts_at(d, settings, args.drops, args.seed)
            probs[i][k] = smoothed(c)
            grid_tvd[i, k] = d.tvd(c / max(c.sum(), 1))
        print(f"  vigor {v:g}: simulated  ({time.perf_counter() - started:.0f} s)", flush=True)

    # 1. profiles
    default = tvds(PhysicsSettings())
    columns = {"default": default}
    fitted_on = {}
    for name in list_profiles():
        data, _ = read_profile(name)
        fitted_on[name] = list(data.get("calibration", {}).get("dice", []))
        columns[name] = tvds(load_profile(name))
        print(f"  profile {name}: simulated  ({time.perf_counter() - started:.0f} s)", flush=True)
    print(f"\n1. Shipped profiles: TVD to the real rolls, {args.drops} drops per die, seed {args.seed}")
    table(dice, {**columns, **ref}, noise)
    for name, on in fitted_on.items():
        held = [i for i, d in enumerate(dice) if d.name not in on]
        mean_held = np.mean([columns[name][i] for i in held])
        mean_def = np.mean([default[i] for i in held])
        worse = [dice[i].name for i in held if columns[name][i] > default[i] + noise[i]]
        print(f"  {name:<13} fitted on {', '.join(on) if on else 'no die'}; held-out mean {mean_held:.4f} "
              f"(default {mean_def:.4f} on the same {len(held)} dice); worse than the default by more than "
              f"the noise on: {', '.join(worse) or 'none'}")  # fmt: skip
    printed_table_cv(dice, sims, noise)
    error_floor(dice, sims, noise, default, args)

    # 2. report
    print(f"\n2. Throw vigor (0: released at rest, the source's set-up; 1: the default throw), {args.drops} drops "
          f"per die and point, seed {args.seed}; prior sd {args.prior:g} toward 1")  # fmt: skip
    cv = cross_validate(dice, probs, vigor, 1.0, args.prior)
    cols = {f"v={v:g}": list(grid_tvd[:, k]) for k, v in enumerate(vigor)}
    cols["loo"] = [grid_tvd[i, cv["loo"][i]] for i in range(len(dice))]
    cols["lofo"] = [grid_tvd[i, cv["lofo"][i]] for i in range(len(dice))]
    table(dice, {**cols, **ref}, noise)
    for how in ("loo", "lofo"):
        print(f"  {how} vigor per die: " + ", ".join(f"{d.name} {vigor[cv[how][i]]:g}" for i, d in enumerate(dice)))
    full = fit_index(dice, probs, list(range(len(dice))), args.prior, vigor, 1.0)
    print(f"  in-sample (all dice): vigor {vigor[full]:g}, mean TVD {grid_tvd[:, full].mean():.4f}")
    goal(dice, cols, ref, noise, default)
    throw_or_table(dice, sims, vigor, probs, grid_tvd, ref, noise, default, args.prior, args)
    if args.physics_drops:
        table_physics(dice, sims, args, ref, noise)
    print(f"\n{time.perf_counter() - started:.0f} s in all; {sims.dropped} drops simulated now "
          f"({sims.seconds:.0f} s), the rest cached in {CACHE.relative_to(ROOT)}")  # fmt: skip
    shutdown_pool()
    return 0


def printed_table_cv(dice, sims, noise) -> None:
    """printed-table's capture fit redone leaving each of its dice, and each of its families, out."""
    data, _ = read_profile("printed-table")
    on = list(data.get("calibration", {}).get("dice", []))
    idx = [i for i, d in enumerate(dice) if d.name in on]
    x = np.array(CAPTURE_GRID)

    cached = [i for i, d in enumerate(dice)
              if all((fingerprint(d), settings_key(PhysicsSettings(capture_energy=c)), 2000, s) in sims.table
                     for c in x for s in (0, 2))]  # fmt: skip
    missing = [
        (d.name, c, s)
        for d in (dice[i] for i in idx)
        for c in x
        for s in (0, 2)
        if (fingerprint(d), settings_key(PhysicsSettings(capture_energy=c)), 2000, s) not in sims.table
    ]
    if missing:  # 350,000 drops: run bench_calibrate.py --free capture --grid 11 (seeds 0 and 2) first
        print(
            f"\n  printed-table cross-validation skipped: {len(missing)} capture-grid runs not cached, "
            f"e.g. {missing[0]}"
        )
        return
    fit_p = {i: [smoothed(sims.counts_at(dice[i], PhysicsSettings(capture_energy=c), 2000, 0, [c])) for c in x]
             for i in cached}  # fmt: skip
    test = {i: [sims.counts_at(dice[i], PhysicsSettings(capture_energy=c), 2000, 2, [c]) for c in x]
            for i in cached}  # fmt: skip
    sub = [dice[i] for i in idx]
    probs = [fit_p[i] for i in idx]
    loo = [fit_index(sub, probs, [j for j in range(len(sub)) if j != k], math.inf, x, 0.0) for k in range(len(sub))]
    lofo = [fit_index(sub, probs, [j for j in range(len(sub)) if family(sub[j].name) != family(sub[k].name)],
                      math.inf, x, 0.0) for k in range(len(sub))]  # fmt: skip

    def score(i: int, g: int) -> float:
        c = test[i][g]
        return dice[i].tvd(c / c.sum())

    print("\n  printed-table (capture on a grid of 11, fitted on seed-0 drops, scored on 2000 seed-2 drops):")
    print(f"  {'die':<13} {'noise':>7} {'default':>8} {'shipped':>8} {'loo':>8} {'(capture)':>9} {'lofo':>8} "
          f"{'(capture)':>9}")  # fmt: skip
    shipped = int(np.argmin(np.abs(x - 0.81)))
    rows = []
    for k, i in enumerate(idx):
        row = (score(i, 0), score(i, shipped), score(i, loo[k]), score(i, lofo[k]))
        rows.append(row)
        print(f"  {dice[i].name:<13} {noise[i]:>7.4f} {row[0]:>8.4f} {row[1]:>8.4f} {row[2]:>8.4f} {x[loo[k]]:>9.2f} "
              f"{row[3]:>8.4f} {x[lofo[k]]:>9.2f}")  # fmt: skip
    m = np.mean(rows, axis=0)
    print(f"  {'mean':<13} {np.mean([noise[i] for i in idx]):>7.4f} {m[0]:>8.4f} {m[1]:>8.4f} {m[2]:>8.4f} "
          f"{'':>9} {m[3]:>8.4f}")  # fmt: skip
    others = [i for i in range(len(dice)) if i not in idx]
    for i in (i for i in others if i not in cached):
        print(f"  off its table: {dice[i].name:<13} capture grid not cached for this design")
    for i in (i for i in others if i in cached):
        print(f"  off its table: {dice[i].name:<13} default {score(i, 0):.4f}, shipped capture 0.81 "
              f"{score(i, shipped):.4f} (noise {noise[i]:.4f})")  # fmt: skip


def throw_or_table(dice, sims, vigor, probs, grid_tvd, ref, noise, default, prior_sd, args) -> None:
    """Cross-validation over the union of the vigor grid (capture 0) and the capture grid (the default throw).

    Candidates have coordinates (vigor, capture); the prior is normal toward the
    default (1, 0) with sd `prior_sd` in each.  The capture grid's drops are the
    2000 seed-0 drops ``bench_calibrate.py --free capture --grid 11`` cached.
    """

    caps = [c for c in CAPTURE_GRID if c > 0]
    if any((fingerprint(d), settings_key(PhysicsSettings(capture_energy=c)), 2000, 0) not in sims.table
           for d in dice for c in caps):  # fmt: skip
        print("\n3. skipped: the capture grid is not cached")
        return
    coords = [(float(v), 0.0) for v in vigor] + [(1.0, c) for c in caps]
    cand_p = [list(probs[i]) for i in range(len(dice))]
    cand_t = [list(grid_tvd[i]) for i in range(len(dice))]
    for i, d in enumerate(dice):
        for c in caps:
            counts = sims.counts_at(d, PhysicsSettings(capture_energy=c), 2000, 0, [c])
            cand_p[i].append(smoothed(counts))
            cand_t[i].append(d.tvd(counts / counts.sum()))
    x = np.array(coords)
    n = len(dice)

    def pick(train: list[int]) -> int:
        total = np.zeros(len(x))
        for j in train:
            total += [deviance(dice[j].counts, dice[j].symmetrized(p)) for p in cand_p[j]]
        if math.isfinite(prior_sd):
            total += (((x - np.array([1.0, 0.0])) / prior_sd) ** 2).sum(axis=1)
        return int(np.argmin(total))

    loo = [pick([j for j in range(n) if j != i]) for i in range(n)]
    lofo = [pick([j for j in range(n) if family(dice[j].name) != family(dice[i].name)]) for i in range(n)]
    default_index = coords.index((1.0, 0.0))

    def on_surface(i: int, train: list[int]) -> int:
        """The fit of the `train` dice on die i's surface; the default when no other die was rolled on it."""
        train = [j for j in train if surface(dice[j].name) == surface(dice[i].name)]
        return pick(train) if train else default_index

    loo_s = [on_surface(i, [j for j in range(n) if j != i]) for i in range(n)]
    lofo_s = [on_surface(i, [j for j in range(n) if family(dice[j].name) != family(dice[i].name)]) for i in range(n)]
    cols = {"default": default, "loo": [cand_t[i][loo[i]] for i in range(n)],
            "lofo": [cand_t[i][lofo[i]] for i in range(n)], "loo-surface": [cand_t[i][loo_s[i]] for i in range(n)],
            "lofo-surface": [cand_t[i][lofo_s[i]] for i in range(n)]}  # fmt: skip
    print(f"\n3. Throw or table: the vigor grid (capture 0) and the capture grid (default throw) as one set of "
          f"{len(x)} candidates, prior sd {prior_sd:g} toward the default in each")  # fmt: skip
    table(dice, {**cols, **ref}, noise)
    for how, idx in (("loo", loo), ("lofo", lofo), ("loo-surface", loo_s), ("lofo-surface", lofo_s)):
        print(f"  {how} (vigor, capture) per die: "
              + ", ".join(f"{d.name} ({x[idx[i]][0]:g}, {x[idx[i]][1]:g})" for i, d in enumerate(dice)))  # fmt: skip
    goal(dice, cols, ref, noise, default)
    if not args.score_drops:
        return

    # the same choices, each held-out die and the default scored on fresh drops (the grid's 400 add noise)
    def fresh(i: int, k: int) -> float:
        v, c = x[k]
        s = PhysicsSettings(capture_energy=float(c)) if c > 0 else throw_settings(float(v))
        counts = sims.counts_at(dice[i], s, args.score_drops, args.score_seed)
        return dice[i].tvd(counts / max(counts.sum(), 1))

    fresh_default = [fresh(i, default_index) for i in range(n)]
    cols = {"default": fresh_default}
    for how, idx in (("loo", loo), ("lofo", lofo), ("loo-surface", loo_s), ("lofo-surface", lofo_s)):
        cols[how] = [fresh(i, idx[i]) for i in range(n)]
    print(f"\n3'. The same choices scored on {args.score_drops} fresh drops (seed {args.score_seed})")
    table(dice, {**cols, **ref}, noise)
    goal(dice, cols, ref, noise, fresh_default)


def goal(dice, cols, ref, noise, default) -> None:
    """The goal's checks on the leave-one-die-out and leave-one-family-out columns."""
    with_ref = [i for i in range(len(dice)) if np.isfinite(ref["ours"][i]) and np.isfinite(ref["bullet"][i])]
    stone = [i for i, d in enumerate(dice) if d.name == "binom3_stone"]
    print("\n  goal checks:")
    for how in [c for c in cols if c.startswith(("loo", "lofo"))]:
        held = cols[how]
        mean_ref_dice = np.mean([held[i] for i in with_ref])
        best_source = min(np.mean([ref[k][i] for i in with_ref]) for k in ("ours", "bullet"))
        worse = [dice[i].name for i in range(len(dice)) if held[i] > default[i] + noise[i]]
        print(f"  {how}: mean TVD {np.mean(held):.4f} over all {len(dice)} dice (noise {np.mean(noise):.4f}, "
              f"ratio {np.mean(held) / np.mean(noise):.2f}, goal <= 1.3); over the {len(with_ref)} dice with the "
              f"source's columns {mean_ref_dice:.4f} vs their best column's mean {best_source:.4f}; worse than "
              f"the default by more than the noise: {', '.join(worse) or 'none'}"
              + (f"; binom3_stone {held[stone[0]]:.4f} (goal <= 0.06)" if stone else ""))  # fmt: skip


#: Section 4's table and die features, each at one value a unit step from the default (0).
FEATURES = {
    "none": {},
    "rolling": {"rolling_friction": 0.05, "spinning_friction": 0.05},
    "soft": {"table_softness": 0.01, "table_damping": 0.5},
    "rounded": {"edge_radius": 0.05},
}
#: Section 4's throws (vigor).
PHYSICS_VIGOR = (0.0, 0.5, 1.0)


def table_physics(dice, sims, args, ref, noise) -> None:
    """4. Throw, table and rounded edges: candidates fitted by cross-validation, held-out dice scored on fresh drops.

    Candidates: every throw of :data:`PHYSICS_VIGOR` with every feature set of
    :data:`FEATURES` (``--physics-drops`` drops, seed ``--physics-seed``), and
    the capture grid at the default throw (2000 seed-0 drops, cached by
    ``bench_calibrate.py --free capture --grid 11``).  Coordinates (vigor,
    capture, rolling, softness, rounding) on a unit scale, the prior toward the
    default (1, 0, 0, 0, 0).  A held-out die is scored on ``--score-drops``
    fresh drops (seed ``--score-seed``) at its chosen candidate, and so is
    the default, so that the simulation's own noise is small beside the
    real counts'.
    """

    from diefab.search.crossval import RULES, deviance_table, held_out_choices, pick_candidate

    started = time.perf_counter()
    cands, coords, drops, seeds = [], [], [], []
    for v in PHYSICS_VIGOR:
        for name, extra in FEATURES.items():
            cands.append(replace(throw_settings(v), **extra))
            coords.append((v, 0.0, *(float(name == f) for f in ("rolling", "soft", "rounded"))))
            drops.append(args.physics_drops)
            seeds.append(args.physics_seed)
    for c in CAPTURE_GRID[1:]:
        if all((fingerprint(d), settings_key(PhysicsSettings(capture_energy=c)), 2000, 0) in sims.table for d in dice):
            cands.append(PhysicsSettings(capture_energy=c))
            coords.append((1.0, c, 0.0, 0.0, 0.0))
            drops.append(2000)
            seeds.append(0)
    coords, x0 = np.array(coords), np.array([1.0, 0.0, 0.0, 0.0, 0.0])
    probs = [[None] * len(cands) for _ in dice]
    for k, s in enumerate(cands):
        for i, d in enumerate(dice):
            probs[i][k] = smoothed(sims.counts_at(d, s, drops[k], seeds[k]))
        print(f"  4. candidate {k + 1}/{len(cands)} {fmt_coords(coords[k])}: simulated  "
              f"({time.perf_counter() - started:.0f} s)", flush=True)  # fmt: skip
    dev = deviance_table(dice, probs)
    names = [d.name for d in dice]
    choices = held_out_choices(names, dev, coords, x0, args.prior, family, surface)

    def score(i: int, s) -> float:
        c = sims.counts_at(dice[i], s, args.score_drops, args.score_seed)
        return dice[i].tvd(c / max(c.sum(), 1))

    default = [score(i, PhysicsSettings()) for i in range(len(dice))]
    cols = {"perfect": [perfect_tvd(d, args.score_drops) for d in dice], "default": default}
    for rule in RULES:
        cols[rule] = [score(i, cands[k]) for i, k in enumerate(choices[rule])]
        print(f"  4. {rule}: scored  ({time.perf_counter() - started:.0f} s)", flush=True)
    print(f"\n4. Throw, table and rounded edges: {len(cands)} candidates (vigor, capture, rolling, softness, "
          f"rounding) fitted on {args.physics_drops} drops per die (capture grid 2000), prior sd {args.prior:g} "
          f"toward the default; each held-out die and the default scored on {args.score_drops} fresh drops "
          f"(seed {args.score_seed})")  # fmt: skip
    table(dice, {**cols, **ref}, noise)
    print(f"  perfect: what a perfect model scores on average against these real rolls with {args.score_drops} "
          "simulated drops (the real rolls' and the simulation's sampling noise together)")  # fmt: skip
    features = {}
    for k, (v, cap, *on) in enumerate(coords):
        if cap == 0.0:  # the throws and features (the capture grid is in section 1)
            label = f"v={v:g}" + "".join(f" {n}" for n, x in zip(("rolling", "soft", "rounded"), on) if x)
            counts = [sims.counts_at(d, cands[k], drops[k], seeds[k]) for d in dice]
            features[label] = [d.tvd(c / max(c.sum(), 1)) for d, c in zip(dice, counts)]
    print(f"\n  each throw and feature on the fitting drops ({args.physics_drops} per die, seed {args.physics_seed}):")
    table(dice, features, noise)
    for rule in RULES:
        print(f"  {rule} candidate per die: "
              + ", ".join(f"{d.name} {fmt_coords(coords[choices[rule][i]])}" for i, d in enumerate(dice)))  # fmt: skip
    k = pick_candidate(dev, range(len(dice)), coords, x0, args.prior)
    fitted = [d.tvd(probs[i][k] / probs[i][k].sum()) for i, d in enumerate(dice)]
    print(f"  in-sample (fitted on all {len(dice)} dice): {fmt_coords(coords[k])}, mean TVD {np.mean(fitted):.4f} "
          "on the fitting drops")  # fmt: skip
    goal(dice, cols, ref, noise, default)


def error_floor(dice, sims, noise, default, args, long_drops: int = 20_000, long_seed: int = 7) -> None:
    """What a perfect model scores at this many drops, beside the default physics on many drops.

    The default at `long_drops` drops (seed `long_seed`, cached like every
    run): its own simulation noise is then small, and what remains is the
    default's error on the die.
    """
    rows, shares = [], {}
    for i, d in enumerate(dice):
        c = sims.counts_at(d, PhysicsSettings(), long_drops, long_seed)
        shares[d.name] = c / c.sum()
        rows.append((d, noise[i], perfect_tvd(d, args.drops), perfect_tvd(d, args.score_drops), default[i],
                     d.tvd(shares[d.name])))  # fmt: skip
    head = (
        f"  {'die':<13} {'rolls':>5} {'noise':>7} {f'perfect {args.drops}':>13} "
        f"{f'perfect {args.score_drops}':>13} {f'default {args.drops}':>13} {f'default {long_drops}':>15}"
    )
    print(f"\n  Where the error comes from: a perfect model at {args.drops} and {args.score_drops} simulated drops, "
          f"and the default physics at {args.drops} (seed {args.seed}) and at {long_drops} drops "
          f"(seed {long_seed})")  # fmt: skip
    print(head)
    for d, z, p1, p2, d1, dl in rows:
        print(f"  {d.name:<13} {d.n:>5} {z:>7.4f} {p1:>13.4f} {p2:>13.4f} {d1:>13.4f} {dl:>15.4f}")
    m = np.mean(np.array([r[1:] for r in rows], dtype=float), axis=0)
    print(f"  {'mean':<13} {'':>5} {m[0]:>7.4f} {m[1]:>13.4f} {m[2]:>13.4f} {m[3]:>13.4f} {m[4]:>15.4f}")
    print(f"  a perfect model at {args.drops} drops: {m[1] / m[0]:.2f}x the noise; "
          f"at {args.score_drops}: {m[2] / m[0]:.2f}x")  # fmt: skip
    print(f"  per value, the default at {long_drops} drops, the real frequencies and the source's Bullet set-up:")
    for d in dice:
        bullet = d.reference.get("bullet")
        print(f"  {d.name:<13} default {'/'.join(f'{x:.3f}' for x in shares[d.name])}; "
              f"real {'/'.join(f'{x:.3f}' for x in d.frequencies)}"
              + (f"; bullet {'/'.join(f'{x:.3f}' for x in bullet)}" if bullet is not None else ""))  # fmt: skip
    means = perfect_means(dice, args.score_drops)
    ratio = means / m[0]
    print(f"  how well {len(dice)} dice measure a mean: a perfect model's mean TVD at {args.score_drops} drops over "
          f"4000 resamplings of the real counts {means.mean():.4f} (sd {means.std():.4f}); above 1.3x the noise "
          f"{np.mean(ratio > 1.3):.1%} of the time, 95th percentile {np.quantile(ratio, 0.95):.2f}x")  # fmt: skip


def perfect_means(dice, drops: int, samples: int = 4000, seed: int = 0) -> np.ndarray:
    """(samples,) a perfect model's mean TVD over `dice`, each die's real and simulated counts drawn afresh."""
    rng = np.random.default_rng(seed)
    per_die = []
    for d in dice:
        real = rng.multinomial(d.n, d.frequencies, size=samples) / d.n
        sim = rng.multinomial(drops, d.frequencies, size=samples) / drops
        per_die.append([d.tvd(s, r) for s, r in zip(sim, real)])
    return np.mean(per_die, axis=0)


def perfect_tvd(die, drops: int, samples: int = 4000, seed: int = 0) -> float:
    """Expected TVD of a perfect model scored on `drops` simulated drops (real and simulated counts both vary)."""
    return scored_tvd(die, die.frequencies, drops, samples, np.random.default_rng(seed), real=True)


def scored_tvd(die, q: np.ndarray, drops: int, samples: int, rng: np.random.Generator, real: bool) -> float:
    """Mean TVD of probabilities `q` to the die's rolls, scored on `drops` drops drawn from `q` (0: `q` itself).

    With `real`, the rolls too are drawn afresh (from `q`: the model is the
    die's truth); without, they are the die's own rolls.
    """
    shape = (samples, q.size)
    rolls = rng.multinomial(die.n, q, size=samples) / die.n if real else np.broadcast_to(die.frequencies, shape)
    sim = np.broadcast_to(q, rolls.shape) if drops == 0 else rng.multinomial(drops, q, size=samples) / drops
    return float(np.mean([die.tvd(s, r) for s, r in zip(sim, rolls)]))


def fmt_coords(x: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:g}" for v in x) + ")"


if __name__ == "__main__":
    sys.exit(main())
