"""Bipyramids and trapezohedra: two pyramids (or two rings of kites) joined at the equator.

The bipyramid has n triangles up to the apex at height ``h`` (``f1 .. fn``)
and n down to the apex at depth ``g`` (``f<n+1> .. f<2n>``) over a regular
n-gon equator of circumradius 1.  The trapezohedron (the d10's shape for
n = 5) has n kites around the top (``f1 .. fn``) and n around the bottom,
turned by half a step; ``t`` and ``u`` are the slopes of the top and bottom
kites' normals.  ``g`` and ``u`` default to ``h`` and ``t``: unequal, they
make the top and bottom halves land with different probabilities.

Examples
--------
>>> from diefab.geometry.polyhedron import solid_angles
>>> d8 = BIPYRAMID.polyhedron({"n": 4, "h": 1.0})
>>> bool(np.allclose(solid_angles(d8, d8.centroid) / (4 * np.pi), 1 / 8))
True
>>> d10 = TRAPEZOHEDRON.polyhedron({"n": 5, "t": 0.7})
>>> len(d10.faces), bool(np.allclose(solid_angles(d10, d10.centroid) / (4 * np.pi), 1 / 10))
(10, True)
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from diefab.dice.families.base import Family, Parameter, integer, width_along
from diefab.dice.families.planes import polyhedron_from_planes
from diefab.geometry.polyhedron import Polyhedron

__all__ = ["BIPYRAMID", "TRAPEZOHEDRON", "bipyramid_polyhedron", "trapezohedron_polyhedron"]


def _ring(n: int, turn: float) -> np.ndarray:
    angle = 2 * np.pi * (np.arange(n) + turn) / n
    return np.column_stack([np.cos(angle), np.zeros(n), np.sin(angle)])


def bipyramid_polyhedron(params: Mapping[str, float]) -> Polyhedron:
    """The bipyramid for complete, checked parameters."""
    n = integer(params, "n")
    u = _ring(n, 0.5) / np.cos(np.pi / n)  # each triangle's equator edge is at distance cos(pi/n)
    # A face holds its equator edge and its apex: (u . x) / cos(pi/n) + y / h = 1.
    top = u + [0, 1 / params["h"], 0]
    bottom = u - [0, 1 / params["g"], 0]
    normals = np.vstack([top, bottom])
    scale = np.linalg.norm(normals, axis=1)
    return polyhedron_from_planes(normals / scale[:, None], 1 / scale)


def trapezohedron_polyhedron(params: Mapping[str, float]) -> Polyhedron:
    """The trapezohedron for complete, checked parameters."""
    n = integer(params, "n")
    top = _ring(n, 0.0) + [0, params["t"], 0]
    bottom = _ring(n, 0.5) - [0, params["u"], 0]
    normals = np.vstack([top, bottom])
    return polyhedron_from_planes(normals, np.ones(2 * n))


_READ = (
    "the value on the face that points up (even n for bipyramids, odd n for trapezohedra, whose "
    "opposite faces are parallel); otherwise at the vertex or edge that points up"
)

BIPYRAMID = Family(
    "bipyramid",
    (
        Parameter("n", 3, 60, "sides of the equator (2n faces)", integer=True),
        Parameter("h", 0.3, 4.0, "height of the top apex (equator circumradius 1)"),
        Parameter("g", 0.3, 4.0, "depth of the bottom apex (default h)", optional=True, default=lambda p: p["h"]),
    ),
    "two n-gon pyramids joined at the equator: 2n triangles",
    build=bipyramid_polyhedron,
    reference="width along f1's normal",
    reference_length=width_along,
    readability=_READ,
)

TRAPEZOHEDRON = Family(
    "trapezohedron",
    (
        Parameter("n", 3, 60, "kites around each apex (2n faces)", integer=True),
        Parameter("t", 0.2, 2.5, "slope of the top kites' normals"),
        Parameter(
            "u", 0.2, 2.5, "slope of the bottom kites' normals (default t)", optional=True, default=lambda p: p["t"]
        ),  # fmt: skip
    ),
    "two rings of n kites, turned by half a step (the d10 for n = 5): 2n faces",
    build=trapezohedron_polyhedron,
    reference="width along f1's normal",
    reference_length=width_along,
    readability=_READ,
)
