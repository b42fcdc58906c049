"""Every landing model, the simulation and every shipped profile fitted on real dice hold their figures on real dice.

The figures (mean TVD to the real rolls over the paper's die and the
real-rolls data) are recorded by ``python benchmarks/bench_realrolls.py
--guard --sims 400 --record``; a model whose mean gets worse than its record
by more than the recorded tolerance fails here.  The simulation's counts are
read from the benchmark's cache, keyed by the design, the settings, the
drops, the seed and the simulation's code: a change to the code that drops
the die misses the cache, and the drops are simulated afresh (the same
seed, so the same drops as recorded when nothing that matters changed).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from diefab.physics.profiles import fitted_profiles
from diefab.search.fidelity import (
    LANDING_MODELS,
    SimulationCache,
    guard_settings,
    load_real_dice,
    model_tvd,
    simulated_tvd,
)

ROOT = Path(__file__).resolve().parents[1]
REALROLLS = ROOT / ".." / "shared" / "realrolls"
GUARD = ROOT / "benchmarks" / "results" / "realrolls-guard.json"
SIM_CACHE = ROOT / "benchmarks" / "results" / "realrolls-sim-cache.json"

pytestmark = pytest.mark.skipif(
    not REALROLLS.is_dir() or not GUARD.is_file(),
    reason="real-rolls data (../shared/realrolls) or recorded figures absent",
)


@pytest.fixture(scope="module")
def recorded():
    return json.loads(GUARD.read_text())


@pytest.fixture(scope="module")
def dice(recorded):
    found = {d.name: d for d in load_real_dice(REALROLLS, published=True)}
    missing = [n for n in recorded["dice"] if n not in found]
    if missing:
        pytest.skip(f"real dice {missing} of the recorded figures are absent")
    return [found[n] for n in recorded["dice"]]


@pytest.mark.parametrize("model", LANDING_MODELS)
def test_landing_model_is_no_worse_on_real_dice_than_recorded(dice, recorded, model):
    tvds = {d.name: model_tvd(d, model) for d in dice}
    mean = float(np.mean(list(tvds.values())))
    worse = {n: round(t - recorded["per_die"][n][model], 4) for n, t in tvds.items()}
    assert mean <= recorded["mean"][model] + recorded["tolerance"], f"{model}: mean TVD {mean:.4f}, per die {worse}"


@pytest.fixture(scope="module")
def sim_cache():
    cache = SimulationCache(None)
    if SIM_CACHE.is_file():
        cache.entries = dict(json.loads(SIM_CACHE.read_text()))  # read only: the test never writes the repository
    return cache


@pytest.fixture(scope="module")
def simulated(dice, recorded):
    """The dice the simulation scores: those whose drops came to rest when the figures were recorded."""
    return [d for d in dice if recorded["per_die"][d.name]["validate"] is not None]


def test_the_simulation_leaves_out_only_dice_whose_drops_do_not_come_to_rest(dice, recorded, simulated, sim_cache):
    from diefab.search.fidelity import SETTLED, settled_share

    for d in dice:
        share = settled_share(d, drops=recorded["drops"], seed=recorded["seed"], cache=sim_cache, workers=2)
        assert (share >= SETTLED) == (d in simulated), f"{d.name}: {share:.0%} of the drops come to rest"


def test_simulation_is_no_worse_on_real_dice_than_recorded(simulated, recorded, sim_cache):
    tvds = [simulated_tvd(d, guard_settings(d)["validate"], drops=recorded["drops"], seed=recorded["seed"],
                          cache=sim_cache, workers=2) for d in simulated]  # fmt: skip
    mean = float(np.mean(tvds))
    assert mean <= recorded["mean"]["validate"] + recorded["tolerance"], f"validate: mean TVD {mean:.4f}"


def test_every_shipped_profile_fitted_on_real_dice_is_guarded(recorded):
    assert sorted(recorded.get("profiles", [])) == fitted_profiles()


@pytest.mark.parametrize("profile", fitted_profiles())
def test_shipped_profile_is_no_worse_on_real_dice_than_recorded(simulated, recorded, sim_cache, profile):
    column = f"validate --profile {profile}"
    if column not in recorded["mean"]:
        pytest.fail(f"no recorded figures for the shipped profile {profile!r}: run {recorded['command']}")
    tvds = [simulated_tvd(d, guard_settings(d, [profile])[column], drops=recorded["drops"], seed=recorded["seed"],
                          cache=sim_cache, workers=2) for d in simulated]  # fmt: skip
    mean = float(np.mean(tvds))
    assert mean <= recorded["mean"][column] + recorded["tolerance"], f"{column}: mean TVD {mean:.4f}"


def test_the_fast_model_is_no_worse_than_the_chain_it_corrects_on_real_dice(dice):
    """The learned corrections were tuned on simulated dice; on real designed dice they must not lose to the chain."""
    from diefab.models.fast import landing_probabilities
    from diefab.models.probabilities import to_values

    chain, fast = [], []
    for d in dice:
        body = d.design.mass_properties()
        p = landing_probabilities(d.design.polyhedron, body.center, inertia=body.inertia / body.mass)
        q = to_values(d.design, p)
        chain.append(d.tvd(q / q.sum()))
        fast.append(model_tvd(d, "fast"))
    assert np.mean(fast) <= np.mean(chain) + 0.005
