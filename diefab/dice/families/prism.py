"""Prisms, flat-ended or capped: n lateral faces around the y axis, ends or pyramid caps.

Lateral face k (``f1 .. fn``) lies on the plane at distance ``hk`` (default
1) from the axis with normal at angle 2 pi (k - 1)/n in the xz-plane; unequal
offsets give the cross-section unequal sides, and so the faces unequal
probabilities.  The ends are flat (``f<n+1>`` at y = l, ``f<n+2>`` at
y = -l) unless a cap height ``k`` is given: then each end is a pyramid with
its apex on the axis at ``+-(l + k)``, faces ``f<n+1> .. f<2n>`` (top) and
``f<2n+1> .. f<3n>`` (bottom).  Steep caps are transitional faces: the die
cannot rest on them, so only the lateral faces carry values -- the binomial
dice of Baktash et al. are such capped prisms.

Examples
--------
>>> poly = PRISM.polyhedron({"n": 5, "l": 1.5, "k": 1.0})
>>> len(poly.faces), poly.names[:5]
(15, ('f1', 'f2', 'f3', 'f4', 'f5'))
>>> len(PRISM.polyhedron({"n": 3, "l": 1.0}).faces)
5
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from diefab.dice.families.base import (
    Family,
    Parameter,
    integer,
    offset_parameters,
    offsets,
    unused_offsets,
    width_along,
)
from diefab.dice.families.planes import polyhedron_from_planes
from diefab.geometry.polyhedron import Polyhedron

__all__ = ["PRISM", "prism_polyhedron"]

MAX_SIDES = 12


def prism_polyhedron(params: Mapping[str, float]) -> Polyhedron:
    """The prism for complete, checked parameters."""
    n = integer(params, "n")
    unused_offsets(params, "h", n, "prism")
    h = offsets(params, "h", n)
    angle = 2 * np.pi * np.arange(n) / n
    u = np.column_stack([np.cos(angle), np.zeros(n), np.sin(angle)])
    l = params["l"]
    if "k" not in params:
        normals = np.vstack([u, [0, 1, 0], [0, -1, 0]])
        return polyhedron_from_planes(normals, np.concatenate([h, [l, l]]))
    # A cap plane holds its lateral face's end edge and the apex (0, +-(l + k), 0):
    # (u . x) / h + (|y| - l) / k = 1.
    k = params["k"]
    top = np.column_stack([u[:, 0] / h, np.full(n, 1 / k), u[:, 2] / h])
    bottom = top * [1, -1, 1]
    scale = np.linalg.norm(top, axis=1)
    cap_offset = (1 + l / k) / scale
    normals = np.vstack([u, top / scale[:, None], bottom / scale[:, None]])
    return polyhedron_from_planes(normals, np.concatenate([h, cap_offset, cap_offset]))


PRISM = Family(
    "prism",
    (
        Parameter("n", 3, MAX_SIDES, "lateral faces", integer=True),
        Parameter("l", 0.2, 4.0, "half-length of the lateral faces along the axis"),
        Parameter("k", 0.05, 4.0, "cap height beyond each end (absent: flat ends)", optional=True),
        *offset_parameters("h", MAX_SIDES, 0.5, 1.5, "distance from the axis of lateral face"),
    ),
    "n-sided prism around the y axis with flat ends or pyramid caps (k); offsets h1..hn shape the cross-section",
    build=prism_polyhedron,
    reference="width across the lateral faces from f1",
    reference_length=width_along,
    readability=(
        "lateral faces: the value on the face that points up (even n) or at the top edge's vertex "
        "at each end (odd n); caps are transitional and carry no value"
    ),
    free=lambda fam, p: ["l", *(["k"] if "k" in p else []), *(f"h{k}" for k in range(1, integer(p, "n") + 1))],
)
