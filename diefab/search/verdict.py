"""The closing check of a designed die, and the verdict: does it roll like its target, and if not, why not.

:func:`closing_check` drops the die on a seed its search never used and
measures its total variation distance (TVD) to the target;
:func:`judge` compares it with a tolerance and, when the die falls short,
says what limits it: the smallest probability a steady face can carry, the
nearest any fair or two-class die comes (:mod:`diefab.search.counting`), or the
drops the search had.  :func:`fast_agreement` says whether the fast model's
prediction for this die can be trusted, by its distance to the simulation's.

Examples
--------
>>> from diefab.dice.targets import parse_target
>>> smallest_probability(parse_target("3d6"))
(Fraction(1, 216), 3)
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from diefab.dice.design import Design
from diefab.dice.targets import Target
from diefab.search.counting import Counted, exact_probabilities, nearest_dice

__all__ = [
    "FAST_TRUST",
    "Verdict",
    "closing_check",
    "fast_agreement",
    "folded_resting_count",
    "judge",
    "smallest_probability",
]

#: The fast model is not trusted for a die when its prediction is further than this (TVD) from the simulation's.
FAST_TRUST = 0.05
#: Seed offset of the closing check: never used by a search (its drops use seed .. seed + steps).
CHECK_SEED_OFFSET = 1_000_003


def closing_check(
    design: Design,
    sims: int,
    seed: int,
    *,
    throws: Sequence[Mapping[str, Any]] = (),
    workers: int | None = None,
    scheduler=None,
    progress: Callable[[int, int], None] | None = None,
    store=None,
) -> dict:
    """Drop `design` `sims` times on seed ``seed + CHECK_SEED_OFFSET`` and measure its fit to the target.

    With `throws`, under each physics setting in turn; the worst (largest
    TVD) is returned, with every one under ``"throws"``.  With `store` (a
    :class:`~diefab.physics.checkpoint.DropStore`), every drop is kept there,
    and drops it already holds are not run again.

    Returns
    -------
    dict
        ``n``, ``landed``, ``seed``, ``tvd``, ``p_value``, ``expected_tvd``
        (a die that rolls the target exactly would show about this TVD at
        these drops), ``probabilities`` ((k,) observed, over
        ``design.support``) and ``folded_faces`` (the resting faces the
        engine holds folded, :func:`folded_resting_count`).
    """
    from diefab.physics.simulate import PhysicsSettings, simulate
    from diefab.stats.goodness import goodness_of_fit

    check_seed = seed + CHECK_SEED_OFFSET
    aligned = design.target_distribution.aligned(design.support)
    checks = []
    runs = list(throws) or [design.physics]
    for i, throw in enumerate(runs):
        tell = None if progress is None else (lambda done, total, i=i: progress(i * sims + done, len(runs) * sims))
        settings = PhysicsSettings.from_mapping(throw)
        run = {"workers": workers, "scheduler": scheduler, "progress": tell}
        if store is None:
            result = simulate(design, sims, seed=check_seed, settings=settings, **run)
        else:
            result = store.run(design, settings, check_seed, sims, **run)
        fit = goodness_of_fit(result.value_counts(design), aligned, seed=check_seed)
        checks.append({"n": result.n, "landed": result.landed, "seed": check_seed, "tvd": float(fit.tvd),
                       "p_value": float(fit.p_value), "expected_tvd": float(fit.expected_tvd),
                       "probabilities": np.asarray(fit.observed, dtype=float)})  # fmt: skip
    worst = max(checks, key=lambda c: c["tvd"])
    worst = {**worst, "folded_faces": folded_resting_count(design, PhysicsSettings.from_mapping(runs[0]))}
    return {**worst, "throws": checks} if throws else worst


def folded_resting_count(design: Design, settings) -> int:
    """How many faces `design` rests on the engine holds folded under `settings` (0 with ``flat_faces``)."""
    from diefab.physics import shapes
    from diefab.physics.world import die_body, import_pybullet

    if settings.flat_faces:
        return 0
    body = die_body(design.polyhedron, design.mass_properties())
    return int(shapes.folded_resting_faces(import_pybullet(), body).sum())


def fast_agreement(design: Design, simulated: np.ndarray) -> dict:
    """The fast model's prediction for `design` against `simulated` (k,) value probabilities.

    Returns
    -------
    dict
        ``fast`` ((k,) the fast model's value probabilities), ``tvd_between``
        (TVD between the two predictions) and ``trusted`` (False when it is
        above :data:`FAST_TRUST`).
    """
    from diefab.models.probabilities import value_probabilities
    from diefab.stats.goodness import tvd

    fast = value_probabilities(design, "fast")
    between = float(tvd(fast, simulated))
    return {"fast": fast, "tvd_between": between, "trusted": between <= FAST_TRUST}


def smallest_probability(target: Target) -> tuple[Fraction, int]:
    """The target's smallest probability, as a fraction, and the value that has it."""
    q = exact_probabilities(target)
    j = int(np.argmin(target.probabilities))
    return q[j], int(target.values[j])


def _smallest_face(counted: Counted) -> float:
    """The smallest probability one face of a counted die lands with."""
    if counted.plan is None:
        return 1 / counted.faces
    plan = counted.plan
    return min(plan.share / plan.n, (1 - plan.share) / plan.bottom)


def _fraction(p: Fraction) -> str:
    return f"{p.numerator}/{p.denominator}" if p.denominator <= 10_000 else f"{float(p):.4g}"


@dataclass(frozen=True)
class Verdict:
    """Whether a die's closing check is within the tolerance, and if not, what limits it."""

    met: bool
    tvd: float
    tolerance: float
    #: One or more sentences: what the die reached and what limits it (empty when met).
    why: str


def judge(
    target: Target,
    check: dict,
    tolerance: float,
    *,
    method: str,
    nearest: Counted | None = None,
    simulated_tvd: float | None = None,
    drops: int = 0,
    max_drops: int | None = None,
) -> Verdict:
    """Compare a closing check's TVD with `tolerance` and, above it, say what limits the die.

    Parameters
    ----------
    check : dict
        From :func:`closing_check`.
    method : str
        How the die carries the target ("fair", "fair-nearest", "two-class",
        "two-class-nearest", "shaped").
    nearest : Counted, optional
        The fair or two-class die nearest the target (computed when not given).
    simulated_tvd : float, optional
        The search's own simulated TVD of the die.
    drops, max_drops : int
        Drops the search spent, and its budget.
    """
    distance = float(check["tvd"])
    if distance <= tolerance:
        return Verdict(True, distance, tolerance, "")
    reasons = []
    if nearest is None:
        found = nearest_dice(target)
        nearest = found[0] if found else None
    p, value = smallest_probability(target)
    if nearest is None:
        reasons.append(f"no fair or two-class die that stays steady has faces for its {len(target.values)} values")
    elif nearest.tvd > tolerance:
        face = _smallest_face(nearest)
        reasons.append(
            f"no steady fair or two-class die comes nearer than TVD {float(nearest.tvd):.4f} (the {nearest.faces}-face "
            f"{nearest.kind} die)"
            + (f": the smallest probability {_fraction(p)} (value {value}) needs a face that lands {float(p):.2%} "
               f"of the time, and the smallest face of that die lands {face:.2%}" if face > 1.5 * float(p) else "")
        )  # fmt: skip
    elif nearest.tvd > 0.5 * tolerance:
        reasons.append(
            f"the nearest steady fair or two-class die (the {nearest.faces}-face {nearest.kind} die) is itself TVD "
            f"{float(nearest.tvd):.4f} from the target, which leaves {tolerance - float(nearest.tvd):.4f} of the "
            "tolerance for tuning its share and for the closing check's noise"
        )  # fmt: skip
    if method == "shaped" and simulated_tvd is not None:
        reasons.append(f"the shaped die's refinement reached simulated TVD {simulated_tvd:.4f}")
    if max_drops is not None and drops + 16_000 > max_drops and (simulated_tvd is None or simulated_tvd > tolerance):
        reasons.append(f"the search spent {drops} of its {max_drops} drops (a larger --max-drops may come nearer)")
    noise = float(check.get("expected_tvd", 0.0))
    if noise > 0.5 * tolerance:
        reasons.append(f"at {check['n']} drops a die that rolled the target exactly would still show TVD about "
                       f"{noise:.4f} (more --validate-sims measures it closer)")  # fmt: skip
    folded = int(check.get("folded_faces", 0))
    if folded:
        reasons.append(f"the engine holds {folded} of the faces the die rests on folded (it rounds a hull's corners "
                       "to 1/10216 of its size), which makes faces alike land unevenly on a die of shallow faces: "
                       "design --flat-faces simulates them flat")  # fmt: skip
    if not reasons or (nearest is not None and distance > float(nearest.tvd) + tolerance):
        reasons.append("the closing check's drops disagree with the search's")
    why = f"validated TVD {distance:.4f} is above the tolerance {tolerance:g}: " + "; ".join(reasons)
    return Verdict(False, distance, tolerance, why)
