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

Which fitting method to use (a grid choice or a mixture, which candidates,
which rule) is itself a choice made on the dice: :func:`nested_choices`
scores the whole procedure, the choice made again without each held-out
die by an inner leave-one-out over the others.

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
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from diefab.core.errors import StatsError

__all__ = [
    "RULES",
    "deviance_table",
    "held_out_choices",
    "nested_choices",
    "pick_candidate",
    "prior_cost",
    "training_rows",
]

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


def prior_cost(coords: np.ndarray, x0: np.ndarray, prior_sd: float) -> np.ndarray:
    """Minus twice the log of the normal prior toward `x0` (sd `prior_sd`) at each row of `coords`, up to a constant.

    `coords` is (candidates, d) or one point (d,); an infinite `prior_sd` is no prior (0 everywhere).
    """
    coords = np.asarray(coords, dtype=float)
    if not math.isfinite(prior_sd):
        return np.zeros(coords.shape[:-1])
    return (((coords - np.asarray(x0, dtype=float)) / prior_sd) ** 2).sum(axis=-1)


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
    return int(np.argmin(total + prior_cost(coords, x0, prior_sd)))


def training_rows(names: Sequence[str], i: int, rule: str, family: Callable[[str], str],
                  surface: Callable[[str], str], among: Sequence[int] | None = None) -> list[int]:  # fmt: skip
    """Rows fitted on when die `i` is held out under `rule` (:data:`RULES`), from `among` (default all); never `i`."""
    if rule not in RULES:
        raise StatsError(f"rule={rule!r} is not one of {', '.join(RULES)}")
    among = range(len(names)) if among is None else among
    if rule.startswith("lofo"):
        rows = [j for j in among if family(names[j]) != family(names[i])]
    else:
        rows = [j for j in among if j != i]
    if rule.endswith("-surface"):
        rows = [j for j in rows if surface(names[j]) == surface(names[i])]
    return rows


def held_out_choices(names: Sequence[str], dev: np.ndarray, coords: np.ndarray, x0: np.ndarray,
                     prior_sd: float, family: Callable[[str], str],
                     surface: Callable[[str], str]) -> dict[str, list[int]]:  # fmt: skip
    """Per rule of :data:`RULES`, the candidate chosen for each held-out die (by its row of `dev`).

    `family` and `surface` name a die's family and what it was rolled on.
    The surface rules fall back to the candidate nearest `x0` (the default)
    when no training die was rolled on the held-out die's surface.
    """
    default = int(np.argmin(((np.asarray(coords, dtype=float) - x0) ** 2).sum(axis=1)))
    out: dict[str, list[int]] = {}
    for rule in RULES:
        picks = []
        for i in range(len(names)):
            rows = training_rows(names, i, rule, family, surface)
            picks.append(pick_candidate(dev, rows, coords, x0, prior_sd) if rows or not rule.endswith("-surface")
                         else default)  # fmt: skip
        out[rule] = picks
    return out


#: A fitting method of :func:`nested_choices`: (training rows, target row) -> (K,) candidate weights.
Method = Callable[[Sequence[int], int], np.ndarray]


def nested_choices(
    n: int, methods: Mapping[str, Method], inner_loss: Callable[[int, np.ndarray], float]
) -> list[tuple[str, np.ndarray, dict[str, float]]]:
    """Leave-one-die-out score of a *choice among methods*: the choice itself is made without the held-out die.

    For each held-out die ``i`` the training dice are every other die.  Each
    method is scored on them by an inner leave-one-out (each training die
    ``j`` predicted by the method fitted on the training dice without ``j``,
    scored by ``inner_loss(j, weights)``); the method of least mean inner loss
    (the first on a tie) is fitted on all training dice and predicts ``i``.
    Die ``i``'s real counts take no part: neither in the inner scores nor in the
    fit.

    Parameters
    ----------
    n : int
        Number of dice.
    methods : mapping of name -> callable ``(rows, target) -> (K,) weights``
        A fitting method: the candidate weights (one-hot for a grid choice)
        predicting die `target` from the dice `rows`.  It may restrict `rows`
        further (to the target's surface, say) but must not look beyond them.
    inner_loss : callable ``(j, weights) -> float``
        How far the prediction `weights` is from die ``j``'s real counts.

    Returns
    -------
    list of (str, (K,) float, dict)
        Per die: the method chosen, its weights for the die, and every
        method's mean inner loss.
    """
    if not methods:
        raise StatsError("no method to choose from")
    out = []
    for i in range(n):
        train = [j for j in range(n) if j != i]
        inner = {name: float(np.mean([inner_loss(j, fit([r for r in train if r != j], j)) for j in train]))
                 for name, fit in methods.items()}  # fmt: skip
        best = min(inner, key=lambda name: inner[name])
        out.append((best, methods[best](train, i), inner))
    return out
