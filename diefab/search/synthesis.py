"""From a target to a die: pick a family and face count, assign values, optimize, check.

:func:`synthesize` tries, in order:

1. a **fair die** whose faces are counted out to the target
   (:mod:`diefab.search.symmetric`): exact by symmetry under any physics, when the
   target's probabilities are multiples of ``1 / m`` and a steady fair die
   with ``m`` faces exists (binomial:4 on 16 faces, a loaded d6 on 20);
2. a **two-class die**: a bipyramid or trapezohedron whose two halves land
   with different probabilities, faces counted out so that one number, the
   top half's share of the landings, decides the whole distribution; that
   share is tuned under the model, or by drops with ``model="simulation"``
   (2d6 on 24 faces, 3dF on 18);
3. **shaped dice**: every other candidate (:func:`candidates`) is optimized
   under the solid-angle model, which is cheap, with values assigned by
   :func:`~diefab.dice.assignment.assign_values` on the starting shape; the best
   is optimized under `model` and -- with ``model="simulation"`` -- refined
   against pybullet: it drops the die, adds the simulated-minus-modelled face
   frequencies to the model as a correction, re-optimizes, and repeats while
   drops are left and the simulated distance to the target is above the
   goal, keeping the design whose simulated distance is smallest;
4. when no fair or two-class die is exact, the one whose face counts come
   nearest (:mod:`diefab.search.counting`) is weighed against the shaped
   die, and the nearer is kept.

Every stage's budget is in model evaluations or drops, so the result is a
function of the target, the options and the seed.  ``faces`` (resting
faces) and ``family`` narrow the candidates (``faces=11`` for 2d6 asks for a
shaped die).  The caller validates the result on a fresh seed
(:func:`diefab.search.verdict.closing_check`).

The candidates are listed in :mod:`diefab.search.candidates`, the counted
dice made in :mod:`diefab.search.counted`, the shaped die refined in
:mod:`diefab.search.refinement`; what the stages share is
:mod:`diefab.search.stage`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.assignment import assign_values, face_classes
from diefab.dice.design import Design
from diefab.dice.targets import Target
from diefab.geometry.polyhedron import resting_faces
from diefab.made.fill import Fill
from diefab.made.mass import mass_properties
from diefab.models.probabilities import MODELS
from diefab.search.candidates import Candidate, candidates, why_not
from diefab.search.counted import (
    COUNTED_FAMILIES,
    STEADY_TIPPING,
    counted_design,
    counted_family,
    fair_design,
    nearest_counted,
    nearest_faces_clause,
    two_class_design,
)
from diefab.search.optimize import INFEASIBLE
from diefab.search.refinement import MIN_THROW_DROPS, REFINE_DROPS, REFINE_GOAL, STEP_EVALUATIONS, not_on_faces, refine
from diefab.search.stage import RANK_MODEL, SearchRun, Synthesis
from diefab.stats.goodness import tvd

__all__ = [
    "COUNTED_FAMILIES",
    "MIN_THROW_DROPS",
    "RANK_MODEL",
    "REFINE_DROPS",
    "REFINE_GOAL",
    "STEADY_TIPPING",
    "STEP_EVALUATIONS",
    "Candidate",
    "Synthesis",
    "candidates",
    "synthesize",
]

#: Candidates whose objectives agree to this many decimals rank by how they are read, then by how many
#: transitional faces they have (the fast model is least sure of them), then by face count.
RANK_DECIMALS = 3
#: Drops the search may spend by default (the two-class tuning's, or the refinement's); the closing check
#: comes on top.
MAX_DROPS = 64_000
#: Model evaluations of each candidate's ranking under the solid-angle model (three starts and a restart).
RANK_EVALUATIONS = 2400
#: Model evaluations of the polish of the ranked winner under the fast model.
POLISH_EVALUATIONS = 3000
#: Drops the refinement of a shaped die leaves for tuning the nearest two-class die it is weighed against.
COUNTED_RESERVE = 10_000
#: Default tolerance: a validated TVD above it is a die that does not roll like its target.
TOLERANCE = 0.02


def _start(candidate: Candidate, target: Target, name: str, fill: Fill, size_mm: float) -> Design:
    """The candidate's starting design, values assigned from its starting shape.

    Faces the starting shape cannot rest on are transitional (a capped
    prism's caps), unless that leaves fewer faces than values.
    """
    poly = candidate.polyhedron()
    # the values are assigned from the solid's balance: a made fill's needs the die's size, set below
    center = mass_properties(poly).center
    resting = resting_faces(poly, center)
    if resting.sum() < len(target.values):  # too few: every face gets a value, the optimizer makes them rest
        resting[:] = True
    probs = MODELS["solid-angle"](poly, center)[resting]
    names = [n for n, r in zip(poly.names, resting) if r]
    classes = face_classes(poly, center)[resting]
    values = assign_values(probs, names, target, classes)
    transitional = [n for n, r in zip(poly.names, resting) if not r]
    return Design(name, candidate.family, candidate.params, values=values, target=target.spec, fill=fill,
                  size_mm=size_mm, transitional=transitional)  # fmt: skip


def synthesize(
    target: Target,
    *,
    faces: int | None = None,
    family: str | None = None,
    fill: Fill | None = None,
    model: str = "simulation",
    budget_seconds: float | None = None,
    max_drops: int = MAX_DROPS,
    tolerance: float = TOLERANCE,
    seed: int = 0,
    name: str = "die",
    size_mm: float = 30.0,
    min_margin: float = 0.05,
    workers: int | None = None,
    scheduler=None,
    settings=None,
    progress: Callable[[str], None] | None = None,
    ticker: Callable[[str, int, int], None] | None = None,
    throws: Sequence[Mapping[str, Any]] = (),
    store=None,
) -> Synthesis:
    """Design a die for `target`.

    A fair or two-class die that carries the target exactly is taken first.
    Otherwise every shaped candidate (:func:`candidates`) is optimized under
    the solid-angle model, which is cheap, for :data:`RANK_EVALUATIONS`
    evaluations; the best (by objective to :data:`RANK_DECIMALS` decimals,
    then by fewest faces read at a vertex or edge, then by fewest
    transitional faces, then by fewest faces) is then optimized under
    `model`, and weighed against the fair or two-class die whose face counts
    come nearest the target (:func:`diefab.search.counting.nearest_dice`): the one
    nearer the target is kept.

    The result is a function of the target, the options and `seed` alone:
    every stage has a budget in model evaluations or drops, and the drops
    give the same counts whatever `workers` or `scheduler`.  Only
    `budget_seconds`, a wall-time cap, can end a stage early; then
    :attr:`Synthesis.capped` is True.

    Parameters
    ----------
    model : {"fast", "solid-angle", "basins", "simulation"}
        The landing model optimized (``basins`` when registered in
        :data:`diefab.models.probabilities.MODELS`); ``simulation`` optimizes the fast
        model and then refines it against pybullet drops.
    budget_seconds : float, optional
        Wall-time cap of the whole search (default none).
    max_drops : int
        Drops the search may spend (a two-class die's tuning, or a shaped
        die's refinement).
    tolerance : float
        The refinement goes on, while drops are left, until the simulated
        TVD is below the smaller of this and :data:`REFINE_GOAL`.
    seed : int
        Seeds the optimizer's random starts and the refinement's drops.
    scheduler : str or distributed.Client, optional
        Run the drops on this Dask cluster.
    settings : PhysicsSettings, optional
        The physics the drops of ``simulation`` use (default: the design's).
    progress : callable(str), optional
        Told what each stage found, one line at a time.
    ticker : callable(stage, done, total), optional
        Told how far each stage is: candidates ranked, or drops spent out of
        `max_drops`.
    throws : sequence of mapping, optional
        Physics settings to refine a shaped die against all at once (a
        robust design; they replace `settings` there): each refinement step
        drops the die under every one, corrects the model by each one's
        simulated-minus-modelled frequencies and minimizes the worst of the
        corrected objectives; a step is judged by its worst simulated TVD.
    store : DropStore, optional
        Keeps every drop (:class:`~diefab.physics.checkpoint.DropStore`): the
        same search run again with the same store drops only what it had
        not, and finds the same die.

    Raises
    ------
    DesignError
        If no candidate reaches a stable, readable die.
    """
    fill = fill or Fill()
    say = progress or (lambda text: None)
    tick = ticker or (lambda stage, done, total: None)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise DesignError(f"seed={seed!r} must be an integer >= 0")
    if isinstance(max_drops, bool) or not isinstance(max_drops, (int, np.integer)) or max_drops < 1:
        raise DesignError(f"max_drops={max_drops!r} must be a positive integer")
    if not (np.isfinite(tolerance) and 0 < tolerance < 1):
        raise DesignError(f"tolerance={tolerance!r} must be in (0, 1)")
    if budget_seconds is not None and not budget_seconds > 0:
        raise DesignError(f"budget_seconds={budget_seconds!r} must be positive")
    deadline = time.monotonic() + (budget_seconds if budget_seconds is not None else np.inf)
    final_model = RANK_MODEL if model == "simulation" else model
    if final_model not in MODELS:
        raise DesignError(f"model {model!r} is not available (models: {', '.join([*MODELS, 'simulation'])})")
    run = SearchRun(seed, max_drops, deadline, workers, scheduler, settings, say, tick, tolerance=tolerance,
                    store=store)  # fmt: skip
    only = family if family in COUNTED_FAMILIES else None
    if family is None and faces is not None:  # a face count only a counted-only family has
        only = next((f for f, m in COUNTED_FAMILIES.items() if m == faces), None)
    if only is not None:
        return counted_family(target, faces, only, name, fill, size_mm, model, final_model, run)
    tick("listing the dice that fit", 0, 1)
    try:
        pool = candidates(target, faces, family)
    except DesignError as exc:
        raise DesignError(f"{exc}{nearest_faces_clause(target, faces)}") from None
    tick("listing the dice that fit", 1, 1)
    fair = fair_design(next((c for c in pool if c.exact), None), target, name, fill, size_mm, final_model, say)
    if fair is not None:
        return fair
    for cand in (c for c in pool if c.plan is not None):
        found = two_class_design(cand, target, name, fill, size_mm, model, run)
        if found is not None:
            return found
    tick("counting the nearest fair or two-class die", 0, 1)
    nearest = nearest_counted(target, faces, family)
    tick("counting the nearest fair or two-class die", 1, 1)
    if nearest is not None:
        say(f"nearest counted die: {nearest.faces}-face {nearest.kind}, TVD {float(nearest.tvd):.4f} "
            "by exact arithmetic")  # fmt: skip
    if nearest is not None and nearest.tvd <= tolerance / 2:  # near enough: no shaped die to weigh it against
        counted = counted_design(nearest, target, name, fill, size_mm, model, final_model, run)
        if counted is not None:
            return counted
    pool = [c for c in pool if not c.exact and c.plan is None]
    if not pool:
        counted = None if nearest is None else counted_design(nearest, target, name, fill, size_mm, model,
                                                                final_model, run)  # fmt: skip
        if counted is not None:
            return counted
        raise DesignError(f"no die found for target {target.spec!r}{why_not(target, faces, family)}")
    best, best_key, tried = None, None, []
    for i, cand in enumerate(pool):
        tick("ranking candidates", i, len(pool))
        try:
            start = _start(cand, target, name, fill, size_mm)
            result = run.optimize(start, model="solid-angle", min_margin=min_margin, starts=2, seed=seed, name=name,
                                  max_evaluations=RANK_EVALUATIONS // 4, budget=RANK_EVALUATIONS)  # fmt: skip
        except DesignError as exc:
            tried.append({"family": cand.family, "faces": cand.faces, "objective": None, "error": str(exc)})
            say(f"{cand.family} ({cand.faces} faces): {exc}")
            continue
        key = (round(result.objective, RANK_DECIMALS), not_on_faces(result.design),
               len(result.design.transitional_faces))  # fmt: skip
        tried.append({"family": cand.family, "faces": cand.faces, "objective": result.objective,
                      "read_off_faces": key[1]})  # fmt: skip
        say(f"{cand.family} ({cand.faces} faces): Eq. (2) {result.objective:.5f} under the solid-angle model")
        if best is None or key < best_key:
            best, best_key = result, key
    tick("ranking candidates", len(pool), len(pool))
    run.note_cap()
    if best is None or best.objective >= INFEASIBLE:
        counted = None if nearest is None else counted_design(nearest, target, name, fill, size_mm, model,
                                                                final_model, run)  # fmt: skip
        if counted is not None:
            return counted
        cut = "; the wall-time cap ended the search early" if run.capped else ""
        raise DesignError(f"no stable, readable die found for target {target.spec!r} (tried {len(tried)} dice)"
                          f"{cut}{nearest_faces_clause(target, faces)}")  # fmt: skip
    # the polish: under the final model, from the ranked winner
    tick(f"polishing under the {final_model} model", 0, 1)
    try:
        again = run.optimize(best.design, model=final_model, min_margin=min_margin, starts=0, seed=seed,
                             name=name, budget=POLISH_EVALUATIONS)  # fmt: skip
        say(f"{again.design.family}: Eq. (2) {again.objective:.5f} under the {final_model} model")
        best = again
    except DesignError as exc:
        say(f"the {final_model} model finds no stable die from the solid-angle optimum: {exc}")
    tick(f"polishing under the {final_model} model", 1, 1)
    run.note_cap()
    out = Synthesis(best.design, best.objective, best.values, final_model, tried)
    if model == "simulation":
        # drops kept back to tune the nearest counted die, if it has to be weighed against this one
        reserve = min(COUNTED_RESERVE, max_drops // 4) if nearest is not None and nearest.plan is not None else 0
        run.max_drops -= reserve
        refine(out, target, min_margin, run, min(REFINE_GOAL, tolerance), throws)
        run.max_drops += reserve
    out.nearest, out.capped, out.drops = nearest, run.capped, run.used
    shaped = (
        out.simulated_tvd
        if out.simulated_tvd is not None
        else float(tvd(out.predicted, target.aligned(out.design.support)))
    )
    if nearest is not None and float(nearest.tvd) < shaped:
        say(f"the nearest counted die (TVD {float(nearest.tvd):.4f}) is nearer the target than the shaped die "
            f"({shaped:.4f})")  # fmt: skip
        counted = counted_design(nearest, target, name, fill, size_mm, model, final_model, run)
        if counted is not None and (counted.simulated_tvd is None or counted.simulated_tvd < shaped):
            counted.tried = tried + counted.tried
            return counted
    return out
