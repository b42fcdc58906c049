"""Cuboids: boxes with a square-or-not cross-section, long or flat, optionally tapered.

Faces in d6 order of opposite pairs: ``f1`` bottom (-y) and ``f2`` top (+y)
at y = -1 and y = +1 (2 model units apart: size_mm measures top to
bottom), ``f3``/``f4`` at x = +-x, ``f5``/``f6`` at z = +-z.  A taper ``t``
leans the four sides inward by slope t, so the top shrinks and the bottom
grows: one face lands more often than its opposite, as on a loaded d6.

Examples
--------
>>> from diefab.geometry.polyhedron import solid_angles
>>> cube = CUBOID.polyhedron({"x": 1.0, "z": 1.0})
>>> bool(np.allclose(solid_angles(cube, cube.centroid) / (4 * np.pi), 1 / 6))
True
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from diefab.dice.families.base import Family, Parameter
from diefab.dice.families.planes import polyhedron_from_planes
from diefab.geometry.polyhedron import Polyhedron

__all__ = ["CUBOID", "cuboid_polyhedron"]


def cuboid_polyhedron(params: Mapping[str, float]) -> Polyhedron:
    """The cuboid for complete, checked parameters."""
    t, x, z = params["t"], params["x"], params["z"]
    # A side through (x, 0, 0) leaning inward by slope t: X + t y = x.
    sides = np.array([[1, t, 0], [-1, t, 0], [0, t, 1], [0, t, -1]], dtype=float)
    scale = np.linalg.norm(sides, axis=1)
    normals = np.vstack([[0, -1, 0], [0, 1, 0], sides / scale[:, None]])
    return polyhedron_from_planes(normals, np.concatenate([[1, 1], np.array([x, x, z, z]) / scale]))


CUBOID = Family(
    "cuboid",
    (
        Parameter("x", 0.2, 4.0, "half-width along x (the height is 2)"),
        Parameter("z", 0.2, 4.0, "half-width along z"),
        Parameter(
            "t",
            0.0,
            0.6,
            "taper: slope at which the sides lean in towards the top (default 0)",
            optional=True,
            default=lambda p: 0.0,
        ),  # fmt: skip
    ),
    "box with faces in opposite pairs (long dice, loaded d6 by taper)",
    build=cuboid_polyhedron,
    reference="face to face, bottom to top",
    reference_length=lambda poly: 2.0,
    readability="the value on the face that points up (its opposite face)",
    free=lambda fam, p: ["x", "z", *(["t"] if p["t"] != 0 else [])],
)
