"""The rhombic triacontahedron with its twelve five-fold corners cut off: 12 pentagons and 30 long hexagons.

The 30 rhombi, their two sharp corners cut into long hexagons (``f13 .. f42``),
lie on planes at distance 1 from the centre, along the icosidodecahedron's directions; the 12 pentagons (``f1 .. f12``)
on planes at distance ``d`` along the icosahedron's vertices.  Every
rotation of the icosahedron maps the die onto itself and each class of faces
onto itself, so under any physics that does not favour an orientation the
pentagons land equally often among themselves, as do the hexagons: the die is
a two-class die whose one number, the pentagons' share of the landings, is
set by ``d`` (near 1: large pentagons; near the corner's distance
1.1756: small ones).  Every face has a parallel opposite face, so the value
is read on the face that points up.

Examples
--------
>>> from diefab.geometry.polyhedron import solid_angles
>>> poly = ICOSAHEDRAL.polyhedron({"d": 1.03})
>>> len(poly.faces), poly.names[0], poly.names[12]
(42, 'f1', 'f13')
>>> share = solid_angles(poly, poly.centroid)[:12] / (4 * np.pi)
>>> bool(np.allclose(share, share[0])), round(float(share.sum()), 3)
(True, 0.173)
"""

from __future__ import annotations

from collections.abc import Mapping
from itertools import product

import numpy as np

from diefab.dice.families.base import Family, Parameter
from diefab.dice.families.planes import polyhedron_from_planes, unit
from diefab.geometry.polyhedron import Polyhedron

__all__ = ["ICOSAHEDRAL", "CORNER", "icosahedral_normals", "icosahedral_polyhedron"]

_PHI = (1 + 5**0.5) / 2
#: Distance of the rhombic triacontahedron's five-fold corners from its centre (inradius 1): a pentagon plane
#: must come nearer than this to cut a face.
CORNER = float(np.hypot(1, 1 / _PHI))


def _orbit(seeds: list[tuple[float, float, float]]) -> np.ndarray:
    """Unit vectors: every cyclic permutation and sign change of `seeds`, each once, in a fixed order."""
    points = set()
    for seed in seeds:
        for shift in range(3):
            turned = np.roll(np.array(seed, dtype=float), shift)
            for signs in product((1.0, -1.0), repeat=3):
                points.add(tuple(np.round(turned * signs, 12) + 0.0))
    return unit(np.array(sorted(points)))


def icosahedral_normals() -> tuple[np.ndarray, np.ndarray]:
    """(12, 3) and (30, 3) float: unit normals of the pentagons (five-fold axes) and the hexagons (two-fold axes)."""
    five = _orbit([(0.0, 1.0, _PHI)])
    two = _orbit([(1.0, 0.0, 0.0), (_PHI / 2, 0.5, 1 / (2 * _PHI))])
    return five, two


def icosahedral_polyhedron(params: Mapping[str, float]) -> Polyhedron:
    """The die for complete, checked parameters: pentagons ``f1 .. f12``, then hexagons ``f13 .. f42``."""
    five, two = icosahedral_normals()
    return polyhedron_from_planes(np.vstack([five, two]), np.r_[np.full(len(five), params["d"]), np.ones(len(two))])


ICOSAHEDRAL = Family(
    "icosahedral",
    (Parameter("d", 0.95, round(CORNER - 0.01, 4), "distance of the 12 pentagons' planes (the 30 hexagons': 1)"),),
    "the rhombic triacontahedron with its 12 five-fold corners cut off: 12 pentagons and 30 hexagons, "
    "two classes of faces",
    build=icosahedral_polyhedron,
    readability="the value on the face that points up (every face has a parallel opposite face)",
)
