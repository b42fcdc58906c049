"""A stated centre of mass and inertia enter every model and the optimizers' inner loops."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from diefab.dice.design import load_design
from diefab.geometry.polyhedron import face_margins
from diefab.made.mass import Fill, mass_properties
from diefab.models.fast import roll_retention
from diefab.models.probabilities import MODELS, value_probabilities
from diefab.search.optimize import Problem, candidate_mass

NAMES = ("a", "b", "c", "d")


def weighted_gem(shift=(0.0, -0.08, 0.03), inertia=None):
    """The paper's gem with a weight that moves its centre of mass by `shift` (model units)."""
    gem = load_design("fudge-gem")
    center = gem.mass_properties().center + np.array(shift)
    return replace(gem, center_of_mass=tuple(center.tolist()), inertia=inertia)


@pytest.mark.parametrize("model", sorted(MODELS))
def test_the_optimizer_scores_a_design_with_its_stated_centre_of_mass(model):
    d = weighted_gem()
    problem = Problem(d, NAMES, model=model, min_margin=0.0)
    _, values, margins = problem.evaluate(dict(d.params))
    assert np.allclose(values, value_probabilities(d, model), atol=1e-12)
    assert np.allclose(margins, face_margins(d.polyhedron, np.array(d.center_of_mass)), atol=1e-12)
    # and not with the fill's own centre of mass, which the weight moved
    plain = Problem(load_design("fudge-gem"), NAMES, model=model, min_margin=0.0).evaluate(dict(d.params))[1]
    assert np.abs(values - plain).sum() > 1e-3


def test_a_candidate_keeps_the_stated_centre_and_inertia_whatever_its_shape():
    inertia = ((0.3, 0.0, 0.0), (0.0, 0.25, 0.0), (0.0, 0.0, 0.3))
    d = weighted_gem(inertia=inertia)
    other = d.with_params(a=d.params["a"] * 1.05)
    props = candidate_mass(d, other.polyhedron)
    solid = mass_properties(other.polyhedron, Fill())
    assert np.allclose(props.center, d.center_of_mass) and props.mass == pytest.approx(solid.mass)
    assert np.allclose(props.inertia / props.mass, inertia)


def test_a_centre_the_candidate_no_longer_holds_is_infeasible():
    d = weighted_gem(shift=(0.0, 0.0, 0.0))
    top = d.polyhedron.vertices[:, 1].max()
    d = replace(d, center_of_mass=(0.0, float(top) - 0.02, 0.0))  # just under the apex
    problem = Problem(d, NAMES, min_margin=0.0)
    score, _, _ = problem.evaluate({**d.params, "b": problem.bounds[1, 0]})
    assert score >= 1.0


def test_simulation_optimizer_checks_feasibility_at_the_stated_centre():
    from diefab.dice.design import design_to_toml
    from diefab.search.simopt import RunSpec, SimulationObjective

    d = weighted_gem(shift=(0.0, 0.25, 0.0))  # high and off the axis: some face no longer holds the die
    assert face_margins(d.polyhedron, np.array(d.center_of_mass))[d.resting_mask()].min() < 0.05
    own = load_design("fudge-gem")
    assert face_margins(own.polyhedron, own.mass_properties().center)[own.resting_mask()].min() > 0.05
    spec = RunSpec(design_toml=design_to_toml(d), names=NAMES, x0=(0.5,) * 4, min_margin=0.05)
    ev = SimulationObjective(spec, workers=1)
    record = ev(ev.problem.unit(dict(d.params)), 16)
    assert record["feasible"] is False and record["drops"] == 0
    assert record["min_margin"] == pytest.approx(
        face_margins(d.polyhedron, np.array(d.center_of_mass))[d.resting_mask()].min()
    )


def test_the_fast_model_uses_a_stated_inertia():
    d = load_design("d6")
    own = mass_properties(d.polyhedron, Fill())
    per_mass = own.inertia / own.mass
    eta = roll_retention(d.polyhedron, own.center)
    assert np.allclose(roll_retention(d.polyhedron, own.center, per_mass), eta)
    # a heavier rim (larger k^2) keeps more energy over an edge: (k^2 - 0) / (k^2 + r^2), squared
    assert np.allclose(roll_retention(d.polyhedron, own.center, 2 * per_mass), ((4 / 3) / (4 / 3 + 2)) ** 2)
    gem = load_design("fudge-gem")
    g = mass_properties(gem.polyhedron, Fill())
    same = replace(gem, inertia=tuple(map(tuple, (g.inertia / g.mass).tolist())))
    assert np.allclose(value_probabilities(same, "fast"), value_probabilities(gem, "fast"), atol=1e-9)
    heavy_rim = replace(gem, inertia=tuple(map(tuple, (1.8 * g.inertia / g.mass).tolist())))
    assert np.abs(value_probabilities(heavy_rim, "fast") - value_probabilities(gem, "fast")).sum() > 1e-3
