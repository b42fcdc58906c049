"""Mass properties: volume, centre of mass and inertia for three fill models.

``solid``
    a uniform solid body (what the paper's Eq. (1) describes);
``shell``
    a thin uniform shell, mass proportional to area (a paper model);
``print``
    a 3D print: an outer wall of given thickness, the inside filled with a
    fraction `infill` of the material.

All quantities are for unit density (volume for ``solid`` and ``print``,
area for ``shell``): scale `mass` and `inertia` by the real density.

Examples
--------
>>> from diefab.geometry import Polyhedron
>>> cube = Polyhedron.from_points([[x, y, z] for x in (0, 2) for y in (0, 2) for z in (0, 2)])
>>> props = mass_properties(cube)
>>> props.mass, props.center.tolist()
(8.0, [1.0, 1.0, 1.0])
>>> bool(np.allclose(props.inertia, 8 * (4 + 4) / 12 * np.eye(3)))
True
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from . import tolerances as tol
from .errors import DesignError, GeometryError
from .geometry import Polyhedron, _cross
from .meshes import ClosedMesh

__all__ = ["Fill", "MassProperties", "inset", "mass_properties", "mesh_mass_properties", "stated"]

_CANONICAL = np.array([[2.0, 1.0, 1.0], [1.0, 2.0, 1.0], [1.0, 1.0, 2.0]]) / 120


@dataclass(frozen=True)
class Fill:
    """How the die is filled.

    Parameters
    ----------
    kind : {"solid", "shell", "print"}
    wall_mm : float
        Outer wall thickness of a print, millimetres.
    infill : float
        Fraction of the inside of a print that is material, in [0, 1].
    """

    kind: Literal["solid", "shell", "print"] = "solid"
    wall_mm: float = 1.2
    infill: float = 0.15

    def __post_init__(self) -> None:
        if self.kind not in ("solid", "shell", "print"):
            raise DesignError(f"fill kind {self.kind!r} is not one of solid, shell, print")
        if not (np.isfinite(self.wall_mm) and self.wall_mm > 0):
            raise DesignError(f"fill wall_mm={self.wall_mm} must be a positive number of millimetres")
        if not (np.isfinite(self.infill) and 0 <= self.infill <= 1):
            raise DesignError(f"fill infill={self.infill} is outside [0, 1]")


@dataclass(frozen=True, eq=False)
class MassProperties:
    """Mass, centre of mass and inertia tensor (about the centre of mass), unit density."""

    mass: float
    center: np.ndarray
    inertia: np.ndarray

    @property
    def principal_moments(self) -> np.ndarray:
        """(3,) float: eigenvalues of :attr:`inertia`, ascending."""
        return np.linalg.eigvalsh(self.inertia)


def _solid_moments(poly: Polyhedron) -> tuple[float, np.ndarray, np.ndarray]:
    """Volume, first moment and second moment ∫ x xᵀ dV of the solid."""
    return _solid_moments_of(poly.vertices[poly.triangles])


def _solid_moments_of(v: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """The same for the closed surface of outward triangles `v` ((t, 3, 3), corners of each)."""
    # tetrahedra (0, a, b, c)
    det = np.einsum("ij,ij->i", v[:, 0], _cross(v[:, 1], v[:, 2]))
    volume = det.sum() / 6
    first = (det[:, None] * v.sum(axis=1)).sum(axis=0) / 24
    a = v.transpose(0, 2, 1)  # columns are the tetrahedron's vertices
    second = np.einsum("t,tij,jk,tlk->il", det, a, _CANONICAL, a)
    return float(volume), first, second


def _shell_moments(poly: Polyhedron) -> tuple[float, np.ndarray, np.ndarray]:
    """Area, first moment and second moment ∫ x xᵀ dA of the surface."""
    return _shell_moments_of(poly.vertices[poly.triangles])


def _shell_moments_of(v: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """The same for the triangles `v` ((t, 3, 3), corners of each)."""
    area = 0.5 * np.linalg.norm(_cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)
    s = v.sum(axis=1)
    first = (area[:, None] * s).sum(axis=0) / 3
    second = np.einsum("t,tki,tkj->ij", area, v, v) + np.einsum("t,ti,tj->ij", area, s, s)
    return float(area.sum()), first, second / 12


def _properties(mass: float, first: np.ndarray, second: np.ndarray) -> MassProperties:
    center = first / mass
    second_c = second - mass * np.outer(center, center)
    inertia = np.trace(second_c) * np.eye(3) - second_c
    return MassProperties(mass, center, 0.5 * (inertia + inertia.T))


def inset(poly: Polyhedron, distance: float) -> Polyhedron | None:
    """The polyhedron with every face moved inward by `distance`, or None if nothing is left."""
    from scipy.optimize import linprog
    from scipy.spatial import HalfspaceIntersection, QhullError

    normals, offsets = poly.normals, poly.offsets - distance
    # Chebyshev centre: the point deepest inside the shrunk half-spaces
    res = linprog(
        c=[0, 0, 0, -1],
        A_ub=np.column_stack([normals, np.ones(len(normals))]),
        b_ub=offsets,
        bounds=[(None, None)] * 3 + [(0, None)],
        method="highs",
    )
    if not res.success or res.x[3] <= tol.LENGTH * max(1.0, float(np.ptp(poly.vertices, axis=0).max())):
        return None
    try:
        hs = HalfspaceIntersection(np.column_stack([normals, -offsets]), res.x[:3])
    except QhullError:
        return None
    try:
        return Polyhedron.from_points(hs.intersections, strict=False)
    except GeometryError:
        # planes of many small faces meet in near-duplicate corners: merge within a sliver of the die's size
        scale = max(1.0, float(np.ptp(poly.vertices, axis=0).max()))
        return Polyhedron.from_points(hs.intersections, strict=False, merge_tolerance=tol.INSET_MERGE * scale)


def mass_properties(poly: Polyhedron, fill: Fill | None = None, *, mm_per_unit: float = 1.0) -> MassProperties:
    """Mass properties of `poly` for the given fill model, unit density.

    Parameters
    ----------
    poly : Polyhedron
        Model units.
    fill : Fill, optional
        Solid by default.
    mm_per_unit : float
        Physical size of one model unit, used to turn a print's wall
        thickness into model units.
    """
    fill = fill or Fill()
    if fill.kind == "solid":
        return _properties(*_solid_moments(poly))
    if fill.kind == "shell":
        return _properties(*_shell_moments(poly))
    outer = _solid_moments(poly)
    inner_poly = inset(poly, fill.wall_mm / mm_per_unit)
    if inner_poly is None:  # wall thicker than the die: it prints solid
        return _properties(*outer)
    inner = _solid_moments(inner_poly)
    hollow = 1 - fill.infill
    return _properties(outer[0] - hollow * inner[0], outer[1] - hollow * inner[1], outer[2] - hollow * inner[2])


def mesh_mass_properties(mesh: ClosedMesh, fill: Fill | None = None, *, mm_per_unit: float = 1.0) -> MassProperties:
    """Mass properties of the body bounded by a closed, possibly non-convex mesh, unit density.

    ``solid`` and ``shell`` are exact for the mesh.  ``print`` takes the
    wall as a thin layer of the surface, ``wall_mm`` thick, and the rest of
    the volume at ``infill``: exact to first order in the wall thickness
    over the body's local size (a convex body's print is computed exactly
    by :func:`mass_properties` on its polyhedron).
    """
    fill = fill or Fill()
    v = mesh.corners
    if fill.kind == "solid":
        return _properties(*_solid_moments_of(v))
    if fill.kind == "shell":
        return _properties(*_shell_moments_of(v))
    solid, surface = _solid_moments_of(v), _shell_moments_of(v)
    wall = fill.wall_mm / mm_per_unit
    if wall * surface[0] >= solid[0]:  # walls meet: the print is solid
        return _properties(*solid)
    return _properties(*(fill.infill * a + (1 - fill.infill) * wall * b for a, b in zip(solid, surface)))


def stated(props: MassProperties, center=None, inertia=None) -> MassProperties:
    """`props` with a stated centre of mass and, optionally, inertia per unit mass (model units).

    Parameters
    ----------
    center : (3,) float, optional
        Replaces the centre of mass; the inertia tensor is kept (it is the
        body's about its own centre of mass) unless `inertia` is given.
    inertia : (3, 3) float, optional
        Inertia tensor about the centre of mass divided by the mass,
        model units²: multiplied by the body's mass.
    """
    c = props.center if center is None else np.asarray(center, dtype=float)
    i = props.inertia if inertia is None else props.mass * np.asarray(inertia, dtype=float)
    return MassProperties(props.mass, c, i)
