"""The fast model per fill: the body's inertia in the chain, the card fills' learned correction, reading rules."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from diefab.core.errors import DesignError
from diefab.dice.design import load_design
from diefab.dice.readings import unreadable
from diefab.made.fill import Fill
from diefab.made.mass import mass_properties
from diefab.models.chain import landing_probabilities, roll_retention
from diefab.models.discrepancy import Discrepancy
from diefab.models.fast import fast_model
from diefab.models.probabilities import FILL_MODELS, model_probabilities
from diefab.search.optimize import Problem

MIRRORS = ((0, 2), (1, 3), (5, 7), (6, 8))


def test_roll_retention_with_the_solids_own_inertia_is_the_default():
    d = load_design("fudge-gem")
    poly = d.polyhedron
    body = mass_properties(poly)
    center = body.center + np.array([0.0, 0.03, 0.0])  # off the solid's centre: the default moves the inertia there
    shift = center - body.center
    moved = (body.inertia + body.mass * (shift @ shift * np.eye(3) - np.outer(shift, shift))) / body.mass
    assert np.allclose(roll_retention(poly, center, moved), roll_retention(poly, center), atol=1e-12)


def test_a_larger_radius_of_gyration_keeps_more_energy_over_every_edge():
    """(k² + r² cos φ) / (k² + r²) grows with k² (cos φ < 1): a shell rolls on where a solid stops."""
    d = load_design("fudge-gem")
    poly = d.polyhedron
    solid = mass_properties(poly)
    shell = mass_properties(poly, Fill("shell"))
    kept_solid = roll_retention(poly, shell.center, solid.inertia / solid.mass)
    kept_shell = roll_retention(poly, shell.center, shell.inertia / shell.mass)
    assert np.all(kept_shell >= kept_solid - 1e-12) and np.any(kept_shell > kept_solid + 1e-3)
    # a cube's edges: phi = 90 degrees, so the retention is (k² / (k² + r²))² exactly
    cube = load_design("d6").polyhedron
    body = mass_properties(cube)
    k2 = body.inertia[0, 0] / body.mass
    half = np.ptp(cube.vertices[:, 0]) / 2
    assert np.allclose(roll_retention(cube, body.center), (k2 / (k2 + 2 * half**2)) ** 2)


def test_fast_model_solid_fill_and_solid_inertia_change_nothing():
    d = load_design("fudge-gem-sim")
    body = d.mass_properties()
    plain = fast_model(d.polyhedron, body.center)
    same = fast_model(d.polyhedron, body.center, fill=Fill("solid"), inertia=body.inertia / body.mass)
    assert np.allclose(plain, same, atol=1e-12)
    assert np.allclose(model_probabilities("fast", d.polyhedron, body, d.fill), plain, atol=1e-12)
    assert "fast" in FILL_MODELS and "solid-angle" not in FILL_MODELS
    # a model without fill keywords sees the centre alone
    assert np.allclose(model_probabilities("solid-angle", d.polyhedron, body, Fill("shell")).sum(), 1.0)


def test_the_shell_correction_keeps_mirror_images_equal_and_sums_to_one():
    d = replace(load_design("fudge-gem-sim"), fill=Fill("shell"))
    body = d.mass_properties()
    p = fast_model(d.polyhedron, body.center, fill=d.fill, inertia=body.inertia / body.mass)
    base = fast_model(d.polyhedron, body.center, inertia=body.inertia / body.mass)
    assert p.sum() == pytest.approx(1.0) and np.all(p >= 0)
    for i, j in MIRRORS:
        assert p[i] == pytest.approx(p[j], abs=1e-9)
    assert np.abs(p - base).sum() > 1e-3  # the layer does something here


def test_a_linear_kernel_discrepancy_reproduces_a_constant_residual_and_survives_json():
    """An affine residual is learned exactly (RBF with a polynomial part), whatever the kernel."""
    rng = np.random.default_rng(7)
    n = 24
    points = np.column_stack([1 + rng.random(n), 0.3 + 0.6 * rng.random(n), 0.1 + 0.9 * rng.random(n),
                              0.5 + 3.5 * rng.random(n), 0.1 + 1.9 * rng.random(n)])  # fmt: skip
    margins = 0.05 + rng.random((n, 9))
    chain = rng.dirichlet(np.ones(9), n)
    shift = np.array([0.01, -0.02, 0.01, -0.02, 0.03, -0.01, 0.005, -0.01, 0.005])  # mirror-symmetric, sums to 0
    fit = Discrepancy.learn(points, margins, chain, chain + shift, smoothing=0.0, physics_coordinates=False,
                            kernel="linear")  # fmt: skip
    params = dict(zip("abcde", points[3] + 0.01))
    assert np.allclose(fit(params, margins[3], chain[3]), shift, atol=1e-9)
    back = Discrepancy.from_json(fit.to_json())
    assert back.kernel == "linear" and np.allclose(back(params, margins[3], chain[3]), shift, atol=1e-6)


def test_read_by_refuses_an_edge_reading():
    sim = load_design("fudge-gem-sim")
    assert unreadable(sim.polyhedron, sim.values, tuple(sim.labels), ("face", "vertex")) is None
    # a gem whose fourth face is read from an edge: the old card template's shape
    edgy = sim.with_params(a=1.096142, b=0.699291, c=0.797116, d=1.188052, e=0.893968)
    assert unreadable(edgy.polyhedron, edgy.values, tuple(edgy.labels)) is None
    why = unreadable(edgy.polyhedron, edgy.values, tuple(edgy.labels), ("face", "vertex"))
    assert why is not None and "edge" in why
    with pytest.raises(DesignError, match="read_by"):
        Problem(sim, ("a", "b"), read_by=("corner",))


@pytest.mark.parametrize("name", ["fudge-gem-sim", "fudge-gem-paper", "fudge-gem-print"])
def test_the_shipped_4df_gems_are_read_from_faces_and_the_apex(name):
    d = load_design(name)
    assert unreadable(d.polyhedron, d.values, tuple(d.labels), ("face", "vertex")) is None


def test_design_takes_the_fill_and_its_settings(run, bad, monkeypatch):
    import diefab.search.synthesis

    seen = {}

    def fake(goal, **kw):
        seen.update(kw)
        raise DesignError("stopped here")

    monkeypatch.setattr(diefab.search.synthesis, "synthesize", fake)
    line = bad("design", "4df", "--fill", "paper", "--card", "120", "--out", "/tmp/diefab-test-fills")
    assert "stopped here" in line
    assert seen["fill"] == Fill("paper", card_g_m2=120.0)
    bad("design", "4df", "--fill", "print", "--infill", "0.5", "--out", "/tmp/diefab-test-fills")
    assert seen["fill"] == Fill("print", infill=0.5)
    line = bad("design", "4df", "--fill", "print", "--infill", "2", "--out", "/tmp/diefab-test-fills")
    assert "infill" in line


def test_chain_uses_the_inertia_it_is_given():
    d = replace(load_design("fudge-gem-sim"), fill=Fill("shell"))
    body = d.mass_properties()
    with_shell = landing_probabilities(d.polyhedron, body.center, inertia=body.inertia / body.mass)
    solid_inertia = landing_probabilities(d.polyhedron, body.center)
    assert not np.allclose(with_shell, solid_inertia)
    for p in (with_shell, solid_inertia):
        assert p.sum() == pytest.approx(1.0)


def test_the_optimizer_scores_a_card_die_with_the_fill_aware_model():
    from diefab.models.probabilities import to_values

    d = replace(load_design("fudge-gem-sim"), fill=Fill("shell"))
    problem = Problem(d, ("a", "b", "c", "d", "e"), model="fast", objective="tvd")
    _, values, _ = problem.evaluate(dict(d.params))
    body = d.mass_properties()
    expected = to_values(d, model_probabilities("fast", d.polyhedron, body, d.fill))
    assert np.allclose(values, expected, atol=1e-12)
    solid_trained = to_values(d, fast_model(d.polyhedron, body.center))
    assert not np.allclose(values, solid_trained, atol=1e-4)


def test_the_written_by_line_of_a_design_makes_the_same_die_again(run, tmp_path):
    """Every setting that shapes the design (the fill's included) is in its header, so the header reproduces it."""
    import shlex

    first = tmp_path / "first"
    code, _, err = run("design", "4df", "--model", "fast", "--validate-sims", "0", "--fill", "print", "--infill",
                       "0.3", "--min-margin", "0.04", "--out", first)  # fmt: skip
    assert code == 0, err
    (path,) = first.glob("*.toml")
    header = path.read_text().splitlines()[0]
    assert header.startswith("# Written by: diefab design ")
    assert "--infill 0.3" in header and "--min-margin 0.04" in header
    again = tmp_path / "again"
    code, _, err = run(*shlex.split(header.removeprefix("# Written by: diefab ")), "--validate-sims", "0",
                       "--out", again)  # fmt: skip
    assert code == 0, err
    a, b = load_design(path), load_design(again / path.name)
    assert a.fill == b.fill == Fill("print", infill=0.3)
    np.testing.assert_allclose(a.polyhedron.vertices, b.polyhedron.vertices, atol=1e-12)
