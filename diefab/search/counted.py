"""Counted dice in a design search: fair and two-class dice whose faces are counted out to a target.

A fair die's values are placed on faces (:func:`fair_design`); a two-class
die's top class must take one share of the landings, found under a model or
tuned by drops (:func:`two_class_design`).  When no counted die is exact,
the nearest (:mod:`diefab.search.counting`) is made the same way
(:func:`counted_design`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import brentq

from diefab.core.errors import DesignError
from diefab.dice.design import Design
from diefab.dice.families import family as get_family
from diefab.dice.readings import unreadable
from diefab.dice.targets import Target
from diefab.made.fill import Fill
from diefab.models.probabilities import model_probabilities, value_probabilities
from diefab.search.candidates import Candidate
from diefab.search.counting import Counted, nearest_dice
from diefab.search.stage import RANK_MODEL, SearchRun, Synthesis
from diefab.search.symmetric import (
    MAX_FACES,
    TwoClass,
    face_counts,
    fair_shapes,
    fair_values,
    tipping_angle,
    tune_share,
    two_class_values,
)
from diefab.search.tuning import share_precision
from diefab.stats.goodness import pearson_divergence, tvd

__all__ = [
    "COUNTED_FAMILIES",
    "STEADY_TIPPING",
    "counted_design",
    "counted_family",
    "fair_design",
    "nearest_counted",
    "nearest_faces_clause",
    "two_class_design",
]

#: Families made only as counted dice (their faces counted out, one share tuned), with their face counts: asked
#: for by name, or by that face count, they skip the shaped candidates.
COUNTED_FAMILIES = {"icosahedral": 42}
#: Smallest tipping angle (degrees) a two-class die's tuning may reach.
STEADY_TIPPING = 9.0
#: Shapes of a two-class die's family scanned for steadiness and the model's share.
SCAN_POINTS = 81


def nearest_counted(target: Target, faces: int | None, family: str | None) -> Counted | None:
    """The fair or two-class die nearest `target` (with `faces` faces, of `family`, if given), or None."""
    found = nearest_dice(target, MAX_FACES if faces is None else max(MAX_FACES, faces), faces)
    if family is not None:
        found = [c for c in found if (c.plan.family if c.plan else _fair_family(c.faces)) == family]
    return found[0] if found else None


def nearest_faces_clause(target: Target, faces: int | None) -> str:
    """What the counted dice with the face count nearest `faces` reach, as a clause for a refusal."""
    if faces is None:
        return ""
    found = nearest_dice(target)
    if not found:
        return ""
    near = min(found, key=lambda c: (abs(c.faces - faces), c.tvd))
    best = found[0]
    if near.faces == faces:  # the count exists, in a family other than the one asked for
        text = f"; a counted die with {faces} faces reaches TVD {float(near.tvd):.4f} ({near.kind} die)"
    else:
        text = f"; the nearest face count, {near.faces}, reaches TVD {float(near.tvd):.4f} ({near.kind} die)"
    if best is not near:
        text += f", and {best.faces} faces reach {float(best.tvd):.4f} ({best.kind})"
    return text


def counted_family(
    target: Target,
    faces: int | None,
    family: str,
    name: str,
    fill: Fill,
    size_mm: float,
    model: str,
    final_model: str,
    run: SearchRun,
) -> Synthesis:
    """The die of `family`, a family made only as a counted die, nearest `target`."""
    nearest = nearest_counted(target, faces, family)
    if nearest is None:
        size = COUNTED_FAMILIES[family]
        raise DesignError(f"the {family} die has {size} faces: it cannot carry the {len(target.values)} values of "
                          f"target {target.spec!r}{'' if faces in (None, size) else f' on {faces} faces'}")  # fmt: skip
    run.say(f"{family}: {nearest.faces} faces counted out, TVD {float(nearest.tvd):.4f} by exact arithmetic")
    found = counted_design(nearest, target, name, fill, size_mm, model, final_model, run)
    if found is None:
        raise DesignError(f"the {family} die for target {target.spec!r} cannot be read")
    return found


def _fair_family(faces: int) -> str | None:
    shapes = fair_shapes(faces)
    return shapes[0][0] if shapes else None


def counted_design(
    nearest: Counted, target: Target, name: str, fill: Fill, size_mm: float, model: str, final_model: str, run
) -> Synthesis | None:
    """The fair or two-class die of `nearest`, which rolls `target` only approximately, or None if unreadable."""
    if nearest.plan is not None:
        cand = Candidate(nearest.plan.family, nearest.plan.params, nearest.faces, plan=nearest.plan)
        found = two_class_design(cand, target, name, fill, size_mm, model, run)
    else:
        family, params = fair_shapes(nearest.faces)[0]
        cand = Candidate(family, params, nearest.faces, exact=True)
        found = fair_design(cand, target, name, fill, size_mm, final_model, run.say, np.array(nearest.counts))
    if found is not None:
        found.nearest = nearest
        found.capped = found.capped or run.capped
        found.drops = run.used
    return found


def fair_design(
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


def two_class_design(
    cand: Candidate,
    target: Target,
    name: str,
    fill: Fill,
    size_mm: float,
    model: str,
    run: SearchRun,
) -> Synthesis | None:
    """The two-class die of `cand`, its share tuned under `model` (by drops for ``simulation``), or None."""
    say, seed = run.say, run.seed
    plan = cand.plan
    exact = bool(np.allclose(_per_value(plan, plan.share), target.probabilities, atol=1e-9))
    fam = get_family(cand.family)
    lo, hi = fam.bounds([plan.other])[0]
    poly0 = cand.polyhedron()
    values = two_class_values(poly0, target, plan)

    # the scan over the family's range weighs a print without its engraved labels (placing them is most of a
    # made body's cost, and they move the balance little); the shapes it settles on are weighed as made
    scan_fill = replace(fill, labels=False) if fill.kind == "print" and fill.labels else fill

    def build(value: float, made: Fill = fill) -> Design:
        return Design(name, cand.family, {**plan.params, plan.other: float(value)}, values=values,
                      target=target.spec, fill=made, size_mm=size_mm)  # fmt: skip

    rank = RANK_MODEL if model == "simulation" else model

    def model_share(value: float, made: Fill = fill) -> float:
        d = build(value, made)
        return float(model_probabilities(rank, d.polyhedron, d.mass_properties(), d.fill)[: plan.n].sum())

    def steady(d: Design, body=None) -> bool:
        return tipping_angle(d.polyhedron, (d.mass_properties() if body is None else body).center) >= STEADY_TIPPING

    start = next(v for k, v in plan.params.items() if k != "n")  # the fair shape's height or slope
    grid = np.linspace(lo, hi, SCAN_POINTS)
    # the shapes around the fair one that stay steady: tuning never leaves them
    scanned, bodies, ok = [build(v, scan_fill) for v in grid], [], []
    for i, d in enumerate(scanned):
        run.tick("scanning the shapes", i, len(grid))
        bodies.append(d.mass_properties())
        ok.append(steady(d, bodies[-1]))
    run.tick("scanning the shapes", len(grid), len(grid))
    i0 = int(np.argmin(np.abs(grid - start)))
    a, b = i0, i0
    while a > 0 and ok[a - 1]:
        a -= 1
    while b < len(grid) - 1 and ok[b + 1]:
        b += 1
    if scan_fill is not fill:  # the ends of the steady range, as made
        while b > a and not steady(build(grid[b])):
            b -= 1
        while a < b and not steady(build(grid[a])):
            a += 1
    grid = grid[a : b + 1]
    lo, hi = float(grid[0]), float(grid[-1])
    shares = np.array([
        float(model_probabilities(rank, d.polyhedron, body, d.fill)[: plan.n].sum())
        for d, body in zip(scanned[a : b + 1], bodies[a : b + 1])
    ])  # fmt: skip
    if scan_fill is not fill:  # the made die's share: the scan's, moved by its labels' nearly constant weight
        near = _crossing(grid, shares - plan.share, start)
        if near is not None:
            at = brentq(lambda v: np.interp(v, grid, shares) - plan.share, grid[near], grid[near + 1], xtol=1e-6)
            shares = shares + (model_share(at) - plan.share)
    i = _crossing(grid, shares - plan.share, start)
    if i is None:
        guess = float(grid[np.argmin(np.abs(shares - plan.share))])
    elif scan_fill is fill:
        guess = brentq(lambda v: model_share(v) - plan.share, grid[i], grid[i + 1], xtol=1e-6)
    else:  # bracket the made die's root on the grid, widening from the scan's
        a, b = i, i + 1
        fa, fb = model_share(grid[a]) - plan.share, model_share(grid[b]) - plan.share
        while fa * fb > 0 and (a > 0 or b < len(grid) - 1):
            if a > 0:
                a -= 1
                fa = model_share(grid[a]) - plan.share
            if fa * fb > 0 and b < len(grid) - 1:
                b += 1
                fb = model_share(grid[b]) - plan.share
        if fa * fb > 0:
            guess = float(grid[a] if abs(fa) < abs(fb) else grid[b])
        else:
            guess = brentq(lambda v: model_share(v) - plan.share, grid[a], grid[b], xtol=1e-6)
    why = unreadable(build(guess).polyhedron, values)
    if why is not None:
        say(f"{cand.family} ({cand.faces} faces, two classes): {why}")
        return None
    slope = (model_share(min(guess + 0.01, hi), scan_fill) - model_share(max(guess - 0.01, lo), scan_fill)) / (
        min(guess + 0.01, hi) - max(guess - 0.01, lo)
    )
    say(f"{cand.family} ({cand.faces} faces): the top {plan.n} faces must take {plan.x}/{plan.x + plan.y} of the "
        f"landings; {plan.other} = {guess:.4f} under the {rank} model")  # fmt: skip
    steps: list[dict] = []
    value = guess
    if model == "simulation":
        before, expected = run.used, [run.max_drops - run.used]

        def share_of(v: float, n: int, s: int) -> tuple[float, int]:
            sim = run.simulate(build(v), n, s, "tuning the share", total=before + expected[0])
            return float(sim.face_counts[: plan.n].sum() / max(sim.landed, 1)), int(sim.landed)

        def planned(drops: int) -> None:  # what the tuning now expects to spend: the progress bar's total
            expected[0] = drops

        precision = share_precision(plan.per_value, run.tolerance)
        # the model's share across the range, moved to agree with the made die at the guess
        shift = model_share(guess) - float(np.interp(guess, grid, shares)) if scan_fill is not fill else 0.0
        tuning = tune_share(share_of, guess, (lo, hi), plan.share, slope=slope, precision=precision,
                            modelled=lambda v: float(np.interp(v, grid, shares)) + shift,
                            max_drops=run.max_drops - run.used, deadline=run.deadline, seed=seed, say=say,
                            planned=planned)  # fmt: skip
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
        share = tuning.share
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


def _crossing(grid: np.ndarray, off: np.ndarray, start: float) -> int | None:
    """Index i of the sign change of `off` between grid[i] and grid[i + 1] nearest `start`, or None."""
    crossings = [i for i in range(len(grid) - 1) if off[i] * off[i + 1] <= 0]
    return min(crossings, key=lambda j: abs(grid[j] - start)) if crossings else None


def _per_value(plan: TwoClass, share: float) -> np.ndarray:
    """(k,) value probabilities of a two-class die whose top half takes `share` of the landings."""
    return plan.per_value(share)
