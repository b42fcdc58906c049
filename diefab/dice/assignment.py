"""Faces to values: which resting face carries which value of a target.

Several faces may carry one value.  The assignment matches face-probability
classes to target probabilities: faces are ranked by their landing
probability on the starting shape (faces the die's symmetry makes equal form
one class and stay together), values by their target probability, and each
face goes to the value that still lacks the most probability; a local search
of moves and swaps then lowers the paper's Eq. (2) between the summed face
probabilities and the target.  The optimizer moves the shape afterwards, so
the assignment only has to put each face where the shape can reach.

Examples
--------
>>> from diefab.dice.targets import parse_target
>>> assign_values([0.3, 0.3, 0.2, 0.1, 0.1], ["f1", "f2", "f3", "f4", "f5"], parse_target("1:6,2:4"))
{'f1': 1, 'f2': 2, 'f3': 1, 'f4': 1, 'f5': 2}
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.targets import Target
from diefab.geometry.polyhedron import Polyhedron, face_margins, solid_angles

__all__ = ["assign_values", "face_classes"]

#: Decimals to which face measures are rounded before faces are compared for symmetry.
CLASS_DECIMALS = 7


def face_classes(poly: Polyhedron, center: np.ndarray) -> np.ndarray:
    """(m,) int: a class per face; faces the die's symmetry maps onto each other share one.

    Faces are compared by solid angle at `center`, area and stability
    margin, which any symmetry of the die (with its centre of mass) keeps.
    """
    size = float(np.ptp(poly.vertices, axis=0).max())
    measures = np.column_stack(
        [solid_angles(poly, center) / (4 * np.pi), poly.areas / size**2, face_margins(poly, center) / size]
    )
    _, classes = np.unique(np.round(measures, CLASS_DECIMALS), axis=0, return_inverse=True)
    return classes.ravel()


def assign_values(
    face_probs: Sequence[float], names: Sequence[str], target: Target, classes: Sequence[int] | None = None
) -> dict[str, int]:
    """Resting face name -> value, every value on at least one face.

    Parameters
    ----------
    face_probs : (m,) float
        Landing probability of each resting face on the starting shape.
    names : (m,) str
        The resting faces.
    target : Target
    classes : (m,) int, optional
        Symmetry classes (:func:`face_classes`): ties in probability are
        broken by class, so equal target values go to faces of one class.

    Raises
    ------
    DesignError
        If there are fewer resting faces than values.
    """
    p = np.asarray(face_probs, dtype=float)
    q = target.probabilities
    m, k = len(p), len(q)
    if m < k:
        raise DesignError(f"{m} resting faces cannot carry the {k} values of target {target.spec!r}")
    classes = np.zeros(m, dtype=int) if classes is None else np.asarray(classes)
    rank = np.empty(k, dtype=int)
    rank[np.lexsort((target.values, -q))] = np.arange(k)  # likelier values first, then smaller
    which = np.empty(m, dtype=int)
    sums, count = np.zeros(k), np.zeros(k, dtype=int)
    for i, f in enumerate(np.lexsort((np.arange(m), classes, -np.round(p, CLASS_DECIMALS)))):
        open_values = count == 0 if (count == 0).sum() >= m - i else np.ones(k, dtype=bool)
        deficit = np.where(open_values, q - sums, -np.inf)
        v = int(np.lexsort((rank, -np.round(deficit, CLASS_DECIMALS)))[0])
        which[f] = v
        sums[v] += p[f]
        count[v] += 1
    which = _improve(p, q, which)
    return {names[f]: int(target.values[which[f]]) for f in range(m)}


def _eq2(sums: np.ndarray, q: np.ndarray) -> float:
    return float(((sums - q) ** 2 / q).sum())


def _improve(p: np.ndarray, q: np.ndarray, which: np.ndarray) -> np.ndarray:
    """Best single move or swap, repeated while Eq. (2) falls."""
    which = which.copy()
    k = len(q)
    while True:
        sums = np.bincount(which, weights=p, minlength=k)
        count = np.bincount(which, minlength=k)
        best, step = _eq2(sums, q) - 1e-12, None
        for f in range(len(p)):
            a = which[f]
            for b in range(k):
                if b == a or count[a] == 1:
                    continue
                trial = sums.copy()
                trial[a] -= p[f]
                trial[b] += p[f]
                if (score := _eq2(trial, q)) < best:
                    best, step = score, ("move", f, b)
            for g in range(f + 1, len(p)):
                b = which[g]
                if b == a:
                    continue
                trial = sums.copy()
                trial[a] += p[g] - p[f]
                trial[b] += p[f] - p[g]
                if (score := _eq2(trial, q)) < best:
                    best, step = score, ("swap", f, g)
        if step is None:
            return which
        if step[0] == "move":
            which[step[1]] = step[2]
        else:
            which[step[1]], which[step[2]] = which[step[2]], which[step[1]]
