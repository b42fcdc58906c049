"""Dice cut by planes: the convex solid ``normals @ x <= offsets``, one named face per plane.

Prisms, bipyramids, trapezohedra, cuboids and the free-form family are all
intersections of half-spaces; building them here keeps face k on plane k
(named ``f<k+1>``) whatever the offsets, so values and labels stay attached
to the same faces while an optimizer moves the planes.

Examples
--------
>>> cube = polyhedron_from_planes(np.vstack([np.eye(3), -np.eye(3)]), np.ones(6))
>>> cube.names, round(cube.volume, 9)
(('f1', 'f2', 'f3', 'f4', 'f5', 'f6'), 8.0)
"""

from __future__ import annotations

import numpy as np

from diefab.core import tolerances as tol
from diefab.core.errors import GeometryError
from diefab.geometry.polyhedron import Polyhedron, _cross

__all__ = ["face_rings", "polyhedron_from_planes", "unit"]


def unit(vectors: np.ndarray) -> np.ndarray:
    """Rows scaled to unit length."""
    vectors = np.asarray(vectors, dtype=float)
    return vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)


def polyhedron_from_planes(normals: np.ndarray, offsets: np.ndarray) -> Polyhedron:
    """The polyhedron ``{x : normals @ x <= offsets}`` with face k on plane k.

    Parameters
    ----------
    normals : (m, 3) float, unit outward normals
    offsets : (m,) float, > 0 (the origin is inside)

    Raises
    ------
    GeometryError
        If the solid is unbounded or degenerate, or a plane does not cut a
        face of its own (it misses the solid or only touches an edge or a
        vertex).
    """
    from scipy.spatial import HalfspaceIntersection, QhullError

    normals = unit(normals)
    offsets = np.asarray(offsets, dtype=float)
    if np.any(offsets <= 0):
        raise GeometryError("every plane offset must be positive (the origin must lie inside the die)")
    if _open_direction(normals):
        raise GeometryError("the planes do not enclose a bounded solid")
    try:
        cut = HalfspaceIntersection(np.column_stack([normals, -offsets]), np.zeros(3))
    except QhullError as exc:
        raise GeometryError(f"the planes do not enclose a solid: {exc}") from exc
    points = cut.intersections
    if not np.all(np.isfinite(points)):
        raise GeometryError("the planes do not enclose a bounded solid")
    eps = tol.LENGTH * 1e3 * max(1.0, float(np.abs(points).max()))
    close = np.abs(points[:, None, :] - points[None, :, :]).max(axis=2) < eps
    points = points[~np.tril(close, -1).any(axis=1)]  # near-duplicates (several planes through one vertex)
    on = np.abs(points @ normals.T - offsets) < eps
    return Polyhedron(points, face_rings(points, normals, on))


def face_rings(points: np.ndarray, normals: np.ndarray, on: np.ndarray) -> tuple[np.ndarray, ...]:
    """Each plane's face: the points on it (`on`, (n, m) bool), counter-clockwise seen from outside.

    A face's points are ordered by their angle about its centre in a basis
    ``(u, v)`` of its plane; every face's basis comes from one row-wise
    cross product.

    Raises
    ------
    GeometryError
        If a plane holds fewer than three points.
    """
    u = _cross(normals, np.where(np.abs(normals[:, :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]))
    v = _cross(normals, u)
    faces = []
    for k in range(len(normals)):
        ring = np.flatnonzero(on[:, k])
        if len(ring) < 3:
            raise GeometryError(f"plane f{k + 1} does not cut a face of the die")
        rel = points[ring] - points[ring].mean(axis=0)
        faces.append(ring[np.argsort(np.arctan2(rel @ v[k], rel @ u[k]))])
    return tuple(faces)


def _open_direction(normals: np.ndarray) -> bool:
    """True if some direction escapes every plane (the normals do not surround the origin)."""
    from scipy.spatial import ConvexHull, QhullError

    # Bounded iff the origin is strictly inside the convex hull of the normals.
    try:
        hull = ConvexHull(normals)
    except QhullError:
        return True
    return bool(np.any(hull.equations[:, 3] > -tol.CONVEXITY))
