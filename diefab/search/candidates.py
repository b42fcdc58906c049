"""The dice that can carry a target: fair, two-class and shaped candidates, simplest first.

:func:`candidates` lists the families and face counts a design search tries
for a target (:func:`~diefab.search.synthesis.synthesize`): a fair die whose faces are
counted out exactly, two-class dice whose one share is tuned, then shaped
dice of several families; ``faces`` and ``family`` narrow the list.

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
from dataclasses import dataclass
from math import ceil

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.families import family as get_family
from diefab.dice.targets import Target
from diefab.search.symmetric import MAX_FACES, MIN_TIPPING, TwoClass, fair_faces, fair_shapes, two_class_plans

__all__ = ["Candidate", "candidates", "why_not"]


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
            f" {target.spec!r}{why_not(target, faces, family)}"
        )
    return sorted(found, key=lambda c: (not c.exact, c.plan is None, c.faces))


def why_not(target: Target, faces: int | None, family: str | None) -> str:
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
