"""Die families: the registry, exact reproductions, symmetric cases, bounds and reference lengths."""

from __future__ import annotations

import numpy as np
import pytest

from diefab.core.errors import DesignError
from diefab.dice.design import Design
from diefab.dice.families import GEM, NGEM, families, family
from diefab.geometry.polyhedron import solid_angles


def _probs(poly):
    return solid_angles(poly, poly.centroid) / (4 * np.pi)


EXAMPLES = {
    "gem": {"a": 1.18, "b": 0.52, "c": 0.72, "d": 1.41},
    "ngem": {"n": 5, "a": 1.3, "b": 0.6, "c": 0.5, "d": 1.6, "sx": 0.2},
    "prism": {"n": 5, "l": 1.5, "k": 0.8, "h2": 1.2},
    "bipyramid": {"n": 4, "h": 1.2, "g": 0.9},
    "trapezohedron": {"n": 5, "t": 0.7, "u": 0.9},
    "cuboid": {"x": 1.5, "z": 0.8, "t": 0.2},
    "freeform": {"n": 12, "h3": 1.2, "h7": 0.8},
    "icosahedral": {"d": 1.02},
}


def test_every_buildable_family_is_registered_with_an_example():
    assert {f.name for f in families() if f.build is not None} == set(EXAMPLES)


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_family_builds_a_convex_die_with_its_reference_and_free_parameters(name):
    fam = family(name)
    poly = fam.polyhedron(EXAMPLES[name])
    assert poly.volume > 0
    assert np.all(_probs(poly) > 0) and _probs(poly).sum() == pytest.approx(1)
    assert fam.length(poly) > 0 and fam.reference and fam.readability
    free = fam.free_names(EXAMPLES[name])
    assert free and not any(p.integer for p in fam.parameters if p.name in free)
    # moving every free parameter a little keeps the faces and their names
    lo, hi = fam.bounds(free).T
    params = fam.complete(EXAMPLES[name])
    moved = {**params, **{n: float(np.clip(params[n] * 1.01, a, b)) for n, a, b in zip(free, lo, hi)}}
    assert fam.polyhedron(moved).names == poly.names


def test_ngem_with_four_sides_is_the_papers_gem_exactly():
    for params in (EXAMPLES["gem"], {"a": 1.61, "b": 0.83, "c": 0.56, "d": 2.04, "e": 1.1}):
        gem = GEM.polyhedron(params)
        ngem = NGEM.polyhedron({**params, "n": 4})
        assert np.array_equal(gem.vertices, ngem.vertices)
        assert all(np.array_equal(f, g) for f, g in zip(gem.faces, ngem.faces)) and gem.names == ngem.names


def test_ngem_has_2n_plus_1_faces_and_mirror_symmetry_until_the_apex_moves():
    for n in range(3, 9):
        poly = NGEM.polyhedron({"n": n, "a": 1.0, "b": 0.6, "c": 0.5, "d": 1.5})
        assert len(poly.faces) == 2 * n + 1
        p = _probs(poly)
        np.testing.assert_allclose(np.sort(p[:n]), np.full(n, p[0]), atol=1e-12)  # regular girdle: equal sides
    shifted = _probs(NGEM.polyhedron({**EXAMPLES["ngem"], "sx": 0.5}))
    assert np.ptp(shifted[6:]) > 0.01


@pytest.mark.parametrize(
    ("name", "params", "faces"),
    [
        ("bipyramid", {"n": 4, "h": 1.0}, 8),  # the octahedron
        ("bipyramid", {"n": 6, "h": 2.0}, 12),
        ("trapezohedron", {"n": 5, "t": 0.7}, 10),  # the d10
        ("cuboid", {"x": 1.0, "z": 1.0}, 6),  # the cube
        ("prism", {"n": 6, "l": 1.0}, 8),
    ],
)
def test_symmetric_members_are_fair_on_each_face_class(name, params, faces):
    poly = family(name).polyhedron(params)
    p = _probs(poly)
    assert len(p) == faces
    if name in ("bipyramid", "trapezohedron") or name == "cuboid":
        np.testing.assert_allclose(p, 1 / faces, atol=1e-12)
    else:
        np.testing.assert_allclose(p[:6], p[0], atol=1e-12)


def test_reference_lengths_are_face_to_face_where_faces_are_parallel():
    assert family("cuboid").length(family("cuboid").polyhedron({"x": 3.0, "z": 0.5})) == 2.0
    prism = family("prism").polyhedron({"n": 6, "l": 2.0, "h1": 1.2, "h4": 0.9})
    assert family("prism").length(prism) == pytest.approx(2.1)
    d8 = family("bipyramid").polyhedron({"n": 4, "h": 1.0})
    assert family("bipyramid").length(d8) == pytest.approx(2 / np.sqrt(3))
    d = Design("box", "cuboid", {"x": 1.0, "z": 1.0}, values={f"f{k}": k for k in range(1, 7)},
               target="uniform:6", size_mm=16.0)  # fmt: skip
    assert d.mm_per_unit == pytest.approx(8.0)


def test_taper_makes_the_bottom_of_a_cuboid_likelier_than_its_top():
    p = _probs(family("cuboid").polyhedron({"x": 1.0, "z": 1.0, "t": 0.3}))
    assert p[0] > p[2] > p[1] and p[2] == pytest.approx(p[5])


@pytest.mark.parametrize(
    ("name", "params", "message"),
    [
        ("ngem", {"n": 4.5, "a": 1, "b": 0.5, "c": 0.5, "d": 1}, "whole number"),
        ("ngem", {"n": 13, "a": 1, "b": 0.5, "c": 0.5, "d": 1}, "outside"),
        ("prism", {"n": 4, "l": 1, "h6": 1.0}, "has no h6"),
        ("freeform", {"n": 12, **{f"h{k}": 0.5 if 4 <= k <= 9 else 1.5 for k in range(1, 13)}}, "f2 does not cut"),
        ("cuboid", {"x": 1.0}, "needs parameter 'z'"),
        ("bipyramid", {"n": 4, "h": True}, "not a number"),
    ],
)
def test_bad_parameters_are_design_errors(name, params, message):
    with pytest.raises(DesignError, match=message):
        family(name).polyhedron(params)


@pytest.mark.parametrize("scale", [0.01, 1.0, 100.0, 1e6])
def test_a_convex_die_lands_the_same_whatever_the_units_of_its_vertices(scale):
    # the throw is defined in model units, so a convex design is brought to the model size (the longest side of
    # its box 2) whatever its vertices' units; size_mm alone gives its real size
    from diefab.models.probabilities import face_probabilities

    box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1.2, 1.2)])
    faces = ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3))

    def die(points):
        return Design("box", "convex", vertices=tuple(map(tuple, points.tolist())), faces=faces, size_mm=24.0,
                      values={f"f{k}": k for k in range(1, 7)}, target="uniform:6")  # fmt: skip

    reference, scaled = die(box / 1.2), die(box * scale)
    assert np.ptp(scaled.polyhedron.vertices, axis=0).max() == pytest.approx(2.0)
    np.testing.assert_allclose(scaled.polyhedron.vertices, reference.polyhedron.vertices, atol=1e-12)
    assert scaled.mm_per_unit == pytest.approx(reference.mm_per_unit)
    for model in ("fast", "basins"):
        np.testing.assert_allclose(face_probabilities(scaled, model), face_probabilities(reference, model), atol=1e-9)
