"""Plane geometry of net layouts: convex-polygon overlap, hulls and the smallest bounding box that fits a page.

All lengths are millimetres.
"""

from __future__ import annotations

import numpy as np

from diefab.core import tolerances as tol

#: Rotations tried for a bounding box (with the hull's own edge directions), radians.
GRID_ANGLES = np.deg2rad(np.arange(0.0, 180.0, 1.0))


def overlap(a: np.ndarray, b: np.ndarray, eps: float = tol.NET_OVERLAP_MM) -> np.ndarray:
    """Separating-axis test of convex polygons, broadcast over leading axes.

    a : (..., K, 2), b : (..., L, 2), vertices in order (repeats allowed).
    Returns true where the interiors overlap by more than `eps` (mm) along
    every axis; polygons that only touch along an edge or at a vertex do not.
    """
    a, b = np.broadcast_arrays(a[..., :, None, :], b[..., None, :, :])
    a, b = a[..., :, 0, :], b[..., 0, :, :]
    edges = np.concatenate([np.roll(a, -1, axis=-2) - a, np.roll(b, -1, axis=-2) - b], axis=-2)
    length = np.linalg.norm(edges, axis=-1)
    valid = length > tol.NET_OVERLAP_MM
    axes = np.stack([edges[..., 1], -edges[..., 0]], axis=-1) / np.where(valid, length, 1.0)[..., None]
    pa = np.einsum("...ad,...vd->...av", axes, a)
    pb = np.einsum("...ad,...vd->...av", axes, b)
    sep = (pa.max(-1) <= pb.min(-1) + eps) | (pb.max(-1) <= pa.min(-1) + eps)
    return ~(sep & valid).any(-1)


def stack_polygons(shapes: list[np.ndarray]) -> np.ndarray:
    """(n, K, 2): polygons of different lengths, short ones padded by repeating their last vertex."""
    k = max(len(p) for p in shapes)
    return np.array([p if len(p) == k else np.concatenate([p, np.repeat(p[-1:], k - len(p), axis=0)]) for p in shapes])


def extents(points: np.ndarray, angles: np.ndarray = GRID_ANGLES) -> tuple[np.ndarray, np.ndarray]:
    """Width and height of the bounding box of `points` (..., n, 2) rotated by each angle: (..., A) each."""
    c, s = np.cos(angles), np.sin(angles)
    x = points[..., 0, None] * c - points[..., 1, None] * s
    y = points[..., 0, None] * s + points[..., 1, None] * c
    return np.ptp(x, axis=-2), np.ptp(y, axis=-2)


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Convex hull vertices of 2D points, counter-clockwise (Andrew's monotone chain)."""
    pts = sorted(set(map(tuple, np.round(points, 9).tolist())))
    if len(pts) < 3:
        return np.array(pts)

    def half(seq):
        out: list = []
        for p in seq:
            while (
                len(out) >= 2
                and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1]) - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0]))
                <= 0
            ):
                out.pop()
            out.append(p)
        return out

    return np.array(half(pts)[:-1] + half(pts[::-1])[:-1])


def fit_box(points: np.ndarray, printable: tuple[float, float], margin: float = 0.0) -> tuple[float, float] | None:
    """(area, angle) of the smallest bounding box, over rotations that fit `printable`; None if none does.

    Candidate angles: a 1-degree grid and every convex-hull edge laid along
    either axis (the minimum-area rectangle has a side on a hull edge).
    """
    hull = convex_hull(points)
    d = np.roll(hull, -1, axis=0) - hull
    base = -np.arctan2(d[:, 1], d[:, 0])
    angles = np.concatenate([GRID_ANGLES, base, base + np.pi / 2])
    w, h = extents(hull, angles)
    w, h = w + 2 * margin, h + 2 * margin
    ok = (w <= printable[0] + 1e-9) & (h <= printable[1] + 1e-9)
    if not ok.any():
        return None
    area = np.where(ok, w * h, np.inf)
    i = int(np.argmin(area))
    return float(area[i]), float(angles[i])
