"""Cross-validation of physics over real dice: which candidate setting predicts a die nothing was fitted on.

Each candidate is a point of physics settings with coordinates on a unit
scale (the throw's vigor, the table's capture, rolling friction, softness,
the edge radius...), simulated for every die.  For a held-out die, the
candidate chosen is the one of least total deviance of the *training*
dice's real counts under the candidate's simulated probabilities, plus a
normal prior toward the default physics: ``sum(((x - x0) / prior_sd)**2)``
over the coordinates, so that a candidate far from the default must earn
its distance on several dice, and one die cannot pull the fit to itself.
The held-out die is then scored on its own simulation at the chosen
candidate, which took no part in the choice.

The training dice of a held-out die (:func:`held_out_choices`):

``loo``
    every other die;
``lofo``
    the dice of the other families;
``loo-surface`` / ``lofo-surface``
    the same, restricted to dice rolled on the held-out die's own surface,
    and the default candidate when there is none.

Examples
--------
Two dice that both prefer candidate 1; held out, each gets it from the other:

>>> import numpy as np
>>> dev = np.array([[5.0, 1.0], [4.0, 0.5]])
>>> pick_candidate(dev, [1], np.array([[0.0], [1.0]]), np.array([0.0]), np.inf)
1
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from diefab.core.errors import StatsError

__all__ = ["RULES", "deviance_table", "held_out_choices", "pick_candidate"]

#: The held-out rules of :func:`held_out_choices`, in print order.
RULES = ("loo", "lofo", "loo-surface", "lofo-surface")


def deviance_table(dice, probabilities: Sequence[Sequence[np.ndarray]]) -> np.ndarray:
    """(dice, candidates) float: deviance of each die's real counts under each candidate's probabilities.

    Parameters
    ----------
    dice : sequence of RealDie
    probabilities : per die, per candidate, (k,) float
        Simulated value probabilities (smoothed, so none is 0), symmetrized
        here within the die's groups.
    """
    from diefab.search.likelihood import deviance

    return np.array([[deviance(d.counts, d.symmetrized(p)) for p in row] for d, row in zip(dice, probabilities)])


def pick_candidate(dev: np.ndarray, train: Sequence[int], coords: np.ndarray, x0: np.ndarray,
                   prior_sd: float) -> int:  # fmt: skip
    """Index of the candidate of least deviance over the `train` dice plus the prior toward `x0`.

    Parameters
    ----------
    dev : (dice, candidates) float
        :func:`deviance_table`.
    train : sequence of int
        Rows of `dev` fitted on (none: the prior alone decides).
    coords : (candidates, d) float
        Unit-scale coordinates of the candidates.
    x0 : (d,) float
        The default's coordinates.
    prior_sd : float
        Standard deviation of the normal prior, coordinate units (inf: none).
    """
    coords = np.asarray(coords, dtype=float)
    if coords.ndim != 2 or dev.shape[1] != len(coords):
        raise StatsError(f"{dev.shape[1]} candidates' deviances for coordinates of shape {coords.shape}")
    if not prior_sd > 0:
        raise StatsError(f"prior_sd={prior_sd!r} must be > 0 (inf: no prior)")
    total = dev[list(train)].sum(axis=0) if len(train) else np.zeros(len(coords))
    if math.isfinite(prior_sd):
        total = total + (((coords - np.asarray(x0, dtype=float)) / prior_sd) ** 2).sum(axis=1)
    return int(np.argmin(total))


def held_out_choices(names: Sequence[str], dev: np.ndarray, coords: np.ndarray, x0: np.ndarray,
                     prior_sd: float, family: Callable[[str], str],
                     surface: Callable[[str], str]) -> dict[str, list[int]]:  # fmt: skip
    """Per rule of :data:`RULES`, the candidate chosen for each held-out die (by its row of `dev`).

    `family` and `surface` name a die's family and what it was rolled on.
    The surface rules fall back to the candidate nearest `x0` (the default)
    when no training die was rolled on the held-out die's surface.
    """
    n = len(names)
    default = int(np.argmin(((np.asarray(coords, dtype=float) - x0) ** 2).sum(axis=1)))
    train = {"loo": lambda i: [j for j in range(n) if j != i],
             "lofo": lambda i: [j for j in range(n) if family(names[j]) != family(names[i])]}  # fmt: skip
    out: dict[str, list[int]] = {}
    for rule in RULES:
        base = train[rule.removesuffix("-surface")]
        picks = []
        for i in range(n):
            rows = base(i)
            if rule.endswith("-surface"):
                rows = [j for j in rows if surface(names[j]) == surface(names[i])]
                if not rows:
                    picks.append(default)
                    continue
            picks.append(pick_candidate(dev, rows, coords, x0, prior_sd))
        out[rule] = picks
    return out
