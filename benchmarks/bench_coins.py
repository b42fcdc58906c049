"""Two thick coins flipped by hand: each landing model, and the simulation of a prism of many sides for each.

    nice -n 10 python benchmarks/bench_coins.py [--sides 16,24,48,128,256] [--drops 400] [--seed 1]
        [--rolling-friction 0,0.01] [--workers 2] | tee benchmarks/results/bench_coins.txt

The coins are the ``thick-coins`` table (:func:`diefab.search.published.thick_coin_dice`):
thickness over diameter 0.354 and 0.577, 1000 flips each, the count of the
coin left on its edge.  A cylinder enters diefab as a prism of ``n`` sides
about its circle (:func:`diefab.search.published.thick_coin`), so every
figure is given for several ``n``:

- ``solid-angle``, ``basins`` and ``fast``: the share of the edge each
  landing model gives (what ``diefab predict`` gives);
- the simulation at the default physics (``--drops`` drops, seed
  ``--seed``), and with Bullet's rolling friction where ``--rolling-friction``
  names values other than 0: the share of drops that come to rest within
  the time limit, the edge's share of those, and the edge's share if every
  drop still moving at the limit were counted on its edge (a coin that
  still moves is most often rolling on it).

The real edge shares and their sampling noise (the binomial standard error)
end each block.  A simulation scores a coin only where its drops come to
rest: the real-dice guard leaves a die out of its simulated columns when
fewer than :data:`diefab.search.fidelity.SETTLED` of them do.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from diefab.models.probabilities import value_probabilities  # noqa: E402
from diefab.physics.simulate import PhysicsSettings, simulate  # noqa: E402
from diefab.physics.world import UNSETTLED  # noqa: E402
from diefab.search.published import COIN_SIDES, thick_coin_dice  # noqa: E402

MODELS = ("solid-angle", "basins", "fast")


def _numbers(text: str, kind) -> list:
    try:
        return [kind(v) for v in text.split(",") if v]
    except ValueError:
        raise SystemExit(f"{text!r}: numbers separated by commas") from None


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sides", default=f"16,24,48,{COIN_SIDES},256", help="prism sides, comma-separated")
    ap.add_argument("--drops", type=int, default=400)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--rolling-friction", default="0", help="Bullet's rolling friction values, comma-separated")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    sides, frictions = _numbers(args.sides, int), _numbers(args.rolling_friction, float)
    if not sides or min(sides) < 3 or not frictions or min(frictions) < 0 or args.drops < 1:
        raise SystemExit("--sides >= 3, --rolling-friction >= 0 and --drops >= 1")
    started = time.perf_counter()
    for i, die in enumerate(thick_coin_dice()):
        ratio = float(np.ptp(die.design.polyhedron.vertices[:, 2])) / 2  # thickness over the diameter 2
        real = die.counts[1] / die.n
        print(f"\n{die.name}: thickness / diameter {ratio:.3f}, {die.n} real flips, edge {real:.3f} "
              f"(+- {np.sqrt(real * (1 - real) / die.n):.3f})")  # fmt: skip
        print(f"{'sides':>5} " + " ".join(f"{m:>11}" for m in MODELS)
              + f" {'rolling fr.':>11} {'at rest':>8} {'edge':>6} {'+- ':>6} {'moving=edge':>11}")  # fmt: skip
        for n in sides:
            design = thick_coin_dice(sides=n)[i].design
            edge = [float(value_probabilities(design, m)[1]) for m in MODELS]
            for k, friction in enumerate(frictions):
                sim = simulate(design, args.drops, seed=args.seed, workers=args.workers,
                               settings=PhysicsSettings(rolling_friction=friction))  # fmt: skip
                counts = np.asarray(sim.value_counts(design), dtype=float)
                rest = counts.sum()
                moving = int(np.count_nonzero(sim.outcomes == UNSETTLED))
                share = counts[1] / rest if rest else np.nan
                se = np.sqrt(share * (1 - share) / rest) if rest else np.nan
                models = " ".join(f"{e:>11.3f}" for e in edge) if k == 0 else " " * (12 * len(MODELS) - 1)
                print(f"{n:>5} {models} {friction:>11g} {rest / args.drops:>8.0%} {share:>6.3f} {se:>6.3f} "
                      f"{(counts[1] + moving) / args.drops:>11.3f}", flush=True)  # fmt: skip
    print(
        f"\nsimulation: {args.drops} drops per row, seed {args.seed}, the default physics but for the rolling "
        f"friction; 'edge' is the edge's share of the drops at rest ({time.perf_counter() - started:.0f} s)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
