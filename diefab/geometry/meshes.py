"""Closed triangle meshes: the real body of a die that need not be convex.

A die rests on its convex hull (:class:`~diefab.geometry.polyhedron.Polyhedron`), but
its mass sits where the body is: a figurine die's centre of mass can lie
millimetres off its hull's centroid.  :class:`ClosedMesh` holds the body as
a watertight, outward-oriented triangle mesh; :mod:`diefab.made.mass` takes its
volume, centre of mass and inertia from it.

Examples
--------
>>> import trimesh
>>> box = ClosedMesh.from_trimesh(trimesh.creation.box(extents=(2, 2, 2)))
>>> round(box.volume, 12), box.is_convex()
(8.0, True)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from diefab.core import tolerances as tol
from diefab.core.errors import GeometryError

__all__ = ["ClosedMesh"]


@dataclass(frozen=True, eq=False)
class ClosedMesh:
    """A watertight triangle mesh with outward normals (model units).

    Attributes
    ----------
    vertices : (n, 3) float
    triangles : (t, 3) int
        Counter-clockwise seen from outside.
    """

    vertices: np.ndarray
    triangles: np.ndarray

    @classmethod
    def from_trimesh(cls, mesh, source: str = "mesh") -> ClosedMesh:
        """Check that `mesh` (a :class:`trimesh.Trimesh`) is closed and orient it outward."""
        if len(mesh.vertices) < 4 or len(mesh.faces) < 4:
            raise GeometryError(f"{source} has fewer than 4 vertices or faces")
        if not np.all(np.isfinite(mesh.vertices)):
            raise GeometryError(f"{source} has NaN or infinite coordinates")
        if not mesh.is_watertight:
            raise GeometryError(f"{source} is not a closed surface (it has open or non-manifold edges)")
        if not mesh.is_winding_consistent:
            raise GeometryError(f"{source} is not consistently oriented")
        triangles = np.array(mesh.faces, dtype=np.intp)
        if mesh.volume < 0:
            triangles = triangles[:, ::-1]
        out = cls(np.array(mesh.vertices, dtype=float), triangles)
        if out.volume <= tol.VOLUME * max(1.0, float(np.ptp(out.vertices, axis=0).max())) ** 3:
            raise GeometryError(f"{source} encloses no volume")
        return out

    @classmethod
    def load(cls, path: str | Path) -> ClosedMesh:
        """Read a closed mesh file (STL, OBJ, PLY, ... through trimesh)."""
        import trimesh

        path = Path(path)
        try:
            mesh = trimesh.load(path, force="mesh", process=True)
        except Exception as exc:  # trimesh raises many types for unreadable files
            raise GeometryError(f"cannot read mesh {path}: {exc}") from exc
        if not isinstance(mesh, trimesh.Trimesh):
            raise GeometryError(f"mesh {path} holds no triangles")
        return cls.from_trimesh(mesh, source=f"mesh {path}")

    def scaled(self, factor: float) -> ClosedMesh:
        """A copy scaled about the origin."""
        return ClosedMesh(self.vertices * factor, self.triangles)

    @property
    def corners(self) -> np.ndarray:
        """(t, 3, 3) float: the vertices of every triangle."""
        return self.vertices[self.triangles]

    @cached_property
    def volume(self) -> float:
        v = self.corners
        return float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6)

    def is_convex(self) -> bool:
        """Whether the body fills its convex hull (to :data:`~diefab.core.tolerances.MESH_REL`)."""
        from scipy.spatial import ConvexHull

        return self.volume >= (1 - tol.MESH_REL) * ConvexHull(self.vertices).volume

    def to_stl(self) -> bytes:
        """The mesh as binary STL bytes."""
        import trimesh

        return trimesh.Trimesh(self.vertices, self.triangles, process=False).export(file_type="stl")
