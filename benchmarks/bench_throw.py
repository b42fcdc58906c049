"""How hard real dice are thrown: the throw's vigor past the paper's drop, fitted on some real dice, scored on others.

    nice -n 10 python benchmarks/bench_throw.py --workers 2 | tee benchmarks/results/bench_throw.txt

The throw is one number, its vigor (:func:`diefab.physics.throw.throw_settings`):
0.5 halfway from the source's gentle release, 1 the paper's drop (the
default), 2 a hard throw (twice the height and spin, a bouncier table).
Every die is simulated at every vigor of ``--vigor`` (``--drops`` drops,
seed ``--seed``; cached with the other held-out benchmarks in
``benchmarks/results/calibrate_loo_cache.jsonl``).  Two sets of real dice:

- *the eight*: the paper's gem and the seven shared dice (``--data``);
- *the cuboids*: the 15 published steel square cuboids
  (:func:`diefab.search.published.square_cuboid_dice`).

A die's vigor is the candidate of least deviance of the real counts of the
dice it is fitted on, plus a normal prior toward 1 (sd ``--prior``), or a
mixture of the candidates (:func:`diefab.search.mixture.fit_weights`).  It is
scored on its own simulated drops at that vigor, which took no part in the
choice.  Rules, none of which sees the die it scores:

- ``loo``: fitted on the other 22 dice;
- ``other set``: the eight fitted on the 15 cuboids, the cuboids on the
  eight: a whole set held out;
- ``loo in set``: fitted on the other dice of its own set;
- ``mix loo``: the mixture fitted on the other 22 dice.

Then the goal's checks on the eight.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_calibrate import Simulations  # noqa: E402
from bench_heldout import CACHE, REALROLLS, perfect_tvd, table  # noqa: E402
from bench_mixture import goal  # noqa: E402

from diefab.physics.simulate import shutdown_pool  # noqa: E402
from diefab.physics.throw import throw_settings  # noqa: E402
from diefab.search.crossval import pick_candidate  # noqa: E402
from diefab.search.fidelity import load_real_dice, noise_tvd, value_tvd  # noqa: E402
from diefab.search.likelihood import deviance, smoothed  # noqa: E402
from diefab.search.mixture import fit_weights, prior_penalty  # noqa: E402
from diefab.search.published import square_cuboid_dice  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vigor", default="0.5,1,1.5,2", help="the candidates' vigor, comma-separated (1 must be one)")
    ap.add_argument("--drops", type=int, default=1000, help="simulated drops per die and vigor")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--prior", type=float, default=0.5, help="prior sd of vigor toward 1 (inf: none)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--data", type=Path, default=REALROLLS)
    args = ap.parse_args()
    try:
        vigor = [float(v) for v in args.vigor.split(",")]
    except ValueError:
        raise SystemExit(f"--vigor {args.vigor!r}: numbers separated by commas") from None
    if 1.0 not in vigor:
        raise SystemExit(f"--vigor {args.vigor!r} must include 1, the default throw")
    if not args.data.is_dir():
        raise SystemExit(f"no real-rolls folder {args.data}")
    if not args.prior > 0:
        raise SystemExit(f"--prior {args.prior} must be > 0 (inf: none)")
    started = time.perf_counter()
    eight, cuboids = load_real_dice(args.data), square_cuboid_dice()
    dice = eight + cuboids
    sets = [list(range(len(eight))), list(range(len(eight), len(dice)))]
    sims = Simulations(CACHE, args.workers)
    freq = np.zeros((len(dice), len(vigor)), dtype=object)
    probs = np.zeros((len(dice), len(vigor)), dtype=object)
    for k, v in enumerate(vigor):
        for i, d in enumerate(dice):
            c = sims.counts_at(d, throw_settings(v), args.drops, args.seed)
            freq[i, k], probs[i, k] = c / c.sum(), d.symmetrized(smoothed(c))
        print(f"  vigor {v:g}: simulated  ({time.perf_counter() - started:.0f} s)", flush=True)
    shutdown_pool()
    coords = np.array(vigor)[:, None]
    dev = np.array([[deviance(d.counts, probs[i, k]) for k in range(len(vigor))] for i, d in enumerate(dice)])
    default = vigor.index(1.0)

    def grid(train: list[int]) -> np.ndarray:
        w = np.zeros(len(vigor))
        w[pick_candidate(dev, train, coords, np.array([1.0]), args.prior)] = 1.0
        return w

    def mix(train: list[int]) -> np.ndarray:
        penalty = prior_penalty(coords, np.array([1.0]), args.prior)
        return fit_weights([dice[j].counts for j in train], [np.array(list(probs[j])) for j in train], penalty)

    def own_set(i: int) -> list[int]:
        return sets[0] if i in sets[0] else sets[1]

    rules = {
        "loo": lambda i: grid([j for j in range(len(dice)) if j != i]),
        "other set": lambda i: grid(sets[1] if i in sets[0] else sets[0]),
        "loo in set": lambda i: grid([j for j in own_set(i) if j != i]),
        "mix loo": lambda i: mix([j for j in range(len(dice)) if j != i]),
    }
    weights = {name: [rule(i) for i in range(len(dice))] for name, rule in rules.items()}
    columns = {"perfect": [perfect_tvd(d, args.drops) for d in dice]}
    columns |= {f"v={v:g}": [value_tvd(d, freq[i, k]) for i, d in enumerate(dice)] for k, v in enumerate(vigor)}
    for name, ws in weights.items():
        columns[name] = [value_tvd(d, sum(w[k] * freq[i, k] for k in range(len(vigor)))) for i, (d, w) in
                         enumerate(zip(dice, ws))]  # fmt: skip
    columns |= {k: [value_tvd(d, d.reference[k]) if k in d.reference else np.nan for d in dice]
                for k in ("ours", "bullet")}  # fmt: skip
    noise = [noise_tvd(d) for d in dice]

    print(f"\nTVD to the real rolls, each die scored on its own {args.drops} drops (seed {args.seed}); prior sd "
          f"{args.prior:g} toward vigor 1; perfect: a perfect model at {args.drops} drops")  # fmt: skip
    for label, rows in (("the eight", sets[0]), ("the published cuboids", sets[1])):
        print(f"\n{label}:")
        shown = [c for c in columns if not np.isnan([columns[c][i] for i in rows]).all()]  # the source's, where given
        table([dice[i] for i in rows], {c: [columns[c][i] for i in rows] for c in shown}, [noise[i] for i in rows])
        mean_noise = np.mean([noise[i] for i in rows])
        for name in ("perfect", f"v={vigor[default]:g}", *rules):
            m = np.nanmean([columns[name][i] for i in rows])
            print(f"  {name:<11} mean {m:.4f} = {m / mean_noise:.2f}x the noise")
        for name in rules:
            chosen = [float(weights[name][i] @ np.array(vigor)) for i in rows]
            print(f"  {name:<11} vigor (mean of the weights) per die: "
                  + ", ".join(f"{dice[i].name} {v:.2f}" for i, v in zip(rows, chosen)))  # fmt: skip
    print("\ngoal checks on the eight:")
    rows = sets[0]
    for name in rules:
        goal([dice[i] for i in rows], [columns[name][i] for i in rows],
             [columns[f"v={vigor[default]:g}"][i] for i in rows], [noise[i] for i in rows], name)  # fmt: skip
    print(f"\n({time.perf_counter() - started:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
