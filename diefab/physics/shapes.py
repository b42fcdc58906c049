"""The die as the physics engine holds it: one hull, or flat-faced parts where the hull would fold a face.

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
a face the die can rest on folds, the die is given as a compound of convex
parts (:func:`flat_parts`), each in a frame where the faces it carries are
planes of constant z: the rounding moves all the corners of such a face by
the same amount along z, so it stays flat, and only moves them within its
plane, by at most 1/10216 of the part's size.  Two opposite faces share a
part (the hull of their corners); another face's part is its pyramid to the
centre of mass.  Faces the die cannot rest on are left to the hull, shrunk
towards the centre of mass by :data:`INSET` so that its rounding never
lifts it past a flat face.  A face flat only within a tolerance (a printed
die's mesh) is made flat too: its corners move onto the plane through their
mean.  The compound costs the engine more per step, so a die whose hull
keeps every resting face flat stays one hull.

Examples
--------
A cube's opposite faces pair up, three parts, each a box with two faces on
planes of constant z:

>>> from itertools import product
>>> import numpy as np
>>> from diefab.geometry.polyhedron import Polyhedron
>>> cube = Polyhedron.from_points(list(product((-1.0, 1.0), repeat=3)))
>>> parts = flat_parts(cube.vertices, cube.normals, cube.faces)
>>> len(parts), [len(q.faces) for q in parts]
(3, [2, 2, 2])
>>> sorted(set(np.round(parts[0].points[:, 2], 12).tolist()))
[-2.0, 0.0]
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["FlatPart", "engine_shape", "flat_parts", "folded_faces", "folded_resting_faces"]

#: The rest of a die whose resting faces are held flat is its hull shrunk by this fraction towards the centre of mass.
INSET = 2e-3
#: Two faces whose unit normals' dot product is below this minus 1 are opposite.
_OPPOSITE = 1e-9
#: A face whose corners leave their best-fit plane by more than this (units of the die's radius) is folded.
FOLD = 1e-9


@dataclass(frozen=True, eq=False)
class FlatPart:
    """A convex part of a die, given in a frame where the die's faces it carries are planes z = constant.

    Attributes
    ----------
    points : (k, 3) float
        The part's corners in its frame: the corners of its faces (the
        first face's at z exactly 0, an opposite face's at one z) and, for
        a single face, the centre of mass.
    position : (3,) float
        The frame's origin in the body frame: the mean of the first face's corners.
    rotation : (3, 3) float
        Columns are the frame's axes in the body frame; the third is the
        first face's outward normal.
    faces : tuple of int
        The die's faces the part carries: one, or two opposite ones.
    """

    points: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    faces: tuple[int, ...]

    def body_points(self) -> np.ndarray:
        """(k, 3) float: the points in the body frame."""
        return self.points @ self.rotation.T + self.position


def _frame(normal: np.ndarray) -> np.ndarray:
    """A rotation whose third column is the unit vector `normal`."""
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u)
    return np.column_stack([u, np.cross(normal, u), normal])


def flat_parts(
    vertices: np.ndarray, normals: np.ndarray, faces: Sequence[Sequence[int]], keep: np.ndarray | None = None
) -> list[FlatPart]:
    """Convex parts of the die `vertices` that carry each face of mask `keep` flat in their own frame.

    Two opposite faces (antiparallel normals) share a part, the hull of
    their corners, which lies inside the die; any other face's part is its
    pyramid to the centre of mass (the origin, inside a convex die).

    Parameters
    ----------
    vertices : (n, 3) float
        Corners, body frame (origin inside the die).
    normals : (m, 3) float
        Outward unit face normals, body frame.
    faces : sequence of m index sequences
        Each face's corners, indices into `vertices`.
    keep : (m,) bool, optional
        The faces to carry (default: all).
    """
    vertices = np.asarray(vertices, dtype=float)
    normals = np.asarray(normals, dtype=float)
    todo = [int(k) for k in np.flatnonzero(np.ones(len(normals), bool) if keep is None else keep)]
    left = set(todo)
    out = []
    for f in todo:
        if f not in left:
            continue
        left.discard(f)
        opposite = [g for g in left if normals[f] @ normals[g] < _OPPOSITE - 1.0]
        corners = vertices[np.asarray(faces[f])]
        center = corners.mean(axis=0)
        rotation = _frame(normals[f])
        local = (corners - center) @ rotation
        local[:, 2] = 0.0
        if opposite:
            g = opposite[0]
            left.discard(g)
            other = (vertices[np.asarray(faces[g])] - center) @ rotation
            other[:, 2] = other[:, 2].mean()
            out.append(FlatPart(np.vstack([local, other]), center, rotation, (f, g)))
        else:
            out.append(FlatPart(np.vstack([local, -center @ rotation]), center, rotation, (f,)))
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


def folded_resting_faces(p, body) -> np.ndarray:
    """(m,) bool: the faces `body` can rest on that pybullet folds as one hull: the faces flat faces hold flat."""
    return folded_faces(p, body) & body.basins.resting


def _write_obj(path: Path, points: np.ndarray) -> None:
    from scipy.spatial import ConvexHull

    triangles = ConvexHull(points).simplices + 1
    text = "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in points.tolist())
    text += "".join(f"f {a} {b} {c}\n" for a, b, c in triangles.tolist())
    path.write_text(text)


def engine_shape(p, body, faces: np.ndarray, client: int, directory: str | Path) -> int:
    """A pybullet collision shape of the convex die `body` that holds the faces of mask `faces` flat.

    The compound of those faces' :func:`flat_parts` and, when they are
    not all of the die's faces, the die's hull shrunk towards its centre of
    mass by :data:`INSET` (so that the engine's rounding never lifts it
    past a flat face).  pybullet builds a compound of meshes only from
    files: each part is written to a Wavefront OBJ file in `directory`,
    which must stay until the bodies of the shape have been created (the
    engine reads the files again then).
    """
    from scipy.spatial.transform import Rotation

    flat = flat_parts(body.vertices, body.normals, body.faces, faces)
    parts = [(q.points, q.position, Rotation.from_matrix(q.rotation).as_quat()) for q in flat]
    if not np.all(faces):
        parts.append(((1.0 - INSET) * body.vertices, np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0])))
    names = []
    for k, (points, _, _) in enumerate(parts):
        path = Path(directory) / f"part{k}.obj"
        _write_obj(path, points)
        names.append(str(path))
    return p.createCollisionShapeArray(
        shapeTypes=[p.GEOM_MESH] * len(parts),
        fileNames=names,
        collisionFramePositions=[position.tolist() for _, position, _ in parts],
        collisionFrameOrientations=[quaternion.tolist() for _, _, quaternion in parts],
        physicsClientId=client,
    )
