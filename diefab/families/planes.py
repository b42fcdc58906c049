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

from .. import tolerances as tol
from ..errors import GeometryError
from ..geometry import Polyhedron

__all__ = ["polyhedron_from_planes", "unit"]


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
    if np.linalg.matrix_rank(normals) < 3 or _open_direction(normals):
        raise GeometryError("the planes do not enclose a bounded solid")
    try:
        cut = HalfspaceIntersection(np.column_stack([normals, -offsets]), np.zeros(3))
    except QhullError as exc:
        raise GeometryError(f"the planes do not enclose a solid: {exc}") from exc
    points = cut.intersections
    if not np.all(np.isfinite(points)):
        raise GeometryError("the planes do not enclose a bounded solid")
    scale = max(1.0, float(np.abs(points).max()))
    points = _unique(points, tol.LENGTH * 1e3 * scale)
    hull = Polyhedron.from_points(points, strict=False)
    order = []
    for k in range(len(normals)):
        match = np.flatnonzero(
            (hull.normals @ normals[k] > 1 - tol.COPLANAR) & (np.abs(hull.offsets - offsets[k]) < 1e-7 * scale)
        )
        if len(match) != 1:
            raise GeometryError(f"plane f{k + 1} does not cut a face of the die")
        order.append(int(match[0]))
    if len(set(order)) != len(hull.faces):
        raise GeometryError("the die has a face that is on no plane")
    return Polyhedron(hull.vertices, tuple(hull.faces[j] for j in order))


def _open_direction(normals: np.ndarray) -> bool:
    """True if some direction d has ``normals @ d <= 0`` for every plane (the solid is unbounded along d)."""
    from scipy.optimize import linprog

    # Bounded iff the normals positively span R^3: no d with N d <= 0 and sum(N d) = -1.
    res = linprog(
        np.zeros(3), A_ub=normals, b_ub=np.zeros(len(normals)), A_eq=normals.sum(axis=0, keepdims=True),
        b_eq=[-1.0], bounds=[(None, None)] * 3, method="highs",
    )  # fmt: skip
    return bool(res.status == 0)


def _unique(points: np.ndarray, eps: float) -> np.ndarray:
    """`points` with near-duplicates (closer than `eps`) merged."""
    keep: list[np.ndarray] = []
    for p in points:
        if not any(np.abs(p - q).max() < eps for q in keep):
            keep.append(p)
    return np.array(keep)
