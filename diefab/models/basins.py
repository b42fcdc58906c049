"""Rest basins of a convex die: where it rolls to, quasi-statically, from any orientation.

:class:`RestBasins` follows the gradient flow of the centre of mass's height
over the sphere of "down" directions exactly, and measures each resting
face's basin (its solid angle, the quasi-static landing probability) and
barrier (its lowest saddle).

Examples
--------
>>> from diefab.geometry.polyhedron import Polyhedron
>>> cube = Polyhedron.from_points([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
>>> basins = RestBasins.of(cube, cube.centroid)
>>> bool(basins.resting.all()), np.allclose(basins.barriers, np.sqrt(2) - 1)
(True, True)
>>> int(basins.face_of(np.array([[0.1, 0.2, -1.0]]))[0]) == int(np.argmin(cube.normals[:, 2]))
True
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from diefab.core import tolerances as tol
from diefab.core.errors import GeometryError
from diefab.geometry.polyhedron import Polyhedron, _cross, resting_faces

__all__ = ["RestBasins"]


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
