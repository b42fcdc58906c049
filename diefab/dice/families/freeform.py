"""The free-form convex family: support planes along a fixed set of n normals, each at its own offset.

The normals are the n points of a Fibonacci lattice on the unit sphere
(fixed for each n), so any convex die whose faces point roughly that way is
reachable by moving the planes ``h1 .. hn`` (default 1): face k (``fk``) is
on plane k.  For targets no named family fits.

Examples
--------
>>> poly = FREEFORM.polyhedron({"n": 8})
>>> len(poly.faces)
8
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from diefab.dice.families.base import Family, Parameter, integer, offset_parameters, offsets, unused_offsets
from diefab.dice.families.planes import polyhedron_from_planes
from diefab.geometry.polyhedron import Polyhedron

__all__ = ["FREEFORM", "fibonacci_normals", "freeform_polyhedron"]

MAX_PLANES = 30


def fibonacci_normals(n: int) -> np.ndarray:
    """(n, 3) float: n nearly evenly spread unit vectors (a Fibonacci lattice)."""
    k = np.arange(n) + 0.5
    y = 1 - 2 * k / n
    r = np.sqrt(1 - y**2)
    phi = np.pi * (3 - np.sqrt(5)) * k
    return np.column_stack([r * np.cos(phi), y, r * np.sin(phi)])


def freeform_polyhedron(params: Mapping[str, float]) -> Polyhedron:
    """The free-form die for complete, checked parameters."""
    n = integer(params, "n")
    unused_offsets(params, "h", n, "free-form die")
    return polyhedron_from_planes(fibonacci_normals(n), offsets(params, "h", n))


FREEFORM = Family(
    "freeform",
    (
        Parameter("n", 6, MAX_PLANES, "planes (faces)", integer=True),
        *offset_parameters("h", MAX_PLANES, 0.5, 1.5, "distance from the centre of plane"),
    ),
    "convex die cut by n planes along fixed, evenly spread normals at free offsets h1..hn",
    build=freeform_polyhedron,
    readability="the value on the face that points up; at the vertex or edge that points up when no face does",
    free=lambda fam, p: [f"h{k}" for k in range(1, integer(p, "n") + 1)],
)
