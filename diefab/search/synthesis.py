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

Examples
--------
>>> from diefab.dice.targets import parse_target
>>> [(c.family, c.faces, c.exact) for c in candidates(parse_target("binomial:4"))][:2]
[('bipyramid', 16, True), ('prism', 5, False)]
>>> [(c.family, c.faces, c.plan is not None) for c in candidates(parse_target("2d6"))][:2]
[('bipyramid', 24, True), ('bipyramid', 24, True)]
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from math import ceil
from typing import Any

import numpy as np
from scipy.optimize import brentq

from diefab.core.errors import DesignError
from diefab.dice.assignment import assign_values, face_classes
from diefab.dice.design import Design
from diefab.dice.families import family as get_family
from diefab.dice.readings import unreadable
from diefab.dice.targets import Target
from diefab.geometry.polyhedron import resting_faces
from diefab.made.fill import Fill
from diefab.made.mass import mass_properties
from diefab.models.probabilities import MODELS, model_probabilities, value_probabilities
from diefab.search.counting import Counted, nearest_dice
from diefab.search.optimize import INFEASIBLE, optimize_design
from diefab.search.symmetric import (
    MAX_FACES,
    MIN_TIPPING,
    TwoClass,
    face_counts,
    fair_faces,
    fair_shapes,
    fair_values,
    tipping_angle,
    tune_share,
    two_class_plans,
    two_class_values,
)
from diefab.stats.goodness import pearson_divergence, tvd

__all__ = ["Candidate", "Synthesis", "candidates", "synthesize"]

#: Model used to rank candidates and to start the simulation refinement.
RANK_MODEL = "fast"
#: Candidates whose objectives agree to this many decimals rank by how they are read, then by how many
#: transitional faces they have (the fast model is least sure of them), then by face count.
RANK_DECIMALS = 3
#: Drops per simulation of a refinement step (half at the first).
REFINE_DROPS = 16_000
#: Refinement stops once the simulated TVD is below this (or below the tolerance, if smaller).
REFINE_GOAL = 0.008
#: Drops the search may spend by default (the two-class tuning's, or the refinement's); the closing check
#: comes on top.
MAX_DROPS = 64_000
#: Model evaluations of each candidate's ranking under the solid-angle model (three starts and a restart).
RANK_EVALUATIONS = 2400
#: Model evaluations of the polish of the ranked winner under the fast model.
POLISH_EVALUATIONS = 3000
#: Model evaluations of each refinement step's re-optimization under the corrected fast model.
STEP_EVALUATIONS = 1000
#: Drops the refinement of a shaped die leaves for tuning the nearest two-class die it is weighed against.
COUNTED_RESERVE = 10_000
#: Default tolerance: a validated TVD above it is a die that does not roll like its target.
TOLERANCE = 0.02
#: Fewest drops under each of several throws in a refinement step.
MIN_THROW_DROPS = 4_000
#: Smallest tipping angle (degrees) a two-class die's tuning may reach.
STEADY_TIPPING = 9.0


@dataclass(frozen=True)
class Candidate:
    """A family, its structural parameters and a starting shape, with the number of faces that carry values."""

    family: str
    params: dict[str, float]
    faces: int
    #: A fair die whose face counts give the target exactly (:mod:`diefab.search.symmetric`): nothing to optimize.
    exact: bool = False
    #: A two-class die whose face counts give the target once one share is tuned (:mod:`diefab.search.symmetric`).
    plan: TwoClass | None = None

    def polyhedron(self):
        return get_family(self.family).polyhedron(self.params)


def _symmetric(target: Target) -> bool:
    """True if the target's probabilities read the same backwards over equally spaced values."""
    v, q = target.values, target.probabilities
    return bool(np.allclose(q, q[::-1], atol=1e-12) and np.allclose(np.diff(v), np.diff(v)[0]))


def _levels(target: Target) -> int:
    return len(np.unique(np.round(target.probabilities, 12)))


def candidates(target: Target, faces: int | None = None, family: str | None = None) -> list[Candidate]:
    """Families and face counts that can carry `target`'s values, simplest first.

    Parameters
    ----------
    faces : int, optional
        Only dice with this many resting faces.
    family : str, optional
        Only this family.

    Raises
    ------
    DesignError
        If nothing fits.
    """
    k = len(target.values)
    if k < 2:
        raise DesignError(f"target {target.spec!r} has one value: any die rolls it; give at least two")
    if np.any(target.probabilities <= 0):
        v = int(target.values[np.argmax(target.probabilities <= 0)])
        raise DesignError(f"target {target.spec!r} gives value {v} probability 0: no face can carry it, leave it out")
    asym = {} if _symmetric(target) else {"sx": 0.1, "sz": 0.05}
    found: list[Candidate] = _fair(target, faces) + _two_class(target, faces)
    first = max(3, ceil((k - 1) / 2))
    for n in range(first, min(first + 2, 13)):
        found.append(Candidate("ngem", {"n": n, "a": 1.3, "b": 0.6, "c": 0.5, "d": 1.5, **asym}, 2 * n + 1))
    if k <= 6:
        found.append(Candidate("cuboid", {"x": 1.0, "z": 0.9, "t": 0.1}, 6))
    if 3 <= k <= 12:  # the lateral faces carry the values, the pointed caps are transitional
        found.append(Candidate("prism", {"n": k, "l": 1.5, "k": 1.0}, k))
    n = max(3, k - 2)
    if n <= 12:
        found.append(Candidate("prism", {"n": n, "l": 1.0}, n + 2))
    if _levels(target) <= 2:
        for n in range(max(3, ceil(k / 2)), 13):
            if (2 * n) % k == 0:
                found.append(Candidate("bipyramid", {"n": n, "h": 1.2, "g": 1.0}, 2 * n))
                found.append(Candidate("trapezohedron", {"n": n, "t": 0.7, "u": 0.8}, 2 * n))
                break
    for n in sorted({max(6, k), max(6, k) + 2}):
        if n <= 30:
            found.append(Candidate("freeform", {"n": n}, n))
    if family is not None:
        get_family(family)  # an unknown name raises with the list of families
        found = [c for c in found if c.family == family]
        if not found and faces is not None:
            found = [_forced(family, faces, asym)]
        elif not found:  # a family none of the above suggests: its member with one face per value, if any
            with contextlib.suppress(DesignError):
                found = [_forced(family, k, asym)]
    if faces is not None:
        found = [c for c in found if c.faces == faces] or ([_forced(family, faces, asym)] if family else [])
        if faces < k:
            raise DesignError(f"--faces {faces} is fewer than the target's {k} values")
    if not found:
        what = f"family {family}" if family else "family"
        raise DesignError(
            f"no {what}{'' if faces is None else f' with {faces} faces'} fits the {k} values of target"
            f" {target.spec!r}{_why_not(target, faces, family)}"
        )
    return sorted(found, key=lambda c: (not c.exact, c.plan is None, c.faces))


def _why_not(target: Target, faces: int | None, family: str | None) -> str:
    """Why no die with `faces` faces fits `target`, and the face counts that do, as a clause for the error."""
    if faces is None:
        return ""
    why = ""
    fewest = fair_faces(target, max(MAX_FACES, faces))
    if fewest is not None and faces % fewest == 0 and faces % 2 == 0 and not fair_shapes(faces):
        why = f": the fair die with {faces} faces tips by less than {MIN_TIPPING:g}° and would roll on"
    try:
        fits = sorted({c.faces for c in candidates(target, None, family)})
    except DesignError:
        return why
    return f"{why}; dice that fit have {', '.join(map(str, fits))} faces"


def _fair(target: Target, faces: int | None) -> list[Candidate]:
    """The fair die with the fewest faces (or with `faces` faces) whose face counts give `target` exactly."""
    fewest = fair_faces(target, max(MAX_FACES, faces or 0))
    if fewest is None or (faces is not None and faces % fewest):
        return []
    m = faces or fewest
    return [Candidate(family, params, m, exact=True) for family, params in fair_shapes(m)]


def _two_class(target: Target, faces: int | None) -> list[Candidate]:
    """Two-class dice that roll `target` once their top half's share is tuned (with `faces` faces, if given)."""
    plans = two_class_plans(target, max(MAX_FACES, faces or 0), enough=2 if faces is None else None)
    return [Candidate(p.family, p.params, p.faces, plan=p) for p in plans if faces in (None, p.faces)][:2]


def _forced(family: str, faces: int, asym: dict[str, float]) -> Candidate:
    """The member of `family` with `faces` faces, when the family has one."""
    if family == "ngem" and faces % 2 == 1 and 7 <= faces <= 25:
        return Candidate("ngem", {"n": (faces - 1) // 2, "a": 1.3, "b": 0.6, "c": 0.5, "d": 1.5, **asym}, faces)
    if family == "prism" and 3 <= faces <= 12:
        return Candidate("prism", {"n": faces, "l": 1.5, "k": 1.0}, faces)
    if family in ("bipyramid", "trapezohedron") and faces % 2 == 0 and 6 <= faces <= 24:
        params = {"h": 1.2, "g": 1.0} if family == "bipyramid" else {"t": 0.7, "u": 0.8}
        return Candidate(family, {"n": faces // 2, **params}, faces)
    if family == "gem" and faces == 9:
        return Candidate("gem", {"a": 1.3, "b": 0.6, "c": 0.5, "d": 1.5}, 9)
    if family == "cuboid" and faces == 6:
        return Candidate("cuboid", {"x": 1.0, "z": 0.9, "t": 0.1}, 6)
    if family == "freeform" and 6 <= faces <= 30:
        return Candidate("freeform", {"n": faces}, faces)
    raise DesignError(f"family {family!r} has no die with {faces} faces")


@dataclass
class Synthesis:
    """What :func:`synthesize` found."""

    design: Design
    objective: float
    #: (k,) value probabilities under the model the design was optimized for.
    predicted: np.ndarray
    model: str
    #: Every candidate tried: family, faces, objective.
    tried: list[dict] = field(default_factory=list)
    #: Refinement steps: simulated TVD at each.
    steps: list[dict] = field(default_factory=list)
    #: How the die carries the target: "fair", "two-class" or "shaped".
    method: str = "shaped"
    #: True if the wall-time cap ended a stage early: the same seed and options may then give another die.
    capped: bool = False
    #: The fair or two-class die whose face counts come nearest the target (:mod:`diefab.search.counting`), if any.
    nearest: Counted | None = None
    #: Drops the search spent.
    drops: int = 0
    #: The simulated TVD of the die kept (the refinement's or the two-class tuning's), if it was simulated.
    simulated_tvd: float | None = None


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
    run = _Run(seed, max_drops, deadline, workers, scheduler, settings, say, tick)
    try:
        pool = candidates(target, faces, family)
    except DesignError as exc:
        raise DesignError(f"{exc}{_nearest_faces(target, faces)}") from None
    fair = _fair_design(next((c for c in pool if c.exact), None), target, name, fill, size_mm, final_model, say)
    if fair is not None:
        return fair
    for cand in (c for c in pool if c.plan is not None):
        found = _two_class_design(cand, target, name, fill, size_mm, model, run)
        if found is not None:
            return found
    nearest = _nearest(target, faces, family)
    if nearest is not None:
        say(f"nearest counted die: {nearest.faces}-face {nearest.kind}, TVD {float(nearest.tvd):.4f} "
            "by exact arithmetic")  # fmt: skip
    if nearest is not None and nearest.tvd <= tolerance / 2:  # near enough: no shaped die to weigh it against
        counted = _counted_design(nearest, target, name, fill, size_mm, model, final_model, run)
        if counted is not None:
            return counted
    pool = [c for c in pool if not c.exact and c.plan is None]
    if not pool:
        counted = None if nearest is None else _counted_design(nearest, target, name, fill, size_mm, model,
                                                                final_model, run)  # fmt: skip
        if counted is not None:
            return counted
        raise DesignError(f"no die found for target {target.spec!r}{_why_not(target, faces, family)}")
    best, best_key, tried = None, None, []
    for i, cand in enumerate(pool):
        tick("ranking candidates", i, len(pool))
        try:
            start = _start(cand, target, name, fill, size_mm)
            result = optimize_design(start, model="solid-angle", min_margin=min_margin, starts=2, seed=seed,
                                     name=name, deadline=deadline, max_evaluations=RANK_EVALUATIONS // 4,
                                     budget=RANK_EVALUATIONS)  # fmt: skip
        except DesignError as exc:
            tried.append({"family": cand.family, "faces": cand.faces, "objective": None, "error": str(exc)})
            say(f"{cand.family} ({cand.faces} faces): {exc}")
            continue
        key = (round(result.objective, RANK_DECIMALS), _not_on_faces(result.design),
               len(result.design.transitional_faces))  # fmt: skip
        tried.append({"family": cand.family, "faces": cand.faces, "objective": result.objective,
                      "read_off_faces": key[1]})  # fmt: skip
        say(f"{cand.family} ({cand.faces} faces): Eq. (2) {result.objective:.5f} under the solid-angle model")
        if best is None or key < best_key:
            best, best_key = result, key
    tick("ranking candidates", len(pool), len(pool))
    run.note_cap()
    if best is None or best.objective >= INFEASIBLE:
        counted = None if nearest is None else _counted_design(nearest, target, name, fill, size_mm, model,
                                                                final_model, run)  # fmt: skip
        if counted is not None:
            return counted
        cut = "; the wall-time cap ended the search early" if run.capped else ""
        raise DesignError(f"no stable, readable die found for target {target.spec!r} (tried {len(tried)} dice)"
                          f"{cut}{_nearest_faces(target, faces)}")  # fmt: skip
    # the polish: under the final model, from the ranked winner
    try:
        again = optimize_design(best.design, model=final_model, min_margin=min_margin, starts=0, seed=seed,
                                name=name, deadline=deadline, budget=POLISH_EVALUATIONS)  # fmt: skip
        say(f"{again.design.family}: Eq. (2) {again.objective:.5f} under the {final_model} model")
        best = again
    except DesignError as exc:
        say(f"the {final_model} model finds no stable die from the solid-angle optimum: {exc}")
    run.note_cap()
    out = Synthesis(best.design, best.objective, best.values, final_model, tried)
    if model == "simulation":
        # drops kept back to tune the nearest counted die, if it has to be weighed against this one
        reserve = min(COUNTED_RESERVE, max_drops // 4) if nearest is not None and nearest.plan is not None else 0
        run.max_drops -= reserve
        _refine(out, target, min_margin, run, min(REFINE_GOAL, tolerance), throws)
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
        counted = _counted_design(nearest, target, name, fill, size_mm, model, final_model, run)
        if counted is not None and (counted.simulated_tvd is None or counted.simulated_tvd < shaped):
            counted.tried = tried + counted.tried
            return counted
    return out


@dataclass
class _Run:
    """What every stage of one search shares: its seed, drop budget, wall-time cap, workers and reporters."""

    seed: int
    max_drops: int
    deadline: float
    workers: int | None
    scheduler: Any
    settings: Any
    say: Callable[[str], None]
    tick: Callable[[str, int, int], None]
    used: int = 0
    capped: bool = False

    def note_cap(self) -> None:
        """Record that the wall-time cap has passed (the stage that just ended may have been cut)."""
        self.capped = self.capped or time.monotonic() > self.deadline

    def simulate(self, design: Design, n: int, seed: int, stage: str, settings=None):
        """Drop `design` `n` times, counting the drops against the budget and ticking `stage`."""
        from diefab.physics.simulate import simulate

        before = self.used
        result = simulate(design, n, seed=seed, workers=self.workers, scheduler=self.scheduler,
                          settings=settings if settings is not None else self.settings,
                          progress=lambda done, total: self.tick(stage, min(before + done, self.max_drops),
                                                                 self.max_drops))  # fmt: skip
        self.used += n
        self.tick(stage, min(self.used, self.max_drops), self.max_drops)
        return result


def _nearest(target: Target, faces: int | None, family: str | None) -> Counted | None:
    """The fair or two-class die nearest `target` (with `faces` faces, of `family`, if given), or None."""
    found = nearest_dice(target, MAX_FACES if faces is None else max(MAX_FACES, faces), faces)
    if family is not None:
        found = [c for c in found if (c.plan.family if c.plan else _fair_family(c.faces)) == family]
    return found[0] if found else None


def _nearest_faces(target: Target, faces: int | None) -> str:
    """What the counted dice with the face count nearest `faces` reach, as a clause for a refusal."""
    if faces is None:
        return ""
    found = nearest_dice(target)
    if not found:
        return ""
    near = min(found, key=lambda c: (abs(c.faces - faces), c.tvd))
    best = found[0]
    text = f"; the nearest face count, {near.faces}, reaches TVD {float(near.tvd):.4f} ({near.kind} die)"
    if best is not near:
        text += f", and {best.faces} faces reach {float(best.tvd):.4f} ({best.kind})"
    return text


def _fair_family(faces: int) -> str | None:
    shapes = fair_shapes(faces)
    return shapes[0][0] if shapes else None


def _counted_design(
    nearest: Counted, target: Target, name: str, fill: Fill, size_mm: float, model: str, final_model: str, run
) -> Synthesis | None:
    """The fair or two-class die of `nearest`, which rolls `target` only approximately, or None if unreadable."""
    if nearest.plan is not None:
        cand = Candidate(nearest.plan.family, nearest.plan.params, nearest.faces, plan=nearest.plan)
        found = _two_class_design(cand, target, name, fill, size_mm, model, run)
    else:
        family, params = fair_shapes(nearest.faces)[0]
        cand = Candidate(family, params, nearest.faces, exact=True)
        found = _fair_design(cand, target, name, fill, size_mm, final_model, run.say, np.array(nearest.counts))
    if found is not None:
        found.nearest = nearest
        found.capped = found.capped or run.capped
        found.drops = run.used
    return found


def _fair_design(
    cand: Candidate | None,
    target: Target,
    name: str,
    fill: Fill,
    size_mm: float,
    model: str,
    say,
    counts: np.ndarray | None = None,
) -> Synthesis | None:
    """The fair die of `cand` with its faces counted out to `target` (or by `counts`), or None if unreadable."""
    if cand is None:
        return None
    poly = cand.polyhedron()
    exact = counts is None
    values = fair_values(poly, target, face_counts(target, cand.faces) if exact else counts)
    why = unreadable(poly, values)
    if why is not None:
        say(f"{cand.family} ({cand.faces} faces, fair): {why}")
        return None
    d = Design(name, cand.family, cand.params, values=values, target=target.spec, fill=fill, size_mm=size_mm)
    predicted = value_probabilities(d, model)
    objective = pearson_divergence(predicted, target.aligned(d.support))
    near = 0.0 if exact else float(tvd(counts / cand.faces, target.probabilities))
    how = "exactly" if exact else f"as near as {cand.faces} faces come (TVD {near:.4f})"
    say(f"{cand.family} ({cand.faces} faces): fair by symmetry, its faces counted out to the target {how}")
    tried = [{"family": cand.family, "faces": cand.faces, "objective": objective, "fair": True}]
    return Synthesis(d, objective, predicted, model, tried, method="fair" if exact else "fair-nearest")


def _two_class_design(
    cand: Candidate,
    target: Target,
    name: str,
    fill: Fill,
    size_mm: float,
    model: str,
    run: _Run,
) -> Synthesis | None:
    """The two-class die of `cand`, its share tuned under `model` (by drops for ``simulation``), or None."""
    say, seed = run.say, run.seed
    plan = cand.plan
    exact = bool(np.allclose(_per_value(plan, plan.share), target.probabilities, atol=1e-9))
    fam = get_family(cand.family)
    lo, hi = fam.bounds([plan.other])[0]
    poly0 = cand.polyhedron()
    values = two_class_values(poly0, target, plan)

    def build(value: float) -> Design:
        return Design(name, cand.family, {**plan.params, plan.other: float(value)}, values=values,
                      target=target.spec, fill=fill, size_mm=size_mm)  # fmt: skip

    rank = RANK_MODEL if model == "simulation" else model

    def model_share(value: float) -> float:
        d = build(value)
        return float(model_probabilities(rank, d.polyhedron, d.mass_properties(), d.fill)[: plan.n].sum())

    start = next(v for k, v in plan.params.items() if k != "n")  # the fair shape's height or slope
    grid = np.linspace(lo, hi, 81)
    # the shapes around the fair one that stay steady: tuning never leaves them
    steady = np.array([tipping_angle(d.polyhedron, d.mass_properties().center) for d in map(build, grid)])
    steady = steady >= STEADY_TIPPING
    i0 = int(np.argmin(np.abs(grid - start)))
    a, b = i0, i0
    while a > 0 and steady[a - 1]:
        a -= 1
    while b < len(grid) - 1 and steady[b + 1]:
        b += 1
    grid = grid[a : b + 1]
    lo, hi = float(grid[0]), float(grid[-1])
    shares = np.array([model_share(v) for v in grid]) - plan.share
    crossings = [i for i in range(len(grid) - 1) if shares[i] * shares[i + 1] <= 0]
    if crossings:
        i = min(crossings, key=lambda j: abs(grid[j] - start))
        guess = brentq(lambda v: model_share(v) - plan.share, grid[i], grid[i + 1], xtol=1e-6)
    else:
        guess = float(grid[np.argmin(np.abs(shares))])
    why = unreadable(build(guess).polyhedron, values)
    if why is not None:
        say(f"{cand.family} ({cand.faces} faces, two classes): {why}")
        return None
    slope = (model_share(min(guess + 0.01, hi)) - model_share(max(guess - 0.01, lo))) / (
        min(guess + 0.01, hi) - max(guess - 0.01, lo)
    )
    say(f"{cand.family} ({cand.faces} faces): the top half must take {plan.x}/{plan.x + plan.y} of the landings; "
        f"{plan.other} = {guess:.4f} under the {rank} model")  # fmt: skip
    steps: list[dict] = []
    value = guess
    if model == "simulation":

        def share_of(v: float, n: int, s: int) -> tuple[float, int]:
            sim = run.simulate(build(v), n, s, "tuning the share")
            return float(sim.face_counts[: plan.n].sum() / max(sim.landed, 1)), int(sim.landed)

        tuning = tune_share(share_of, guess, (lo, hi), plan.share, slope=slope, max_drops=run.max_drops - run.used,
                            deadline=run.deadline, seed=seed, say=say)  # fmt: skip
        run.capped = run.capped or tuning.capped
        value = tuning.value
        goal = target.aligned(target.values)
        steps = [
            {"step": i, plan.other: v, "share": p, "landed": n, "simulated_tvd": tvd(_per_value(plan, p), goal)}
            for i, (v, p, n) in enumerate(tuning.evaluations)
        ]
    d = build(value)
    if unreadable(d.polyhedron, values) is not None:
        say(f"{cand.family} ({cand.faces} faces): tuned to {plan.other} = {value:.4f}, which cannot be read")
        return None
    if model == "simulation":  # the share the drops say the settled shape has: the goal, or near it
        share = float(np.interp(value, *zip(*sorted((v, p) for v, p, _ in tuning.evaluations))))
        predicted = _per_value(plan, share)[np.searchsorted(target.values, d.support)]
    else:
        predicted = value_probabilities(d, rank)
    objective = pearson_divergence(predicted, target.aligned(d.support))
    tried = [{"family": cand.family, "faces": cand.faces, "objective": objective, "two_class": True}]
    found = Synthesis(d, objective, predicted, "simulation" if model == "simulation" else rank, tried, steps,
                      "two-class" if exact else "two-class-nearest", capped=run.capped, drops=run.used)  # fmt: skip
    if model == "simulation":
        found.simulated_tvd = float(tvd(predicted, target.aligned(d.support)))
    return found


def _per_value(plan: TwoClass, share: float) -> np.ndarray:
    """(k,) value probabilities of a two-class die whose top half takes `share` of the landings."""
    return (np.array(plan.alpha) * share + np.array(plan.beta) * (1 - share)) / plan.n


def _not_on_faces(design: Design) -> int:
    """How many resting faces are read at a vertex or edge rather than on a face (the gem's apex excepted)."""
    from diefab.dice.readings import readings

    found = readings(design.polyhedron)
    apex = design.family in ("gem", "ngem")
    k = [design.polyhedron.face_index(n) for n in design.values]
    return sum(
        1 for i in k if found[i] is None or (found[i].kind != "face" and not (apex and found[i].kind == "vertex"))
    )


def _refine(
    out: Synthesis,
    target: Target,
    min_margin: float,
    run: _Run,
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
        drops = REFINE_DROPS if step else REFINE_DROPS // 2
        return max(drops // len(runs), MIN_THROW_DROPS) if len(runs) > 1 else drops

    step = 0
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
        correction = np.array([sim.face_probabilities for sim in sims]) - modelled  # one row per throw
        try:
            result = optimize_design(design, model=RANK_MODEL, min_margin=min_margin, starts=0, seed=run.seed,
                                     name=design.name, correction=correction, deadline=run.deadline,
                                     budget=STEP_EVALUATIONS)  # fmt: skip
        except DesignError:
            break
        run.note_cap()
        design = replace(result.design, description=design.description)
        objective, predicted = result.objective, result.values
        step += 1
    out.model = "simulation"
