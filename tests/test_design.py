"""Designs, templates, labels and the TOML schema."""

from __future__ import annotations

import numpy as np
import pytest

from diefab.core.errors import DesignError
from diefab.dice.design import Design, design_to_toml, list_templates, load_design, parse_design
from diefab.models.probabilities import face_probabilities, value_probabilities


def test_templates_ship_and_load():
    names = {d.name for d in list_templates()}
    assert {"fudge-gem", "fudge-gem-solid-angle", "d6", "d8"} <= names
    paper = load_design("fudge-gem")
    assert paper.params == {"a": 1.18, "b": 0.52, "c": 0.72, "d": 1.41}
    fig4 = load_design("fudge-gem-solid-angle")
    assert fig4.params == {"a": 1.61, "b": 0.83, "c": 0.56, "d": 2.04}


@pytest.mark.parametrize("design", [d.name for d in list_templates()])
def test_every_template_is_stable_and_a_distribution(design):
    d = load_design(design)
    d.check_stable()
    probs = value_probabilities(d)
    assert np.all(probs > 0)
    assert probs.sum() == pytest.approx(1)


def test_gem_values_and_labels_follow_the_paper():
    d = load_design("fudge-gem")
    v = d.value_of
    assert v["f5"] == 0
    assert {abs(v["f6"]), abs(v["f8"])} == {1} and v["f6"] == -v["f8"]
    assert {abs(v["f7"]), abs(v["f9"])} == {2}
    assert {abs(v["f1"]), abs(v["f3"])} == {3}
    assert {abs(v["f2"]), abs(v["f4"])} == {4}
    assert d.label_face["f7"] == "f4" and d.label_face["f5"] is None
    assert d.label_of["f4"] == "+2"  # f4 carries f7's value
    assert d.label_of["f5"] == "4dF"  # the top never faces up: the template puts a logo there
    # the smallest faces carry +-2, as the paper says
    assert {d.label_of["f2"], d.label_of["f4"]} == {"\u22122", "+2"}


def test_d6_labels_are_on_opposite_faces():
    d = load_design("d6")
    poly = d.polyhedron
    for rest, up in d.label_face.items():
        np.testing.assert_allclose(poly.normals[poly.face_index(up)], -poly.normals[poly.face_index(rest)])
    np.testing.assert_allclose(value_probabilities(d), 1 / 6)
    np.testing.assert_allclose(value_probabilities(load_design("d8")), 1 / 8)


def test_toml_round_trip(tmp_path):
    d = load_design("fudge-gem").with_params(e=0.7)
    path = tmp_path / "x.toml"
    path.write_text(design_to_toml(d, comment="made by a test"))
    back = load_design(path)
    assert back.params == d.params
    assert back.values == d.values and back.labels == d.labels
    assert back.fill == d.fill and back.size_mm == d.size_mm
    np.testing.assert_allclose(face_probabilities(back), face_probabilities(d))


def test_shell_and_solid_fill_agree_roughly_as_the_paper_says():
    d = load_design("fudge-gem")
    from diefab.made.fill import Fill

    solid = value_probabilities(d)
    shell = value_probabilities(d, fill=Fill("shell"))
    assert np.abs(solid - shell).max() < 0.01  # "no substantial difference"


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ({"a": 2.5}, r"a=2.5 is outside \[1, 2\]"),
        ({"b": float("nan")}, "not a finite"),
        ({"z": 1.0}, "no parameter 'z'"),
        ({"e": 1.9}, "convex"),
    ],
)
def test_bad_parameters(override, message):
    with pytest.raises(DesignError, match=message):
        load_design("fudge-gem").with_params(**override)


def test_unstable_design_is_reported():
    d = load_design("fudge-gem").with_params(a=2.0, b=0.3, c=1.0, d=0.5)
    with pytest.raises(DesignError, match="unstable"):
        d.check_stable()


def test_unknown_template_and_family():
    with pytest.raises(DesignError, match="unknown template.*diefab design TARGET"):
        load_design("no-such-die")
    with pytest.raises(DesignError, match="unknown family"):
        parse_design('name = "x"\nfamily = "blob"\n')


def test_malformed_toml_names_file_and_line(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text('name = "x"\nfamily = "gem"\n[params\na = 1\n')
    with pytest.raises(DesignError, match=r"broken\.toml.*line 3"):
        load_design(path)


def test_schema_errors():
    with pytest.raises(DesignError, match="unknown key"):
        parse_design('name = "x"\nfamily = "gem"\ncolour = "red"\n')
    with pytest.raises(DesignError, match="has no value"):
        parse_design('name = "x"\nfamily = "gem"\n[params]\na=1.2\nb=0.5\nc=0.5\nd=1.5\n[values]\nf1 = 1\n')
    with pytest.raises(DesignError, match="does not exist"):
        Design("x", "gem", {"a": 1.2, "b": 0.5, "c": 0.5, "d": 1.5}, labels={"f10": "x"})


def test_convex_design_from_vertices_rejects_non_convex_input():
    text = """
name = "bad"
family = "convex"
target = "uniform:6"
vertices = [[-1,-1,-1],[1,-1,-1],[1,1,-1],[-1,1,-1],[-1,-1,1],[1,-1,1],[1,1,1],[-1,1,1],[0,0,0]]
"""
    with pytest.raises(DesignError, match="not a vertex"):
        parse_design(text)


def test_mesh_design(tmp_path):
    import trimesh

    trimesh.creation.box(extents=(2, 2, 2)).export(tmp_path / "cube.stl")
    text = """
name = "cube"
family = "mesh"
mesh = "cube.stl"
target = "uniform:6"
[values]
f1 = 1
f2 = 2
f3 = 3
f4 = 4
f5 = 5
f6 = 6
"""
    (tmp_path / "cube.toml").write_text(text)
    d = load_design(tmp_path / "cube.toml")
    np.testing.assert_allclose(value_probabilities(d), 1 / 6)
    assert d.mm_per_unit == pytest.approx(d.size_mm / 2)


@pytest.mark.parametrize(
    ("spec", "template"),
    [
        ("3dF", "3df"),
        ("binomial:4", "binomial-4"),
        ("UNIFORM:3", "uniform-3"),
        ("2d6", "2d6"),
        ("3d6", "3d6"),
        ("2d4", "2d4"),
        ("2d8", "2d8"),
        ("uniform:5", "uniform-5"),
        ("uniform:7", "uniform-7"),
    ],  # fmt: skip
)
def test_a_target_name_finds_its_ready_made_die(spec, template):
    from diefab.dice.design import list_templates, template_path

    if template not in {d.name for d in list_templates()}:
        pytest.skip(f"no template {template} in this checkout")
    assert template_path(spec).name == f"{template}.toml"
    d = load_design(spec)
    assert d.name == template and d.target_distribution.values.tolist() == sorted(set(d.values.values()))
