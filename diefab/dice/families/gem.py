"""The paper's 9-faced gem: a pyramid frustum on an inverted pyramid.

Examples
--------
>>> poly = gem_polyhedron(GEM.check_params({"a": 1.18, "b": 0.52, "c": 0.72, "d": 1.41}))
>>> poly.names
('f1', 'f2', 'f3', 'f4', 'f5', 'f6', 'f7', 'f8', 'f9')
>>> float(poly.vertices[8, 1])
-1.41
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from diefab.core.errors import DesignError, GeometryError
from diefab.dice.families.base import Family, Parameter
from diefab.geometry.polyhedron import Polyhedron

__all__ = ["GEM", "gem_center_of_mass_y", "gem_parameters", "gem_polyhedron", "gem_vertices"]

GEM = Family(
    "gem",
    (
        Parameter("a", 1.0, 2.0, "aspect ratio: girdle half-length along x (the z half-length is 1)"),
        Parameter("b", 0.3, 0.9, "top shrinkage: the top's z half-length"),
        Parameter("c", 0.1, 1.0, "top height above the girdle"),
        Parameter("d", 0.5, 4.0, "bottom depth: the apex is at y = -d"),
        Parameter(
            "e", 0.1, 2.0, "the top's x half-length (default a*b)", optional=True, default=lambda p: p["a"] * p["b"]
        ),
    ),
    "frustum of a pyramid on an inverted pyramid: 9 faces (the paper's 'gem')",
    build=lambda params: gem_polyhedron(params),
    reference="girdle short side",
    reference_length=lambda poly: 2.0,
    readability="the value on the face that points up; resting on its top the gem points its apex up",
)

# Faces exactly as the paper lists them (1-based vertex numbers), outward CCW.
_GEM_FACES = tuple(
    np.array(f) - 1
    for f in (
        (5, 6, 2, 1),
        (6, 7, 3, 2),
        (7, 8, 4, 3),
        (8, 5, 1, 4),
        (8, 7, 6, 5),
        (9, 1, 2),
        (9, 2, 3),
        (9, 3, 4),
        (9, 4, 1),
    )
)


def gem_vertices(a: float, b: float, c: float, d: float, e: float | None = None) -> np.ndarray:
    """(9, 3) float: the paper's gem vertices v1..v9; `e` defaults to ``a * b``."""
    e = a * b if e is None else e
    return np.array(
        [
            (-a, 0, -1),
            (a, 0, -1),
            (a, 0, 1),
            (-a, 0, 1),
            (-e, c, -b),
            (e, c, -b),
            (e, c, b),
            (-e, c, b),
            (0, -d, 0),
        ],
        dtype=float,
    )


def gem_center_of_mass_y(a: float, b: float, c: float, d: float) -> float:
    """The paper's Eq. (1): y of the solid gem's centre of mass (e = a*b)."""
    return (c**2 * (3 * b**2 + 2 * b + 1) - d**2) / (4 * (c * (b**2 + b + 1) + d))


_GEM_TEMPLATE = Polyhedron(gem_vertices(1.5, 0.5, 0.5, 1.5), _GEM_FACES)


def gem_polyhedron(params: Mapping[str, float]) -> Polyhedron:
    """The gem for validated parameters."""
    try:
        return _GEM_TEMPLATE.with_vertices(gem_vertices(**params))
    except GeometryError as exc:
        raise DesignError(f"gem parameters {dict(params)} do not give a convex die: {exc}") from exc


def gem_parameters(poly: Polyhedron) -> dict[str, float] | None:
    """The gem parameters a, b, c, d, e of `poly`, or None when it is not a gem.

    A gem is recognized by its topology (the paper's nine faces, as
    :func:`gem_polyhedron` builds them) and by vertices that are exactly
    :func:`gem_vertices` of the parameters read off them; parameters outside
    the family box are still returned.

    Examples
    --------
    >>> gem_parameters(gem_polyhedron({"a": 1.18, "b": 0.52, "c": 0.72, "d": 1.41}))["e"]
    0.6136
    """
    if poly.faces is not _GEM_TEMPLATE.faces and (
        len(poly.faces) != len(_GEM_FACES) or not all(np.array_equal(f, g) for f, g in zip(poly.faces, _GEM_FACES))
    ):
        return None
    v = poly.vertices
    params = {"a": float(v[1, 0]), "b": float(-v[4, 2]), "c": float(v[4, 1]), "d": float(-v[8, 1]), "e": float(v[5, 0])}
    if not np.array_equal(v, gem_vertices(**params)):
        return None
    return params
