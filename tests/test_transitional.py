"""Transitional faces: faces a die cannot rest on carry no value and get probability 0 everywhere."""

from __future__ import annotations

import json

import numpy as np
import pytest

from diefab.core.errors import DesignError
from diefab.dice.design import Design, design_to_toml, parse_design
from diefab.dice.families import gem_polyhedron
from diefab.geometry.polyhedron import Polyhedron, resting_faces, solid_angles
from diefab.models.basins import RestBasins
from diefab.models.probabilities import MODELS, basin_shares, face_probabilities, value_probabilities

#: A gem too flat for its girdle faces f1-f4: the die rolls off them onto f5-f9.
TIPPY = gem_polyhedron({"a": 1.0, "b": 0.5, "c": 0.2, "d": 0.3})
RESTING_VALUES = {"f5": 0, "f6": 1, "f7": 2, "f8": 3, "f9": 4}


def tippy(**kwargs) -> Design:
    args = {"values": RESTING_VALUES, "target": "binomial:4", **kwargs}
    vertices = tuple(map(tuple, TIPPY.vertices.tolist()))
    faces = tuple(tuple(map(int, f)) for f in TIPPY.faces)
    return Design("tippy", "convex", vertices=vertices, faces=faces, **args)


def test_faces_without_a_value_are_transitional_named_or_not():
    assert tippy().transitional_faces == ("f1", "f2", "f3", "f4")
    named = tippy(transitional=["f1", "f3"])
    assert named.transitional_faces == ("f1", "f2", "f3", "f4") and named.transitional == ("f1", "f3")
    named.check_stable(0.01)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"values": {**RESTING_VALUES, "f1": 4}}, "unstable"),
        ({"values": {k: v for k, v in RESTING_VALUES.items() if k != "f6"}}, "f6 has no value"),
        ({"transitional": ["f6"], "values": {k: v for k, v in RESTING_VALUES.items() if k != "f6"}}, "named"),
        ({"transitional": ["f5"]}, "has a value"),
        ({"transitional": ["f77"]}, "does not exist"),
        ({"transitional": "f1"}, "list"),
    ],
)
def test_a_face_is_resting_or_transitional_never_both(kwargs, message):
    with pytest.raises(DesignError, match=message):
        tippy(**kwargs).check_stable(0.0)


def test_transitional_round_trips_through_toml():
    d = tippy(transitional=["f2"])
    again = parse_design(design_to_toml(d))
    assert again.transitional == ("f2",) and again.values == d.values


@pytest.mark.parametrize("model", sorted(MODELS))
def test_every_model_gives_transitional_faces_nothing(model):
    d = tippy()
    p = face_probabilities(d, model)
    assert np.all(p >= 0) and p.sum() == pytest.approx(1)
    assert np.all(p[~d.resting_mask()] == 0)
    assert value_probabilities(d, model).sum() == pytest.approx(1)


def test_solid_angle_of_a_transitional_face_goes_where_the_flow_ends():
    center = TIPPY.centroid
    omega = solid_angles(TIPPY, center) / (4 * np.pi)
    targets = RestBasins.of(TIPPY, center).targets
    p = MODELS["solid-angle"](TIPPY, center)
    expected = omega.copy()
    for g in np.flatnonzero(~resting_faces(TIPPY, center)):
        expected[targets[g]] += expected[g]
        expected[g] = 0
    assert np.allclose(p, expected)
    # the girdle faces are about as high as the top, which is the lowest rest: they tip on to it
    assert set(targets[:4].tolist()) == {4}


def test_a_simulated_die_never_lands_on_a_transitional_face():
    from diefab.physics.simulate import simulate

    d = tippy()
    result = simulate(d, 120, seed=3, workers=1)
    assert result.face_counts[:4].sum() == 0
    assert result.value_counts(d).sum() == result.landed > 100


def test_predict_reports_transitional_faces(run, tmp_path):
    path = tmp_path / "tippy.toml"
    path.write_text(design_to_toml(tippy(transitional=["f1"])))
    code, out, err = run("predict", path, "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["transitional"] == ["f1", "f2", "f3", "f4"] and data["transitional_named"] == ["f1"]
    faces = {f["name"]: f for f in data["faces"]}
    assert faces["f1"]["value"] is None and not faces["f1"]["resting"] and faces["f1"]["rolls_to"] == "f5"
    assert faces["f1"]["probability"] == 0 and sum(data["values"].values()) == pytest.approx(1)
    code, out, _ = run("predict", path)
    assert code == 0 and "4 transitional faces" in out


# ----------------------------------------------------------------------
# the basins model


def test_basins_model_of_a_cube_is_uniform_and_off_centre_matches_monte_carlo():
    cube = Polyhedron.from_points([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    p, bound = RestBasins.of(cube, np.zeros(3)).shares()
    assert bound < 2e-3 and np.allclose(p, 1 / 6, atol=bound)
    center = np.array([0.1, 0.2, -0.3])
    basins = RestBasins.of(cube, center)
    p, bound = basins.shares()
    d = np.random.default_rng(5).normal(size=(200_000, 3))
    mc = np.bincount(basins.face_of(d / np.linalg.norm(d, axis=1)[:, None]), minlength=6) / len(d)
    assert np.abs(p - mc).max() < 4 * np.sqrt(0.25 / len(d)) + bound
    assert p.sum() == pytest.approx(1)


def test_basins_model_gives_transitional_faces_nothing_and_sums_to_one():
    p, bound = basin_shares(TIPPY, TIPPY.centroid)
    assert np.all(p[~resting_faces(TIPPY, TIPPY.centroid)] == 0) and p.sum() == pytest.approx(1) and bound < 1e-2


def test_predict_basins_states_its_accuracy(run):
    code, out, err = run("predict", "fudge-gem", "--model", "basins", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert 0 <= data["error_bound"] < 1e-2 and sum(data["values"].values()) == pytest.approx(1)


# ----------------------------------------------------------------------
# many faces


def _rounded_cube(count: int = 16) -> Design:
    """A cube with rounded edges and corners: 6 faces it rests on and hundreds of transitional ones."""
    import itertools

    import trimesh

    sphere = trimesh.creation.uv_sphere(radius=0.25, count=[count, count]).vertices
    corners = np.array(list(itertools.product((-0.75, 0.75), repeat=3)))
    poly = Polyhedron.from_points((corners[:, None, :] + sphere[None]).reshape(-1, 3), strict=False)
    resting = resting_faces(poly, poly.centroid)
    values = {}
    for k in np.flatnonzero(resting):
        n = poly.normals[k]
        axis = int(np.argmax(np.abs(n)))
        values[poly.names[k]] = 1 + axis + (3 if n[axis] < 0 else 0)
    vertices = tuple(map(tuple, poly.vertices.tolist()))
    faces = tuple(tuple(map(int, f)) for f in poly.faces)
    return Design("rounded", "convex", vertices=vertices, faces=faces, values=values, target="uniform:6")


def test_a_die_with_hundreds_of_faces_predicts_and_rolls():
    from diefab.physics.simulate import simulate

    d = _rounded_cube()
    assert len(d.polyhedron.faces) >= 500 and len(d.values) == 6
    for model in MODELS:
        assert np.allclose(value_probabilities(d, model), 1 / 6, atol=0.03)
    result = simulate(d, 48, seed=0, workers=1)
    assert result.outcomes.dtype.itemsize >= 4 and result.landed + result.cocked + result.unsettled == 48
    assert result.value_counts(d).sum() == result.landed > 40
