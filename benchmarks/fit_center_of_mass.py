"""How far a real die's centre of mass must move for the quasi-static model to fit its own rolls.

    python benchmarks/fit_center_of_mass.py [--dice bunny_d6] [--evals 150]

A diagnostic, in-sample by construction: for each die with real rolls (the
shared data and the published printed dice), the centre of mass is moved to
minimise the deviance of the die's real counts under the ``basins`` model
(the quasi-static limit, no throw), by Nelder-Mead from the printed body's
own centre; a centre that would let the die rest on a face with no value
(one no real roll showed) is refused.  It prints the shift as a fraction of the hull's longest side,
the deviance and the TVD before and
after.  A die that needs a shift of a few per cent is one a print's fill or
supports could explain; one that needs far more, or still misses, is not a
matter of its mass alone.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from diefab.core.errors import DesignError, GeometryError  # noqa: E402
from diefab.models.probabilities import value_probabilities  # noqa: E402
from diefab.search.fidelity import load_real_dice, noise_tvd  # noqa: E402
from diefab.search.likelihood import deviance  # noqa: E402


def fit(die, evals: int) -> dict:
    """The centre of mass (model units) of least deviance under ``basins``, and the figures before and after."""
    design = die.design
    start = np.asarray(design.mass_properties().center, dtype=float)
    side = float(np.ptp(design.polyhedron.vertices, axis=0).max())

    def probabilities(shift: np.ndarray) -> np.ndarray:
        moved = dataclasses.replace(design, center_of_mass=tuple((start + shift * side).tolist()))
        return value_probabilities(moved, "basins")

    def cost(shift: np.ndarray) -> float:
        try:
            return deviance(die.counts.astype(float), probabilities(shift))
        except (DesignError, GeometryError):  # the centre left the die, or rests it on a face with no value
            return np.inf

    simplex = np.vstack([np.zeros(3), 0.02 * np.eye(3)])
    res = minimize(cost, np.zeros(3), method="Nelder-Mead",
                   options={"initial_simplex": simplex, "maxfev": evals, "xatol": 1e-3, "fatol": 0.1})  # fmt: skip
    counts = die.counts.astype(float)
    before, after = probabilities(np.zeros(3)), probabilities(res.x)  # the start and the fit, once each
    return {"shift": res.x, "deviance": (deviance(counts, before), deviance(counts, after)),
            "tvd": (die.tvd(before), die.tvd(after)), "evals": int(res.nfev)}  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dice", default="", help="comma-separated die names (default: every printed die)")
    parser.add_argument("--evals", type=int, default=150, help="most evaluations of the basins model per die")
    args = parser.parse_args(argv)
    # printed dice only: the cuboids and the coins are homogeneous solids
    dice = [d for d in load_real_dice(ROOT / ".." / "shared" / "realrolls", paper=False, published=True)
            if not d.name.startswith(("cuboid-", "coin-"))]  # fmt: skip
    if args.dice:
        dice = [d for d in dice if d.name in args.dice.split(",")]
    print(f"{'die':<22} {'rolls':>5} {'noise':>6} {'TVD':>6} {'fitted':>7} {'deviance':>9} {'fitted':>7} "
          f"{'shift / side':>12}")  # fmt: skip
    for die in dice:
        started = time.perf_counter()
        r = fit(die, args.evals)
        print(f"{die.name:<22} {die.n:>5} {noise_tvd(die, 4000):>6.3f} {r['tvd'][0]:>6.3f} {r['tvd'][1]:>7.3f} "
              f"{r['deviance'][0]:>9.1f} {r['deviance'][1]:>7.1f} {np.linalg.norm(r['shift']):>12.3f}"
              f"   ({r['evals']} evaluations, {time.perf_counter() - started:.0f} s)", flush=True)  # fmt: skip
    print("\nin-sample: the centre of mass is fitted to the die's own rolls under the basins model; shift / side: "
          "how far it moved, as a fraction of the hull's longest side")  # fmt: skip


if __name__ == "__main__":
    main()
