"""A die with rounded edges: its body, the flat part of each face, and where it lands.

Landing model of a rounded die
------------------------------
A rounded die can only rest on the flat parts of its faces; a die that lands
on a rounded edge rolls off onto one of them.  The rounded die's prediction is
the solid angle that each *flat* face polygon subtends at the centre of mass,
normalised by their sum (the rounded zones' share is spread in proportion).
Without rounding this is exactly the paper's solid-angle model.

The body is the die shrunk by the radius and grown back by a ball
(:func:`rounded_body`), built and checked with manifold3d.
"""

from __future__ import annotations

import math

import numpy as np

from diefab.core import tolerances as tol
from diefab.fabricate.engrave import checked
from diefab.geometry.polyhedron import Polyhedron
from diefab.made.mass import inset

__all__ = [
    "ROUND_SEGMENTS",
    "flat_face_probabilities",
    "flat_faces",
    "hull_body",
    "mesh_moments",
    "rotation_to_down",
    "rounded_body",
]

#: Segments of the spheres that round edges and corners.
ROUND_SEGMENTS = 32

# ----------------------------------------------------------------------
# small pure helpers


def mesh_moments(vertices: np.ndarray, triangles: np.ndarray) -> tuple[float, np.ndarray]:
    """Volume and first moment ∫ x dV of a closed, outward-oriented triangle mesh.

    Returns
    -------
    volume : float
    first : (3,) float
        Divide by the volume for the centre of mass.
    """
    v = np.asarray(vertices, dtype=float)[np.asarray(triangles)]
    det = np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2]))
    return float(det.sum() / 6), (det[:, None] * v.sum(axis=1)).sum(axis=0) / 24


def _polygon_solid_angle(points: np.ndarray, center: np.ndarray) -> float:
    """Solid angle of a planar convex polygon (ordered ring, (k, 3)) seen from `center`."""
    r = points - center
    a = np.repeat(r[:1], len(r) - 2, axis=0)
    b, c = r[1:-1], r[2:]
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    triple = np.einsum("ij,ij->i", a, np.cross(b, c))
    denom = la * lb * lc + (a * b).sum(1) * lc + (a * c).sum(1) * lb + (b * c).sum(1) * la
    return float(abs((2 * np.arctan2(triple, denom)).sum()))


def flat_face_probabilities(flat_faces: list[np.ndarray | None], center: np.ndarray) -> np.ndarray:
    """(m,) float: solid angle of each flat face polygon at `center`, normalised to sum 1.

    `flat_faces` holds an ordered (k, 3) ring per face, or None where rounding
    left no flat part (probability 0).
    """
    omega = np.array([0.0 if f is None else _polygon_solid_angle(f, center) for f in flat_faces])
    return omega / omega.sum()


def rotation_to_down(normal: np.ndarray) -> np.ndarray:
    """(3, 3): the rotation taking unit vector `normal` to (0, 0, -1) (Rodrigues)."""
    target = np.array([0.0, 0.0, -1.0])
    axis = np.cross(normal, target)
    s, c = np.linalg.norm(axis), float(normal @ target)
    if s < 1e-12:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    k = axis / s
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * kx + (1 - c) * kx @ kx


# ----------------------------------------------------------------------
# building


def hull_body(points_mm: np.ndarray):
    import manifold3d

    return checked(manifold3d.Manifold.hull_points(np.ascontiguousarray(points_mm, dtype=float)), "building the hull")


def rounded_body(poly: Polyhedron, scale: float, inset_mm: float, radius_mm: float, clip):
    """The polyhedron shrunk by `inset_mm`, grown back by spheres of `radius_mm`, clipped by `clip`."""
    import manifold3d

    core = inset(poly, inset_mm / scale) if inset_mm > 0 else poly
    if core is None:
        return None
    if radius_mm <= 0:
        return hull_body(core.vertices * scale)
    # the sphere's polygon must cover the true sphere, so the flat faces land on the original planes
    cover = radius_mm / math.cos(math.pi / ROUND_SEGMENTS) ** 2
    sphere = manifold3d.Manifold.sphere(cover, ROUND_SEGMENTS).to_mesh64()
    sphere_pts = np.asarray(sphere.vert_properties)[:, :3]
    points = (core.vertices * scale)[:, None, :] + sphere_pts[None, :, :]
    body = hull_body(points.reshape(-1, 3))
    return checked(body ^ clip, "clipping the rounded body to the face planes")


def flat_faces(poly: Polyhedron, scale: float, round_mm: float) -> list[np.ndarray | None]:
    """The flat part of each face after rounding by `round_mm` (mm, ordered rings), None where none is left.

    Rounding is the die shrunk by the radius and grown back by a ball, so the
    flat part of face k is face k of the shrunk die moved out by the radius
    along its normal: exact, whatever the face's orientation.
    """
    rings = [poly.vertices[f] * scale for f in poly.faces]
    if round_mm <= 0:
        return rings
    core = inset(poly, round_mm / scale)
    if core is None:
        return [None] * len(poly.faces)
    out: list[np.ndarray | None] = []
    for k in range(len(poly.faces)):
        cos = core.normals @ poly.normals[k]
        j = int(np.argmax(cos))
        if cos[j] < 1 - tol.COPLANAR or core.areas[j] * scale**2 <= tol.AREA * scale**2:
            out.append(None)
            continue
        out.append(core.vertices[core.faces[j]] * scale + round_mm * poly.normals[k])
    return out
