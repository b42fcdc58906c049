"""Basin shares as spherical polygons: exact on symmetric dice, and the cube map's answer within its bound."""

from __future__ import annotations

import numpy as np
import pytest

from diefab.dice.design import load_design
from diefab.dice.families import gem_polyhedron
from diefab.geometry.polyhedron import Polyhedron, resting_faces
from diefab.models.basins import RestBasins

CUBE = Polyhedron.from_points([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])


@pytest.mark.parametrize("name, k", [("d6", 6), ("d8", 8), ("d20", 20)])
def test_platonic_dice_are_uniform_to_rounding(name, k):
    d = load_design(name)
    p, bound = RestBasins.of(d.polyhedron, d.mass_properties().center).exact_shares()
    assert bound < 1e-12 and np.abs(p - 1 / k).max() < 1e-12


def test_off_centre_cube_matches_monte_carlo_and_the_cube_map():
    center = np.array([0.1, 0.2, -0.3])
    basins = RestBasins.of(CUBE, center)
    p, bound = basins.exact_shares()
    d = np.random.default_rng(5).normal(size=(200_000, 3))
    mc = np.bincount(basins.face_of(d / np.linalg.norm(d, axis=1)[:, None]), minlength=6) / len(d)
    assert np.abs(p - mc).max() < 4 * np.sqrt(0.25 / len(d))
    grid, grid_bound = basins.shares()
    assert np.abs(p - grid).max() <= grid_bound and p.sum() == pytest.approx(1, abs=1e-12)


@pytest.mark.parametrize(
    "poly",
    [
        load_design("fudge-gem").polyhedron,
        gem_polyhedron({"a": 1.0, "b": 0.5, "c": 0.2, "d": 0.3}),  # four transitional faces
        gem_polyhedron({"a": 1.2, "b": 0.7, "c": 0.4, "d": 0.5}),
    ],
)
def test_gems_agree_with_the_cube_map_and_transitional_faces_get_nothing(poly):
    center = poly.centroid + np.array([0.02, -0.03, 0.01])
    basins = RestBasins.of(poly, center)
    p, bound = basins.exact_shares()
    grid, grid_bound = basins.shares()
    assert np.abs(p - grid).max() <= grid_bound + bound
    assert np.all(p[~resting_faces(poly, center)] == 0) and p.sum() == pytest.approx(1, abs=1e-12)
    assert np.all(p >= 0)
