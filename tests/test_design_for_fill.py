"""benchmarks/design_for_fill.py: which simulations a correction pools, and the step along a simulated slope."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from diefab.dice.design import load_design
from diefab.models.fast import fast_model
from diefab.models.probabilities import to_values
from diefab.stats.goodness import tvd

SCRIPT = Path(__file__).resolve().parent.parent / "benchmarks" / "design_for_fill.py"


@pytest.fixture(scope="module")
def script():
    spec = importlib.util.spec_from_file_location("design_for_fill", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def fast_probabilities(die) -> np.ndarray:
    body = die.mass_properties()
    return fast_model(die.polyhedron, body.center, fill=die.fill, inertia=body.inertia / body.mass)


def record(die, counts, center=True) -> dict:
    out = {"fill": die.fill.to_mapping(), "params": dict(die.params), "face_counts": list(counts)}
    if center:
        out["center"] = die.mass_properties().center.tolist()
    return out


def test_pool_skips_simulations_of_another_body(script):
    die = load_design("fudge-gem-sim")
    other = die.with_params(d=die.params["d"] + 0.05)
    counts = np.arange(1, 10) * 100
    moved = record(die, counts[::-1])
    moved["center"] = (np.asarray(moved["center"]) + 1e-3).tolist()  # dropped with a body that has moved since
    kept = [record(die, counts), record(other, 2 * counts), record(die, counts[::-1], center=False), moved]
    q, p, used = script.pooled_frequencies(die, kept)
    assert used == 2
    np.testing.assert_allclose(q, 3 * counts / (3 * counts.sum()))  # weighted by drops
    want = (counts.sum() * fast_probabilities(die) + 2 * counts.sum() * fast_probabilities(other)) / (3 * counts.sum())
    np.testing.assert_allclose(p, want)


def test_step_along_the_simulated_slope_lowers_the_tvd(script):
    """With a 'simulation' that is the fast model itself, the step must improve the fast model's fit."""
    die = load_design("fudge-gem-sim").with_params(b=0.62, d=1.35)
    goal = die.target_distribution.aligned(die.support)

    def dropped(d):
        return np.round(fast_probabilities(d) * 1e7)

    before = tvd(to_values(die, fast_probabilities(die)), goal)
    moved = script.refit_simulated(die, dropped(die), dropped, ("face", "vertex"), 0.05, 0.05, 0.01)
    after = tvd(to_values(moved, fast_probabilities(moved)), goal)
    step = np.array([moved.params[k] - die.params[k] for k in die.params])
    assert np.abs(step).max() > 0 and after < before


def test_pool_compares_with_the_chosen_model(script):
    """With --model basins the pooled model probabilities are the basins model's, weighted by drops."""
    from diefab.models.probabilities import face_probabilities

    die = load_design("fudge-gem-sim")
    other = die.with_params(c=die.params["c"] + 0.03)
    counts = np.arange(1, 10) * 10
    q, p, used = script.pooled_frequencies(die, [record(die, counts), record(other, 3 * counts)], "basins")
    assert used == 2
    want = (face_probabilities(die, "basins") + 3 * face_probabilities(other, "basins")) / 4
    np.testing.assert_allclose(p, want)
    assert abs(p.sum() - 1) < 1e-12


def test_near_refit_with_the_basins_model_lowers_its_tvd(script):
    """With no correction, the damped step must bring the basins model's value probabilities nearer 4dF."""
    from diefab.models.probabilities import face_probabilities

    die = load_design("fudge-gem-sim")
    goal = die.target_distribution.aligned(die.support)
    zero = np.zeros(len(die.polyhedron.faces))
    moved = script.refit_near(die, zero, ("face", "vertex"), 0.05, 0.05, "basins")
    before = tvd(to_values(die, face_probabilities(die, "basins")), goal)
    after = tvd(to_values(moved, face_probabilities(moved, "basins")), goal)
    assert moved.params != die.params and after < before
    assert moved.margins()[moved.resting_mask()].min() > 0.05


def test_printed_table_gem_keeps_the_profile_and_stands(script):
    """The shipped printed-table gem carries printed-table's physics, so a plain validate drops it so."""
    from diefab.physics.profiles import read_profile

    die = load_design("fudge-gem-print-table")
    assert dict(die.physics) == read_profile("printed-table")[0]["physics"]
    assert die.fill.kind == "print" and die.fill.to_mapping() == load_design("fudge-gem-print").fill.to_mapping()
    assert die.margins()[die.resting_mask()].min() >= 0.05  # as made, engraved labels included
