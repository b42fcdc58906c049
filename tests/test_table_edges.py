"""The table's softness and the die's rounded edges: geometry of the shrunk hull, and drops that still count right."""

from __future__ import annotations

from itertools import product

import numpy as np
import pytest

from diefab.core.errors import PhysicsError
from diefab.dice.design import load_design
from diefab.geometry.polyhedron import Polyhedron
from diefab.physics.edges import shrunk_body
from diefab.physics.simulate import PhysicsSettings
from diefab.physics.world import die_body, run_batch
from diefab.search.calibrate import PARAMETERS, settings_at


class _Solid:
    """Mass properties of a homogeneous solid, enough for die_body."""

    def __init__(self, center, mass, inertia) -> None:
        self.center, self.mass, self.inertia = np.asarray(center, float), float(mass), np.asarray(inertia, float)


def _box(a: float, b: float, c: float):
    poly = Polyhedron.from_points(list(product((-a, a), (-b, b), (-c, c))))
    m = 8 * a * b * c
    inertia = np.diag([m * (b * b + c * c), m * (a * a + c * c), m * (a * a + b * b)]) / 3
    return poly, die_body(poly, _Solid(np.zeros(3), m, inertia))


def test_the_new_settings_are_off_by_default_and_left_out_of_stored_settings():
    s = PhysicsSettings()
    assert (s.table_softness, s.table_damping, s.edge_radius) == (0.0, 0.0, 0.0)
    stored = s.as_dict()
    assert not {"table_softness", "table_damping", "edge_radius"} & set(stored)
    on = PhysicsSettings(table_softness=0.01, table_damping=0.5, edge_radius=0.05)
    assert PhysicsSettings.from_mapping(on.as_dict()) == on


@pytest.mark.parametrize("name, bad", [("table_softness", 0.2), ("table_softness", -1e-3), ("table_damping", 11.0),
                                       ("edge_radius", 0.3), ("edge_radius", float("nan"))])  # fmt: skip
def test_bad_values_are_one_line_physics_errors(name, bad):
    with pytest.raises(PhysicsError, match=name) as info:
        PhysicsSettings(**{name: bad})
    assert "\n" not in str(info.value)


def test_they_are_calibration_parameters():
    s = settings_at(PhysicsSettings(), ["softness", "table_damping", "edge_radius"], [0.01, 0.5, 0.04])
    assert (s.table_softness, s.table_damping, s.edge_radius) == (0.01, 0.5, 0.04)
    assert all(PARAMETERS[n].low == 0.0 for n in ("softness", "table_damping", "edge_radius"))


def test_a_box_shrunk_keeps_its_faces_and_their_rest_heights():
    poly, body = _box(1.0, 0.8, 0.5)
    shrunk, faces = shrunk_body(body, 0.1)
    assert sorted(faces.tolist()) == list(range(6))
    # every face plane moved in by the radius: the engine's margin puts it back where the sharp face was
    support = (shrunk.vertices @ shrunk.normals.T).max(axis=0)
    np.testing.assert_allclose(support + 0.1, body.heights[faces], atol=1e-9)
    np.testing.assert_allclose(shrunk.heights, body.heights[faces])
    np.testing.assert_allclose(shrunk.normals, body.normals[faces], atol=1e-12)
    # the shrunk box is the box of half-widths reduced by the radius
    np.testing.assert_allclose(np.sort(np.abs(shrunk.vertices).max(axis=0)), [0.4, 0.7, 0.9], atol=1e-9)
    assert shrunk.basins.resting.all()


def test_rounding_lowers_each_barrier_by_the_cut_of_its_edges():
    """A box's barrier over an edge is |foot| - h: shrunk by r the foot moves in by r sqrt(2), the rest height not."""
    _poly, body = _box(1.0, 0.8, 0.5)
    r = 0.05
    shrunk, faces = shrunk_body(body, r)
    sharp = body.basins.barriers[faces]
    rounded = shrunk.basins.barriers
    # the lowest saddle of the box's largest faces (height 0.5) is over its long edge: foot at distance |(0, 0.8, 0.5)|
    big = np.flatnonzero(np.isclose(body.heights[faces], 0.5))
    np.testing.assert_allclose(sharp[big], np.hypot(0.8, 0.5) - 0.5, atol=1e-9)
    np.testing.assert_allclose(rounded[big], np.hypot(0.8 - r, 0.5 - r) + r - 0.5, atol=1e-9)
    assert np.all(rounded < sharp)


def test_a_face_narrower_than_the_rounding_vanishes():
    """A cube with one corner cut by a small triangle: rounded more than the triangle's inradius, it loses that face."""
    cut = 0.1
    pts = [p for p in product((-1.0, 1.0), repeat=3) if p != (1.0, 1.0, 1.0)]
    pts += [(1.0 - cut, 1.0, 1.0), (1.0, 1.0 - cut, 1.0), (1.0, 1.0, 1.0 - cut)]
    poly = Polyhedron.from_points(pts)
    body = die_body(poly, _Solid(np.zeros(3), 8.0, np.eye(3) * 16 / 3))
    small = int(np.argmax(body.normals @ (np.ones(3) / np.sqrt(3))))
    kept, faces = shrunk_body(body, 0.001)
    assert small in faces.tolist() and len(faces) == 7
    gone, faces = shrunk_body(body, 0.1)
    assert small not in faces.tolist() and len(faces) == 6


@pytest.mark.parametrize("radius", [0.0, -0.1, 0.5, 2.0])
def test_a_radius_not_below_every_face_distance_is_refused(radius):
    _poly, body = _box(1.0, 0.8, 0.5)
    with pytest.raises(PhysicsError, match="edge radius"):
        shrunk_body(body, radius)


@pytest.fixture(scope="module")
def gem():
    pytest.importorskip("pybullet")
    design = load_design("fudge-gem")
    return design, die_body(design.polyhedron, design.mass_properties())


@pytest.mark.parametrize("extra", [{"edge_radius": 0.03}, {"table_softness": 0.005, "table_damping": 0.5}])
def test_drops_still_land_on_the_faces_of_the_sharp_die(gem, extra):
    """The gem's faces differ widely in probability: a wrong face numbering would move the counts far.

    300 drops at one seed with and without the feature: the two face
    distributions differ by sampling noise (a TVD of about 0.1 at most), and
    every drop ends on a face (none unsettled).
    """
    _design, body = gem
    sharp = run_batch(body, PhysicsSettings(), 11, 0, 300)
    other = run_batch(body, PhysicsSettings(**extra), 11, 0, 300)
    assert (other >= -1).all()
    p = np.bincount(sharp[sharp >= 0], minlength=9) / (sharp >= 0).sum()
    q = np.bincount(other[other >= 0], minlength=9) / (other >= 0).sum()
    assert 0.5 * np.abs(p - q).sum() < 0.16
