"""How well diefab predicts real dice: every die with real rolls, every landing model, one score each.

The dice are the paper's die as made (a paper model, i.e. a shell fill, of
the gem a=1.18 b=0.52 c=0.72 d=1.41, with its 405 real rolls of Table 2)
and every file of a real-rolls folder (:mod:`diefab.physics.realrolls`).  Each is a
:class:`~diefab.search.calibrate.RealDie`: its design as made and its counts per
value.  :func:`model_tvd` scores a landing model (``solid-angle``,
``basins``, ``fast``: what ``diefab predict`` gives) and
:func:`simulated_tvd` the simulation (what ``diefab validate`` gives) by
their TVD to the real frequencies, mirror-image outcomes compared up to
relabelling (:func:`diefab.physics.realrolls.grouped_tvd`).

A die the simulation cannot settle is left out of the simulated columns:
where fewer than :data:`SETTLED` of its drops at its own physics come to
rest within the time limit (a thick coin, a prism of many sides, still
rolls on its edge), the drops that did are not a sample of its landings.

Simulated counts are cached (:class:`SimulationCache`) under a key of the
design, the physics settings, the seed, the number of drops and the
simulation's code (:func:`simulation_key`), so that a guard of the
simulation's figures costs a look-up until the code changes.

Examples
--------
>>> die = paper_die()
>>> die.n, die.design.support[0], die.design.support[-1]
(405, -4, 4)
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from diefab.core.errors import DiefabError
from diefab.search.realdie import RealDie

__all__ = [
    "LANDING_MODELS",
    "PAPER_DIE_TOML",
    "SETTLED",
    "TABLE_2",
    "SimulationCache",
    "guard_scores",
    "guard_settings",
    "landing_model_scores",
    "load_real_dice",
    "mean_scores",
    "model_tvd",
    "noise_tvd",
    "paper_die",
    "settled_share",
    "simulated_tvd",
    "simulation_key",
]

#: The landing models ``diefab predict`` offers, scored against real dice.
LANDING_MODELS = ("solid-angle", "basins", "fast")

#: Share of a die's drops that must come to rest for the simulation to score it.
SETTLED = 0.95

#: The paper's real rolls (Table 2) of its final die, values -4 .. 4.
TABLE_2 = (0, 20, 48, 80, 89, 83, 66, 17, 2)

#: The paper's die as made: a paper model (shell) of its final gem.
PAPER_DIE_TOML = """\
name = "paper-gem"
description = "the paper's die as made: a paper model (shell) of the gem a=1.18 b=0.52 c=0.72 d=1.41"
family = "gem"
target = "4df"
size_mm = 30.0
[params]
a = 1.18
b = 0.52
c = 0.72
d = 1.41
[fill]
kind = "shell"
"""


def paper_die() -> RealDie:
    """The paper's die as made, with its 405 real rolls (Table 2)."""
    from diefab.dice.design import parse_design

    return RealDie("paper-gem", parse_design(PAPER_DIE_TOML, source="the paper's die"), np.array(TABLE_2))


def load_real_dice(folder: str | Path | None, *, paper: bool = True, published: bool = False) -> list[RealDie]:
    """The paper's die (if `paper`), every die of the real-rolls `folder` (``*.json``, sorted by name) and,
    if `published`, the published dice shipped with diefab (:func:`diefab.search.published.printed_dice`,
    :func:`diefab.search.published.square_cuboid_dice`, :func:`diefab.search.published.thick_coin_dice`).

    A `folder` that is None or does not exist contributes no die.
    """
    from diefab.search.realdie import realrolls_die

    dice = [paper_die()] if paper else []
    if folder is not None and Path(folder).is_dir():
        dice += [realrolls_die(p) for p in sorted(Path(folder).glob("*.json"))]
    if published:
        from diefab.search.published import printed_dice, square_cuboid_dice, thick_coin_dice

        dice += printed_dice() + square_cuboid_dice() + thick_coin_dice()
    return dice


def model_tvd(die: RealDie, model: str) -> float:
    """TVD of a landing model's prediction of `die` (as ``diefab predict --model MODEL``) to its real rolls."""
    from diefab.models.probabilities import value_probabilities

    return die.tvd(value_probabilities(die.design, model))


def landing_model_scores(die: RealDie, *, alpha: float = 0.05, seed: int = 0) -> dict[str, dict[str, Any]]:
    """Each landing model's prediction of `die` against its real rolls, and which model is the one to trust.

    Per model: ``predicted`` (value probabilities), ``tvd`` to the real
    frequencies (:meth:`RealDie.tvd`), ``expected_tvd`` (what the rolls would
    show if the model were right; None where it gives a rolled value no
    chance), ``p_value`` (chi-squared of the counts against it) and
    ``to_trust`` (:func:`diefab.models.choice.best_model`).
    """
    from diefab.models.choice import best_model
    from diefab.models.probabilities import value_probabilities
    from diefab.stats.goodness import goodness_of_fit

    trust = best_model(die.design).name
    out = {}
    for name in LANDING_MODELS:
        p = value_probabilities(die.design, name)
        fit = goodness_of_fit(die.counts, p, alpha=alpha, seed=seed) if np.all(p[die.counts > 0] > 0) else None
        out[name] = {"predicted": p.tolist(), "tvd": die.tvd(p),
                     "expected_tvd": None if fit is None else fit.expected_tvd_exact,
                     "p_value": 0.0 if fit is None else fit.p_value, "to_trust": name == trust}  # fmt: skip
    return out


def noise_tvd(die: RealDie, samples: int = 20_000, seed: int = 0) -> float:
    """Expected TVD of `die`'s number of rolls to the distribution they were drawn from (at the observed one).

    What a perfect model scores on average (Monte-Carlo, compared up to relabelling like every model).
    """
    rng = np.random.default_rng(seed)
    draws = rng.multinomial(die.n, die.frequencies, size=samples) / die.n
    return float(np.mean([die.tvd(d) for d in draws]))


def simulation_key(die: RealDie, settings, drops: int, seed: int) -> str:
    """Hex key of a simulation of `die`: its design, the settings, drops, seed and the simulation's code.

    The code is the source text of the modules that drop a die
    (:mod:`diefab.physics.simulate`, :mod:`diefab.physics.world`), the outcome version and
    pybullet's version: any change to them is a new key.
    """
    import importlib.metadata
    import inspect

    from diefab.dice.design import design_to_toml
    from diefab.physics import simulate as physics
    from diefab.physics import world

    h = hashlib.sha256()
    for part in (design_to_toml(die.design), json.dumps(settings.as_dict(), sort_keys=True), str(drops), str(seed),
                 inspect.getsource(physics), inspect.getsource(world), str(world.OUTCOME_VERSION),
                 importlib.metadata.version("pybullet")):  # fmt: skip
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()[:24]


class SimulationCache:
    """Simulated value counts on disk, one JSON object of key -> counts (:func:`simulation_key`).

    Parameters
    ----------
    path : path or None
        The cache file (None: nothing is kept).  It is read once and
        rewritten atomically after each new entry.
    """

    def __init__(self, path: str | Path | None) -> None:
        self.path = None if path is None else Path(path)
        self.entries: dict[str, list[int]] = {}
        if self.path is not None and self.path.is_file():
            try:
                self.entries = dict(json.loads(self.path.read_text()))
            except (OSError, ValueError) as exc:
                raise DiefabError(f"simulation cache {self.path} is unreadable: {exc}") from None

    def counts(self, die: RealDie, settings, drops: int, seed: int, workers: int | None = 1) -> np.ndarray:
        """(k,) int: value counts of `drops` drops of `die` (landed drops only), simulated or cached."""
        from diefab.core.files import atomic_write
        from diefab.physics.simulate import simulate

        key = simulation_key(die, settings, drops, seed)
        if key not in self.entries:
            result = simulate(die.design, drops, seed=seed, workers=workers, settings=settings)
            self.entries[key] = np.asarray(result.value_counts(die.design)).astype(int).tolist()
            if self.path is not None:
                atomic_write(self.path, json.dumps(self.entries, indent=0, sort_keys=True) + "\n")
        return np.array(self.entries[key], dtype=np.int64)


def simulated_tvd(die: RealDie, settings=None, *, drops: int, seed: int = 0, cache: SimulationCache | None = None,
                  workers: int | None = 1) -> float:  # fmt: skip
    """TVD of `drops` simulated drops of `die` (landed ones) to its real rolls, as ``diefab validate`` scores.

    `settings` default to the design's own physics (``[physics]`` over the defaults).
    """
    from diefab.physics.simulate import PhysicsSettings

    if settings is None:
        settings = PhysicsSettings.from_mapping(die.design.physics)
    counts = (cache or SimulationCache(None)).counts(die, settings, drops, seed, workers)
    return die.tvd(counts / max(int(counts.sum()), 1))


def mean_scores(dice: Sequence[RealDie], scores: Mapping[str, Mapping[str, float]]) -> dict[str, float]:
    """Per column, the mean of `scores` (die name -> column -> TVD) over `dice`, leaving out dice not scored (NaN)."""
    columns = next(iter(scores.values())).keys() if scores else ()
    means = {}
    for c in columns:
        column = np.array([scores[d.name][c] for d in dice], dtype=float)
        means[c] = float(np.mean(column[~np.isnan(column)])) if not np.isnan(column).all() else float("nan")
    return means


def guard_settings(die: RealDie, profiles: Sequence[str] = ()) -> dict[str, Any]:
    """The physics of each simulated column of the guard for `die`: ``validate`` and ``validate --profile P``.

    ``validate`` is the simulation at the die's own physics (the defaults
    for these dice); ``validate --profile P`` the simulation under each of
    `profiles` (shipped names or files) over the die's physics.
    """
    from diefab.physics.profiles import load_profile
    from diefab.physics.simulate import PhysicsSettings

    columns = {"validate": PhysicsSettings.from_mapping(die.design.physics)}
    return columns | {f"validate --profile {p}": load_profile(p, base=die.design.physics) for p in profiles}


def settled_share(die: RealDie, *, drops: int, seed: int, cache: SimulationCache | None = None,
                  workers: int | None = 1) -> float:  # fmt: skip
    """The share of `drops` drops of `die` at its own physics that come to rest (simulated or cached)."""
    settings = guard_settings(die)["validate"]
    return float((cache or SimulationCache(None)).counts(die, settings, drops, seed, workers).sum()) / drops


def guard_scores(dice: Sequence[RealDie], *, drops: int, seed: int, cache: SimulationCache | None,
                 workers: int | None = 1, profiles: Sequence[str] = ()) -> dict[str, Any]:  # fmt: skip
    """Per die, the TVD to its real rolls of each landing model and each simulated column (:func:`guard_settings`).

    A die of which fewer than :data:`SETTLED` of the drops come to rest at
    its own physics (:func:`settled_share`) gets NaN in every simulated column.
    """
    cache = cache if cache is not None else SimulationCache(None)  # one for the whole table: no drop run twice
    out: dict[str, dict[str, float]] = {}
    for die in dice:
        row = {m: model_tvd(die, m) for m in LANDING_MODELS}
        settles = settled_share(die, drops=drops, seed=seed, cache=cache, workers=workers) >= SETTLED
        for column, settings in guard_settings(die, profiles).items():
            row[column] = (simulated_tvd(die, settings, drops=drops, seed=seed, cache=cache, workers=workers)
                           if settles else float("nan"))  # fmt: skip
        out[die.name] = row
    return out
