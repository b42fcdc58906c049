"""Mass integrals of polyhedra and closed meshes: volume, first and second moments, inertia.

Every body here has unit density: a solid's mass is its volume, a sheet's its
area.  Moments add, so a body made of parts (walls, infill, card, tabs) is the
sum of its parts' moments (:func:`combine`), turned into a centre of mass and
an inertia tensor once (:func:`properties`).

Examples
--------
>>> from diefab.geometry.polyhedron import Polyhedron
>>> cube = Polyhedron.from_points([[x, y, z] for x in (0, 2) for y in (0, 2) for z in (0, 2)])
>>> props = properties(*solid_moments(cube))
>>> props.mass, props.center.tolist()
(8.0, [1.0, 1.0, 1.0])
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diefab.geometry.polyhedron import Polyhedron, _cross

__all__ = [
    "MassProperties",
    "Moments",
    "combine",
    "point_moments",
    "properties",
    "sheet_moments",
    "shell_moments",
    "shell_moments_of",
    "solid_moments",
    "solid_moments_of",
    "stated",
]

_CANONICAL = np.array([[2.0, 1.0, 1.0], [1.0, 2.0, 1.0], [1.0, 1.0, 2.0]]) / 120


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


Moments = tuple[float, np.ndarray, np.ndarray]  # mass, first moment (3,), second moment ∫ x xᵀ (3, 3)


def solid_moments(poly: Polyhedron) -> Moments:
    """Volume, first moment and second moment ∫ x xᵀ dV of the solid."""
    return solid_moments_of(poly.vertices[poly.triangles])


def solid_moments_of(v: np.ndarray) -> Moments:
    """The same for the closed surface of outward triangles `v` ((t, 3, 3), corners of each)."""
    # tetrahedra (0, a, b, c)
    det = np.einsum("ij,ij->i", v[:, 0], _cross(v[:, 1], v[:, 2]))
    volume = det.sum() / 6
    first = (det[:, None] * v.sum(axis=1)).sum(axis=0) / 24
    a = v.transpose(0, 2, 1)  # columns are the tetrahedron's vertices
    second = np.einsum("t,tij,jk,tlk->il", det, a, _CANONICAL, a)
    return float(volume), first, second


def sheet_moments(v: np.ndarray, weight: np.ndarray | float = 1.0) -> Moments:
    """Area, first and second moment of triangles `v` (t, 3, 3), each weighted (area density)."""
    area = 0.5 * np.linalg.norm(_cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1) * weight
    s = v.sum(axis=1)
    first = (area[:, None] * s).sum(axis=0) / 3
    second = np.einsum("t,tki,tkj->ij", area, v, v) + np.einsum("t,ti,tj->ij", area, s, s)
    return float(area.sum()), first, second / 12


def shell_moments_of(v: np.ndarray) -> Moments:
    """Area, first moment and second moment ∫ x xᵀ dA of the triangles `v` ((t, 3, 3), corners of each)."""
    return sheet_moments(v)


def shell_moments(poly: Polyhedron) -> Moments:
    """Area, first moment and second moment ∫ x xᵀ dA of the surface."""
    return shell_moments_of(poly.vertices[poly.triangles])


def point_moments(mass: float, at: np.ndarray) -> Moments:
    return float(mass), mass * at, mass * np.outer(at, at)


def combine(*terms: tuple[float, Moments]) -> Moments:
    """Σ weight · moments."""
    mass = sum(w * m[0] for w, m in terms)
    first = sum(w * m[1] for w, m in terms)
    second = sum(w * m[2] for w, m in terms)
    return float(mass), first, second


def properties(mass: float, first: np.ndarray, second: np.ndarray) -> MassProperties:
    center = first / mass
    second_c = second - mass * np.outer(center, center)
    inertia = np.trace(second_c) * np.eye(3) - second_c
    return MassProperties(mass, center, 0.5 * (inertia + inertia.T))


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
