"""Quasi-static capture (``capture_energy``): off by default, ends drops only earlier, the basins model at its limit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.stats import chisquare

from diefab.core.errors import PhysicsError
from diefab.dice.design import load_design
from diefab.models.probabilities import basins_model
from diefab.physics.profiles import load_profile, profile_to_toml
from diefab.physics.simulate import PhysicsSettings
from diefab.physics.world import World, die_body, initial_conditions, run_batch
from diefab.search.calibrate import PARAMETERS, make_spec, real_die

pytest.importorskip("pybullet")


@pytest.fixture(scope="module")
def gem():
    return load_design("fudge-gem")


@pytest.fixture(scope="module")
def body(gem):
    return die_body(gem.polyhedron, gem.mass_properties())


def run(body, settings, states):
    world = World(body, settings)
    try:
        return world.run(states, with_steps=True)
    finally:
        world.close()


def test_capture_is_off_by_default_and_left_out_of_stored_settings():
    s = PhysicsSettings()
    assert s.capture_energy == 0.0 and "capture_energy" not in s.as_dict()
    assert PhysicsSettings.from_mapping(s.as_dict()) == s  # settings stored before the setting existed
    on = PhysicsSettings(capture_energy=0.2)
    assert on.as_dict()["capture_energy"] == 0.2 and PhysicsSettings.from_mapping(on.as_dict()) == on


@pytest.mark.parametrize("bad", [-0.1, float("nan"), float("inf"), 101.0, "x", True])
def test_bad_capture_is_a_one_line_physics_error(bad):
    with pytest.raises(PhysicsError, match="capture_energy") as info:
        PhysicsSettings(capture_energy=bad)
    assert "\n" not in str(info.value)


def test_default_outcomes_are_the_rigid_simulation_s(body):
    """The gem's first 120 drops at seed 5 under the default physics, as the physics gave before capture existed."""
    out = run_batch(body, PhysicsSettings(), 5, 0, 120)
    assert np.bincount(out[out >= 0], minlength=9).tolist() == [2, 5, 3, 2, 43, 22, 10, 19, 14]
    assert out[:12].tolist() == [4, 1, 4, 8, 6, 6, 5, 4, 4, 7, 4, 6]


def test_capture_only_ever_ends_a_drop_earlier(body):
    """Capture adds landings at the same checks of the same trajectories: never a later end, never another face
    at the same end."""
    settings = PhysicsSettings()
    states = initial_conditions(2, 0, 96, settings)
    rigid, rigid_steps = run(body, settings, states)
    off, off_steps = run(body, dataclasses.replace(settings, capture_energy=0.0), states)
    assert np.array_equal(rigid, off) and np.array_equal(rigid_steps, off_steps)
    earlier = 0
    for capture in (0.05, 0.3):
        out, steps = run(body, dataclasses.replace(settings, capture_energy=capture), states)
        assert np.all(steps <= rigid_steps)
        same = steps == rigid_steps
        assert np.array_equal(out[same], rigid[same])
        earlier = max(earlier, int(np.sum(~same)))
    assert earlier > 0  # it does act


def test_huge_capture_is_the_basins_model(gem, body):
    """Dropped from just above the ground, a die captured at the first check is still in free flight, its
    orientation uniform: its face is the basin a uniform direction lies in, the basins model's distribution."""
    settings = PhysicsSettings(drop_height=body.radius + 0.2, height_jitter=0.0, capture_energy=100.0)
    out = run_batch(body, settings, 0, 0, 3000)
    assert np.all(out >= 0)
    counts = np.bincount(out, minlength=9)
    p = basins_model(gem.polyhedron, gem.mass_properties().center)
    assert chisquare(counts[p > 0], 3000 * p[p > 0] / p[p > 0].sum()).pvalue > 1e-3
    assert counts[p == 0].sum() == 0
    rigid = run_batch(body, PhysicsSettings(), 0, 0, 3000)
    rigid = np.bincount(rigid[rigid >= 0], minlength=9)
    assert chisquare(rigid[p > 0], rigid.sum() * p[p > 0] / p[p > 0].sum()).pvalue < 1e-6  # not already true


def test_capture_is_a_calibration_parameter_searched_on_a_square_scale(gem):
    die = real_die("gem", gem, "0,20,48,80,89,83,66,17,2")
    spec = make_spec([die], free=("restitution", "capture"))
    assert spec.bounds[1] == (PARAMETERS["capture"].low, PARAMETERS["capture"].high) == (0.0, 1.0)
    assert spec.x0 == (pytest.approx(0.3 / 0.9), 0.0)  # the start is the defaults: capture off
    assert np.allclose(spec.values([0.5, 0.5]), [0.45, 0.25])
    assert np.allclose(spec.unit(spec.values([0.2, 0.3])), [0.2, 0.3])
    assert spec.settings([0.5, 0.5]).capture_energy == pytest.approx(0.25)


def test_profile_keeps_capture(tmp_path):
    s = PhysicsSettings(restitution=0.6, capture_energy=0.12)
    path = tmp_path / "p.toml"
    path.write_text(profile_to_toml(s, name="p"))
    assert load_profile(str(path)) == s
    assert "capture_energy" not in profile_to_toml(PhysicsSettings())


def test_cli_capture_option(run):
    code, out, err = run("validate", "d6", "--sims", "48", "--workers", "1", "--capture-energy", "0.1", "--json")
    assert code == 0, err
    code, out, err = run("validate", "d6", "--sims", "10", "--capture-energy", "-1")
    assert code == 2 and "capture_energy" in err and len(err.strip().splitlines()) == 1
