"""Convex polyhedra: the :class:`Polyhedron` value and pure functions on it.

A polyhedron is a vertex array and a tuple of polygonal faces, each an
index array listed counter-clockwise seen from outside (outward normal by the
right-hand rule).  Construction validates that the surface is closed, every
face planar and non-degenerate, and the solid convex; every derived quantity
(normals, areas, edges, volume) is computed from those two arrays on demand.
Where a die rolls to from any orientation is :class:`diefab.models.basins.RestBasins`.

Examples
--------
>>> cube = Polyhedron.from_points([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
>>> len(cube.faces), round(cube.volume, 12), round(cube.surface_area, 12)
(6, 8.0, 24.0)
>>> probs = solid_angles(cube, cube.centroid) / (4 * np.pi)
>>> np.allclose(probs, 1 / 6)
True
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from diefab.core import tolerances as tol
from diefab.core.errors import GeometryError

#: Most triangles of a convex hull read (a die's hull, even a rounded scan's, has a few thousand).
MAX_HULL_TRIANGLES = 50_000
#: Most faces of a polyhedron (after merging coplanar triangles): the models scale with the faces squared.
MAX_FACES = 5_000

__all__ = [
    "Polyhedron",
    "face_margins",
    "hull_diameter",
    "resting_faces",
    "solid_angles",
    "up_faces",
]


def _hull(points) -> tuple[np.ndarray, object]:
    """(points as floats, their scipy ``ConvexHull``), refusing what no die's hull is."""
    from scipy.spatial import ConvexHull, QhullError

    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < 4:
        raise GeometryError(f"need at least 4 points in 3D, got shape {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise GeometryError("points contain NaN or infinite coordinates")
    try:
        hull = ConvexHull(pts)
    except QhullError as exc:
        raise GeometryError("points are degenerate (coplanar, collinear or coincident)") from exc
    if hull.volume <= tol.VOLUME * max(1.0, np.ptp(pts, axis=0).max() ** 3):
        raise GeometryError("points span no volume")
    if len(hull.simplices) > MAX_HULL_TRIANGLES:
        raise GeometryError(f"the convex hull has {len(hull.simplices):,} triangles, more than the "
                            f"{MAX_HULL_TRIANGLES:,} a die's hull needs: simplify the mesh")  # fmt: skip
    return pts, hull


def hull_diameter(points) -> float:
    """The largest distance between two of `points`, found among their hull's vertices in bounded memory.

    Refuses what :meth:`Polyhedron.from_points` refuses, before any distance.

    Examples
    --------
    >>> from itertools import product
    >>> round(hull_diameter(list(product((0.0, 1.0), repeat=3))) ** 2, 12)
    3.0
    """
    from scipy.spatial.distance import cdist

    pts, hull = _hull(points)
    corners = pts[hull.vertices]
    rows = max(1, 4_000_000 // len(corners))  # distances held at once: 32 MB
    return float(np.sqrt(max(cdist(corners[i : i + rows], corners, "sqeuclidean").max()
                             for i in range(0, len(corners), rows))))  # fmt: skip


@dataclass(frozen=True, eq=False)
class Polyhedron:
    """A closed convex polyhedron with outward-oriented polygonal faces.

    Parameters
    ----------
    vertices : (n, 3) float
        Vertex coordinates, model units.
    faces : sequence of int sequences
        Vertex indices of each face, counter-clockwise seen from outside.
    names : sequence of str, optional
        One name per face; ``f1 .. fm`` by default.
    flatness : float, optional
        Largest distance (model units) a vertex may lie off its face's plane,
        or outside another face's, for faces measured off a real object (a
        printed die's mesh); the planes are the faces' best fits
        (:attr:`face_flatness` reports each face's distance).  By default the
        faces must be planar to rounding (:data:`~diefab.tolerances.PLANARITY`).

    Raises
    ------
    GeometryError
        If the faces are not planar, the surface is not closed, a face or the
        volume is degenerate, or the solid is not convex.
    """

    vertices: np.ndarray
    faces: tuple[np.ndarray, ...]
    names: tuple[str, ...] = ()
    flatness: float | None = None

    def __post_init__(self) -> None:
        vertices = np.array(self.vertices, dtype=float)
        if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) < 4:
            raise GeometryError(f"vertices must be an (n, 3) array with n >= 4, got shape {vertices.shape}")
        if not np.all(np.isfinite(vertices)):
            raise GeometryError("vertices contain NaN or infinite coordinates")
        vertices.setflags(write=False)
        faces = []
        for k, face in enumerate(self.faces):
            idx = np.array(face, dtype=np.intp)
            if idx.ndim != 1 or len(idx) < 3:
                raise GeometryError(f"face {k} has fewer than 3 vertices")
            if idx.min() < 0 or idx.max() >= len(vertices):
                raise GeometryError(f"face {k} refers to a vertex that does not exist")
            if len(set(idx.tolist())) != len(idx):
                raise GeometryError(f"face {k} repeats a vertex")
            idx.setflags(write=False)
            faces.append(idx)
        names = tuple(self.names) if self.names else tuple(f"f{k + 1}" for k in range(len(faces)))
        if len(names) != len(faces):
            raise GeometryError(f"{len(names)} face names for {len(faces)} faces")
        if len(set(names)) != len(names):
            raise GeometryError("face names are not unique")
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "faces", tuple(faces))
        object.__setattr__(self, "names", names)
        self._validate()

    # ------------------------------------------------------------------
    # construction
    @classmethod
    def from_points(
        cls, points: Iterable[Sequence[float]], *, strict: bool = True, merge_tolerance: float | None = None
    ) -> Polyhedron:
        """The convex hull of `points`, with coplanar hull triangles merged into faces.

        Parameters
        ----------
        points : (n, 3) float
        strict : bool
            If true, every point must be a vertex of the hull: a point inside
            or on the boundary means the list does not describe a convex
            polyhedron, and :class:`GeometryError` says which one.
        merge_tolerance : float, optional
            Merge near-coplanar hull triangles too (a scanned or printed
            mesh's flat faces are rarely exactly flat): neighbouring
            triangles whose vertices all lie within this distance of the
            plane of the group's largest triangle become one face, whose
            plane is the supporting plane with the group's mean normal.  The
            result is the intersection of those supporting half-spaces, so
            it contains every point and no vertex moves by much more than
            the tolerance.  By default the vertices are the points
            themselves, and neighbouring hull triangles are merged only where
            they make one convex polygon flat to rounding; triangles a hair
            off each other's planes stay triangles.
        """
        pts, hull = _hull(points)
        if merge_tolerance is not None and merge_tolerance > 0:
            if strict and len(hull.vertices) != len(pts):
                missing = sorted(set(range(len(pts))) - set(hull.vertices.tolist()))
                raise GeometryError(
                    f"point {missing[0]} {pts[missing[0]].tolist()} is not a vertex of the convex hull: "
                    "the points are not in convex position"
                )
            return cls.from_points(_merged_hull(pts, hull, merge_tolerance), strict=False)
        faces = _merge_coplanar(pts, hull)
        if len(faces) > MAX_FACES:
            raise GeometryError(f"the convex hull has {len(faces):,} faces, more than the {MAX_FACES:,} diefab "
                                "models: simplify the mesh or give it a larger merge tolerance")  # fmt: skip
        used = sorted({int(i) for f in faces for i in f})
        if strict and len(used) != len(pts):
            missing = sorted(set(range(len(pts))) - set(used))
            raise GeometryError(
                f"point {missing[0]} {pts[missing[0]].tolist()} is not a vertex of the convex hull: "
                "the points are not in convex position"
            )
        remap = -np.ones(len(pts), dtype=np.intp)
        remap[used] = np.arange(len(used))
        return cls(pts[used], tuple(remap[f] for f in faces))

    @classmethod
    def from_mesh(cls, path: str | Path) -> Polyhedron:
        """Load a convex mesh (OBJ, STL, PLY, ... through trimesh).

        Coplanar triangles are merged into polygonal faces.  A mesh that is
        not convex (its volume falls short of its hull's) is rejected.
        """
        import trimesh

        path = Path(path)
        try:
            mesh = trimesh.load(path, force="mesh", process=True)
        except Exception as exc:  # trimesh raises many types for unreadable files
            raise GeometryError(f"cannot read mesh {path}: {exc}") from exc
        if len(mesh.vertices) < 4:
            raise GeometryError(f"mesh {path} has fewer than 4 vertices")
        poly = cls.from_points(mesh.vertices, strict=False)
        # A convex mesh is its own hull: the same surface area (and volume, when closed).
        if abs(mesh.area - poly.surface_area) > tol.MESH_REL * poly.surface_area:
            raise GeometryError(
                f"mesh {path} is not a convex surface: "
                f"area {mesh.area:.6g} differs from its hull's {poly.surface_area:.6g}"
            )
        if mesh.is_watertight and abs(abs(mesh.volume) - poly.volume) > tol.MESH_REL * poly.volume:
            raise GeometryError(
                f"mesh {path} is not convex: volume {abs(mesh.volume):.6g} < hull volume {poly.volume:.6g}"
            )
        return poly

    def with_vertices(self, vertices: np.ndarray) -> Polyhedron:
        """The same topology and names on new vertex positions (validated).

        Cheaper than constructing anew: the combinatorial structure is
        shared, only the geometry (planarity, convexity, degeneracy) is checked.
        """
        vertices = np.array(vertices, dtype=float)
        if vertices.shape != self.vertices.shape:
            raise GeometryError(f"need vertices of shape {self.vertices.shape}, got {vertices.shape}")
        if not np.all(np.isfinite(vertices)):
            raise GeometryError("vertices contain NaN or infinite coordinates")
        vertices.setflags(write=False)
        new = object.__new__(Polyhedron)
        object.__setattr__(new, "vertices", vertices)
        object.__setattr__(new, "faces", self.faces)
        object.__setattr__(new, "names", self.names)
        object.__setattr__(new, "flatness", self.flatness)
        for key in _TOPOLOGY:
            new.__dict__[key] = getattr(self, key)
        new._validate()
        return new

    def scaled(self, factor: float) -> Polyhedron:
        """A copy scaled about the origin."""
        return self.with_vertices(self.vertices * factor)

    # ------------------------------------------------------------------
    # derived quantities
    @cached_property
    def _ring(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Every face's boundary as directed edges, face by face.

        Returns ``(tail, head, face, start)``: vertex indices of each directed
        edge, the face it bounds, and where each face's edges begin.
        """
        tail = np.concatenate(self.faces)
        sizes = np.array([len(f) for f in self.faces])
        start = np.concatenate([[0], np.cumsum(sizes)[:-1]])
        after = np.arange(1, len(tail) + 1)
        after[start + sizes - 1] = start  # each face's last edge ends at its first vertex
        face = np.repeat(np.arange(len(self.faces)), sizes)
        return tail, tail[after], face, start

    @cached_property
    def triangles(self) -> np.ndarray:
        """(t, 3) int: a fan triangulation of every face, outward oriented."""
        return np.array([(f[0], f[k], f[k + 1]) for f in self.faces for k in range(1, len(f) - 1)], dtype=np.intp)

    @cached_property
    def triangle_face(self) -> np.ndarray:
        """(t,) int: the face each row of :attr:`triangles` belongs to."""
        return np.repeat(np.arange(len(self.faces)), [len(f) - 2 for f in self.faces])

    @cached_property
    def _newell(self) -> np.ndarray:
        """(m, 3): twice the vector area of each face (Newell's method)."""
        tail, head, _, start = self._ring
        return np.add.reduceat(_cross(self.vertices[tail], self.vertices[head]), start, axis=0)

    @cached_property
    def areas(self) -> np.ndarray:
        """(m,) float: face areas."""
        return 0.5 * np.linalg.norm(self._newell, axis=1)

    @cached_property
    def normals(self) -> np.ndarray:
        """(m, 3) float: outward unit normals."""
        return self._newell / (2 * self.areas[:, None])

    @cached_property
    def offsets(self) -> np.ndarray:
        """(m,) float: plane offsets, ``normals[k] @ x == offsets[k]`` on face k."""
        tail, _, face, start = self._ring
        mean = np.add.reduceat(self.vertices[tail], start, axis=0) / np.diff(np.append(start, len(tail)))[:, None]
        return np.einsum("ij,ij->i", self.normals, mean)

    @cached_property
    def face_flatness(self) -> np.ndarray:
        """(m,) float: largest distance of each face's vertices from the face's plane (model units)."""
        tail, _, face, _ = self._ring
        dist = np.abs(np.einsum("ij,ij->i", self.vertices[tail], self.normals[face]) - self.offsets[face])
        out = np.zeros(len(self.faces))
        np.maximum.at(out, face, dist)
        return out

    @cached_property
    def face_centroids(self) -> np.ndarray:
        """(m, 3) float: area centroids of the faces."""
        v = self.vertices[self.triangles]
        tri_area = 0.5 * np.linalg.norm(_cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)
        weighted = np.zeros((len(self.faces), 3))
        np.add.at(weighted, self.triangle_face, tri_area[:, None] * v.mean(axis=1))
        return weighted / self.areas[:, None]

    @cached_property
    def edges(self) -> np.ndarray:
        """(e, 2) int: undirected edges, each once, lower index first."""
        tail, head, _, _ = self._ring
        return np.unique(np.sort(np.column_stack([tail, head]), axis=1), axis=0)

    @cached_property
    def edge_faces(self) -> np.ndarray:
        """(e, 2) int: the two faces meeting at each edge of :attr:`edges`.

        Column 0 is the face that traverses the edge from lower to higher
        vertex index, column 1 the face on the other side.
        """
        tail, head, face, _ = self._ring
        lookup = dict(zip(zip(tail.tolist(), head.tolist()), face.tolist()))
        return np.array([(lookup[int(i), int(j)], lookup[int(j), int(i)]) for i, j in self.edges], dtype=np.intp)

    @cached_property
    def volume(self) -> float:
        """Enclosed volume."""
        v = self.vertices[self.triangles]
        return float(np.einsum("ij,ij->i", v[:, 0], _cross(v[:, 1], v[:, 2])).sum() / 6)

    @cached_property
    def surface_area(self) -> float:
        return float(self.areas.sum())

    @cached_property
    def centroid(self) -> np.ndarray:
        """(3,) float: centre of mass of the uniform solid."""
        v = self.vertices[self.triangles]
        six_vol = np.einsum("ij,ij->i", v[:, 0], _cross(v[:, 1], v[:, 2]))
        return (six_vol[:, None] * v.sum(axis=1)).sum(axis=0) / (4 * six_vol.sum())

    # ------------------------------------------------------------------
    def face_index(self, name: str) -> int:
        """Position of the face called `name`."""
        try:
            return self.names.index(name)
        except ValueError:
            raise GeometryError(f"no face named {name!r}; faces are {', '.join(self.names)}") from None

    def to_trimesh(self):
        """The surface as a :class:`trimesh.Trimesh` (triangulated)."""
        import trimesh

        return trimesh.Trimesh(np.array(self.vertices), self.triangles, process=False)

    # ------------------------------------------------------------------
    def _validate(self) -> None:
        scale = max(1.0, float(np.ptp(self.vertices, axis=0).max()))
        if np.any(self.areas <= tol.AREA * scale**2):
            k = int(np.argmin(self.areas))
            raise GeometryError(f"face {self.names[k]} is degenerate (area {self.areas[k]:.3g})")
        # closed, 2-manifold, consistently oriented: every directed edge once, with its reverse
        tail, head, face, _ = self._ring
        n = len(self.vertices)
        code, back = tail * n + head, head * n + tail
        if len(np.unique(code)) != len(code):
            raise GeometryError("an edge is traversed twice in the same direction: faces are inconsistently oriented")
        open_edges = ~np.isin(back, code)
        if open_edges.any():
            i = int(np.argmax(open_edges))
            raise GeometryError(f"surface is not closed: edge {(int(tail[i]), int(head[i]))} has only one face")
        lengths = np.linalg.norm(self.vertices[head] - self.vertices[tail], axis=1)
        if np.any(lengths <= tol.LENGTH * scale):
            raise GeometryError("an edge has zero length")
        flat = self.face_flatness
        planarity = tol.PLANARITY * scale if self.flatness is None else max(float(self.flatness), tol.PLANARITY * scale)
        if flat.max() > planarity:
            k = int(np.argmax(flat))
            raise GeometryError(f"face {self.names[k]} is not planar (off by {flat[k]:.3g})")
        if self.volume <= tol.VOLUME * scale**3:
            raise GeometryError("volume is not positive: the solid is flat or its faces are oriented inward")
        height = self.vertices @ self.normals.T - self.offsets
        convexity = tol.CONVEXITY * scale if self.flatness is None else max(planarity, tol.CONVEXITY * scale)
        if height.max() > convexity:
            v, k = np.unravel_index(np.argmax(height), height.shape)
            raise GeometryError(f"not convex: vertex {v} lies {height[v, k]:.3g} outside face {self.names[k]}")


#: Cached properties that depend on the faces only, shared by :meth:`Polyhedron.with_vertices`.
_TOPOLOGY = ("_ring", "triangles", "triangle_face", "edges", "edge_faces")


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (k, 3) arrays (np.cross has a large fixed overhead)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def _merge_coplanar(points: np.ndarray, hull) -> list[np.ndarray]:
    """Merge coplanar hull triangles into faces, each an outward CCW ring of vertex indices.

    A face grows from its lowest-numbered triangle over shared edges to
    triangles in its plane.  A group whose union is not a convex polygon
    (triangles that are coplanar only within tolerance: a vertex a hair off
    the plane, inside the group or on a slight fold) stays as its triangles.
    """
    simplices, equations = hull.simplices, hull.equations
    group = np.full(len(simplices), -1)
    groups: list[list[int]] = []
    for seed in range(len(simplices)):
        if group[seed] >= 0:
            continue
        ref = equations[seed]
        group[seed], members, stack = len(groups), [seed], [seed]
        while stack:
            for u in hull.neighbors[stack.pop()]:
                if (
                    group[u] < 0
                    and 1 - ref[:3] @ equations[u, :3] < tol.COPLANAR
                    and abs(equations[u, 3] - ref[3]) < tol.COPLANAR * (1 + abs(ref[3]))
                ):
                    group[u] = len(groups)
                    members.append(u)
                    stack.append(u)
        groups.append(sorted(members))
    flat = 0.5 * tol.PLANARITY * max(1.0, float(np.ptp(points, axis=0).max()))
    faces = []
    for g in groups:
        n = equations[g, :3].mean(axis=0)
        ring = _ring(points, simplices[g], n / np.linalg.norm(n), flat)
        if ring is None:
            faces.extend(_ring(points, simplices[[t]], equations[t, :3]) for t in g)  # a triangle is always flat
        else:
            faces.append(_drop_collinear(points, ring))
    return faces


def _ring(points: np.ndarray, triangles: np.ndarray, n: np.ndarray, flat: float = np.inf) -> np.ndarray | None:
    """The outline of coplanar `triangles` as a ring CCW about `n`, or None if it is not a convex polygon
    whose vertices lie within `flat` of one plane."""
    idx = np.unique(triangles)
    p = points[idx]
    centre = p.mean(axis=0)
    if len(triangles) > 1 and np.abs((p - centre) @ n).max() > flat:
        return None
    u = p[0] - centre
    u -= (u @ n) * n
    u /= np.linalg.norm(u)
    w = np.cross(n, u)
    ring = idx[np.argsort(np.arctan2((p - centre) @ w, (p - centre) @ u))]
    if len(triangles) == 1:
        return ring
    outline = _outline(triangles)
    if outline is None:
        return None
    if len(outline) == len(ring):
        start = int(np.flatnonzero(outline == ring[0])[0])
        turned = np.roll(outline, -start)
        if np.array_equal(turned, ring) or np.array_equal(np.roll(turned[::-1], 1), ring):
            return ring  # the usual case: every vertex on the outline, in angle order
    if np.cross(*(points[outline[1:3]] - points[outline[0]])) @ n < 0:
        outline = outline[::-1]
    a, b, c = points[np.roll(outline, 1)], points[outline], points[np.roll(outline, -1)]
    turns = _cross(b - a, c - b) @ n
    scale = np.linalg.norm(b - a, axis=1) * np.linalg.norm(c - b, axis=1)
    return outline if np.all(turns > -tol.COLLINEAR * scale) else None


def _outline(triangles: np.ndarray) -> np.ndarray | None:
    """The boundary of a disc of triangles as one cycle of vertices, or None if it is not one cycle."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    nexts: dict[int, list[int]] = {}
    for a, b in unique[count == 1].tolist():
        nexts.setdefault(a, []).append(b)
        nexts.setdefault(b, []).append(a)
    if not nexts or any(len(v) != 2 for v in nexts.values()):
        return None
    first = next(iter(nexts))
    ring = [first, nexts[first][0]]
    while ring[-1] != first:
        a, b = nexts[ring[-1]]
        ring.append(b if a == ring[-2] else a)
    return np.array(ring[:-1]) if len(ring) - 1 == len(nexts) else None


def _merged_hull(points: np.ndarray, hull, tolerance: float) -> np.ndarray:
    """Vertices of the intersection of the supporting planes of near-coplanar hull triangle groups.

    Groups grow from the largest triangle not yet taken over shared edges,
    taking a neighbour whose three vertices lie within `tolerance` of the
    seed triangle's plane.
    """
    from scipy.spatial import HalfspaceIntersection, QhullError

    simplices, normals = hull.simplices, hull.equations[:, :3]
    v = points[simplices]
    area = 0.5 * np.linalg.norm(_cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)
    group = np.full(len(simplices), -1)
    planes = []
    for seed in np.argsort(-area, kind="stable"):
        if group[seed] >= 0:
            continue
        g = len(planes)
        n0, d0 = normals[seed], normals[seed] @ points[simplices[seed, 0]]
        group[seed], members, stack = g, [seed], [seed]
        while stack:
            t = stack.pop()
            for u in hull.neighbors[t]:
                if group[u] < 0 and normals[u] @ n0 > 0 and np.abs(points[simplices[u]] @ n0 - d0).max() <= tolerance:
                    group[u] = g
                    members.append(u)
                    stack.append(u)
        n = (area[members, None] * normals[members]).sum(axis=0)
        n /= np.linalg.norm(n)
        planes.append(np.append(n, -(points[np.unique(simplices[members])] @ n).max()))
    inside = points[hull.vertices].mean(axis=0)
    try:
        corners = HalfspaceIntersection(np.array(planes), inside).intersections
    except QhullError as exc:
        raise GeometryError(f"merging hull faces within {tolerance:g} failed: {exc}") from None
    # several planes through (nearly) one corner give copies of it
    scale = max(1.0, float(np.ptp(points, axis=0).max()))
    _, keep = np.unique(np.round(corners / (tol.LENGTH * 1e3 * scale)), axis=0, return_index=True)
    return corners[np.sort(keep)]


def _drop_collinear(points: np.ndarray, ring: np.ndarray) -> np.ndarray:
    """Remove vertices that lie on the straight line through their neighbours."""
    p = points[ring]
    prev, nxt = np.roll(p, 1, axis=0), np.roll(p, -1, axis=0)
    cross = np.linalg.norm(np.cross(p - prev, nxt - p), axis=1)
    scale = np.linalg.norm(p - prev, axis=1) * np.linalg.norm(nxt - p, axis=1)
    return ring[cross > tol.COLLINEAR * scale]


def solid_angles(poly: Polyhedron, point: np.ndarray) -> np.ndarray:
    """Solid angle (sr) that each face subtends at `point`.

    Exact, by the Van Oosterom--Strackee formula on a fan triangulation of
    every face.  For a point inside the polyhedron the angles are positive
    and sum to 4 pi.

    Parameters
    ----------
    poly : Polyhedron
    point : (3,) float

    Returns
    -------
    (m,) float, steradians
    """
    r = poly.vertices[poly.triangles] - np.asarray(point, dtype=float)
    a, b, c = r[:, 0], r[:, 1], r[:, 2]
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    triple = np.einsum("ij,ij->i", a, _cross(b, c))
    denom = (
        la * lb * lc
        + np.einsum("ij,ij->i", a, b) * lc
        + np.einsum("ij,ij->i", a, c) * lb
        + np.einsum("ij,ij->i", b, c) * la
    )
    omega = 2 * np.arctan2(triple, denom)
    return np.bincount(poly.triangle_face, weights=omega, minlength=len(poly.faces))


def face_margins(poly: Polyhedron, point: np.ndarray) -> np.ndarray:
    """Stability margin of every face for a centre of mass at `point`.

    The signed distance, within the face plane, from the projection of
    `point` to the face's boundary: positive when the projection falls inside
    the face (the die can rest on it), negative outside.

    Returns
    -------
    (m,) float, model units
    """
    point = np.asarray(point, dtype=float)
    tail, head, face, start = poly._ring
    n = poly.normals[face]
    q = point - (n @ point - poly.offsets[face])[:, None] * n  # projection into each edge's face plane
    p0, edge = poly.vertices[tail], poly.vertices[head] - poly.vertices[tail]
    inward = _cross(n, edge)
    inward /= np.linalg.norm(inward, axis=1)[:, None]
    line = np.einsum("ij,ij->i", q - p0, inward)
    t = np.clip(np.einsum("ij,ij->i", q - p0, edge) / np.einsum("ij,ij->i", edge, edge), 0, 1)
    seg = np.linalg.norm(p0 + t[:, None] * edge - q, axis=1)
    inside = np.minimum.reduceat(line, start) >= 0
    distance = np.minimum.reduceat(seg, start)
    return np.where(inside, distance, -distance)


def resting_faces(poly: Polyhedron, point: np.ndarray) -> np.ndarray:
    """(m,) bool: the faces a die with its centre of mass at `point` can rest on.

    A face can hold the die when the centre of mass projects inside it by
    more than :data:`~diefab.core.tolerances.REST_MARGIN` (relative to the die's
    size); the others are **transitional**: a die put down on one rolls off
    it.
    """
    scale = max(1.0, float(np.ptp(poly.vertices, axis=0).max()))
    return face_margins(poly, point) > tol.REST_MARGIN * scale


def up_faces(poly: Polyhedron) -> list[int | None]:
    """For each resting face, the face that points up, or None for a tie.

    When the die rests on face k, "up" is ``-normals[k]``; the face read is
    the one whose outward normal is closest to up.  If two faces are equally
    close (the gem resting on its top, whose apex points up) there is no such
    face and the entry is None.
    """
    cos = -poly.normals @ poly.normals.T
    out: list[int | None] = []
    for k in range(len(poly.faces)):
        row = cos[k].copy()
        row[k] = -np.inf
        order = np.argsort(row)[::-1]
        best, second = row[order[0]], row[order[1]]
        out.append(None if best - second < tol.TIE else int(order[0]))
    return out
