"""The n-gon gem: a frustum on an inverted pyramid over an n-sided girdle (2n + 1 faces).

The girdle is the n-gon circumscribed about the ellipse with semi-axes
``a`` (x) and 1 (z), its first vertex at angle pi + pi/n; the top is the same
n-gon with semi-axes ``e`` and ``b`` at height ``c``; the apex is at
``(sx, -d, sz)``.  ``e`` may differ from ``a*b`` only for n = 4, whose
girdle edges run along the axes (other girdles would bend the sides).
Faces: the n sides (girdle to top), the top, the n triangles down to the
apex -- for n = 4 exactly the paper's gem, face by face and vertex by
vertex.  ``sx`` and ``sz`` (0 by default) shift the apex: the asymmetric
variant, for targets without the gem's mirror symmetry.

Examples
--------
>>> from diefab.dice.families.gem import gem_vertices
>>> p = {"n": 4, "a": 1.18, "b": 0.52, "c": 0.72, "d": 1.41}
>>> bool(np.array_equal(NGEM.polyhedron(p).vertices, gem_vertices(1.18, 0.52, 0.72, 1.41)))
True
>>> len(NGEM.polyhedron({**p, "n": 5}).faces)
11
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.families.base import Family, Parameter, integer
from diefab.geometry.polyhedron import Polyhedron

__all__ = ["NGEM", "ngem_polyhedron"]


def _girdle(n: int) -> np.ndarray:
    """(n, 2): the n-gon circumscribed about the unit circle, first vertex at pi + pi/n (x, z)."""
    theta = np.pi + np.pi / n + 2 * np.pi * np.arange(n) / n
    # Rounded so that the square's corners are exactly (+-1, +-1): the paper's gem.
    return np.round(np.column_stack([np.cos(theta), np.sin(theta)]) / np.cos(np.pi / n), 12)


def _faces(n: int) -> tuple[np.ndarray, ...]:
    girdle, top, apex = np.arange(n), n + np.arange(n), 2 * n
    sides = [(top[k], top[(k + 1) % n], girdle[(k + 1) % n], girdle[k]) for k in range(n)]
    bottoms = [(apex, girdle[k], girdle[(k + 1) % n]) for k in range(n)]
    return tuple(np.array(f) for f in [*sides, top[::-1], *bottoms])


def ngem_polyhedron(params: Mapping[str, float]) -> Polyhedron:
    """The n-gon gem for complete, checked parameters."""
    n = integer(params, "n")
    if n != 4 and "e" in params:
        raise DesignError(f"e={params['e']:g} needs n=4: other girdles keep their sides flat only with e = a*b")
    e = params["e"] if n == 4 else params["a"] * params["b"]
    ring = _girdle(n)
    girdle = np.column_stack([params["a"] * ring[:, 0], np.zeros(n), ring[:, 1]])
    top = np.column_stack([e * ring[:, 0], np.full(n, params["c"]), params["b"] * ring[:, 1]])
    apex = [params["sx"], -params["d"], params["sz"]]
    return Polyhedron(np.vstack([girdle, top, apex]), _faces(n))


NGEM = Family(
    "ngem",
    (
        Parameter("n", 3, 12, "sides of the girdle (the die has 2n+1 faces; n=4 is the paper's gem)", integer=True),
        Parameter("a", 1.0, 2.0, "aspect ratio: the girdle's x semi-axis (its z semi-axis is 1)"),
        Parameter("b", 0.3, 0.9, "top shrinkage: the top's z semi-axis"),
        Parameter("c", 0.1, 1.0, "top height above the girdle"),
        Parameter("d", 0.5, 4.0, "bottom depth: the apex is at y = -d"),
        Parameter(
            "e",
            0.1,
            2.0,
            "the top's x semi-axis (default a*b; free only for n=4)",
            optional=True,
            default=lambda p: p["a"] * p["b"] if p["n"] == 4 else None,
        ),
        Parameter("sx", -0.8, 0.8, "apex shift along x (default 0)", optional=True, default=lambda p: 0.0),
        Parameter("sz", -0.8, 0.8, "apex shift along z (default 0)", optional=True, default=lambda p: 0.0),
    ),
    "frustum on an inverted pyramid over an n-gon girdle: 2n+1 faces; apex shifts sx, sz make it asymmetric",
    build=ngem_polyhedron,
    free=lambda fam, p: ["a", "b", "c", "d", *(["e"] if p["n"] == 4 else [])] + [s for s in ("sx", "sz") if p[s] != 0],
    reference="girdle width across z (n = 4: girdle short side)",
    reference_length=lambda poly: 2.0,
    readability=(
        "the value on the face that points up; resting on its top the gem points its apex up, "
        "and the apex means the top's value"
    ),
)
