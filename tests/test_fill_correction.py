"""The fast model per fill: each made fill's learned correction of the gem, and its invariants."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from diefab.core.errors import DesignError
from diefab.dice.design import load_design
from diefab.dice.families import GEM
from diefab.geometry.polyhedron import face_margins
from diefab.made.mass import Fill, mass_properties
from diefab.models.fast import (
    FILL_COORDINATES,
    FILL_LAYERS,
    FillCorrection,
    body_excess,
    fast_model,
    fill_discrepancy,
    gem_discrepancy,
    landing_probabilities,
)

MIRRORS = ((0, 2), (1, 3), (5, 7), (6, 8))


def random_gems(k: int, seed: int):
    """`k` random gems of the family box that rest on every face as shells (cheap bodies)."""
    base = load_design("fudge-gem")
    bounds = GEM.bounds(list("abcde"))
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < k:
        x = bounds[:, 0] + rng.random(5) * (bounds[:, 1] - bounds[:, 0])
        try:
            d = base.with_params(**dict(zip("abcde", x.tolist())))
            if d.margins(Fill("shell")).min() > 0.02:
                out.append(d)
        except DesignError:
            continue
    return out


def test_each_made_fill_has_its_own_correction_learned_at_its_default_settings():
    for kind in FILL_LAYERS:
        layer = fill_discrepancy(kind)
        assert layer is not None and layer.kind == kind
        assert layer.info["fill"] == Fill(kind=kind).to_mapping()
        assert layer.coordinates in FILL_COORDINATES and layer.penalty >= 0
        assert layer.margins.min() > 0 and layer.excess.min() > 0
        assert len(layer.points) >= 20
    assert fill_discrepancy("solid") is None


def test_the_solid_fill_is_unchanged_by_the_fill_layers():
    for d in [load_design("fudge-gem-sim"), *random_gems(3, 1)]:
        body = d.mass_properties(Fill())
        poly, center, inertia = d.polyhedron, body.center, body.inertia / body.mass
        margins = face_margins(poly, center)
        solid = gem_discrepancy().correct(landing_probabilities(poly, center), d.params, margins)
        assert np.array_equal(fast_model(poly, center), solid)
        assert np.allclose(fast_model(poly, center, fill=Fill(), inertia=inertia), solid, atol=1e-12)


@pytest.mark.parametrize("kind", FILL_LAYERS)
def test_a_made_fill_whose_body_is_the_solid_gets_the_solid_prediction(kind):
    for d in [load_design("fudge-gem-sim"), *random_gems(3, 2)]:
        body = mass_properties(d.polyhedron)
        poly, center = d.polyhedron, body.center
        solid = fast_model(poly, center)
        assert np.allclose(fast_model(poly, center, fill=Fill(kind), inertia=body.inertia / body.mass), solid,
                           atol=1e-12)  # fmt: skip
        assert np.array_equal(fast_model(poly, center, fill=Fill(kind)), solid)  # no inertia: the solid's
    # a print at 100 % infill without labels is the solid, so it rolls like it
    d = load_design("fudge-gem-sim")
    full = d.mass_properties(Fill("print", infill=1.0, labels=False))
    assert abs(body_excess(d.polyhedron, full.inertia / full.mass)) < 1e-12
    assert np.allclose(fast_model(d.polyhedron, full.center, fill=Fill("print", infill=1.0, labels=False),
                                  inertia=full.inertia / full.mass), fast_model(d.polyhedron, full.center),
                       atol=1e-12)  # fmt: skip


@pytest.mark.parametrize("kind", FILL_LAYERS)
def test_fill_predictions_are_distributions_that_keep_mirror_images_equal(kind):
    """Any body (here the shell's, on the mirror planes) with any layer: >= 0, sums to 1, mirror faces equal."""
    for d in random_gems(12, 3):
        body = d.mass_properties(Fill("shell"))
        p = fast_model(d.polyhedron, body.center, fill=Fill(kind), inertia=body.inertia / body.mass)
        assert np.all(p >= 0) and p.sum() == pytest.approx(1.0, abs=1e-12)
        for i, j in MIRRORS:
            assert p[i] == pytest.approx(p[j], abs=1e-9)


@pytest.mark.parametrize("kind", FILL_LAYERS)
def test_the_learned_residual_sums_to_zero_keeps_mirrors_and_is_proportional_to_the_excess(kind):
    layer = fill_discrepancy(kind)
    d = random_gems(1, 4)[0]
    body = d.mass_properties(Fill("shell"))
    margins = face_margins(d.polyhedron, body.center)
    p = fast_model(d.polyhedron, body.center, inertia=body.inertia / body.mass)
    r = layer.residual(d.params, margins, p, 0.3)
    assert abs(r.sum()) < 1e-7  # the stored residuals are rounded to 1e-8
    for i, j in MIRRORS:
        assert r[i] == r[j]
    assert np.allclose(layer.residual(d.params, margins, p, 0.6), 2 * r, atol=1e-15)


def test_a_body_no_further_out_than_the_solid_gets_no_correction():
    layer = fill_discrepancy("paper")
    d = load_design("fudge-gem-sim")
    body = mass_properties(d.polyhedron)
    margins = face_margins(d.polyhedron, body.center)
    p = fast_model(d.polyhedron, body.center)
    for excess in (0.0, -0.2):
        assert np.array_equal(layer.correct(p, d.params, margins, excess), p)
    outside = dict(d.params, a=GEM.bounds(["a"])[0, 1] + 0.5)
    assert np.array_equal(layer.correct(p, outside, margins, 0.5), p)


def synthetic(n: int, seed: int):
    """Training arrays whose residual is exactly ``s / mean(s) * W @ phi`` for the shape coordinates."""
    rng = np.random.default_rng(seed)
    bounds = GEM.bounds(list("abcde"))
    points = bounds[:, 0] + rng.random((n, 5)) * (bounds[:, 1] - bounds[:, 0])
    margins = 0.05 + rng.random((n, 9))
    base = rng.dirichlet(np.full(9, 5.0), n)
    excess = 0.4 + 0.3 * rng.random(n)
    unit = (points - bounds[:, 0]) / (bounds[:, 1] - bounds[:, 0])
    phi = np.hstack([np.ones((n, 1)), unit])
    w = 1e-3 * rng.normal(size=(6, 5))
    w[:, 2] = -(2 * w[:, 0] + 2 * w[:, 1] + 2 * w[:, 3] + 2 * w[:, 4])  # classes weigh 2, 2, 1, 2, 2 faces
    r5 = (excess / excess.mean())[:, None] * (phi @ w)
    residual = r5[:, [0, 1, 0, 1, 2, 3, 4, 3, 4]]
    return points, margins, base, excess, base + residual, residual


def test_learn_recovers_an_exact_linear_residual_and_survives_json():
    points, margins, base, excess, freq, residual = synthetic(40, 5)
    fit = FillCorrection.learn("paper", points, margins, base, excess, freq, coordinates="shape", penalty=0.0)
    for i in (0, 17):
        params = dict(zip("abcde", points[i]))
        assert np.allclose(fit.residual(params, margins[i], base[i], excess[i]), residual[i], atol=1e-10)
    back = FillCorrection.from_json(fit.to_json())
    assert (back.kind, back.coordinates, back.penalty) == ("paper", "shape", 0.0)
    params = dict(zip("abcde", points[3]))
    assert np.allclose(back.residual(params, margins[3], base[3], excess[3]), residual[3], atol=1e-7)
    # a large penalty leaves only the constant: the least-squares residual per unit of relative excess
    flat = FillCorrection.learn("paper", points, margins, base, excess, freq, coordinates="shape", penalty=1e9)
    t = excess / excess.mean()
    assert np.allclose(flat.residual(params, margins[3], base[3], excess.mean()), t @ residual / (t @ t), atol=1e-9)


def test_the_kernel_term_learns_what_a_linear_function_cannot_and_keeps_the_invariants():
    """A residual quadratic in d: the kernel term follows it, sums to 0 and survives JSON."""
    points, margins, base, excess, _, _ = synthetic(120, 7)
    unit = (points - GEM.bounds(list("abcde"))[:, 0]) / np.ptp(GEM.bounds(list("abcde")), axis=1)
    bowl = 0.08 * (unit[:, 3] - 0.5) ** 2  # class f5 gains it, f1 (two faces) gives it back
    r5 = (excess / excess.mean())[:, None] * np.outer(bowl, [-0.5, 0.0, 1.0, 0.0, 0.0])
    residual = r5[:, [0, 1, 0, 1, 2, 3, 4, 3, 4]]
    freq = base + residual
    kw = {"coordinates": "shape", "penalty": 1e-3}
    linear = FillCorrection.learn("paper", points[:100], margins[:100], base[:100], excess[:100], freq[:100], **kw)
    kernel = FillCorrection.learn("paper", points[:100], margins[:100], base[:100], excess[:100], freq[:100], **kw,
                                  kernel_length=1.0, kernel_penalty=1e-5)  # fmt: skip
    errors = {"linear": [], "kernel": []}
    for i in range(100, 120):
        params = dict(zip("abcde", points[i]))
        for name, fit in (("linear", linear), ("kernel", kernel)):
            r = fit.residual(params, margins[i], base[i], excess[i])
            errors[name].append(np.abs(r - residual[i]).max())
            assert abs(r.sum()) < 1e-12
            for j, k in MIRRORS:
                assert r[j] == r[k]
    assert np.mean(errors["kernel"]) < 0.5 * np.mean(errors["linear"])
    back = FillCorrection.from_json(kernel.to_json())
    assert (back.kernel_length, back.kernel_penalty) == (1.0, 1e-5)
    params = dict(zip("abcde", points[110]))
    assert np.allclose(back.residual(params, margins[110], base[110], excess[110]),
                       kernel.residual(params, margins[110], base[110], excess[110]), atol=1e-7)  # fmt: skip
    assert np.allclose(kernel.residual(params, margins[110], base[110], 0.6),
                       2 * kernel.residual(params, margins[110], base[110], 0.3), atol=1e-15)  # fmt: skip


@pytest.mark.parametrize(
    "change, words",
    [
        ({"kind": "solid"}, "fill kind"),
        ({"kernel_length": -1.0}, "kernel_length"),
        ({"kernel_length": 0.5, "kernel_penalty": 0.0}, "kernel_penalty"),
        ({"kernel_length": 0.5, "kernel_penalty": 1e-3, "coordinates": "constant"}, "kernel term"),
        ({"coordinates": "cubic"}, "coordinates"),
        ({"penalty": -1.0}, "penalty"),
        ({"excess": "zero"}, "excess"),
        ({"margins": "unstable"}, "stable"),
        ({"points": "short"}, "points"),
        ({"n": 5}, "at least"),
    ],
)
def test_learn_checks_its_input(change, words):
    n = change.get("n", 20)
    points, margins, base, excess, freq, _ = synthetic(n, 6)
    kw = {"coordinates": change.get("coordinates", "physics"), "penalty": change.get("penalty", 1.0)}
    kw |= {k: change[k] for k in ("kernel_length", "kernel_penalty") if k in change}
    if change.get("excess") == "zero":
        excess = excess * 0
    if change.get("margins") == "unstable":
        margins = margins - 2
    if change.get("points") == "short":
        points = points[:, :4]
    with pytest.raises(DesignError, match=words):
        FillCorrection.learn(change.get("kind", "paper"), points, margins, base, excess, freq, **kw)


@pytest.mark.parametrize("kind", ["paper", "print"])
def test_the_packaged_correction_was_learned_on_the_bodies_the_code_builds(kind):
    """A changed body model (a new net layout moves the glue tabs) makes the learned counts stale."""
    layer = fill_discrepancy(kind)
    base = replace(load_design("fudge-gem"), fill=Fill(kind))
    recorded = layer.info["bodies"][0]
    body = base.with_params(**recorded["params"]).mass_properties()
    assert np.allclose(body.center, recorded["center"], atol=1e-6)
    assert np.allclose(body.inertia / body.mass, recorded["inertia"], atol=1e-6)
