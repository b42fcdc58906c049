"""Die families, registered in one table.

A family turns a parameter mapping into a :class:`~diefab.geometry.Polyhedron`
and knows its parameters' bounds and its reference length (what ``size_mm``
measures).  ``gem`` is the paper's 9-faced gem (:mod:`.gem`); ``convex`` is
any convex polyhedron given by its vertices (and optionally faces) in the
design file; ``mesh`` is a mesh file.
"""

from __future__ import annotations

from ..errors import DesignError
from .base import Family, Parameter
from .gem import GEM, gem_center_of_mass_y, gem_parameters, gem_polyhedron, gem_vertices

__all__ = [
    "GEM",
    "Family",
    "Parameter",
    "family",
    "gem_center_of_mass_y",
    "gem_parameters",
    "gem_polyhedron",
    "gem_vertices",
]

CONVEX = Family("convex", (), "any convex polyhedron given by its vertices")
MESH = Family("mesh", (), "a convex mesh file (OBJ, STL, PLY)")

_FAMILIES = {f.name: f for f in (GEM, CONVEX, MESH)}


def family(name: str) -> Family:
    """The family called `name`."""
    try:
        return _FAMILIES[name]
    except KeyError:
        raise DesignError(f"unknown family {name!r} (known: {', '.join(_FAMILIES)})") from None
