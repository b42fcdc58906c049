"""Spanning trees of a polyhedron's face-adjacency graph: the fold edges of its nets.

Every spanning tree is one way to cut the surface open (its edges are
folds, every other edge is cut).  Small dice have few enough to try them
all; larger ones get candidate trees from steepest-edge unfoldings and
random minimum spanning trees.
"""

from __future__ import annotations

import itertools
import math
from functools import lru_cache

import numpy as np

from diefab.geometry.polyhedron import Polyhedron

# ----------------------------------------------------------------------
# topology helpers


def face_ring(face: np.ndarray):
    return zip(face.tolist(), np.roll(face, -1).tolist())


def edge_key(a: int, b: int) -> tuple[int, int]:
    return (a, b) if a < b else (b, a)


def edge_lookup(poly: Polyhedron) -> dict[tuple[int, int], int]:
    cache = poly.__dict__.setdefault("_net_edge_lookup", None)
    if cache is None:
        cache = {(int(a), int(b)): e for e, (a, b) in enumerate(poly.edges)}
        poly.__dict__["_net_edge_lookup"] = cache
    return cache


def spanning_tree_count(poly: Polyhedron) -> int:
    """Number of spanning trees of the face-adjacency graph (Kirchhoff's theorem).

    Exact while it fits a float's mantissa; beyond, its order of magnitude
    (a die with hundreds of faces has more than 10**300).
    """
    m = len(poly.faces)
    lap = np.zeros((m, m))
    for a, b in poly.edge_faces:
        lap[a, b] -= 1
        lap[b, a] -= 1
        lap[a, a] += 1
        lap[b, b] += 1
    _, log_count = np.linalg.slogdet(lap[1:, 1:])
    if log_count < 700:
        return int(round(math.exp(log_count)))
    return 10 ** int(log_count / math.log(10))


def _find(parent: list[int], x: int) -> int:
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


def all_trees(poly: Polyhedron) -> list[tuple[int, ...]]:
    """Every spanning tree, as sorted tuples of edge indices.

    They depend on the faces' adjacency alone, so dice of one shape with
    other proportions share one enumeration.
    """
    pairs = tuple((int(a), int(b)) for a, b in poly.edge_faces)
    return list(_all_trees(len(poly.faces), pairs))


@lru_cache(maxsize=16)
def _all_trees(m: int, pairs: tuple[tuple[int, int], ...]) -> tuple[tuple[int, ...], ...]:
    out = []
    for combo in itertools.combinations(range(len(pairs)), m - 1):
        parent = list(range(m))
        for e in combo:
            ra, rb = _find(parent, pairs[e][0]), _find(parent, pairs[e][1])
            if ra == rb:
                break
            parent[ra] = rb
        else:
            out.append(combo)
    return tuple(out)


def kruskal(poly: Polyhedron, weights: np.ndarray) -> tuple[int, ...]:
    m, ef = len(poly.faces), poly.edge_faces
    parent = list(range(m))
    tree = []
    for e in np.argsort(weights, kind="stable"):
        ra, rb = _find(parent, int(ef[e, 0])), _find(parent, int(ef[e, 1]))
        if ra != rb:
            parent[ra] = rb
            tree.append(int(e))
    return tuple(sorted(tree))


def steepest_edge_tree(poly: Polyhedron, direction: np.ndarray) -> tuple[int, ...]:
    """Schlickeiser's steepest-edge unfolding: every vertex but the highest cuts its steepest upward edge.

    The cut edges span the vertices, so the remaining (fold) edges form a
    spanning tree of the faces.
    """
    v, edges = poly.vertices, poly.edges
    d = v[edges[:, 1]] - v[edges[:, 0]]
    slope = d @ direction / np.linalg.norm(d, axis=1)
    best = np.full(len(v), -np.inf)
    choice = np.full(len(v), -1)
    for e, (a, b) in enumerate(edges):
        # the edge rises from a to b with slope[e]
        if slope[e] > best[a]:
            best[a], choice[a] = slope[e], e
        if -slope[e] > best[b]:
            best[b], choice[b] = -slope[e], e
    top = int(np.argmax(v @ direction))
    cut = {int(choice[i]) for i in range(len(v)) if i != top}
    folds = tuple(e for e in range(len(edges)) if e not in cut)
    return folds if len(folds) == len(poly.faces) - 1 else ()


def heuristic_trees(poly: Polyhedron, count: int, rng: np.random.Generator) -> list[tuple[int, ...]]:
    trees: dict[tuple[int, ...], None] = {}
    k = np.arange(count) + 0.5
    phi, theta = np.arccos(1 - 2 * k / count), np.pi * (1 + 5**0.5) * k
    dirs = np.column_stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)])
    for d in dirs:
        t = steepest_edge_tree(poly, d)
        if t and is_tree(poly, t):
            trees[t] = None
    lengths = np.linalg.norm(np.diff(poly.vertices[poly.edges], axis=1)[:, 0], axis=1)
    for _ in range(count // 2):
        # long edges are good folds (they keep the net compact); jitter for variety
        trees[kruskal(poly, -lengths * rng.uniform(0.5, 1.5, len(lengths)))] = None
        trees[kruskal(poly, rng.random(len(lengths)))] = None
    return list(trees)


def is_tree(poly: Polyhedron, tree: tuple[int, ...]) -> bool:
    """True if the edges `tree` connect all faces without a cycle."""
