"""How near the held-out goal over every die with real rolls any model could come: its floor, part by part.

    python benchmarks/goal_floor.py | tee benchmarks/results/goal_floor.txt

The goal asks for a held-out mean TVD to the real rolls within 1.3x the
mean sampling noise over every die the simulation scores (the eight, the 15
published cuboids and the source's three further dice: 26).  Some of that
mean no model can remove, and this script measures how much, with no
simulation (a few seconds):

- ``perfect``: a model whose probabilities are the die's true ones, scored
  as the benchmark scores (``--drops`` simulated drops against the real
  rolls, both drawn afresh; 0 drops: its exact probabilities, so only the
  real rolls' noise);
- ``law of the ratio``: a cuboid is seen by any model only through its
  aspect ratio, so on the cuboids no model beats the best smooth law of the
  ratio through their counts (``benchmarks/fit_cuboid_curves.py``): two
  logistic pieces in log ratio meeting at the fair cube, each cuboid
  predicted by the law fitted to the other 14 (held out) or to all 15
  (in-sample, more than any model can hope for);
- ``best prediction``: the bunny d6, which no model predicts, at the best
  of every prediction made of it (diefab's landing models and the source's
  own columns), whichever is nearest its rolls.

Each line is the mean over the 26 of one such floor, as a multiple of the
mean noise; a line above 1.3x says the goal is out of reach of any model
that cannot do better than its assumptions.

The goal's other part, no held-out die worse than under the default physics
by more than its noise, is checked for the law of the ratio on the
cuboids, against the default physics' drops of ``bench_throw.py`` (read
from the held-out benchmarks' cache; simulated there if absent): 1000
drops at seed 3 and 3000 drops at seed 6, its two runs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_calibrate import Simulations  # noqa: E402
from bench_heldout import CACHE, scored_tvd  # noqa: E402
from fit_cuboid_curves import curves, fit  # noqa: E402

from diefab.physics.simulate import shutdown_pool  # noqa: E402
from diefab.physics.throw import throw_settings  # noqa: E402
from diefab.search.fidelity import LANDING_MODELS, load_real_dice, noise_tvd  # noqa: E402
from diefab.search.published import printed_dice, square_cuboid_dice  # noqa: E402

REALROLLS = ROOT / ".." / "shared" / "realrolls"
LAW = "two-sided logit 2"
GOAL = 1.3
#: The (drops, seed) of the default physics' runs in ``bench_throw.py``.
DEFAULT_RUNS = ((1000, 3), (3000, 6))


def ratio_laws(cuboids) -> tuple[np.ndarray, np.ndarray]:
    """Each cuboid's (rectangle, square) shares under the best law of the ratio: fitted without it, and with it."""
    ratio = np.array([float(d.name.split("-")[1]) for d in cuboids])
    square = np.array([d.counts[-1] for d in cuboids], dtype=float)  # values (rectangle, square): square last
    n = np.array([d.n for d in cuboids], dtype=float)
    law, start = curves(ratio)[LAW]
    every = np.arange(len(cuboids))
    inside = law(fit(law, start, square, n, every))
    held = np.array([law(fit(law, start, square, n, np.delete(every, i)))[i] for i in every])
    return np.c_[1 - held, held], np.c_[1 - inside, inside]


def best_prediction(die) -> tuple[np.ndarray, str]:
    """The nearest to the die's rolls of every prediction made of it: diefab's landing models, the source's."""
    from diefab.models.probabilities import value_probabilities

    made = {m: value_probabilities(die.design, m) for m in LANDING_MODELS} | dict(die.reference)
    name = min(made, key=lambda m: die.tvd(made[m]))
    return np.asarray(made[name], dtype=float), name


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--drops",
        default="1000,3000,0",
        help="simulated drops a prediction is scored on, comma-separated (0: its exact probabilities)",
    )
    ap.add_argument("--samples", type=int, default=4000, help="Monte-Carlo draws per die and figure")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--data", type=Path, default=REALROLLS)
    args = ap.parse_args(argv)
    try:
        drops = [int(x) for x in args.drops.split(",")]
    except ValueError:
        raise SystemExit(f"--drops {args.drops!r}: whole numbers, comma-separated") from None
    if not drops or min(drops) < 0:
        raise SystemExit(f"--drops {args.drops!r}: each >= 0")
    if args.samples < 1:
        raise SystemExit(f"--samples {args.samples}: at least 1")
    if not args.data.is_dir():
        raise SystemExit(f"no real-rolls folder {args.data}")
    rng = np.random.default_rng(args.seed)
    groups = {"the eight": load_real_dice(args.data), "the published cuboids": square_cuboid_dice(),
              "the source's further dice": printed_dice()}  # fmt: skip
    dice = [d for g in groups.values() for d in g]
    cuboids = groups["the published cuboids"]
    if any(d.counts.size != 2 for d in cuboids):
        raise SystemExit("a published cuboid is not counted as (rectangle, square)")
    noise = np.array([noise_tvd(d) for d in dice])
    held, inside = ratio_laws(cuboids)
    on_cuboid = [i for i, d in enumerate(dice) if d in cuboids]
    bunny = next(i for i, d in enumerate(dice) if d.name == "bunny_d6")
    best, best_by = best_prediction(dice[bunny])

    def figures(n: int) -> dict[str, np.ndarray]:
        """Per die: a perfect model, the laws of the ratio (cuboids), the bunny's best prediction, at `n` drops."""
        perfect = np.array([scored_tvd(d, d.frequencies, n, args.samples, rng, True) for d in dice])
        law = {k: perfect.copy() for k in ("held", "in")}
        for j, i in enumerate(on_cuboid):
            for k, q in (("held", held[j]), ("in", inside[j])):
                law[k][i] = scored_tvd(dice[i], q, n, args.samples, rng, False)
        bunny_best = scored_tvd(dice[bunny], best, n, args.samples, rng, False)
        return {"perfect": perfect, "law held": law["held"], "law in": law["in"], "bunny": bunny_best}

    runs = {n: figures(n) for n in drops}
    name = {n: f"{n} drops" if n else "exact" for n in drops}
    print(f"every die the simulation scores ({len(dice)}): mean noise {noise.mean():.4f}; "
          f"the goal: held-out mean <= {GOAL}x, {GOAL * noise.mean():.4f}")  # fmt: skip
    print(
        "\nper die, scored on each number of drops (exact: the probabilities themselves): a perfect model; "
        "on the cuboids, the law of the ratio held out and in-sample"
    )
    head = "".join(f" {'perfect':>8s} {'law held':>9s} {'law in':>8s}" for _ in drops)
    print(f"{'':30s}" + "".join(f" {name[n]:>27s}" for n in drops))
    print(f"{'die':22s} {'noise':>7s}" + head)
    for i, d in enumerate(dice):
        row = ""
        for n in drops:
            f = runs[n]
            law = f"{f['law held'][i]:9.4f} {f['law in'][i]:8.4f}" if i in on_cuboid else f"{'':9s} {'':8s}"
            row += f" {f['perfect'][i]:8.4f} {law}"
        print(f"{d.name:22s} {noise[i]:7.4f}" + row)
    print(
        f"\nbunny_d6 (noise {noise[bunny]:.4f}): the best of every prediction of it is {best_by}, "
        + ", ".join(f"{runs[n]['bunny']:.4f} on {name[n]}" for n in drops)
    )

    scenarios = {
        "every die perfectly": lambda f: f["perfect"],
        "... but the bunny at its best prediction": lambda f: _with(f["perfect"], bunny, f["bunny"]),
        "... and the cuboids by the law in-sample": lambda f: _with(f["law in"], bunny, f["bunny"]),
        "... and the cuboids by the law held out": lambda f: _with(f["law held"], bunny, f["bunny"]),
    }
    print(
        f"\nthe mean over the {len(dice)} dice, as a multiple of the noise, if each die were predicted so "
        f"(goal <= {GOAL}x):"
    )
    print(f"{'':44s}" + "".join(f" {name[n]:>16s}" for n in drops))
    for label, pick in scenarios.items():
        cells = "".join(f" {pick(runs[n]).mean():8.4f} {pick(runs[n]).mean() / noise.mean():5.2f}x" for n in drops)
        print(f"{label:44s}{cells}")
    worse_than_default(cuboids, held, noise[on_cuboid])
    return 0


def worse_than_default(cuboids, held: np.ndarray, noise: np.ndarray) -> None:
    """Each cuboid's TVD under the law held out beside the default physics', and where it is worse beyond the noise."""
    sims = Simulations(CACHE, workers=2)
    counts = {run: [sims.counts_at(d, throw_settings(1.0), *run) for d in cuboids] for run in DEFAULT_RUNS}
    default = {run: [d.tvd(c / c.sum()) for d, c in zip(cuboids, cs)] for run, cs in counts.items()}
    shutdown_pool()
    law = [d.tvd(q) for d, q in zip(cuboids, held)]
    print(
        "\nthe cuboids: the law of the ratio held out (exact) against the default physics "
        + " and ".join(f"on {n} drops (seed {seed})" for n, seed in DEFAULT_RUNS)
    )
    print(f"{'die':14s} {'noise':>7s} {'law held':>9s}" + "".join(f" {f'default {n}':>13s}" for n, _ in DEFAULT_RUNS))
    for j, d in enumerate(cuboids):
        cells = "".join(f" {default[run][j]:13.4f}" for run in DEFAULT_RUNS)
        print(f"{d.name:14s} {noise[j]:7.4f} {law[j]:9.4f}{cells}")
    for n, seed in DEFAULT_RUNS:
        worse = [d.name for j, d in enumerate(cuboids) if law[j] > default[n, seed][j] + noise[j]]
        print(f"  worse than the default on {n} drops by more than the noise: {', '.join(worse) or 'none'}")


def _with(floor: np.ndarray, i: int, value: float) -> np.ndarray:
    out = floor.copy()
    out[i] = value
    return out


if __name__ == "__main__":
    raise SystemExit(main())
