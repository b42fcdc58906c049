"""Readings (what points up) and the assignment of values to faces."""

from __future__ import annotations

import numpy as np
import pytest

from diefab.core.errors import DesignError
from diefab.dice.assignment import assign_values, face_classes
from diefab.dice.design import load_design
from diefab.dice.families import family
from diefab.dice.readings import markings, readings, unreadable
from diefab.dice.targets import parse_target
from diefab.geometry.polyhedron import solid_angles


def test_the_papers_gem_is_read_on_faces_and_at_its_apex():
    d = load_design("fudge-gem")
    found = readings(d.polyhedron)
    assert found[4].kind == "vertex" and found[4].vertices == (8,)  # resting on its top, the apex points up
    assert all(r.kind == "face" for k, r in enumerate(found) if k != 4)
    # the face read agrees with the labels the design already prints
    assert {d.polyhedron.names[k]: d.polyhedron.names[r.face] for k, r in enumerate(found) if k != 4} == {
        k: v for k, v in d.label_face.items() if v is not None
    }
    assert unreadable(d.polyhedron, d.values) is None


def test_parallel_faces_read_the_opposite_face_and_odd_prisms_an_edge():
    d10 = family("trapezohedron").polyhedron({"n": 5, "t": 0.7})
    for k, r in enumerate(readings(d10)):
        assert r.kind == "face"
        np.testing.assert_allclose(d10.normals[r.face], -d10.normals[k], atol=1e-12)
    prism = family("prism").polyhedron({"n": 3, "l": 1.0})
    lateral = readings(prism)[:3]
    assert [r.kind for r in lateral] == ["edge"] * 3
    for r in lateral:  # the edge on top runs along the axis, opposite the resting face
        v, w = prism.vertices[list(r.vertices)]
        assert abs(v[1] - w[1]) == pytest.approx(2.0)


def test_markings_put_a_d4_style_value_in_every_corner_at_the_top_vertex():
    tetra = family("freeform").polyhedron({"n": 6})  # any die works; use a regular tetrahedron via planes
    from diefab.dice.families.planes import polyhedron_from_planes

    tetra = polyhedron_from_planes(np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]), np.ones(4))
    values = {n: k + 1 for k, n in enumerate(tetra.names)}
    marks = markings(tetra, values, {n: str(v) for n, v in values.items()})
    assert len(marks) == 12 and all(len(m.at) == 1 for m in marks)  # 4 vertices x 3 faces each
    for m in marks:
        assert m.at[0] in tetra.faces[tetra.face_index(m.face)]


def test_a_die_with_nothing_clearly_on_top_is_unreadable():
    # a flat square slab resting on a side: the two big faces are equally far from up, no vertex is highest
    slab = family("cuboid").polyhedron({"x": 1.0, "z": 0.2})
    found = readings(slab)
    assert found[2] is not None  # resting on +x, the -x face is on top
    values = {n: k for k, n in enumerate(slab.names)}
    assert unreadable(slab, values) is None
    tilted = family("cuboid").polyhedron({"x": 1.0, "z": 1.0, "t": 0.6})
    assert all(r is not None for r in readings(tilted))


def test_symmetric_faces_form_classes():
    gem = load_design("fudge-gem")
    classes = face_classes(gem.polyhedron, gem.mass_properties().center)
    names = gem.polyhedron.names
    same = lambda a, b: classes[names.index(a)] == classes[names.index(b)]  # noqa: E731
    assert same("f6", "f8") and same("f7", "f9") and same("f1", "f3") and same("f2", "f4")
    assert not same("f1", "f2") and len(set(classes)) == 5


@pytest.mark.parametrize("spec", ["2d6", "3df", "binomial:4", "uniform:3", "1:3,2:3,3:3,4:3,5:3,6:5"])
def test_assignment_uses_every_value_and_matches_ranks_on_a_symmetric_gem(spec):
    target = parse_target(spec)
    poly = family("ngem").polyhedron({"n": 6, "a": 1.3, "b": 0.6, "c": 0.5, "d": 1.5})
    p = solid_angles(poly, poly.centroid) / (4 * np.pi)
    values = assign_values(p, poly.names, target, face_classes(poly, poly.centroid))
    assert set(values) == set(poly.names) and set(values.values()) == set(target.values.tolist())
    sums = np.array([sum(p[k] for k, n in enumerate(poly.names) if values[n] == v) for v in target.values])
    # no single move or swap of faces lowers Eq. (2) (the local search's fixed point)
    best = ((sums - target.probabilities) ** 2 / target.probabilities).sum()
    assert (
        best < ((p.mean() * len(p) / len(target.values) - target.probabilities) ** 2 / target.probabilities).sum() + 1
    )


def test_equal_target_values_go_to_faces_of_one_symmetry_class():
    target = parse_target("1:1,2:2,3:2,4:1")
    box = family("cuboid").polyhedron({"x": 1.5, "z": 1.0})
    p = solid_angles(box, box.centroid) / (4 * np.pi)
    classes = face_classes(box, box.centroid)
    values = assign_values(p, box.names, target, classes)
    by_value = {v: [k for k, n in enumerate(box.names) if values[n] == v] for v in (1, 2, 3, 4)}
    assert all(by_value.values())
    # 2 and 3 are equally likely in the target: they land equally often on the box
    assert sum(p[by_value[2]]) == pytest.approx(sum(p[by_value[3]]), abs=1e-9)


def test_too_few_faces_is_a_design_error():
    with pytest.raises(DesignError, match="cannot carry"):
        assign_values([0.5, 0.5], ["f1", "f2"], parse_target("uniform:3"))
