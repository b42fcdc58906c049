"""diefab against real rolls: every die of the real-rolls data through the command line as shipped.

For each die (one JSON file of the data folder) the reader
(:mod:`diefab.physics.realrolls`) writes its design TOML; then

    diefab predict DIE.toml --model solid-angle|basins|fast --json
    diefab validate DIE.toml --sims N --seed S --json

run as subprocesses, and the table gives each one's TVD to the real counts,
beside the source's own quasi-static model (``ours``) and Bullet simulation
(``bullet``) and the sampling noise of the real counts (the TVD a perfect
model would score on average).  Outcomes in one of the data's ambiguous
groups are compared up to relabelling within the group, for every column.

With ``--landing`` it measures instead what the landing rule itself gains:
each die is validated twice on the same drops (same seed), once with the
default rule (a die has landed when it can no longer leave its face: in the
face's basin below its barrier, or still on it for 1 s) and once with a plain
short still window (``--energy-fraction 0``: still on a resting face for
``--settle-time`` 0.1 s), and the TVD of each to the real counts is printed.

The paper's die as made (a paper model of its final gem, 405 real rolls,
Table 2) is the first row of every table; ``--guard`` adds the published
dice shipped with diefab (:mod:`diefab.search.published`): the source's
further printed dice, 15 steel square cuboids and two thick coins.

With ``--guard`` it computes, in this process, the figures the real-dice
guard test (``tests/test_realrolls_guard.py``) checks: each landing model's
TVD per die and ``validate`` at ``--sims`` drops (seed ``--seed``), at the
default physics and under each shipped profile fitted on real dice
(:func:`diefab.physics.profiles.fitted_profiles`), simulated counts cached
in ``benchmarks/results/realrolls-sim-cache.json`` under a key of the design, settings, drops, seed
and the simulation's code; ``--record`` writes their means over the dice
to ``benchmarks/results/realrolls-guard.json``, the figures the test
holds every model to (worse by more than ``tolerance`` fails).

Usage::

    nice -n 10 python benchmarks/bench_realrolls.py [--sims 2000] [--workers 2] [--data DIR] [--out DIR]
        [--physics PROFILE] [--capture-energy C]    # validate under a profile / with quasi-static capture
    nice -n 10 python benchmarks/bench_realrolls.py --landing [--dice armadilo_d3,dragon_d3,kitten_d3]
    nice -n 10 python benchmarks/bench_realrolls.py --guard --sims 400 [--record]   # the guard's figures
    python benchmarks/bench_realrolls.py --domain    # the fast model's correction inside and outside its domain
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from diefab.physics.profiles import fitted_profiles
from diefab.physics.realrolls import RealRolls, load_real_rolls
from diefab.search.fidelity import (
    LANDING_MODELS,
    PAPER_DIE_TOML,
    SETTLED,
    TABLE_2,
    SimulationCache,
    guard_scores,
    guard_settings,
    load_real_dice,
    mean_scores,
    noise_tvd,
    settled_share,
    simulation_key,
)
from diefab.search.published import printed_dice

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / ".." / "shared" / "realrolls"
MODELS = LANDING_MODELS
GUARD = ROOT / "benchmarks" / "results" / "realrolls-guard.json"
SIM_CACHE = ROOT / "benchmarks" / "results" / "realrolls-sim-cache.json"
#: How much worse than its recorded mean TVD a model may get before the guard fails.
GUARD_TOLERANCE = 0.005


def cli(*args: str) -> tuple[dict, float]:
    """Run ``diefab ARGS --json``; its JSON output and wall time."""
    started = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "diefab", *args, "--json"], capture_output=True, text=True)
    seconds = time.perf_counter() - started
    if proc.returncode != 0:
        raise SystemExit(f"diefab {' '.join(args)} failed: {proc.stderr.strip()}")
    return json.loads(proc.stdout), seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA, help="Folder of real-rolls JSON files.")
    parser.add_argument("--out", type=Path, default=Path("out/realrolls"), help="Where the design files go.")
    parser.add_argument("--sims", type=int, default=2000, help="Drops per validation.")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--landing", action="store_true", help="Compare the landing rule with a still window.")
    parser.add_argument("--dice", default="", help="Comma-separated die names (default: every die).")
    parser.add_argument("--physics", default=None, help="Physics profile for validate (default: the defaults).")
    parser.add_argument("--capture-energy", default=None, help="validate --capture-energy (default: off).")
    parser.add_argument("--guard", action="store_true", help="The real-dice guard's figures (in this process).")
    parser.add_argument("--record", action="store_true", help="--guard: record them as the guard's figures.")
    parser.add_argument("--domain", action="store_true", help="The fast model's correction in and out of its domain.")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    if args.domain:
        correction_domain(args)
        return
    if args.guard:
        guard(args)
        return
    files = sorted(args.data.glob("*.json"))
    if args.dice:
        files = [f for f in files if f.stem in args.dice.split(",")]
    if not files:
        raise SystemExit(f"no JSON files in {args.data}")
    if args.landing:
        compare_landing(files, args)
        return
    columns = ["noise", *MODELS, "validate", "ours", "bullet"]
    rows, times = [], {m: 0.0 for m in (*MODELS, "validate")}
    print(f"{'die':<13} {'rolls':>5} {'faces':>5} {'rest':>4} " + " ".join(f"{c:>11}" for c in columns))
    (args.out / "paper-gem.toml").write_text(PAPER_DIE_TOML)
    paper = RealRolls(name="paper-gem", outcomes=tuple(range(-4, 5)), counts=np.array(TABLE_2))
    for path in [None, *files] if not args.dice or "paper-gem" in args.dice.split(",") else files:
        rolls = paper if path is None else load_real_rolls(path)
        if path is not None:
            for name, content in rolls.design_files().items():
                (args.out / name).write_text(content)
        design = str(args.out / f"{rolls.name}.toml")
        row = {"noise": rolls.noise_tvd()}
        info = {}
        for model in MODELS:
            data, seconds = cli("predict", design, "--model", model)
            times[model] += seconds
            row[model] = rolls.tvd({int(k): v for k, v in data["values"].items()})
            info = {"faces": len(data["faces"]), "resting": len(data["faces"]) - len(data["transitional"])}
        profile = ("--physics", args.physics) if args.physics else ()
        if args.capture_energy is not None:
            profile += ("--capture-energy", args.capture_energy)
        data, seconds = cli("validate", design, "--sims", str(args.sims), "--seed", str(args.seed),
                            "--workers", str(args.workers), *profile)  # fmt: skip
        times["validate"] += seconds
        landed = max(data["landed"], 1)
        row["validate"] = rolls.tvd({int(k): c / landed for k, c in data["counts"].items()})
        for key in ("ours", "bullet"):
            ref = rolls.reference.get(key)
            row[key] = rolls.tvd(dict(zip(rolls.outcomes, ref))) if ref is not None else float("nan")
        rows.append(row)
        lost = data["cocked"] + data["unsettled"]
        print(f"{rolls.name:<13} {rolls.n:>5} {info['faces']:>5} {info['resting']:>4} "
              + " ".join(f"{row[c]:>11.4f}" for c in columns)
              + (f"   ({lost} of {data['n']} drops cocked/unsettled)" if lost else ""), flush=True)  # fmt: skip
    mean = {c: float(np.nanmean([r[c] for r in rows])) for c in columns}
    print(f"{'mean':<13} {'':>5} {'':>5} {'':>4} " + " ".join(f"{mean[c]:>11.4f}" for c in columns))
    print(
        f"\nTVD to the real counts (ambiguous groups compared up to relabelling). validate: {args.sims} pybullet "
        f"drops per die, seed {args.seed}, {args.workers} workers, "
        + (f"physics profile {args.physics}" if args.physics else "default physics settings")
        + (f", capture energy {args.capture_energy}" if args.capture_energy is not None else "")
        + ". noise: expected TVD of "
        "the real counts to their own distribution (Monte-Carlo, 20,000 samples). ours/bullet: the source's "
        "quasi-static model and Bullet simulation, normalised."
    )
    print("wall time per command over all dice (s): "
          + ", ".join(f"{k} {v:.1f}" for k, v in times.items())
          + f"; {os.cpu_count()} cores (shared machine)")  # fmt: skip


def _validated_tvd(rolls, design: str, args, *extra: str) -> tuple[float, dict, float]:
    data, seconds = cli("validate", design, "--sims", str(args.sims), "--seed", str(args.seed),
                        "--workers", str(args.workers), *extra)  # fmt: skip
    landed = max(data["landed"], 1)
    return rolls.tvd({int(k): c / landed for k, c in data["counts"].items()}), data, seconds


def compare_landing(files: list[Path], args) -> None:
    """TVD to the real counts with the landing rule and with a plain 0.1 s still window, same drops."""
    head = ("die", "rolls", "noise", "rule", "window", "gain", "rule lost", "window lost", "rule s", "window s")
    print(f"{head[0]:<13} " + " ".join(f"{h:>11}" for h in head[1:]))
    rows = []
    for path in files:
        rolls = load_real_rolls(path)
        for name, content in rolls.design_files().items():
            (args.out / name).write_text(content)
        design = str(args.out / f"{rolls.name}.toml")
        rule, d_rule, s_rule = _validated_tvd(rolls, design, args)
        window, d_window, s_window = _validated_tvd(rolls, design, args, "--energy-fraction", "0")
        lost = [d["cocked"] + d["unsettled"] for d in (d_rule, d_window)]
        rows.append((rule, window))
        print(f"{rolls.name:<13} {rolls.n:>11} {rolls.noise_tvd():>11.4f} {rule:>11.4f} {window:>11.4f} "
              f"{window - rule:>11.4f} {lost[0]:>11} {lost[1]:>11} {s_rule:>11.1f} {s_window:>11.1f}",
              flush=True)  # fmt: skip
    rule, window = np.mean(rows, axis=0)
    print(f"{'mean':<13} {'':>11} {'':>11} {rule:>11.4f} {window:>11.4f} {window - rule:>11.4f}")
    print(
        f"\nTVD to the real counts; {args.sims} pybullet drops per die and rule, seed {args.seed} (the same drops "
        f"for both), {args.workers} workers. rule: the default landing rule (basin and barrier, or still 1 s); "
        "window: --energy-fraction 0 (still 0.1 s on a resting face). gain: window minus rule (positive: the rule "
        f"agrees better with the real rolls). lost: drops cocked or unsettled. {os.cpu_count()} cores (shared machine)"
    )


def _cell(tvd: float) -> str:
    """A TVD for the guard's table, or "unsettled" where the simulation does not score the die."""
    return f"{'unsettled':>13}" if np.isnan(tvd) else f"{tvd:>13.4f}"


def die_sets(dice) -> dict[str, list]:
    """The dice with real rolls by set: the paper's die and the shared dice, the source's further dice, the cuboids,
    the thick coins."""
    printed = {d.name for d in printed_dice()}
    published = ("cuboid-", "coin-")
    return {"the paper's die and the shared dice": [d for d in dice if not d.name.startswith(published)
                                                    and d.name not in printed],
            "the source's further printed dice": [d for d in dice if d.name in printed],
            "the published cuboids": [d for d in dice if d.name.startswith("cuboid-")],
            "the thick coins": [d for d in dice if d.name.startswith("coin-")]}  # fmt: skip


def correction_domain(args) -> None:
    """Why the general correction holds only in its domain: each die by the chain alone, by the correction
    applied regardless of its domain, and by ``fast`` as shipped, against the real counts."""
    from diefab.models.chain import landing_probabilities
    from diefab.models.correction import face_features, packaged_correction
    from diefab.models.probabilities import to_values, value_probabilities

    dice = load_real_dice(args.data, published=True)
    if args.dice:
        dice = [d for d in dice if d.name in args.dice.split(",")]
    correction = packaged_correction()
    columns = ("chain alone", "forced", "fast")
    print(f"{'die':<22} {'rolls':>5} {'noise':>7} {'domain':>7} " + " ".join(f"{c:>12}" for c in columns))
    rows = {}
    for d in dice:
        poly, body = d.design.polyhedron, d.design.mass_properties()
        center, inertia = body.center, body.inertia / body.mass
        chain = landing_probabilities(poly, center, inertia=inertia, **correction.chain)
        features, resting = face_features(poly, center, chain)
        alone = np.where(resting, chain, 0.0)
        faces = {"chain alone": alone / alone.sum(), "forced": correction.correct(chain, features, resting)}
        tvd = {k: d.tvd(to_values(d.design, p)) for k, p in faces.items()}
        tvd["fast"] = d.tvd(value_probabilities(d.design, "fast"))
        inside = correction.covers(features, resting)
        rows[d.name] = tvd
        print(f"{d.name:<22} {d.n:>5} {noise_tvd(d, 4000):>7.4f} {'yes' if inside else 'no':>7} "
              + " ".join(f"{tvd[c]:>12.4f}" for c in columns), flush=True)  # fmt: skip
    sets = die_sets(dice)
    shared = [d for d in sets["the paper's die and the shared dice"] if d.name != "paper-gem"]
    sets = {"the paper's die and the shared dice": sets.pop("the paper's die and the shared dice"),
            "the shared dice": shared, **sets}  # fmt: skip
    for label, group in sets.items():
        if group:
            print(f"mean, {label} ({len(group)}): "
                  + ", ".join(f"{c} {np.mean([rows[d.name][c] for d in group]):.4f}" for c in columns))  # fmt: skip
    print(
        "\nTVD to the real counts; domain: whether the die lies in the general correction's domain (no "
        "transitional face, features within the training range); forced: the correction applied regardless; "
        "fast: as shipped (the chain alone outside the domain; a gem gets the gem correction instead)"
    )


def guard(args) -> None:
    """Print (and with ``--record`` write) the guard's figures: TVD per die and model, and their means."""
    dice = load_real_dice(args.data, published=True)
    if args.dice:
        dice = [d for d in dice if d.name in args.dice.split(",")]
    started = time.perf_counter()
    cache = SimulationCache(SIM_CACHE)
    profiles = fitted_profiles()
    scores = guard_scores(dice, drops=args.sims, seed=args.seed, cache=cache, workers=args.workers,
                          profiles=profiles)  # fmt: skip
    columns = [*MODELS, "validate", *(f"validate --profile {p}" for p in profiles)]
    print(f"{'die':<13} {'rolls':>5} {'noise':>8} " + " ".join(f"{c.split()[-1]:>13}" for c in columns))
    for d in dice:
        print(f"{d.name:<13} {d.n:>5} {noise_tvd(d, 4000):>8.4f} " + " ".join(_cell(scores[d.name][c])
                                                                         for c in columns))  # fmt: skip
    unsettled = [d for d in dice if np.isnan(scores[d.name]["validate"])]
    if unsettled:
        shares = [settled_share(d, drops=args.sims, seed=args.seed, cache=cache) for d in unsettled]
        print("unsettled: " + ", ".join(f"{d.name} {share:.0%}" for d, share in zip(unsettled, shares))
              + f" of the drops at the default physics come to rest (under {SETTLED:.0%}): left out of the "
              "simulated columns and their means")  # fmt: skip
    mean = mean_scores(dice, scores)
    for label, group in die_sets(dice).items():
        if group:
            m = mean_scores(group, scores)
            print(f"mean, {label} ({len(group)}): " + ", ".join(f"{c} {m[c]:.4f}" for c in columns
                                                                 if not np.isnan(m[c])))  # fmt: skip
    print(f"{'mean':<13} {'':>5} {'':>8} " + " ".join(f"{mean[c]:>13.4f}" for c in columns))
    print(f"\nTVD to the real counts; validate: {args.sims} drops per die, seed {args.seed}, default physics "
          f"and each shipped profile fitted on real dice ({', '.join(profiles)}), "
          f"{time.perf_counter() - started:.0f} s ({os.cpu_count()} cores, shared machine)")  # fmt: skip
    if GUARD.is_file():
        old = json.loads(GUARD.read_text())
        print("recorded: " + ", ".join(f"{c} {old['mean'][c]:.4f}" for c in columns if c in old["mean"]))
    if args.record:
        from diefab.core.files import atomic_write

        data = {"tolerance": GUARD_TOLERANCE, "drops": args.sims, "seed": args.seed, "profiles": profiles,
                "dice": [d.name for d in dice], "mean": {c: round(mean[c], 5) for c in columns},
                "per_die": {d.name: {c: None if np.isnan(scores[d.name][c]) else round(scores[d.name][c], 5)
                                     for c in columns} for d in dice},
                "command": f"python benchmarks/bench_realrolls.py --guard --sims {args.sims} --seed {args.seed} "
                           "--record"}  # fmt: skip
        atomic_write(GUARD, json.dumps(data, indent=1) + "\n")
        # the cache keeps only this run's simulations: entries of older code can never be read again
        used = {simulation_key(d, settings, args.sims, args.seed) for d in dice
                for settings in guard_settings(d, profiles).values()}  # fmt: skip
        atomic_write(SIM_CACHE, json.dumps({k: v for k, v in cache.entries.items() if k in used}, indent=0,
                                           sort_keys=True) + "\n")  # fmt: skip
        print(f"recorded in {GUARD.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
