"""The chain model's five constants fitted to real dice instead of to pybullet: in-sample, and held out.

    nice -n 10 python benchmarks/fit_chain.py | tee benchmarks/results/fit_chain.txt

The chain (:mod:`diefab.models.chain`) is the physics inside ``fast``:
first contact, quasi-static toppling, energy-barrier tumbling for a while,
a weight on rest height.  Its constants (temperature, duration, area
power, height weight, roll power) are fitted to pybullet drops.  Fitted
instead to real counts, by Nelder-Mead on the mean of each die's TVD over
its sampling noise (so a die of many rolls does not outweigh one of few),
from the shipped constants:

1. in-sample: on every die, and on each set of dice alone (the eight, the
   15 published cuboids, the source's further printed dice), each fit
   scored on every set;
2. held out: each set predicted from a fit on the other two, and each die
   from a fit on the other dice of its own set.

The model is deterministic, so the scores carry no simulation noise:
a perfect model would score the noise (1.00x).  A fit that helps in-sample
and hurts held out is following its training dice, not the physics.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from diefab.models import chain  # noqa: E402
from diefab.models.probabilities import to_values  # noqa: E402
from diefab.search.fidelity import load_real_dice, noise_tvd  # noqa: E402
from diefab.search.published import printed_dice, square_cuboid_dice  # noqa: E402

#: The shipped constants, fitted to pybullet.
SHIPPED = {"temperature": chain.TEMPERATURE, "tau": chain.TAU, "area_power": chain.AREA_POWER,
           "height_weight": chain.HEIGHT_WEIGHT, "roll_power": chain.ROLL_POWER}  # fmt: skip


class Scorer:
    """Each die's TVD to its real rolls under the chain at given constants, over its noise."""

    def __init__(self, dice) -> None:
        self.dice = dice
        self.bodies = [(d.design.polyhedron, d.design.mass_properties().center) for d in dice]
        self.noise = np.array([noise_tvd(d) for d in dice])

    def tvd(self, constants: dict[str, float], rows) -> np.ndarray:
        """(len(rows),) TVD of each die of `rows` (1 where the chain has no answer at `constants`)."""
        out = []
        for i in rows:
            poly, center = self.bodies[i]
            p = chain.landing_probabilities(poly, center, **constants)
            out.append(self.dice[i].tvd(to_values(self.dice[i].design, p)) if np.isfinite(p).all() else 1.0)
        return np.array(out)

    def fit(self, rows, evals: int) -> dict[str, float]:
        """The constants of least mean TVD / noise over the dice `rows`, from the shipped ones."""
        rows = list(rows)
        fitted, _ = chain.fit_constants(lambda kw: float(np.mean(self.tvd(kw, rows) / self.noise[rows])),
                                        maxfev=evals, fatol=1e-5)  # fmt: skip
        return fitted


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--evals", type=int, default=600, help="most evaluations per fit")
    parser.add_argument("--data", type=Path, default=ROOT / ".." / "shared" / "realrolls")
    args = parser.parse_args(argv)
    if args.evals < 1:
        raise SystemExit(f"--evals {args.evals} must be >= 1")
    started = time.perf_counter()
    sets = {"the eight": load_real_dice(args.data), "the cuboids": square_cuboid_dice(), "further": printed_dice()}
    dice = [d for group in sets.values() for d in group]
    set_of = np.array([k for k, group in enumerate(sets.values()) for _ in group])
    members = {name: np.flatnonzero(set_of == k) for k, name in enumerate(sets)}
    s = Scorer(dice)
    everyone = np.arange(len(dice))

    def ratios(tvd: np.ndarray) -> list[str]:
        return [f"{tvd[rows].mean():.4f} ({tvd[rows].mean() / s.noise[rows].mean():.2f}x)" for rows in members.values()]

    print(f"chain constants fitted to real dice: mean TVD (and over the mean noise) per set, {args.evals} evaluations")
    print(f"{'constants':<34}" + "".join(f"{name:>20}" for name in sets))
    shipped = s.tvd(SHIPPED, everyone)
    print(f"{'shipped (fitted to pybullet)':<34}" + "".join(f"{r:>20}" for r in ratios(shipped)))
    fits = {"every die": everyone} | {name: rows for name, rows in members.items()}
    for label, rows in fits.items():
        x = s.fit(rows, args.evals)
        print(f"{'fitted on ' + label:<34}" + "".join(f"{r:>20}" for r in ratios(s.tvd(x, everyone))), flush=True)
        print("    " + ", ".join(f"{k} {v:.3g}" for k, v in x.items()))
    held = np.zeros(len(dice))
    for rows in members.values():
        held[rows] = s.tvd(s.fit(np.setdiff1d(everyone, rows), args.evals), rows)
    print(f"{'held out: each set from the others':<34}" + "".join(f"{r:>20}" for r in ratios(held)), flush=True)
    loo = np.zeros(len(dice))
    for i in everyone:
        loo[i] = s.tvd(s.fit(np.setdiff1d(members[list(sets)[set_of[i]]], [i]), args.evals), [i])[0]
    print(f"{'held out: each die from its set':<34}" + "".join(f"{r:>20}" for r in ratios(loo)))
    print(f"\n{'die':<22} {'rolls':>5} {'noise':>7} {'shipped':>8} {'loo':>8}")
    for i, d in enumerate(dice):
        print(f"{d.name:<22} {d.n:>5} {s.noise[i]:>7.4f} {shipped[i]:>8.4f} {loo[i]:>8.4f}")
    print(f"\n({time.perf_counter() - started:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
