"""A die of 542 faces (a rounded cube: 6 faces it rests on) through predict, validate, net and stl."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_transitional import _rounded_cube

from diefab.dice.design import design_to_toml

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def big(tmp_path_factory):
    design = _rounded_cube(16)
    path = tmp_path_factory.mktemp("big") / "rounded.toml"
    path.write_text(design_to_toml(design))
    assert len(design.polyhedron.faces) >= 500
    return design, path


@pytest.mark.parametrize("model", ["solid-angle", "basins", "fast"])
def test_predict(big, run, model):
    _, path = big
    code, out, err = run("predict", path, "--model", model, "--json")
    assert code == 0, err
    values = json.loads(out)["values"]
    assert len(values) == 6 and np.allclose(list(values.values()), 1 / 6, atol=0.03)


def test_validate(big, run):
    _, path = big
    code, out, err = run("validate", path, "--sims", "40", "--workers", "1", "--seed", "3", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["n"] == 40 and sum(data["counts"].values()) == data["landed"] > 30


def test_net_keeps_every_face_and_overlaps_nothing(big):
    from shapely import STRtree
    from shapely.geometry import Polygon

    from diefab.fabricate.net import design_net

    design, _ = big
    poly = design.polyhedron
    net = design_net(design)
    scale = net.mm_per_unit
    for k, ring in enumerate(net.faces):  # congruent: every side keeps its length
        sides = np.linalg.norm(np.roll(ring, -1, axis=0) - ring, axis=1)
        solid = poly.vertices[poly.faces[k]] * scale
        assert np.allclose(sides, np.linalg.norm(np.roll(solid, -1, axis=0) - solid, axis=1), atol=1e-6)
    assert len(net.fold_edges) == len(poly.faces) - net.n_pieces
    assert sorted(t.edge for t in net.tabs) == sorted(net.cut_edges.tolist())
    for piece in range(net.n_pieces):
        shapes = [Polygon(net.faces[k]) for k in np.flatnonzero(net.face_piece == piece)]
        shapes += [Polygon(t.polygon) for t in net.tabs if net.face_piece[t.face] == piece]
        tree = STRtree(shapes)
        for i, j in zip(*tree.query(shapes, predicate="intersects")):
            if i < j:
                assert shapes[i].intersection(shapes[j]).area < 1e-6


def test_stl_is_sound(big):
    from diefab.fabricate.stl import build_solid

    design, _ = big
    solid = build_solid(design)
    assert solid.report["watertight"] and solid.report["bodies"] == 1 and solid.report["genus"] == 0
    assert sorted(solid.report["labels"].values()) == ["1", "2", "3", "4", "5", "6"]


def test_net_command_writes_the_net(big, run, tmp_path):
    from dataclasses import replace

    from diefab.made.mass import Fill

    design, _ = big
    path = tmp_path / "rounded.toml"  # glued edge to edge: 5 mm tabs would weigh enough to tip it onto f145
    path.write_text(design_to_toml(replace(design, fill=Fill("paper", tabs=False))))
    code, out, err = run("net", path, "--tab-width", "0", "--format", "svg", "--out", tmp_path, "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["pieces"] >= 1 and (tmp_path / "rounded-net.svg").is_file()
