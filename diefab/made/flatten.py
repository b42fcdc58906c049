"""Faces laid flat along a spanning tree: the geometry a net's search measures.

Every face has its own plane frame (:func:`face_frames`); a tree edge is a
hinge, a rigid motion of the plane taking one face's frame into its
neighbour's (:func:`hinges_of`).  :func:`place_trees` lays out many trees at
once (the hinges composed from the root down by pointer jumping), and
:func:`count_overlaps` counts the face pairs that overlap in each layout.

All lengths are millimetres; layout coordinates have y pointing up.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from diefab.geometry.flat import overlap, stack_polygons
from diefab.geometry.polyhedron import Polyhedron

__all__ = [
    "count_overlaps", "face_frames", "hinges_of", "homogeneous", "place_trees", "rigid", "rooted", "tree_parents",
]  # fmt: skip


def face_frames(poly: Polyhedron, scale: float) -> list[np.ndarray]:
    """Each face in its own plane frame, mm, counter-clockwise seen from outside."""
    out = []
    for k, f in enumerate(poly.faces):
        p = poly.vertices[f] * scale
        u = p[1] - p[0]
        u /= np.linalg.norm(u)
        w = np.cross(poly.normals[k], u)
        out.append(np.column_stack([(p - p[0]) @ u, (p - p[0]) @ w]))
    return out


def rigid(src_a, src_b, dst_a, dst_b) -> np.ndarray:
    """3x3 rotation + translation taking segment src to segment dst."""
    ang = math.atan2(*(dst_b - dst_a)[::-1]) - math.atan2(*(src_b - src_a)[::-1])
    c, s = math.cos(ang), math.sin(ang)
    rot = np.array([[c, -s], [s, c]])
    out = np.eye(3)
    out[:2, :2] = rot
    out[:2, 2] = dst_a - rot @ src_a
    return out


def hinges_of(poly: Polyhedron, local: list[np.ndarray]) -> np.ndarray:
    """(e, 2, 3, 3): ``[e, 0]`` maps face ``edge_faces[e, 1]``'s frame into ``edge_faces[e, 0]``'s; ``[e, 1]`` back."""
    out = np.empty((len(poly.edges), 2, 3, 3))
    pos = [{int(v): i for i, v in enumerate(f)} for f in poly.faces]
    for e, ((a, b), (fi, fj)) in enumerate(zip(poly.edges, poly.edge_faces)):
        a, b = int(a), int(b)
        m = rigid(local[fj][pos[fj][a]], local[fj][pos[fj][b]], local[fi][pos[fi][a]], local[fi][pos[fi][b]])
        out[e, 0] = m
        out[e, 1] = np.linalg.inv(m)
    return out


def rooted(poly: Polyhedron, tree: tuple[int, ...], root: int = 0):
    """Parent face, hinge (edge, direction) and BFS order of a spanning tree rooted at `root`."""
    m, ef = len(poly.faces), poly.edge_faces
    adj: list[list[tuple[int, int, int]]] = [[] for _ in range(m)]
    for e in tree:
        a, b = int(ef[e, 0]), int(ef[e, 1])
        adj[a].append((b, e, 0))  # child b in parent a's frame: hinge [e, 0]
        adj[b].append((a, e, 1))
    parent = np.full(m, -1)
    parent[root] = root
    hinge = np.full((m, 2), -1)
    order, queue = [root], deque([root])
    while queue:
        f = queue.popleft()
        for g, e, d in adj[f]:
            if parent[g] < 0:
                parent[g], hinge[g] = f, (e, d)
                order.append(g)
                queue.append(g)
    return parent, hinge, order


def homogeneous(local: list[np.ndarray]) -> np.ndarray:
    """(m, K, 3) homogeneous coordinates, short faces padded by repeating their last vertex."""
    flat = stack_polygons(local)
    return np.concatenate([flat, np.ones((*flat.shape[:2], 1))], axis=2)


def tree_parents(poly: Polyhedron, trees: list[tuple[int, ...]], root: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Parent face and hinge (edge, direction) of every face in each spanning tree rooted at `root`.

    The same as :func:`rooted` for every tree (a tree has one parent per
    face), grown one level at a time over all trees at once.

    Returns
    -------
    parent : (T, m) int
        The parent face; the root is its own parent.
    hinge : (T, m, 2) int
        ``(edge, 0)`` where the face is ``edge_faces[edge, 1]`` (laid out in
        its parent ``edge_faces[edge, 0]``'s frame by ``hinges[edge, 0]``),
        ``(edge, 1)`` the other way round; ``(-1, -1)`` at the root.
    """
    n, m = len(trees), len(poly.faces)
    parent = np.full((n, m), -1, dtype=np.intp)
    parent[:, root] = root
    hinge = np.full((n, m, 2), -1, dtype=np.intp)
    if n == 0 or m == 1:
        return parent, hinge
    edges = np.asarray(trees, dtype=np.intp)
    a, b = poly.edge_faces[edges, 0], poly.edge_faces[edges, 1]
    rows = np.broadcast_to(np.arange(n)[:, None], edges.shape)
    pending = np.ones(edges.shape, dtype=bool)
    while pending.any():
        seen_a, seen_b = parent[rows, a] >= 0, parent[rows, b] >= 0
        grown = False
        for child, par, d, new in ((b, a, 0, seen_a & ~seen_b), (a, b, 1, seen_b & ~seen_a)):
            new &= pending
            if new.any():
                t, c = rows[new], child[new]
                parent[t, c] = par[new]
                hinge[t, c, 0], hinge[t, c, 1] = edges[new], d
                pending &= ~new
                grown = True
        if not grown:  # not spanning trees: the faces out of reach keep parent -1
            break
    return parent, hinge


def place_trees(trees: list[tuple[int, ...]], poly, hinges, padded) -> tuple[np.ndarray, np.ndarray]:
    """(T, m, K, 2) face polygons of every tree's layout, and (T, m) each face's parent in its tree (root 0)."""
    m = len(poly.faces)
    par, hinge = tree_parents(poly, trees)
    rel = np.tile(np.eye(3), (len(trees), m, 1, 1))
    ok = hinge[..., 0] >= 0
    rel[ok] = hinges[hinge[ok][:, 0], hinge[ok][:, 1]]
    # pointer jumping: world[f] is the product of the hinges from the root down to f; each pass doubles
    # the stretch of path it covers (the root's own transform is the identity, and its parent itself)
    world = rel.copy()
    rows = np.arange(len(trees))[:, None]
    up = par.copy()
    for _ in range(max(1, int(np.ceil(np.log2(max(m, 2)))))):
        world = world[rows, up] @ world
        up = up[rows, up]
    return np.einsum("tmij,mkj->tmki", world, padded)[..., :2], par


def count_overlaps(world: np.ndarray, sizes: list[int]) -> np.ndarray:
    """(T,) number of overlapping face pairs in each layout of `world` (T, m, K, 2).

    Pairs whose circumscribing circles are apart are skipped before the
    separating-axis test.
    """
    t, m = world.shape[:2]
    iu, ju = np.triu_indices(m, 1)
    step = max(1, int(4e6 // len(iu)))  # layouts per pass: bounded memory for dice with many faces
    if t > step:
        return np.concatenate([count_overlaps(world[k : k + step], sizes) for k in range(0, t, step)])
    mask = np.arange(world.shape[2])[None, :] < np.array(sizes)[:, None]
    centre = (world * mask[None, :, :, None]).sum(axis=2) / np.array(sizes)[None, :, None]
    radius = np.linalg.norm(world - centre[:, :, None], axis=-1).max(axis=2)
    near = np.linalg.norm(centre[:, iu] - centre[:, ju], axis=-1) < radius[:, iu] + radius[:, ju]
    tt, pp = np.nonzero(near)
    clash = np.zeros(t, dtype=np.intp)
    for start in range(0, len(tt), 4096):
        sl = slice(start, start + 4096)
        hit = overlap(world[tt[sl], iu[pp[sl]]], world[tt[sl], ju[pp[sl]]])
        np.add.at(clash, tt[sl][hit], 1)
    return clash
