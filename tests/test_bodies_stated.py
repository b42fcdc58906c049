"""Any closed mesh, mass from the real body, a stated centre of mass and inertia, near-coplanar merging."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from diefab.core.errors import DesignError
from diefab.dice.design import Design, design_to_toml, load_design, parse_design
from diefab.geometry.polyhedron import Polyhedron
from diefab.models.probabilities import MODELS, face_probabilities

REALROLLS = Path("/work/shared/realrolls")


def _l_shape(tmp_path, extra: str = "") -> Path:
    """A closed, non-convex L of two boxes (2 x 1 x 1 and 1 x 1 x 1 on top at one end), as a mesh design."""
    import trimesh

    a = trimesh.creation.box(extents=(2, 1, 1))
    b = trimesh.creation.box(extents=(1, 1, 1))
    b.apply_translation([-0.5, 0, 1])
    body = trimesh.boolean.union([a, b], engine="manifold")
    body.export(tmp_path / "l.stl")
    path = tmp_path / "l.toml"
    path.write_text(f'name = "l"\nfamily = "mesh"\nmesh = "l.stl"\nsize_mm = 20\ntarget = "1"\n{extra}\n')
    return path


def _with_resting_values(path: Path) -> Design:
    """Load a design whose values are filled in for the faces it can rest on."""
    from diefab.geometry.polyhedron import resting_faces

    text = path.read_text()
    mesh_design = _probe(path)
    poly = mesh_design.polyhedron
    resting = resting_faces(poly, mesh_design.mass_properties().center)
    values = "\n".join(f"{poly.names[k]} = 0" for k in np.flatnonzero(resting))
    return parse_design(text + "[values]\n" + values + "\n", base=path.parent)


def _probe(path: Path) -> Design:
    from diefab.geometry.meshes import ClosedMesh

    mesh = ClosedMesh.load(path.with_suffix(".stl"))
    n = len(Polyhedron.from_points(mesh.vertices, strict=False, merge_tolerance=0.01 / 10).faces)
    values = "\n".join(f"f{k} = 0" for k in range(1, n + 1))
    return parse_design(path.read_text() + "[values]\n" + values + "\n", base=path.parent)


def test_a_non_convex_mesh_rests_on_its_hull_with_the_mass_of_its_body(tmp_path):
    d = _with_resting_values(_l_shape(tmp_path))
    poly = d.polyhedron
    assert not d.body_mesh.is_convex()
    assert d.body_mesh.volume == pytest.approx(3 * (2 / 2) ** 3)  # longest side 2 units: no rescaling
    assert poly.volume > d.body_mesh.volume  # the hull fills the notch
    com = d.mass_properties().center
    # the L's own centroid: (2 * (0, 0, 0) + 1 * (-0.5, 0, 1)) / 3
    assert np.allclose(com, [-1 / 6, 0, 1 / 3], atol=1e-12)
    assert not np.allclose(com, poly.centroid, atol=1e-3)
    shell = d.mass_properties(d.fill.__class__(kind="shell")).center
    assert not np.allclose(shell, com, atol=1e-3)
    for model in MODELS:
        p = face_probabilities(d, model)
        assert p.sum() == pytest.approx(1) and np.all(p[~d.resting_mask()] == 0)


def test_print_fill_of_a_non_convex_mesh_lies_between_shell_and_solid(tmp_path):
    from diefab.made.mass import Fill

    d = _with_resting_values(_l_shape(tmp_path))
    solid = d.mass_properties(Fill("solid"))
    thin = d.mass_properties(Fill("print", wall_mm=0.2, infill=0.0))
    full = d.mass_properties(Fill("print", wall_mm=0.2, infill=1.0))
    assert np.allclose(full.center, solid.center) and full.mass == pytest.approx(solid.mass)
    shell = d.mass_properties(Fill("shell"))
    assert np.allclose(thin.center, shell.center)
    assert thin.mass == pytest.approx(shell.mass * 0.2 / d.mm_per_unit)


def test_a_stated_center_of_mass_and_inertia_replace_the_fills(tmp_path):
    d6 = load_design("d6")
    weighted = Design(**{**_fields(d6), "center_of_mass": (0.0, 0.0, -0.3)})
    assert np.allclose(weighted.mass_properties().center, [0, 0, -0.3])
    assert np.allclose(weighted.mass_properties().inertia, d6.mass_properties().inertia)
    p = face_probabilities(weighted, "solid-angle")
    assert p[0] > 1 / 6 + 0.05  # f1 is -z: heavier side down
    inertia = ((0.5, 0, 0), (0, 0.6, 0), (0, 0, 0.7))
    both = Design(**{**_fields(d6), "center_of_mass": (0.0, 0.0, -0.3), "inertia": inertia})
    props = both.mass_properties()
    assert np.allclose(props.inertia, props.mass * np.array(inertia))
    again = parse_design(design_to_toml(both))
    assert again.center_of_mass == (0.0, 0.0, -0.3) and again.inertia == inertia
    from diefab.physics.simulate import _body

    body = _body(both)
    assert np.allclose(body.center, [0, 0, -0.3]) and np.allclose(np.sort(body.inertia), [4, 4.8, 5.6])


@pytest.mark.parametrize(
    "extra, message",
    [
        ({"center_of_mass": (0, 0, 1.5)}, "not inside"),
        ({"center_of_mass": (0, 0)}, "three finite numbers"),
        ({"center_of_mass": (0, float("nan"), 0)}, "three finite numbers"),
        ({"inertia": ((1, 0, 0), (0, 1, 0), (0, 0, 3))}, "sum of the other two"),
        ({"inertia": ((1, 0.5, 0), (0, 1, 0), (0, 0, 1))}, "not symmetric"),
        ({"inertia": ((1, 0), (0, 1))}, "3x3"),
        ({"merge_tolerance_mm": -1}, "merge_tolerance_mm"),
    ],
)
def test_stated_body_is_checked(extra, message):
    with pytest.raises(DesignError, match=message):
        Design(**{**_fields(load_design("d6")), **extra}).mass_properties()


def _fields(d: Design) -> dict:
    return {"name": d.name, "family": d.family, "values": d.values, "target": d.target, "size_mm": d.size_mm,
            "vertices": d.vertices, "faces": d.faces}  # fmt: skip


def test_near_coplanar_hull_triangles_merge_within_the_tolerance():
    rng = np.random.default_rng(0)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    # a subdivided cube whose face points are off their planes by up to 1e-4
    grid = np.linspace(-1, 1, 5)
    face_points = [p for a in grid for b in grid for p in ([a, b, 1], [a, b, -1], [a, 1, b], [a, -1, b],
                                                           [1, a, b], [-1, a, b])]  # fmt: skip
    points = np.unique(np.vstack([corners, face_points]), axis=0)
    points += rng.uniform(-1e-4, 1e-4, points.shape)
    with pytest.raises(Exception):  # noqa: B017 -- exact merging: the faces are not planar, or many slivers
        poly = Polyhedron.from_points(points, strict=False)
        assert len(poly.faces) == 6
    merged = Polyhedron.from_points(points, strict=False, merge_tolerance=5e-4)
    assert len(merged.faces) == 6 and merged.volume == pytest.approx(8, rel=1e-3)
    assert np.all(np.abs(np.abs(merged.vertices) - 1) < 1e-3)


@pytest.mark.skipif(not REALROLLS.is_dir(), reason="real-rolls data not present")
def test_real_figurine_die_loads_with_its_stated_body():
    from diefab.physics.realrolls import load_real_rolls

    rolls = load_real_rolls(REALROLLS / "dragon_d3.json")
    text = rolls.design_files()["dragon_d3.toml"]
    d = parse_design(text)
    assert d.transitional_faces and sorted(d.support) == [1, 2, 3]
    hull_centroid_mm = d.polyhedron.centroid * d.mm_per_unit
    com_mm = d.mass_properties().center * d.mm_per_unit
    assert np.linalg.norm(com_mm - hull_centroid_mm) == pytest.approx(1.196, abs=0.05)  # the data's offset
    p = dict(zip(d.support, face_probabilities(d, "solid-angle") @ _value_matrix(d)))
    assert rolls.tvd(p) < 0.1


def _value_matrix(d: Design) -> np.ndarray:
    m = np.zeros((len(d.polyhedron.faces), len(d.support)))
    for k, name in enumerate(d.polyhedron.names):
        if name in d.values:
            m[k, d.support.index(d.values[name])] = 1
    return m


def test_grouped_tvd_relabels_only_within_a_group():
    from diefab.physics.realrolls import RealRolls, grouped_tvd

    q = np.array([0.1, 0.4, 0.3, 0.2])
    swapped = q[[3, 2, 1, 0]]
    assert grouped_tvd(swapped, q, (0, 1, 2, 3), ((0, 3), (1, 2))) == pytest.approx(0)
    assert grouped_tvd(swapped, q, (0, 1, 2, 3), ((0, 3),)) == pytest.approx(0.1)
    rolls = RealRolls(name="d3", outcomes=(1, 2, 3), counts=np.array([100, 100, 100]), groups=((1, 2),))
    assert rolls.tvd({1: 0.5, 2: 0.25, 3: 0.25}) == pytest.approx(1 / 6)
    assert rolls.tvd({1: 1 / 3, 2: 1 / 3, 3: 0.3, 0: 1 / 30}) == pytest.approx(1 / 30)  # mass on no outcome
    # sampling noise: about sqrt((K - 1) / (2 pi N)) for K outcomes and N rolls
    assert 0.8 < rolls.noise_tvd(samples=4000) / np.sqrt(2 / (2 * np.pi * 300)) < 1.2
