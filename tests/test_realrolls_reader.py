"""Real-rolls files: their units, and designs whose listed faces are planar only to a printer's precision."""

from __future__ import annotations

import json

import numpy as np
import pytest

from diefab.core.errors import DesignError
from diefab.dice.design import Design, parse_design
from diefab.models.probabilities import face_probabilities
from diefab.physics.realrolls import load_real_rolls

BOX_MM = np.array([20.0, 16.0, 12.0])


def _box_file(tmp_path, units: str | None = "mm", scale: float = 1.0, **geometry) -> str:
    """A real-rolls file of a 20 x 16 x 12 mm cuboid (value 1 on the x faces, 2 on y, 3 on z), in `units`.

    `scale` is the number of `units` per mm of the box.
    """
    from scipy.spatial import ConvexHull

    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * BOX_MM / 2
    hull = ConvexHull(corners)
    normals = hull.equations[:, :3]
    axis = np.argmax(np.abs(normals), axis=1)
    volume = float(np.prod(BOX_MM))
    inertia = volume * np.diag([BOX_MM[[1, 2]] @ BOX_MM[[1, 2]], BOX_MM[[0, 2]] @ BOX_MM[[0, 2]],
                                BOX_MM[[0, 1]] @ BOX_MM[[0, 1]]]) / 12  # fmt: skip
    faces = {str(a + 1): np.flatnonzero(axis == a).tolist() for a in range(3)}
    geo = {"hull_vertices": (corners * scale).tolist(), "hull_faces": hull.simplices.tolist(), **geometry}
    if units is not None:
        geo["units"] = units
    data = {
        "shape": "box",
        "physical": {"outcomes": [1, 2, 3], "counts": [30, 30, 40]},
        "geometry": geo,
        "fabricated_body": {"volume": volume * scale**3, "com": [0.0, 0.0, 0.0],
                            "inertia_about_com_unit_density": (inertia * scale**5).tolist()},
        "outcome_faces": faces,
        "outcome_stable_faces": faces,
    }  # fmt: skip
    path = tmp_path / f"box-{units}-{scale:g}.json"
    path.write_text(json.dumps(data))
    return path


def _design(path) -> Design:
    return parse_design(load_real_rolls(path).design_files()["box.toml"])


@pytest.mark.parametrize(("units", "scale", "extra"), [("cm", 0.1, {}), ("m", 1e-3, {}), ("in", 1 / 25.4, {}),
                                                       ("model", 0.1, {"size_mm": 20.0}),
                                                       (None, 1.0, {})])  # fmt: skip
def test_units_give_the_same_die_as_millimetres(tmp_path, units, scale, extra):
    ref = _design(_box_file(tmp_path))
    d = _design(_box_file(tmp_path, units, scale, **extra))
    assert d.size_mm == pytest.approx(ref.size_mm, rel=1e-9)
    assert d.mm_per_unit == pytest.approx(ref.mm_per_unit, rel=1e-9)
    assert d.values == ref.values
    np.testing.assert_allclose(d.mass_properties().center, ref.mass_properties().center, atol=1e-12)
    np.testing.assert_allclose(np.array(d.inertia), np.array(ref.inertia), rtol=1e-9)
    np.testing.assert_allclose(face_probabilities(d, "basins"), face_probabilities(ref, "basins"), atol=1e-9)


def test_a_die_in_centimetres_keeps_faces_a_millimetre_tolerance_would_merge_if_read_as_mm(tmp_path):
    # a 20 mm box in cm spans 2 units: read as mm it would be a 2 mm die, merged at 0.05 mm = 2.5 % of its size
    d = _design(_box_file(tmp_path, "cm", 0.1))
    assert d.size_mm == pytest.approx(20.0)  # face to face along the longest side
    assert len(d.polyhedron.faces) == 6


@pytest.mark.parametrize(("units", "extra", "message"), [
    ("furlong", {}, "geometry.units = 'furlong' is not one of"),
    ("model", {}, "needs geometry.size_mm"),
    ("mm", {"size_mm": 20.0}, "geometry.size_mm is for model units"),
    ("model", {"size_mm": -1.0}, "geometry.size_mm"),
])  # fmt: skip
def test_bad_units_are_refused_by_name(tmp_path, units, extra, message):
    with pytest.raises(DesignError, match=message):
        load_real_rolls(_box_file(tmp_path, units, 1.0, **extra))


@pytest.mark.parametrize("scale", [1e-4, 1000.0])
def test_a_hull_no_die_spans_is_refused_by_its_span(tmp_path, scale):
    with pytest.raises(DesignError, match="hull_vertices span"):
        load_real_rolls(_box_file(tmp_path, "mm", scale))


def test_a_binomial_target_of_any_size_is_read():
    from diefab.physics.realrolls import _designed_target

    np.testing.assert_allclose(_designed_target("binom3", (0, 1, 2, 3)), [1 / 8, 3 / 8, 3 / 8, 1 / 8])
    assert _designed_target("binom2000", (1000,))[0] == pytest.approx(0.01784, rel=1e-3)  # about 1/sqrt(pi N / 2)


# ---------------------------------------------------------------------------
# listed faces planar within a tolerance in mm

CUBE = [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
CUBE_FACES = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]


def _cube(offset: float, size_mm: float = 20.0, **kw) -> Design:
    """A listed-faces cube (edge 2 units) with vertex 7 pushed out along x by `offset` units, off face f2's plane."""
    vertices = np.array(CUBE, dtype=float)
    vertices[7, 0] += offset
    return Design("cube", "convex", vertices=tuple(map(tuple, vertices.tolist())), faces=tuple(map(tuple, CUBE_FACES)),
                  size_mm=size_mm, target="1", values={f"f{k}": 1 for k in range(1, 7)}, **kw)  # fmt: skip


def _mm_per_listed_unit(d: Design) -> float:
    """Millimetres per unit of the vertices as listed (the die is brought to a longest side of 2 model units)."""
    return d.mm_per_unit * 2 / np.ptp(np.array(d.vertices), axis=0).max()


def test_listed_faces_within_the_default_flatness_load_and_report_it():
    d = _cube(0.02)
    flat = d.face_flatness_mm
    assert set(flat) == set(d.polyhedron.names)
    # a quad with one corner off by h has its best-fit plane h / 4 from every corner
    assert flat["f2"] == pytest.approx(0.02 / 4 * _mm_per_listed_unit(d), rel=1e-3)
    assert 0.02 < flat["f2"] < 0.05
    assert max(v for k, v in flat.items() if k != "f2") < 1e-9  # the faces the vertex moved within stay planar
    assert face_probabilities(d, "solid-angle").sum() == pytest.approx(1)


def test_exact_faces_report_zero_flatness():
    assert max(_cube(0.0).face_flatness_mm.values()) < 1e-12


def test_a_face_beyond_the_tolerance_is_refused_with_its_distance_in_mm():
    with pytest.raises(DesignError, match=r"face f2 is 0\.14\d* mm off its plane, beyond the 0\.05 mm"):
        _cube(0.1).polyhedron  # noqa: B018


def test_the_stated_tolerance_applies_to_listed_faces_and_scales_with_the_die():
    d = _cube(0.1, merge_tolerance_mm=0.2)
    assert d.face_flatness_mm["f2"] == pytest.approx(0.1 / 4 * _mm_per_listed_unit(d), rel=1e-3)
    with pytest.raises(DesignError, match="mm off its plane"):
        _cube(0.02, merge_tolerance_mm=0.01).polyhedron  # noqa: B018
    # the same shape is 10x fewer millimetres off on a die 10x smaller: within the default tolerance
    small = _cube(0.1, size_mm=2.0)
    assert small.face_flatness_mm["f2"] == pytest.approx(d.face_flatness_mm["f2"] / 10, rel=1e-9)
