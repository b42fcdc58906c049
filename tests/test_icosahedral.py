"""The icosahedral die: two classes of faces, each equally likely among itself by symmetry."""

import numpy as np
import pytest

from diefab.dice.families import family
from diefab.dice.families.icosahedral import CORNER, ICOSAHEDRAL
from diefab.geometry.polyhedron import solid_angles
from diefab.search.symmetric import tipping_angle


@pytest.mark.parametrize("d", [0.96, 1.0, 1.02, 1.1, 1.16])
def test_faces_are_twelve_pentagons_and_thirty_hexagons_with_equal_classes(d):
    poly = ICOSAHEDRAL.polyhedron({"d": d})
    sides = [len(f) for f in poly.faces]
    assert sides[:12] == [5] * 12 and sides[12:] == [6] * 30  # the rhombi, their sharp corners cut
    # the centroid is the centre of symmetry, and every face has a parallel opposite
    assert np.allclose(poly.centroid, 0, atol=1e-9)
    assert np.allclose(np.sort(poly.normals @ poly.normals.T, axis=1)[:, 0], -1)
    share = solid_angles(poly, poly.centroid) / (4 * np.pi)
    assert share.sum() == pytest.approx(1)
    assert np.allclose(share[:12], share[0]) and np.allclose(share[12:], share[12])


def test_the_pentagons_shrink_as_their_planes_move_out():
    ds = np.linspace(0.96, CORNER - 0.02, 9)
    shares = [
        solid_angles(p, p.centroid)[:12].sum() / (4 * np.pi)
        for p in map(lambda d: ICOSAHEDRAL.polyhedron({"d": d}), ds)
    ]
    assert np.all(np.diff(shares) < 0)


def test_the_die_that_3d6_asks_for_is_steady():
    """Near the share 3d6 asks for (the pentagons a sixth of the landings), the die tips by more than 12 degrees."""
    poly = family("icosahedral").polyhedron({"d": 1.02})
    assert tipping_angle(poly, poly.centroid) > 12


@pytest.mark.slow  # builds two grids of 81 dice of 42 faces each, twice
def test_design_makes_the_icosahedral_die_by_name_or_by_its_face_count():
    from diefab.dice.targets import parse_target
    from diefab.search.counting import nearest_icosahedral
    from diefab.search.synthesis import synthesize

    target = parse_target("3d6")
    by_name = synthesize(target, family="icosahedral", model="fast")
    by_faces = synthesize(target, faces=42, model="fast")
    assert by_name.design.family == by_faces.design.family == "icosahedral"
    assert by_name.design.params == by_faces.design.params
    assert by_name.method == "two-class-nearest"
    # the fast model respects the die's symmetry: at the share it was tuned to, the die rolls the counted plan
    plan = nearest_icosahedral(target).plan
    assert np.allclose(by_name.predicted, plan.per_value(plan.share), atol=1e-4)
    pentagons = [by_name.design.values[f"f{k}"] for k in range(1, 13)]
    assert np.bincount(pentagons, minlength=19)[3:].tolist() == list(plan.alpha)
