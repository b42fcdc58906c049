"""CMA-ES or Nelder--Mead for design by simulation?

Both methods start from the same point (the fast model's optimum for
``fudge-gem``, e free), use the same common random numbers, the same drop
schedule and the same wall-time budget; then each one's best design is
validated with fresh drops (another physics seed) and compared by TVD and
Eq. (2) to 4dF.  One method runs at a time (the machine has 2 cores).

Usage::

    python benchmarks/bench_simopt.py                     # 4 minutes per method, 1000 drops/evaluation
    python benchmarks/bench_simopt.py --budget 1 --validate 5000
"""

from __future__ import annotations

import argparse

import numpy as np

from diefab.dice.design import design_to_toml, load_design
from diefab.physics.simulate import PhysicsSettings, simulate
from diefab.search.simopt import RunSpec, best_design, optimize_by_simulation, start_point
from diefab.stats.goodness import pearson_divergence, tvd


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--design", default="fudge-gem")
    ap.add_argument("--budget", type=float, default=4.0, help="minutes per method")
    ap.add_argument("--sims-per-eval", type=int, default=1000)
    ap.add_argument("--validate", type=int, default=10_000, help="drops of the validation (physics seed 1)")
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args(argv)

    d = load_design(args.design)
    names = ("a", "b", "c", "d", "e")
    x0 = start_point(d, names, model="fast")
    goal = d.target_distribution.aligned(d.support)
    rows = []
    for method in ("cma", "nm"):
        spec = RunSpec(
            design_toml=design_to_toml(d), names=names, x0=tuple(x0.tolist()), seed=0,
            sims_per_eval=args.sims_per_eval, max_sims=16 * args.sims_per_eval, method=method,
            physics=PhysicsSettings.from_mapping(d.physics).as_dict(),
        )  # fmt: skip
        result = optimize_by_simulation(spec, workers=args.workers, budget_seconds=args.budget * 60)
        best = best_design(spec, result.best, f"{d.name}-{method}")
        check = simulate(best, args.validate, seed=1, workers=args.workers)
        q = check.value_probabilities(best)
        rows.append((method, result, tvd(q, goal), pearson_divergence(q, goal)))
        print(f"{method}: {result.evaluations} evaluations, {result.drops:,} drops; best {spec.objective} "
              f"{result.best['objective']:.5f} at {result.best['drops']} drops; params "
              + " ".join(f"{k}={v:.4f}" for k, v in best.params.items()), flush=True)  # fmt: skip
    print(f"\nsame start, same {args.budget:g}-minute budget, {args.sims_per_eval} drops/evaluation at first; "
          f"validation: {args.validate} fresh drops (seed 1)")  # fmt: skip
    print(f"{'method':<8}{'evals':>7}{'drops':>11}{'run eq2':>10}{'valid. TVD':>12}{'valid. eq2':>12}")
    for method, result, t, e in rows:
        print(
            f"{method:<8}{result.evaluations:>7}{result.drops:>11,}{result.best['objective']:>10.5f}{t:>12.4f}{e:>12.5f}"
        )
    noise = np.sqrt(8 / (2 * np.pi * args.validate))
    print(f"(TVD of a perfect die at {args.validate} drops: ~{noise:.4f})")


if __name__ == "__main__":
    main()
