"""Convex polyhedra: the :class:`Polyhedron` value and pure functions on it.

A polyhedron is a vertex array and a tuple of polygonal faces, each an
index array listed counter-clockwise seen from outside (outward normal by the
right-hand rule).  Construction validates that the surface is closed, every
face planar and non-degenerate, and the solid convex; every derived quantity
(normals, areas, edges, volume) is computed from those two arrays on demand.

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

from . import tolerances as tol
from .errors import GeometryError

__all__ = [
    "Polyhedron",
    "RestBasins",
    "face_margins",
    "resting_faces",
    "solid_angles",
    "up_faces",
]


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

    Raises
    ------
    GeometryError
        If the faces are not planar, the surface is not closed, a face or the
        volume is degenerate, or the solid is not convex.
    """

    vertices: np.ndarray
    faces: tuple[np.ndarray, ...]
    names: tuple[str, ...] = ()

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
            the tolerance.  By default only exactly coplanar triangles are
            merged and the vertices are the points themselves.
        """
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
        if merge_tolerance is not None and merge_tolerance > 0:
            if strict and len(hull.vertices) != len(pts):
                missing = sorted(set(range(len(pts))) - set(hull.vertices.tolist()))
                raise GeometryError(
                    f"point {missing[0]} {pts[missing[0]].tolist()} is not a vertex of the convex hull: "
                    "the points are not in convex position"
                )
            return cls.from_points(_merged_hull(pts, hull, merge_tolerance), strict=False)
        faces = _merge_coplanar(pts, hull.simplices, hull.equations)
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
        head = np.concatenate([np.roll(f, -1) for f in self.faces])
        face = np.repeat(np.arange(len(self.faces)), [len(f) for f in self.faces])
        start = np.concatenate([[0], np.cumsum([len(f) for f in self.faces])[:-1]])
        return tail, head, face, start

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
        dist = np.abs(np.einsum("ij,ij->i", self.vertices[tail], self.normals[face]) - self.offsets[face])
        if dist.max() > tol.PLANARITY * scale:
            k = int(face[np.argmax(dist)])
            raise GeometryError(f"face {self.names[k]} is not planar (off by {dist.max():.3g})")
        if self.volume <= tol.VOLUME * scale**3:
            raise GeometryError("volume is not positive: the solid is flat or its faces are oriented inward")
        height = self.vertices @ self.normals.T - self.offsets
        if height.max() > tol.CONVEXITY * scale:
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


def _merge_coplanar(points: np.ndarray, simplices: np.ndarray, equations: np.ndarray) -> list[np.ndarray]:
    """Group hull triangles by plane and return each group's boundary polygon, outward CCW."""
    normals = equations[:, :3]
    groups: list[list[int]] = []
    for t in range(len(simplices)):
        for g in groups:
            ref = equations[g[0]]
            if 1 - normals[t] @ ref[:3] < tol.COPLANAR and abs(equations[t, 3] - ref[3]) < tol.COPLANAR * (
                1 + abs(ref[3])
            ):
                g.append(t)
                break
        else:
            groups.append([t])
    faces = []
    for g in groups:
        n = normals[g].mean(axis=0)
        n /= np.linalg.norm(n)
        idx = np.unique(simplices[g])
        p = points[idx]
        centre = p.mean(axis=0)
        u = p[0] - centre
        u -= (u @ n) * n
        u /= np.linalg.norm(u)
        w = np.cross(n, u)
        ang = np.arctan2((p - centre) @ w, (p - centre) @ u)
        ring = idx[np.argsort(ang)]
        faces.append(_drop_collinear(points, ring))
    return faces


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
    more than :data:`~diefab.tolerances.REST_MARGIN` (relative to the die's
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


@dataclass(frozen=True, eq=False)
class RestBasins:
    """Where a die rolls to when it creeps downhill from any orientation.

    With the centre of mass at the origin, the height of the centre of mass
    of a die touching the ground with unit "down" direction *d* (body
    coordinates) is the support function ``U(d) = max_v v . d`` over the
    vertices.  On the sphere of directions U is linear on the normal cone of
    each vertex; its minima are the normals of the faces the die can rest
    on.  Its gradient flow (the die rolling quasi-statically, always
    downhill) is piecewise simple: inside the cone of vertex v, d moves on
    the great circle away from ``v / |v|`` until it reaches the arc of an
    edge (v, w).  If the foot of the perpendicular from the centre of mass
    to the edge line lies beyond w, the flow crosses into w's cone (the die
    pivots on to w); otherwise the arc is a valley and d slides along it,
    away from the direction ``s_e`` of that foot, to the normal of one of
    the edge's two faces.  :meth:`face_of` follows this flow exactly: it
    tells which face's **basin** a direction lies in.

    The saddles of U are the valley arcs' ``s_e`` that lie strictly inside
    their arcs, and the rim of a basin is made of flow lines running into
    saddles, along which U grows away from the saddle: the lowest point of
    face f's rim is its lowest saddle, ``min_e |foot_e| - h_f`` above its
    rest height ``h_f`` (:attr:`barriers`).  A die oriented inside f's basin
    whose total mechanical energy per unit weight is below
    ``h_f + barriers[f]`` can never leave it, since its centre of mass is
    never lower than ``U(d)``: the physics validator's early stop.

    A **transitional** face (one the die cannot rest on, see
    :func:`resting_faces`) has an empty basin: its normal is no minimum of
    U.  A flow that reaches it goes on as the die tips off it: about the
    point of the face nearest to the foot of the centre of mass, toward that
    foot, until it ends on a resting face (:attr:`targets`).  Saddles
    between two regions that drain to the same resting face are not on any
    basin's rim and do not count in :attr:`barriers`.

    Attributes
    ----------
    vertices : (n, 3) float
        Hull vertices relative to the centre of mass.
    neighbors : (n, k) int
        For each vertex, its neighbours along edges (padded by repetition).
    away : (n, k, 3) float
        Unit vectors from each of those neighbours toward the vertex.
    crosses : (n, k) bool
        True where the flow crosses that edge into the neighbour's cone.
    arc_angles : (n, k, 2) float
        Signed angle from the edge's foot direction to each of its two face normals, about the edge.
    arc_axes : (n, k, 3) float
        Unit edge direction those angles are measured about.
    arc_feet : (n, k, 3) float
        Unit direction of the edge's foot ``s_e``.
    arc_faces : (n, k, 2) int
        The edge's two faces.
    barriers : (m,) float
        Lowest saddle of each resting face's basin above its rest height
        (infinite for the only resting face of a die, 0 for a transitional
        face).
    targets : (m,) int
        The resting face the flow ends on from each face's normal (the face
        itself when the die can rest on it).
    normals : (m, 3) float
        Outward unit face normals.
    """

    vertices: np.ndarray
    neighbors: np.ndarray
    away: np.ndarray
    crosses: np.ndarray
    arc_angles: np.ndarray
    arc_axes: np.ndarray
    arc_feet: np.ndarray
    arc_faces: np.ndarray
    barriers: np.ndarray
    targets: np.ndarray
    normals: np.ndarray

    @property
    def resting(self) -> np.ndarray:
        """(m,) bool: the faces the die can rest on."""
        return self.targets == np.arange(len(self.targets))

    @classmethod
    def of(cls, poly: Polyhedron, center: np.ndarray) -> RestBasins:
        """The basins of `poly` with its centre of mass at `center` (inside the polyhedron)."""
        center = np.asarray(center, dtype=float)
        heights = poly.offsets - poly.normals @ center
        if heights.min() <= 0:
            raise GeometryError(f"the centre of mass {center.tolist()} is not inside the polyhedron")
        resting = resting_faces(poly, center)
        m = len(poly.faces)
        vertices = poly.vertices - center
        edges, faces = poly.edges, poly.edge_faces
        p0, p1 = vertices[edges[:, 0]], vertices[edges[:, 1]]
        axis = p1 - p0
        t = -np.einsum("ij,ij->i", p0, axis) / np.einsum("ij,ij->i", axis, axis)
        axis /= np.linalg.norm(axis, axis=1)[:, None]
        foot = p0 + t[:, None] * (p1 - p0)
        reach = np.linalg.norm(foot, axis=1)
        feet = foot / reach[:, None]

        def angle(n: np.ndarray) -> np.ndarray:
            return np.arctan2(np.einsum("ij,ij->i", axis, _cross(feet, n)), np.einsum("ij,ij->i", feet, n))

        angles = np.stack([angle(poly.normals[faces[:, 0]]), angle(poly.normals[faces[:, 1]])], axis=1)
        # per vertex, its incident edges (padded by repeating the first)
        incident: list[list[tuple[int, int, bool]]] = [[] for _ in range(len(vertices))]
        for k, (i, j) in enumerate(edges):
            incident[i].append((k, j, bool(t[k] >= 1)))  # from i the flow crosses to j if the foot is beyond j
            incident[j].append((k, i, bool(t[k] <= 0)))
        width = max(len(row) for row in incident)
        table = np.array([row + [row[0]] * (width - len(row)) for row in incident])  # (n, width, 3)
        edge, other, crosses = table[..., 0], table[..., 1], table[..., 2].astype(bool)
        away = vertices[:, None, :] - vertices[other]
        away /= np.linalg.norm(away, axis=2)[..., None]
        parts = (vertices, other, away, crosses, angles[edge], axis[edge], feet[edge], faces[edge])
        # where the flow ends from each transitional face, lowest first: it only ever descends
        targets = np.arange(m)
        flow = cls(*parts, np.zeros(m), targets, poly.normals)
        for g in sorted(np.flatnonzero(~resting), key=lambda g: heights[g]):
            targets[g] = flow.face_of(_tipping_direction(poly, g, center))[0]
        valley = (t > 0) & (t < 1)
        saddle = valley & (angles[:, 0] * angles[:, 1] < 0)  # the foot strictly inside the arc
        saddle &= targets[faces[:, 0]] != targets[faces[:, 1]]  # inside one basin it is no rim
        barriers = np.where(resting, np.inf, 0.0)
        for side in (0, 1):
            ends = targets[faces[saddle, side]]
            np.minimum.at(barriers, ends, reach[saddle] - heights[ends])
        return cls(*parts, barriers, targets, poly.normals)

    #: Cells along each edge of the cube map behind :meth:`lookup`.
    LOOKUP_CELLS = 64

    @cached_property
    def _cube_map(self) -> np.ndarray:
        """(6, c, c) int: the basin of each cube-map cell whose four corners agree, -1 where they differ."""
        c = self.LOOKUP_CELLS
        grid = np.linspace(-1.0, 1.0, c + 1)
        u, v = (np.tile(a.ravel(), 6) for a in np.meshgrid(grid, grid, indexing="ij"))
        cube = np.repeat(np.arange(6), (c + 1) ** 2)
        corners = self.face_of(_cube_directions(cube, u, v)).reshape(6, c + 1, c + 1)
        a, b, e, f = corners[:, :-1, :-1], corners[:, 1:, :-1], corners[:, :-1, 1:], corners[:, 1:, 1:]
        return np.where((a == b) & (a == e) & (a == f), a, -1)

    def lookup(self, down: np.ndarray) -> np.ndarray:
        """Same as :meth:`face_of`, through a cube map of the basins (exact flow only near basin rims).

        A cell of the map whose four corners lie in one basin takes that
        basin; directions in other cells are followed by :meth:`face_of`.
        Building the map costs one :meth:`face_of` over ``6 (c + 1)**2``
        directions, once per die.
        """
        d = np.atleast_2d(np.asarray(down, dtype=float))
        table, c = self._cube_map, self.LOOKUP_CELLS
        cube, u, v = _cube_coordinates(d)
        i = np.clip(((u + 1) * (c / 2)).astype(np.intp), 0, c - 1)
        j = np.clip(((v + 1) * (c / 2)).astype(np.intp), 0, c - 1)
        out = table[cube, i, j]
        rim = np.flatnonzero(out < 0)
        if len(rim):
            out[rim] = self.face_of(d[rim])
        return out

    def shares(self, cells: int = 32, levels: int = 6) -> tuple[np.ndarray, float]:
        """(m,) float: the share of all orientations whose downhill flow ends on each face, and its error bound.

        Integrates the basins over the sphere of "down" directions (uniform
        for a uniformly random orientation) on the cube map: each of the six
        cube faces is split into `cells` x `cells` cells; a cell whose four
        corners lie in one basin gives that basin its exact solid angle, the
        others (and, for three levels, the cell holding each resting face's
        normal, so that no small basin hides inside a cell) are split in
        four, `levels` times.  The cells still mixed at the end are shared
        by their corners; their total solid angle over 4 pi is returned as
        the bound (a basin narrower than a finest cell, about
        ``90 / (cells 2**levels)`` degrees, could still be missed).
        """
        total = np.zeros(len(self.targets))
        rest = self.normals[self.resting]
        rest_cube, rest_u, rest_v = _cube_coordinates(rest)

        def corner_faces(cube: np.ndarray, u0: np.ndarray, v0: np.ndarray, size: float) -> np.ndarray:
            """(k, 4): the basin at each corner of each cell, every distinct corner followed once."""
            cu = np.concatenate([u0, u0, u0 + size, u0 + size])
            cv = np.concatenate([v0, v0 + size, v0, v0 + size])
            cc = np.tile(cube, 4)
            n = int(round(2 / size)) + 1  # grid points along a cube face at this level
            iu, iv = (np.round((x + 1) / size).astype(np.int64) for x in (cu, cv))
            _, first, inverse = np.unique((cc * n + iu) * n + iv, return_index=True, return_inverse=True)
            faces = self.face_of(_cube_directions(cc[first], cu[first], cv[first]))[inverse.ravel()]
            return faces.reshape(4, -1).T

        size = 2.0 / cells
        grid = -1.0 + size * np.arange(cells)
        cu, cv = (a.ravel() for a in np.meshgrid(grid, grid, indexing="ij"))
        cube = np.repeat(np.arange(6), len(cu))
        u0, v0 = np.tile(cu, 6), np.tile(cv, 6)
        for level in range(levels + 1):
            corners = corner_faces(cube, u0, v0, size)
            forced = np.zeros(len(u0), dtype=bool)
            if level < 3:
                for c, a, b in zip(rest_cube, rest_u, rest_v):
                    forced |= (cube == c) & (u0 <= a) & (a <= u0 + size) & (v0 <= b) & (b <= v0 + size)
            uniform = np.all(corners == corners[:, :1], axis=1) & ~forced
            np.add.at(total, corners[uniform, 0], _cell_solid_angle(u0[uniform], v0[uniform], size))
            mixed = ~uniform
            if level == levels:
                area = _cell_solid_angle(u0[mixed], v0[mixed], size)
                for k in range(4):
                    np.add.at(total, corners[mixed, k], area / 4)
                return total / (4 * np.pi), float(area.sum() / (4 * np.pi))
            size /= 2
            k = int(mixed.sum())
            cube = np.repeat(cube[mixed], 4)
            u0 = np.repeat(u0[mixed], 4) + np.tile([0, 0, size, size], k)
            v0 = np.repeat(v0[mixed], 4) + np.tile([0, size, 0, size], k)
        raise AssertionError("unreachable")

    def exact_shares(self, samples: int = 64, rounds: int = 40) -> tuple[np.ndarray, float]:
        """(m,) float: the share of all orientations whose downhill flow ends on each face, by spherical polygons.

        Inside the normal cone of a vertex v the flow runs along great
        circles away from ``v / |v|`` (the apex), so the fate of a direction
        depends only on where its great circle through the apex leaves the
        cone.  Along each side of each cone the fate is piecewise constant;
        the side is sampled at `samples` points, every change of fate found
        by `rounds` bisections, and each piece, with the apex, spans a
        spherical triangle whose signed area (Van Oosterom and Strackee)
        goes to that fate.  Summed over the sides of a cone the signed
        triangles tile it exactly (the cone lies in the apex's open
        hemisphere, since the centre of mass is inside the die), so the
        shares sum to 1 and are exact up to the bisection (``2**-rounds``
        of a sample step), provided no basin meets a cone side only between
        two neighbouring samples that agree.

        Returns the shares and the bound: the share of the sphere in the
        triangles over the bisection brackets left at the end.
        """
        n, width = self.neighbors.shape
        real = np.ones((n, width), dtype=bool)
        real[:, 1:] = self.neighbors[:, 1:] != self.neighbors[:, :1]  # rows are padded by repeating the first
        vi, ki = np.nonzero(real)
        p, q = self.normals[self.arc_faces[vi, ki, 0]], self.normals[self.arc_faces[vi, ki, 1]]
        inside = np.zeros((n, 3))
        np.add.at(inside, vi, p + q)
        inside /= np.linalg.norm(inside, axis=1)[:, None]
        c = inside[vi]
        # orient each side with its cone on the left
        swap = np.einsum("ij,ij->i", _cross(p, q), c) < 0
        p, q = np.where(swap[:, None], q, p), np.where(swap[:, None], p, q)
        apex = self.vertices[vi] / np.linalg.norm(self.vertices[vi], axis=1)[:, None]
        sides = len(vi)

        def point(side: np.ndarray, t: np.ndarray) -> np.ndarray:
            x = (1 - t)[:, None] * p[side] + t[:, None] * q[side]
            return x / np.linalg.norm(x, axis=1)[:, None]

        def fate(side: np.ndarray, t: np.ndarray) -> np.ndarray:
            x = point(side, t)
            x = x + tol.TIP * (c[side] - x)  # just inside the cone
            return self.face_of(x / np.linalg.norm(x, axis=1)[:, None])

        t = (np.arange(samples) + 0.5) / samples
        side = np.repeat(np.arange(sides), samples)
        found = fate(side, np.tile(t, sides)).reshape(sides, samples)
        s, j = np.nonzero(found[:, 1:] != found[:, :-1])
        lo, hi = t[j], t[j + 1]
        left = found[s, j]
        for _ in range(rounds):
            mid = 0.5 * (lo + hi)
            same = fate(s, mid) == left
            lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
        # pieces of each side: [0, b1], [b1, b2], ..., [bk, 1], with the fate of the samples inside them
        cut = 0.5 * (lo + hi)
        starts = np.concatenate([np.arange(sides), s])
        at = np.concatenate([np.zeros(sides), cut])
        order = np.lexsort((at, starts))
        starts, at = starts[order], at[order]
        ends = np.append(at[1:], 1.0)
        ends[np.append(starts[1:] != starts[:-1], True)] = 1.0
        fates = np.concatenate([found[:, 0], found[s, j + 1]])[order]
        total = np.zeros(len(self.targets))
        np.add.at(total, fates, _signed_triangle(apex[starts], point(starts, at), point(starts, ends)))
        slack = np.abs(_signed_triangle(apex[s], point(s, lo), point(s, hi))).sum()
        return total / (4 * np.pi), float(slack / (4 * np.pi))

    def face_of(self, down: np.ndarray) -> np.ndarray:
        """(k,) int: the face whose basin each unit direction of `down` ((k, 3), body frame) lies in."""
        d = np.array(np.atleast_2d(down), dtype=float)
        out = np.full(len(d), -1)
        v = np.argmax(d @ self.vertices.T, axis=1)  # the lowest vertex: d lies in its normal cone
        live = np.arange(len(d))
        for _ in range(len(self.vertices) + 1):  # the flow visits each vertex cone at most once
            if len(live) == 0:
                break
            dl, vl = d[live], v[live]
            apex = self.vertices[vl] / np.linalg.norm(self.vertices[vl], axis=1)[:, None]
            u = np.einsum("ij,ij->i", dl, apex)[:, None] * dl - apex  # downhill tangent
            norm = np.linalg.norm(u, axis=1)
            u /= np.where(norm > 0, norm, 1.0)[:, None]
            # on x(theta) = cos(theta) d + sin(theta) u, the cone's side k (away_k . x >= 0)
            # is crossed at theta = atan2(away_k . u, away_k . d) + pi / 2; the first one is the exit
            away = self.away[vl]
            theta = np.arctan2(np.einsum("ikj,ij->ik", away, u), np.einsum("ikj,ij->ik", away, dl)) + np.pi / 2
            k = np.argmin(theta, axis=1)
            t = theta[np.arange(len(live)), k][:, None]
            x = np.cos(t) * dl + np.sin(t) * u
            cross = self.crosses[vl, k]
            # a valley: slide away from the foot direction, to the end of the arc on that side
            axis, foot = self.arc_axes[vl, k], self.arc_feet[vl, k]
            phi = np.arctan2(np.einsum("ij,ij->i", axis, _cross(foot, x)), np.einsum("ij,ij->i", foot, x))
            ends = self.arc_angles[vl, k]
            side = np.where(phi >= 0, np.argmax(ends, axis=1), np.argmin(ends, axis=1))
            out[live[~cross]] = self.targets[self.arc_faces[vl, k, side][~cross]]
            d[live[cross]] = x[cross]
            v[live[cross]] = self.neighbors[vl, k][cross]
            live = live[cross]
        return out


def _signed_triangle(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(k,) float: signed solid angle of the spherical triangles a, b, c ((k, 3) unit vectors each)."""
    det = np.einsum("ij,ij->i", a, _cross(b, c))
    dots = 1 + np.einsum("ij,ij->i", a, b) + np.einsum("ij,ij->i", b, c) + np.einsum("ij,ij->i", c, a)
    return 2 * np.arctan2(det, dots)


def _tipping_direction(poly: Polyhedron, face: int, center: np.ndarray) -> np.ndarray:
    """(1, 3): "down" (body frame) just after a die put down on transitional `face` starts to tip off it.

    The die pivots about the point of the face nearest to the foot of the
    centre of mass, so "down" turns from the face normal toward the foot.
    """
    n = poly.normals[face]
    foot = center + (poly.offsets[face] - n @ center) * n
    ring = poly.vertices[poly.faces[face]]
    edge = np.roll(ring, -1, axis=0) - ring
    t = np.clip(np.einsum("ij,ij->i", foot - ring, edge) / np.einsum("ij,ij->i", edge, edge), 0, 1)
    nearest = ring + t[:, None] * edge
    k = int(np.argmin(np.linalg.norm(nearest - foot, axis=1)))
    toward = foot - nearest[k]
    toward /= np.linalg.norm(toward)
    down = n + tol.TIP * toward
    return (down / np.linalg.norm(down))[None]


def _cube_directions(cube: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(k, 3) unit directions of cube-map points: cube ``2 axis + (sign > 0)``, coordinates u, v in [-1, 1]."""
    cube = np.asarray(cube)
    axis = cube // 2
    d = np.empty((len(u), 3))
    rows = np.arange(len(u))
    d[rows, axis] = np.where(cube % 2 == 1, 1.0, -1.0)
    d[rows, (axis + 1) % 3], d[rows, (axis + 2) % 3] = u, v
    return d / np.linalg.norm(d, axis=1)[:, None]


def _cube_coordinates(d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cube-map cube and coordinates u, v of directions `d` (k, 3): the inverse of :func:`_cube_directions`."""
    d = np.atleast_2d(d)
    rows = np.arange(len(d))
    axis = np.argmax(np.abs(d), axis=1)
    major = d[rows, axis]
    return 2 * axis + (major > 0), d[rows, (axis + 1) % 3] / np.abs(major), d[rows, (axis + 2) % 3] / np.abs(major)


def _cell_solid_angle(u0: np.ndarray, v0: np.ndarray, size: float) -> np.ndarray:
    """Solid angle of the cube-map cells [u0, u0 + size] x [v0, v0 + size] (on the plane at distance 1)."""

    def corner(x, y):
        return np.arctan2(x * y, np.sqrt(1 + x * x + y * y))

    u1, v1 = u0 + size, v0 + size
    return corner(u1, v1) - corner(u0, v1) - corner(u1, v0) + corner(u0, v0)
