"""The die as the physics engine holds it: one hull, or one pyramid per face when the hull would fold its faces.

Bullet rounds the corners of a convex hull to a grid of 1/10216 of the
hull's bounding box on each axis (``btConvexHullComputer``, which every
hull goes through).  A triangle stays flat, and so does a face that lies
across an axis, but any other face with four or more corners does not: its
corners leave its plane by up to a grid step, so in the engine it folds
along a diagonal and the die rests on one half of it.  The fold is tiny
(about 1e-4 of the die's size), but where a die rests is decided by its
support polygon, and the fold halves it: on a die whose faces are shallow,
the faces the grid folds most land least, and faces its symmetry makes
alike land unevenly (a fair 26-face trapezohedron's least folded kites
landed about twice as often as its most folded ones).

:func:`folded_faces` measures the folds on the hull the engine made.  When
there are any, the die is given as a compound of pyramids, one per face:
the face is the pyramid's base and the centre of mass its apex (inside a
convex die, so the pyramids fill it).  Each pyramid is given in a frame
whose plane z = 0 is its face, so the rounding, which moves every base
corner by the same amount along z, keeps the face flat, and only moves its
corners within the face's plane by at most 1/10216 of the face's size.  A
face that is itself flat only within a tolerance (a printed die's mesh) is
made flat there too: its corners move onto the plane through their mean.
The compound costs the engine more per step (two to four times on the dice
measured), so a die whose hull keeps every face flat stays one hull.

Examples
--------
The cube's six pyramids have square bases on z = 0 and their apex at the
centre, a half-width below:

>>> from itertools import product
>>> import numpy as np
>>> from diefab.geometry.polyhedron import Polyhedron
>>> cube = Polyhedron.from_points(list(product((-1.0, 1.0), repeat=3)))
>>> pyramids = face_pyramids(cube.vertices, cube.normals, cube.faces)
>>> len(pyramids), {len(p.points) for p in pyramids}
(6, {5})
>>> float(np.abs(pyramids[0].points[:4, 2]).max()), float(pyramids[0].points[4, 2])
(0.0, -1.0)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["FacePyramid", "engine_shape", "face_pyramids", "folded_faces"]

#: A face whose corners leave their best-fit plane by more than this (units of the die's radius) is folded.
FOLD = 1e-9


@dataclass(frozen=True, eq=False)
class FacePyramid:
    """One face's pyramid in the face's own frame.

    Attributes
    ----------
    points : (k + 1, 3) float
        The face's ``k`` corners (z exactly 0) and then the apex (the
        centre of mass), in the face's frame.
    position : (3,) float
        The frame's origin in the body frame: the mean of the face's corners.
    rotation : (3, 3) float
        Columns are the frame's axes in the body frame; the third is the
        face's outward normal.
    """

    points: np.ndarray
    position: np.ndarray
    rotation: np.ndarray

    def body_points(self) -> np.ndarray:
        """(k + 1, 3) float: the points in the body frame."""
        return self.points @ self.rotation.T + self.position


def _frame(normal: np.ndarray) -> np.ndarray:
    """A rotation whose third column is the unit vector `normal`."""
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u)
    return np.column_stack([u, np.cross(normal, u), normal])


def face_pyramids(vertices: np.ndarray, normals: np.ndarray, faces: Sequence[Sequence[int]]) -> list[FacePyramid]:
    """The pyramid over each face of the convex die `vertices`, apex at the origin (its centre of mass).

    Parameters
    ----------
    vertices : (n, 3) float
        Corners, body frame (origin inside the die).
    normals : (m, 3) float
        Outward unit face normals, body frame.
    faces : sequence of m index sequences
        Each face's corners, indices into `vertices`.
    """
    vertices = np.asarray(vertices, dtype=float)
    out = []
    for ring, normal in zip(faces, np.asarray(normals, dtype=float)):
        corners = vertices[np.asarray(ring)]
        center = corners.mean(axis=0)
        rotation = _frame(normal)
        local = (corners - center) @ rotation
        local[:, 2] = 0.0
        apex = -center @ rotation
        out.append(FacePyramid(np.vstack([local, apex]), center, rotation))
    return out


def folded_faces(p, body) -> np.ndarray:
    """(m,) bool: the faces of `body` that pybullet folds when it holds the die as one hull (module notes)."""
    from scipy.spatial import cKDTree

    client = p.connect(p.DIRECT)  # a world of its own, so that nothing is left in the caller's
    try:
        shape = p.createCollisionShape(p.GEOM_MESH, vertices=body.vertices.tolist(), physicsClientId=client)
        probe = p.createMultiBody(0, shape, physicsClientId=client)
        _, held = p.getMeshData(probe, -1, physicsClientId=client)
    finally:
        p.disconnect(physicsClientId=client)
    held = np.asarray(held, dtype=float)
    if held.ndim != 2 or len(held) < 4:  # the engine gave no corners to measure: take its faces as folded
        return np.ones(len(body.faces), dtype=bool)
    rounded = held[cKDTree(held).query(body.vertices)[1]]  # each corner as the engine holds it
    fold = np.zeros(len(body.faces))
    for k, ring in enumerate(body.faces):
        if len(ring) > 3:
            corners = rounded[np.asarray(ring)]
            fold[k] = np.linalg.svd(corners - corners.mean(axis=0), compute_uv=False)[-1]
    return fold > FOLD * body.radius


def _write_obj(path: Path, points: np.ndarray) -> None:
    from scipy.spatial import ConvexHull

    triangles = ConvexHull(points).simplices + 1
    text = "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in points.tolist())
    text += "".join(f"f {a} {b} {c}\n" for a, b, c in triangles.tolist())
    path.write_text(text)


def engine_shape(p, body, client: int, directory: str | Path) -> int:
    """A pybullet collision shape of the convex die `body`: the compound of its :func:`face_pyramids`.

    pybullet builds a compound of meshes only from files: each pyramid is
    written to a Wavefront OBJ file in `directory`, which must stay until
    the bodies of the shape have been created (the engine reads the files
    again then).
    """
    from scipy.spatial.transform import Rotation

    pyramids = face_pyramids(body.vertices, body.normals, body.faces)
    names = []
    for k, pyramid in enumerate(pyramids):
        path = Path(directory) / f"face{k}.obj"
        _write_obj(path, pyramid.points)
        names.append(str(path))
    return p.createCollisionShapeArray(
        shapeTypes=[p.GEOM_MESH] * len(pyramids),
        fileNames=names,
        collisionFramePositions=[q.position.tolist() for q in pyramids],
        collisionFrameOrientations=[Rotation.from_matrix(q.rotation).as_quat().tolist() for q in pyramids],
        physicsClientId=client,
    )
