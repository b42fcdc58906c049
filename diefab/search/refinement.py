"""The refinement of a shaped die against simulated drops: correct the model, re-optimize, repeat.

Each step drops the die, adds the simulated-minus-modelled face frequencies
to the fast model as a correction, and re-optimizes under it; the die whose
simulated distance to the target is smallest is kept.

Far from the target a few drops measure the error, near it many are needed:
a step's drops keep the sampling noise near a seventh of the smallest
simulated TVD so far (:func:`refinement_drops`).  The iteration is a fixed
point that can overshoot: once a step comes out worse than the best so far,
every later measurement of the correction is taken in at half the weight of
the one before, the rest being the corrections measured already.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.design import Design
from diefab.dice.targets import Target
from diefab.models.probabilities import model_probabilities
from diefab.search.stage import RANK_MODEL, SearchRun, Synthesis
from diefab.stats.goodness import tvd

__all__ = [
    "MIN_REFINE_DROPS",
    "MIN_THROW_DROPS",
    "REFINE_DROPS",
    "REFINE_GOAL",
    "REFINE_NOISE",
    "RELAX",
    "STEP_EVALUATIONS",
    "not_on_faces",
    "refine",
    "refinement_drops",
]

#: Most drops per simulation of a refinement step; the first step drops half of it.
REFINE_DROPS = 16_000
#: Fewest drops per simulation of a refinement step after the first.
MIN_REFINE_DROPS = 2_000
#: A step after the first drops the die REFINE_NOISE (K - 1) / d² times, with d the smallest
#: simulated TVD so far and K the target's values: the sampling noise of the TVD stays near d / 7.
REFINE_NOISE = 8.0
#: Factor on the weight of each new measurement of the correction after a step that overshot.
RELAX = 0.5
#: Refinement stops once the simulated TVD is below this (or below the tolerance, if smaller).
REFINE_GOAL = 0.008
#: Model evaluations of each refinement step's re-optimization under the corrected fast model.
STEP_EVALUATIONS = 1000
#: Fewest drops under each of several throws in a refinement step.
MIN_THROW_DROPS = 4_000


def refinement_drops(best_tvd: float, values: int) -> int:
    """Drops for a refinement step after the first, when the smallest simulated TVD so far is `best_tvd`.

    A perfect die of `values` equally likely values shows a TVD of about
    sqrt((values - 1) / (2 pi n)) after n drops
    (:func:`diefab.stats.goodness.expected_tvd`), so REFINE_NOISE (values - 1) /
    best_tvd² drops measure the die's error to about a seventh of `best_tvd`;
    the count is kept within [MIN_REFINE_DROPS, REFINE_DROPS].
    """
    low = min(MIN_REFINE_DROPS, REFINE_DROPS)
    if not best_tvd > 0:
        return REFINE_DROPS
    return int(np.clip(REFINE_NOISE * (values - 1) / best_tvd**2, low, REFINE_DROPS))


def not_on_faces(design: Design) -> int:
    """How many resting faces are read at a vertex or edge rather than on a face (the gem's apex excepted)."""
    from diefab.dice.readings import readings

    found = readings(design.polyhedron)
    apex = design.family in ("gem", "ngem")
    k = [design.polyhedron.face_index(n) for n in design.values]
    return sum(
        1 for i in k if found[i] is None or (found[i].kind != "face" and not (apex and found[i].kind == "vertex"))
    )


def refine(
    out: Synthesis,
    target: Target,
    min_margin: float,
    run: SearchRun,
    goal_tvd: float,
    throws: Sequence[Mapping[str, Any]] = (),
) -> None:
    """Correct the model by simulation until the simulated TVD is below `goal_tvd` or the drops run out.

    Updates `out`.  The drops use the run's settings; with `throws`, every
    step drops the die under each instead (a share of the drops each, at
    least :data:`MIN_THROW_DROPS`) and its TVD is the worst.
    """
    from diefab.physics.simulate import PhysicsSettings

    goal = target.aligned(out.design.support)
    design, objective, predicted = out.design, out.objective, out.predicted
    best_tvd = np.inf
    runs = [PhysicsSettings.from_mapping(t) for t in throws] or [None]

    def step_drops(step: int) -> int:
        drops = refinement_drops(best_tvd, len(goal)) if step else REFINE_DROPS // 2
        return max(drops // len(runs), MIN_THROW_DROPS) if len(runs) > 1 else drops

    step, correction, weight = 0, None, 1.0
    while True:
        drops = step_drops(step)
        if not step:  # the first step judges the model's die: within the budget, however small
            drops = min(drops, (run.max_drops - run.used) // len(runs))
        if drops < 1 or (step and run.used + drops * len(runs) > run.max_drops):
            break
        if step and time.monotonic() > run.deadline:
            run.capped = True
            break
        sims = [run.simulate(design, drops, run.seed + step, "refinement drops", settings=s) for s in runs]
        each = [float(tvd(sim.value_probabilities(design), goal)) for sim in sims]
        distance = max(each)
        kept = distance < best_tvd
        out.steps.append({"step": step, "drops": drops, "params": dict(design.params), "simulated_tvd": distance,
                          "kept": kept, **({"throw_tvds": each} if len(sims) > 1 else {})})  # fmt: skip
        worst = " (worst of " + ", ".join(f"{v:.4f}" for v in each) + ")" if len(sims) > 1 else ""
        run.say(f"refinement {step}: simulated TVD {distance:.4f}{worst} at {drops} drops")
        if kept:
            best_tvd = distance
            out.design, out.objective, out.predicted = design, objective, predicted
            out.simulated_tvd = distance
        if distance < goal_tvd or run.used + step_drops(step + 1) * len(runs) > run.max_drops:
            break
        body = design.mass_properties()
        modelled = model_probabilities(RANK_MODEL, design.polyhedron, body, design.fill)
        measured = np.array([sim.face_probabilities for sim in sims]) - modelled  # one row per throw
        if not kept:  # the last move overshot
            weight *= RELAX
        correction = measured if correction is None else correction + weight * (measured - correction)
        try:
            result = run.optimize(design, model=RANK_MODEL, min_margin=min_margin, starts=0, seed=run.seed,
                                  name=design.name, correction=correction, budget=STEP_EVALUATIONS)  # fmt: skip
        except DesignError:
            break
        run.note_cap()
        design = replace(result.design, description=design.description)
        objective, predicted = result.objective, result.values
        step += 1
    out.model = "simulation"
