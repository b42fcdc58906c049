"""The die as the engine holds it: one pyramid per face, each face exactly flat, together the whole die."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from diefab.dice.design import Design, load_design
from diefab.physics.shapes import flat_parts
from diefab.physics.simulate import PhysicsSettings, simulate
from diefab.physics.world import die_body
from diefab.search.symmetric import fair_shapes


def fair_die(faces: int) -> Design:
    """The steadiest fair die with `faces` faces that diefab offers, each face its own value."""
    ((family, params),) = fair_shapes(faces)
    return Design(
        f"fair-{faces}", family, params, values={f"f{k + 1}": k + 1 for k in range(faces)}, target=f"uniform:{faces}"
    )


@pytest.mark.parametrize("name", ["d6", "d20", "fudge-gem", "3df", "uniform-7", "3d6"])
def test_flat_parts_carry_each_face_once_flat_and_lie_in_the_die(name):
    d = load_design(name)
    body = die_body(d.polyhedron, d.mass_properties())
    parts = flat_parts(body.vertices, body.normals, body.faces)
    carried = sorted(f for q in parts for f in q.faces)
    assert carried == list(range(len(body.faces)))
    for q in parts:
        assert np.allclose(q.rotation.T @ q.rotation, np.eye(3), atol=1e-12)
        assert np.linalg.det(q.rotation) == pytest.approx(1.0)
        assert np.allclose(q.rotation[:, 2], body.normals[q.faces[0]], atol=1e-12)
        points = q.body_points()
        # inside the die (its faces' half-spaces)
        assert np.all(points @ body.normals.T <= body.heights + 1e-9)
        start = 0
        for f in q.faces:
            k = len(body.faces[f])
            z = q.points[start : start + k, 2]
            assert np.all(z == z[0])  # exactly one plane, whatever the rounding of the corners
            assert np.allclose(points[start : start + k], body.vertices[body.faces[f]], atol=1e-9)
            start += k
        assert q.points[0, 2] == 0.0
        if len(q.faces) == 2:
            assert body.normals[q.faces[0]] @ body.normals[q.faces[1]] == pytest.approx(-1.0)
        else:
            assert np.allclose(points[-1], 0.0, atol=1e-12)  # the apex is the centre of mass


def test_the_engine_folds_kites_and_not_triangles():
    """The engine rounds a hull's corners: a trapezohedron's kites fold; triangles and a cube's squares do not."""
    from diefab.physics.shapes import folded_faces
    from diefab.physics.world import import_pybullet

    for name, folded in (("uniform-5", True), ("2d6", False), ("d6", False)):
        d = load_design(name)
        faces = folded_faces(import_pybullet(), die_body(d.polyhedron, d.mass_properties()))
        assert faces.all() == faces.any() == folded, name


def chi2_uniform(counts) -> float:
    expected = counts.sum() / len(counts)
    return float(((counts - expected) ** 2 / expected).sum())


def test_a_fair_die_of_shallow_faces_lands_on_each_alike_with_flat_faces():
    """The 26-face trapezohedron's kites are shallow: the engine's one hull folds them, and they land unevenly."""
    d = fair_die(26)
    flat = simulate(d, 1500, seed=5, workers=2, settings=PhysicsSettings(flat_faces=True))
    hull = simulate(d, 1500, seed=5, workers=2)
    bound = chi2.ppf(0.999, len(flat.face_counts) - 1)
    assert flat.landed >= 1400 and hull.landed >= 1400
    assert chi2_uniform(flat.face_counts) < bound, flat.face_counts.tolist()
    assert chi2_uniform(hull.face_counts) > bound, hull.face_counts.tolist()


def test_flat_faces_leave_a_die_the_hull_keeps_flat_as_it_was():
    d = load_design("2d6")  # triangles only
    one = simulate(d, 96, seed=3, workers=1)
    two = simulate(d, 96, seed=3, workers=1, settings=PhysicsSettings(flat_faces=True))
    assert np.array_equal(one.outcomes, two.outcomes)
