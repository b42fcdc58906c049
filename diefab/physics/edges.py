"""Rounded edges and corners: a die body shrunk by a radius, for the engine to sweep by a ball of it.

A printed die's edges and corners are rounded.  Its shape is modelled as
the hull shrunk by the edge radius ``r`` (every face plane moved inward by
``r``) swept by a ball of radius ``r`` (the Minkowski sum): its faces lie
in the planes of the sharp die's faces, and every edge and corner is
rounded with radius ``r``.  Bullet sweeps a convex hull by its collision
margin, so the engine gets the shrunk hull's vertices and a margin of
``r``.

Where the die rests, its centre of mass lies at the height of the shrunk
hull's support function plus ``r``: the rest basins of the rounded die are
those of the shrunk hull (:class:`~diefab.models.basins.RestBasins`), a
little smaller than the sharp die's for the faces whose edges the rounding
cuts most.  A face narrower than ``2 r`` vanishes from the shrunk hull: the
rounded die cannot rest on it.

Examples
--------
A cube of half-width 1 rounded by 0.1 keeps its six faces, each 0.9 from the
centre on the shrunk hull:

>>> import numpy as np
>>> from diefab.geometry.polyhedron import Polyhedron
>>> from diefab.physics.world import die_body
>>> from itertools import product
>>> cube = Polyhedron.from_points(list(product((-1.0, 1.0), repeat=3)))
>>> class Unit:
...     center, mass, inertia = np.zeros(3), 8.0, np.eye(3) * 8 / 6 * 2
>>> shrunk, faces = shrunk_body(die_body(cube, Unit()), 0.1)
>>> sorted(faces.tolist()), round(float(np.abs(shrunk.vertices).max()), 9)
([0, 1, 2, 3, 4, 5], 0.9)
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from diefab.core.errors import PhysicsError
from diefab.models.basins import RestBasins

__all__ = ["shrunk_body"]

#: Hull triangles of the shrunk die within this distance (units of the die's radius) of one plane are one face.
_MERGE = 1e-7


def shrunk_body(body, radius: float):
    """The die `body` with every face plane moved inward by `radius` (model units), and its faces' origin.

    Parameters
    ----------
    body : diefab.physics.world.DieBody
        The sharp die, body frame (centre of mass at the origin).
    radius : float
        Edge radius, model units, > 0 and below every face's distance from
        the centre of mass.

    Returns
    -------
    shrunk : DieBody
        The shrunk hull: its vertices, its faces' normals, its rest basins,
        and as heights the rest heights of the *rounded* die (the shrunk
        faces' distances plus `radius`, which are the sharp die's).  Mass
        and inertia are the sharp die's (the rounding removes a sliver).
    faces : (m',) int
        For each face of `shrunk`, the index of the sharp die's face in its
        plane (a face narrower than the rounding has none and is absent).

    Raises
    ------
    PhysicsError
        `radius` is not positive, or not below the distance from the centre
        of mass to every face.
    """
    from scipy.spatial import HalfspaceIntersection, QhullError

    from diefab.geometry.polyhedron import Polyhedron

    r = float(radius)
    if not r > 0:
        raise PhysicsError(f"edge radius {r!r} must be > 0")
    if r >= body.heights.min():
        raise PhysicsError(f"edge radius {r:.4g} is not below the distance {body.heights.min():.4g} from the "
                           "centre of mass to the nearest face")  # fmt: skip
    halfspaces = np.hstack([body.normals, -(body.heights - r)[:, None]])
    try:
        points = HalfspaceIntersection(halfspaces, np.zeros(3)).intersections
    except QhullError as exc:
        raise PhysicsError(f"cannot shrink the die by {r:.4g}: {exc}") from None
    poly = Polyhedron.from_points(points, strict=False, merge_tolerance=_MERGE * body.radius)
    # each face of the shrunk hull lies in one of the sharp die's planes: the one of the nearest normal
    faces = np.argmax(poly.normals @ body.normals.T, axis=1)
    if len(set(faces.tolist())) != len(faces):
        raise PhysicsError(f"the die shrunk by {r:.4g} has two faces in one plane")
    heights = body.heights[faces]
    basins = RestBasins.of(poly, np.zeros(3))
    shrunk = replace(body, vertices=poly.vertices, normals=poly.normals, heights=heights, basins=basins,
                     faces=tuple(np.asarray(f) for f in poly.faces))  # fmt: skip
    return shrunk, faces
