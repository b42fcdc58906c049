"""The symmetry group of a polyhedron: the rotations and reflections that map it onto itself.

A symmetry fixes the centroid of the vertices and permutes vertices, edges
and faces.  It is found from one reference face: a symmetry takes that face
to a face of the same shape, with one of its vertices first and either
orientation, and that choice fixes the orthogonal map; each candidate is
kept if it carries every vertex onto a vertex.  What a symmetric die's
paper body needs from it is the *fixed set* of the group (the symmetry axis
of a gem, the mirror plane of a die with one mirror, the centre of a cube):
a body symmetric under the group has its centre of mass there, and how far
a glue-tab layout puts its tabs' centre of mass off it is the asymmetry the
net adds (:func:`off_axis`).

Examples
--------
>>> from diefab import Polyhedron
>>> cube = Polyhedron.from_points([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)])
>>> len(symmetries(cube))  # the full octahedral group, reflections included
48
>>> box = Polyhedron.from_points([[x, y, z] for x in (0, 3) for y in (0, 2) for z in (0, 1)])
>>> len(symmetries(box)), float(off_axis(symmetries(box), box.vertices.mean(axis=0) + [0.5, 0, 0]))
(8, 0.5)
>>> symmetries(cube).fixed_set, symmetries(box).fixed_set
('centre', 'centre')
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diefab.core import tolerances as tol
from diefab.geometry.polyhedron import Polyhedron

__all__ = ["Symmetries", "off_axis", "symmetries"]


@dataclass(frozen=True, eq=False)
class Symmetries:
    """A polyhedron's symmetry group, identity first.

    Attributes
    ----------
    center : (3,) float
        The fixed point (centroid of the vertices), model units.
    matrices : (g, 3, 3) float
        Orthogonal maps ``x -> M (x - center) + center``.
    vertex, edge, face : (g, V), (g, E), (g, F) int
        Where each symmetry takes each vertex, edge (index into
        ``poly.edges``) and face.
    """

    center: np.ndarray
    matrices: np.ndarray
    vertex: np.ndarray
    edge: np.ndarray
    face: np.ndarray

    def __len__(self) -> int:
        return len(self.matrices)

    @property
    def projector(self) -> np.ndarray:
        """(3, 3) orthogonal projection onto the fixed set (the mean of the group's matrices)."""
        return self.matrices.mean(axis=0)

    @property
    def fixed_set(self) -> str:
        """What the group fixes: ``"centre"``, ``"axis"``, ``"plane"`` or ``"space"`` (no symmetry)."""
        rank = int(round(float(np.trace(self.projector))))
        return ("centre", "axis", "plane", "space")[rank]

    def subgroup(self, keep: np.ndarray) -> Symmetries:
        """The symmetries selected by the boolean mask or index array `keep` (a subgroup if the caller says so)."""
        return Symmetries(self.center, self.matrices[keep], self.vertex[keep], self.edge[keep], self.face[keep])


def symmetries(poly: Polyhedron) -> Symmetries:
    """Every orthogonal map of `poly` onto itself (within :data:`~diefab.core.tolerances.SYMMETRY_REL` of its size)."""
    from scipy.spatial import cKDTree

    verts = poly.vertices
    center = verts.mean(axis=0)
    rel = verts - center
    eps = tol.SYMMETRY_REL * float(np.linalg.norm(rel, axis=1).max())
    sizes = np.array([len(f) for f in poly.faces])
    areas, normals, cents = poly.areas, poly.normals, poly.face_centroids
    perims = np.array([np.linalg.norm(verts[f] - verts[np.roll(f, -1)], axis=1).sum() for f in poly.faces])
    scale = max(float(np.abs(rel).max()), tol.LENGTH)
    same = (
        (sizes[:, None] == sizes[None, :])
        & (np.abs(areas[:, None] - areas[None, :]) <= eps * scale * 4)
        & (np.abs(perims[:, None] - perims[None, :]) <= eps * 4 * sizes[:, None])
    )
    ref = int(np.argmin(same.sum(axis=1)))  # the rarest face shape: the fewest candidates
    f0 = poly.faces[ref]
    frame = np.column_stack([verts[f0[0]] - cents[ref], verts[f0[1]] - cents[ref], normals[ref]])
    inverse = np.linalg.inv(frame)
    tree = cKDTree(verts)
    probe = rel[np.linspace(0, len(rel) - 1, min(8, len(rel))).astype(int)]
    maps, perms = [], []
    for f in np.flatnonzero(same[ref]):
        ring = poly.faces[f]
        n = len(ring)
        for i in range(n):
            for step in (1, -1):
                image = np.column_stack([verts[ring[i]] - cents[f], verts[ring[(i + step) % n]] - cents[f], normals[f]])
                m = image @ inverse
                if not np.allclose(m.T @ m, np.eye(3), atol=1e-6):
                    continue
                if tree.query(probe @ m.T + center)[0].max() > eps:  # most candidates fail on a few vertices
                    continue
                dist, idx = tree.query(rel @ m.T + center)
                if dist.max() <= eps and len(np.unique(idx)) == len(verts):
                    maps.append(m)
                    perms.append(idx)
    order = np.argsort([np.abs(m - np.eye(3)).max() for m in maps], kind="stable")  # identity first
    maps, perms = [maps[k] for k in order], [perms[k] for k in order]
    edge_of = {(int(a), int(b)): e for e, (a, b) in enumerate(poly.edges)}
    edge_of.update({(b, a): e for (a, b), e in list(edge_of.items())})
    face_of = {frozenset(f.tolist()): k for k, f in enumerate(poly.faces)}
    edge_perm = np.array([[edge_of[int(p[a]), int(p[b])] for a, b in poly.edges] for p in perms])
    face_perm = np.array([[face_of[frozenset(p[f].tolist())] for f in poly.faces] for p in perms])
    return Symmetries(center, np.array(maps), np.array(perms), edge_perm, face_perm)


def off_axis(group: Symmetries, point: np.ndarray) -> float:
    """Distance of `point` (model units) from the fixed set of `group`, model units."""
    rel = np.asarray(point, dtype=float) - group.center
    return float(np.linalg.norm(rel - group.projector @ rel))
