"""benchmarks/design_for_fill.py: which simulations a correction pools, and the step along a simulated slope."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from diefab.design import load_design
from diefab.fastmodel import fast_model
from diefab.models import to_values
from diefab.stats import tvd

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
