"""Design a 4dF gem for a material: the fast model, corrected by simulations of the die in that fill.

Run:  python benchmarks/design_for_fill.py --fill paper|print [--rounds 3] [--drops 20000] [--out templates]
      [--physics PROFILE] [--model fast|basins] [--name NAME]

Starts from the model's optimum for the fill (``diefab optimize
fudge-gem-sim --fill FILL --model fast``) and repeats: drop the current die
in pybullet with its fill (`--drops`, a new physics seed every round; the
counts are appended to ``OUT/NAME-rounds.jsonl``, or ``--rounds-file``),
take the simulated face frequencies minus the model's probabilities
(averaged over mirror-image faces) as a fixed correction, and re-fit the
parameters to 4dF under the fast model plus that correction, from the
current die.  Where the fast model's error changes slowly with the shape,
this converges in a few rounds (defect correction); each round prints the
simulated TVD of the die it dropped.  With ``--pool die`` the correction
pools every simulation of that very die kept in the rounds file; with
``--pool fill`` every simulation in this fill kept there, each against the
fast model at its own parameters (weighted by drops): the correction then
carries the sampling noise of all the drops, not of one round's, which is
what a die meant to validate within 0.015 needs (``--pool-radius`` keeps
only the dice whose parameters lie that close to the current one's).
With ``--refit near`` the re-fit is a damped Gauss-Newton step instead of a
new optimum: the least-squares fit of the corrected fast model's value
probabilities to 4dF nearest the current die, at most ``--max-step`` away
in the unit cube of the parameters, so the die stays where the correction
was measured (the fast model's error changes with the shape).  With
``--refit simulated`` the slope comes from the simulation itself: the die
and the die moved by ``--fd-step`` in each free parameter (unit cube) are
dropped with the same seed (common random numbers, so the difference is
not swamped by sampling noise), and the damped least-squares step on the
mirror-averaged value probabilities uses that Jacobian: no fast model at
all, for where its slope is wrong.  Every round records the
body's centre of mass, and a round whose body, recomputed now, has moved
(another tab layout, another print model) is left out of the pool.  The last design is written as
``fudge-gem-FILL.toml`` (the fill's default settings: 160 g/m² card with
glue tabs, or 0.4 mm nozzle, 2 perimeters, 0.2 mm layers, 4 top and bottom
layers, 15 % infill).  Validate it on a fresh seed with ``diefab validate``.

``--physics PROFILE`` drops every die under that physics profile (a shipped
profile's name or a TOML file) and writes its ``[physics]`` table into the
design, so that a plain ``diefab validate`` drops it so too; a round is
pooled only with rounds of the same physics.  ``--model`` is the landing
model the simulations correct: ``fast`` (default; learned on the default
physics) or ``basins`` (the quasi-static model, which a die with a large
quasi-static capture follows more closely).  ``--name`` names the design
(default ``fudge-gem-FILL``).
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from diefab.core.errors import PhysicsError
from diefab.core.files import atomic_write
from diefab.dice.design import design_to_toml, load_design
from diefab.dice.readings import unreadable
from diefab.made.mass import Fill
from diefab.models.probabilities import FILL_MODELS, MODELS, face_probabilities, to_values
from diefab.physics.profiles import load_profile, read_profile
from diefab.physics.simulate import simulate
from diefab.search.optimize import optimize_design
from diefab.stats.goodness import tvd

MIRRORS = ((0, 2), (1, 3), (5, 7), (6, 8))  # the gem's mirror-image faces


def symmetric(p: np.ndarray) -> np.ndarray:
    out = np.array(p, dtype=float)
    for i, j in MIRRORS:
        out[[i, j]] = out[[i, j]].mean()
    return out


def pooled_frequencies(design, records: list[dict], model: str = "fast") -> tuple[np.ndarray, np.ndarray, int]:
    """Simulated face frequencies and `model`'s probabilities, pooled over `records` by drops; records used.

    Each record is compared with `model` at its own parameters; one
    without a stored centre of mass, or whose centre no longer matches its
    body as computed now, is skipped (it was dropped with another body).
    """
    q_sum, p_sum, n_sum, used = 0.0, 0.0, 0.0, 0
    for r in records:
        die = design.with_params(**r["params"])
        body = die.mass_properties()
        if "center" not in r or not np.allclose(r["center"], body.center, rtol=0, atol=1e-9):
            continue
        counts = np.asarray(r["face_counts"], dtype=float)
        p = face_probabilities(die, model)
        q_sum, p_sum, n_sum, used = q_sum + counts, p_sum + counts.sum() * p, n_sum + counts.sum(), used + 1
    return q_sum / n_sum, p_sum / n_sum, used


def refit_near(design, correction: np.ndarray, read_by, min_margin: float, max_step: float, model: str = "fast"):
    """The design nearest `design` whose corrected `model` value probabilities fit 4dF (damped Gauss-Newton).

    Least squares over the value probabilities plus a small pull towards the
    current parameters (it picks the nearest of the dice that fit equally
    well), then the step is cut to `max_step` in the unit cube and halved
    until the die stands on every face by `min_margin` and reads as made.
    """
    from scipy.optimize import least_squares

    from diefab.dice.families import family
    from diefab.search.optimize import Problem

    names = family(design.family).free_names(design.params)
    problem = Problem(design, tuple(names), model, "tvd", min_margin, correction, tuple(read_by))
    goal = design.target_distribution.aligned(design.support)
    x0 = problem.unit(design.params)

    def residual(x):
        values = problem.evaluate(problem.params(x))[1]
        miss = np.where(np.isfinite(values), values - goal, 1.0)
        return np.concatenate([miss, 0.05 * (x - x0)])

    x1 = least_squares(residual, x0, bounds=(0.0, 1.0), diff_step=1e-4).x
    return _damped(design, problem, x0, x1 - x0, max_step)


def _damped(design, problem, x0: np.ndarray, step: np.ndarray, max_step: float):
    """`design` moved by `step` (unit cube), cut to `max_step` and halved until it stands and reads as made."""
    from diefab.search.optimize import INFEASIBLE

    step = step * min(1.0, max_step / max(float(np.linalg.norm(step)), 1e-12))
    for _ in range(8):
        if problem.evaluate(problem.params(x0 + step))[0] < INFEASIBLE:
            return design.with_params(**problem.params(x0 + step))
        step = step / 2
    return design


def refit_simulated(design, counts: np.ndarray, dropped, read_by, min_margin: float, max_step: float, h: float):
    """A damped Gauss-Newton step along the simulated slope (common random numbers).

    `counts` are the die's face counts with some seed, `dropped(die)` drops
    another die with that same seed.  Each free parameter is moved by `h`
    in the unit cube (backwards at the upper bound); the Jacobian of the
    mirror-averaged value probabilities is the difference quotient.
    """
    from diefab.dice.families import family
    from diefab.search.optimize import Problem

    names = family(design.family).free_names(design.params)
    problem = Problem(design, tuple(names), "fast", "tvd", min_margin, None, tuple(read_by))
    goal = design.target_distribution.aligned(design.support)
    x0 = problem.unit(design.params)

    def values(die, c):
        v = to_values(die, c / c.sum())
        return (v + v[::-1]) / 2  # 4dF's mirror values: the symmetric gem cannot tell them apart

    v0 = values(design, counts)
    jac = np.empty((len(v0), len(names)))
    for i in range(len(names)):
        dx = np.zeros(len(names))
        dx[i] = h if x0[i] + h <= 1 else -h
        die = design.with_params(**problem.params(x0 + dx))
        jac[:, i] = (values(die, dropped(die)) - v0) / dx[i]
    lam = 0.05**2  # the same small pull towards the current die as refit_near's
    step = -np.linalg.solve(jac.T @ jac + lam * np.eye(len(names)), jac.T @ (v0 - goal))
    return _damped(design, problem, x0, step, max_step)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fill", choices=("paper", "print"), required=True)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--drops", type=int, default=20_000)
    ap.add_argument("--seed", type=int, default=100, help="physics seed of the first round (then +1 each)")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--min-margin", type=float, default=0.05)
    ap.add_argument("--out", type=Path, default=Path("templates"))
    ap.add_argument("--rounds-file", type=Path, default=None,
                    help="where the simulations are kept (default OUT/fudge-gem-FILL-rounds.jsonl)")  # fmt: skip
    ap.add_argument("--pool", choices=("die", "fill"), default="die",
                    help="correction from the simulations of this very die, or of every die in this fill")  # fmt: skip
    ap.add_argument("--start", type=Path, default=None, help="continue from this design file (skip the fast optimum)")
    ap.add_argument("--pool-radius", type=float, default=float("inf"),
                    help="--pool fill: only dice with every parameter within this of the current die's")  # fmt: skip
    ap.add_argument("--refit", choices=("optimum", "near", "simulated"), default="optimum",
                    help="re-fit to the corrected model's optimum, a damped step towards it, or a damped step "
                         "along the simulated slope")  # fmt: skip
    ap.add_argument("--objective", choices=("eq2", "tvd"), default="eq2",
                    help="--refit optimum: objective minimized (tvd: the measure validate reports)")  # fmt: skip
    ap.add_argument("--fd-step", type=float, default=0.05, help="--refit simulated: finite-difference step, unit cube")
    ap.add_argument("--max-step", type=float, default=0.05, help="--refit near: largest step, unit cube")
    ap.add_argument("--physics", default=None,
                    help="physics profile the die is dropped under and keeps as its [physics] table")  # fmt: skip
    ap.add_argument("--model", choices=("fast", "basins"), default="fast", help="landing model the drops correct")
    ap.add_argument("--name", default=None, help="design name (default fudge-gem-FILL)")
    ap.add_argument("--read-by", default="face,vertex",
                    help="reading conventions a value may use (net and stl mark faces and the gem's apex)")  # fmt: skip
    args = ap.parse_args()
    for name in ("rounds", "drops", "max_step", "fd_step", "pool_radius"):
        if not getattr(args, name) > 0:
            ap.error(f"--{name.replace('_', '-')} must be positive, got {getattr(args, name)}")
    if args.fd_step > 0.5:
        ap.error(f"--fd-step must be at most 0.5 (unit cube), got {args.fd_step}")

    read_by = tuple(args.read_by.split(","))
    name = args.name or f"fudge-gem-{args.fill}"
    physics = {}
    if args.physics is not None:
        try:
            load_profile(args.physics)  # a bad setting stops here, before the first drop
        except PhysicsError as exc:
            ap.error(str(exc))
        physics = read_profile(args.physics)[0]["physics"]
    base = load_design("fudge-gem-sim")
    design = replace(base, name=name, fill=Fill(args.fill), physics=physics)
    goal = design.target_distribution.aligned(design.support)
    t0 = time.perf_counter()
    if args.start is not None:
        design = replace(design, params=load_design(args.start).params)
    else:
        design = optimize_design(design, model=args.model, min_margin=args.min_margin, starts=6, seed=0,
                                 read_by=read_by).design  # fmt: skip
    print(f"start for {design.fill.describe()}: "
          + " ".join(f"{k}={v:.4f}" for k, v in design.params.items()), flush=True)  # fmt: skip
    correction = np.zeros(len(design.polyhedron.faces))
    history = []
    rounds_file = args.rounds_file or args.out / f"{name}-rounds.jsonl"  # one simulation a line

    def drop(die, seed: int) -> np.ndarray:
        """Face counts of `die` dropped `--drops` times with `seed`, kept in the rounds file."""
        result = simulate(die, args.drops, seed=seed, workers=args.workers)
        with rounds_file.open("a", encoding="utf-8") as f:
            f.write(json.dumps({"fill": die.fill.to_mapping(), "physics": physics, "params": dict(die.params),
                                "drops": args.drops,
                                "seed": seed, "face_counts": result.face_counts.tolist(),
                                "cocked": result.cocked, "unsettled": result.unsettled,
                                "center": die.mass_properties().center.tolist()}) + "\n")  # fmt: skip
        return np.asarray(result.face_counts, dtype=float)

    for k in range(args.rounds):
        counts = drop(design, args.seed + k)
        kept = [r for r in map(json.loads, rounds_file.read_text(encoding="utf-8").splitlines())
                if r["fill"] == design.fill.to_mapping() and r.get("physics", {}) == physics
                and (args.pool == "fill" or r["params"] == dict(design.params))
                and max(abs(r["params"][n] - v) for n, v in design.params.items()) <= args.pool_radius]  # fmt: skip
        q, p, used = pooled_frequencies(design, kept, args.model)
        sim_tvd = tvd(to_values(design, counts / counts.sum()), goal)  # this round's drops alone
        if unreadable(design.polyhedron, design.values, tuple(design.labels), read_by) is None:
            history.append((dict(design.params), sim_tvd))  # only a die that reads as made can be the answer
        alone = face_probabilities(design, args.model)
        print(f"round {k + 1}: simulated TVD {sim_tvd:.4f} ({args.drops} drops, seed {args.seed + k}); "
              f"{args.model} model alone {tvd(to_values(design, alone), goal):.4f}; correction from "
              f"{used} simulations; {time.perf_counter() - t0:.0f} s", flush=True)  # fmt: skip
        correction = symmetric(q - p)
        if k == args.rounds - 1:
            break

        def corrected(poly, center, *, fill=None, inertia=None, r=correction):
            extra = {"fill": fill, "inertia": inertia} if args.model in FILL_MODELS else {}
            out = np.clip(MODELS[args.model](poly, center, **extra) + r, 0, None)
            return out / out.sum()

        if args.refit == "simulated":
            design = refit_simulated(design, counts, lambda die, s=args.seed + k: drop(die, s), read_by,
                                     args.min_margin, args.max_step, args.fd_step)  # fmt: skip
            print("  step: " + " ".join(f"{k}={v:.4f}" for k, v in design.params.items()), flush=True)
            continue
        if args.refit == "near":
            design = refit_near(design, correction, read_by, args.min_margin, args.max_step, args.model)
            print("  step: " + " ".join(f"{k}={v:.4f}" for k, v in design.params.items()), flush=True)
            continue
        MODELS["corrected"] = corrected
        FILL_MODELS.add("corrected")
        try:
            fit = optimize_design(design, model="corrected", objective=args.objective, min_margin=args.min_margin,
                                  starts=0, seed=0, read_by=read_by)  # fmt: skip
        finally:
            del MODELS["corrected"]
            FILL_MODELS.discard("corrected")
        design = replace(fit.design, name=name)
        print("  refit: " + " ".join(f"{k}={v:.4f}" for k, v in design.params.items()), flush=True)
    if not history:
        raise SystemExit(f"no round's die reads by {args.read_by}: nothing written")
    best_params, best_tvd = min(history, key=lambda h: h[1])
    under = f" under the physics profile {args.physics}" if args.physics else ""
    final = replace(
        design.with_params(**best_params),
        description=f"4dF gem designed for {design.fill.describe()}{under} "
        f"({args.model} model corrected by simulation)",
    )
    options = "".join(f" --{k} {v}" for k, v in (("physics", args.physics), ("name", args.name),
                                                 ("start", args.start)) if v is not None)  # fmt: skip
    comment = (
        f"Written by: python benchmarks/design_for_fill.py --fill {args.fill} --rounds {args.rounds} "
        f"--drops {args.drops} --seed {args.seed} --pool {args.pool} --pool-radius {args.pool_radius:g} "
        f"--refit {args.refit} --objective {args.objective} --max-step {args.max_step:g} --fd-step {args.fd_step:g} "
        f"--min-margin {args.min_margin:g} --model {args.model}"
        f"{options}\nsimulated TVD {best_tvd:.4f} in its round"
    )
    path = atomic_write(args.out / f"{final.name}.toml", design_to_toml(final, comment=comment))
    print(f"wrote {path} (the round with the lowest simulated TVD, {best_tvd:.4f})")


if __name__ == "__main__":
    main()
