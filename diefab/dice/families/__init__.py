"""Die families, registered in one table.

A family turns a parameter mapping into a :class:`~diefab.geometry.polyhedron.Polyhedron`
and knows its parameters' bounds, its reference length (what ``size_mm``
measures) and how its faces are read.  One module per family:

``gem``  the paper's 9-faced gem (:mod:`.gem`)
``ngem``  the gem over an n-gon girdle, 2n+1 faces, with an asymmetric variant (:mod:`.ngem`)
``prism``  flat-ended or capped prisms (:mod:`.prism`)
``bipyramid``, ``trapezohedron``  (:mod:`.bipyramid`)
``icosahedral``  the rhombic triacontahedron with pentagons at its five-fold corners, 42 faces (:mod:`.icosahedral`)
``cuboid``  boxes, long and tapered (:mod:`.cuboid`)
``freeform``  planes at free offsets along fixed normals (:mod:`.freeform`)
``convex``, ``mesh``  any convex polyhedron given by vertices or a mesh file in the design
"""

from __future__ import annotations

from diefab.core.errors import DesignError
from diefab.dice.families.base import Family, Parameter
from diefab.dice.families.bipyramid import BIPYRAMID, TRAPEZOHEDRON
from diefab.dice.families.cuboid import CUBOID
from diefab.dice.families.freeform import FREEFORM
from diefab.dice.families.gem import GEM, gem_center_of_mass_y, gem_parameters, gem_polyhedron, gem_vertices
from diefab.dice.families.icosahedral import ICOSAHEDRAL
from diefab.dice.families.ngem import NGEM
from diefab.dice.families.prism import PRISM

__all__ = [
    "GEM",
    "Family",
    "Parameter",
    "families",
    "family",
    "gem_center_of_mass_y",
    "gem_parameters",
    "gem_polyhedron",
    "gem_vertices",
]

CONVEX = Family("convex", (), "any convex polyhedron given by its vertices")
MESH = Family("mesh", (), "a convex mesh file (OBJ, STL, PLY)")

_FAMILIES = {
    f.name: f for f in (GEM, NGEM, PRISM, BIPYRAMID, TRAPEZOHEDRON, ICOSAHEDRAL, CUBOID, FREEFORM, CONVEX, MESH)
}


def families() -> list[Family]:
    """Every registered family, in the table's order."""
    return list(_FAMILIES.values())


def family(name: str) -> Family:
    """The family called `name`."""
    try:
        return _FAMILIES[name]
    except KeyError:
        raise DesignError(f"unknown family {name!r} (known: {', '.join(_FAMILIES)})") from None
