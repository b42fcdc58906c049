"""Geometry the page draws: the die's faces, colors and labels for the 3D view, and the net as SVG polygons."""

from __future__ import annotations

from html import escape

import numpy as np

from diefab.geometry.polyhedron import Polyhedron


def die_data(poly: Polyhedron, colors: list[str], labels: list[str], lift: float = 0.002) -> dict:
    """What the page's 3D die is drawn from (``die.js``): the faces, their colors and their printed values.

    Parameters
    ----------
    poly : Polyhedron
    colors : list of str
        One CSS color per face.
    labels : list of str
        The text printed on each face ("" for none).
    lift : float
        Height of a label above its face, model units.

    Returns
    -------
    dict
        ``vertices`` : (n, 3) list, model units; ``faces`` : lists of vertex
        indices; ``colors``, ``labels`` : one per face; ``quads`` : each
        face's label corners (:func:`label_quad`, flattened to 4 points:
        top-left, top-right, bottom-left, bottom-right).
    """
    quads = [sum(label_quad(poly, k, lift), []) for k in range(len(poly.faces))]
    return {"vertices": np.round(poly.vertices, 6).tolist(), "faces": [list(map(int, f)) for f in poly.faces],
            "colors": list(colors), "labels": list(labels), "quads": np.round(quads, 6).tolist()}  # fmt: skip


def made_mesh(poly: Polyhedron, vertices: np.ndarray, triangles: np.ndarray, engraved: np.ndarray) -> dict:
    """The die as made (a printable solid's mesh) for the 3D view: each triangle with the face it belongs to.

    Parameters
    ----------
    poly : Polyhedron
        The die's polyhedron, model units.
    vertices : (n, 3) float
        The solid's vertices, model units (millimetres / ``mm_per_unit``).
    triangles : (t, 3) int
        Outward triangles.
    engraved : (t,) bool
        Triangles of the labels (walls and floors of an engraving, or raised text).

    Returns
    -------
    dict
        ``vertices``, ``triangles``, ``face_of`` (the face whose plane is
        nearest to each triangle's centroid: its own face, or the face its
        label is cut into) and ``engraved`` (0/1), as lists.
    """
    v = np.asarray(vertices, dtype=float)
    t = np.asarray(triangles, dtype=np.int64)
    centroids = v[t].mean(axis=1)
    face_of = np.argmin(np.abs(centroids @ poly.normals.T - poly.offsets), axis=1)
    return {"vertices": np.round(v, 5).tolist(), "triangles": t.tolist(), "face_of": face_of.tolist(),
            "engraved": np.asarray(engraved, dtype=int).tolist()}  # fmt: skip


def face_at(poly: Polyhedron, point) -> int:
    """Index of the face of the (convex) die nearest to `point` on its surface (a click on the 3D die).

    Parameters
    ----------
    point : (3,) float
        A point on or near the surface, model units.
    """
    distance = np.abs(poly.normals @ np.asarray(point, dtype=float) - poly.offsets)
    return int(np.argmin(distance))


def label_frame(poly: Polyhedron, k: int) -> np.ndarray:
    """(3, 3) rotation for a label on face `k` that reads upright when the face is seen from outside.

    "Up" on the face is the projection of the die's +z (or +y for a face
    normal to z) onto the face.
    """
    n = poly.normals[k] / np.linalg.norm(poly.normals[k])
    up = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    up = up - n * (up @ n)
    up /= np.linalg.norm(up)
    right = np.cross(up, n)
    return np.column_stack([right, up, n])


def net_svg(faces: list[np.ndarray], names: list[str], labels: dict[str, str], colors: list[str],
            width_px: int = 420) -> str:  # fmt: skip
    """An SVG of the net's faces, one ``<polygon data-face=NAME>`` each, for the page (not for printing).

    Parameters
    ----------
    faces : list of (k, 2) float
        Each face's corners on the sheet, mm (the pieces of all pages side by side).
    """
    pts = np.vstack(faces)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.03 * float((hi - lo).max())
    lo, hi = lo - pad, hi + pad
    w, h = hi - lo
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{lo[0]:.2f} {lo[1]:.2f} {w:.2f} {h:.2f}" '
             f'width="{width_px}" height="{width_px * h / w:.0f}" class="studio-net">']  # fmt: skip
    for poly, name, color in zip(faces, names, colors):
        c = poly.mean(axis=0)
        points = " ".join(f"{x:.2f},{y:.2f}" for x, y in poly)
        size = 0.35 * float(np.sqrt(_area(poly)))
        parts.append(f'<g class="net-face" data-face="{escape(name)}"><polygon points="{points}" fill="{color}" '
                     f'stroke="#333" stroke-width="{0.01 * w:.3f}"/>')  # fmt: skip
        text = labels.get(name, "")
        if text:
            parts.append(f'<text x="{c[0]:.2f}" y="{c[1]:.2f}" font-size="{size:.2f}" text-anchor="middle" '
                         f'dominant-baseline="central" font-family="sans-serif" pointer-events="none">'
                         f"{escape(text)}</text>")  # fmt: skip
        parts.append("</g>")
    parts.append("</svg>")
    return "".join(parts)


def _area(p: np.ndarray) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(float(x @ np.roll(y, -1) - y @ np.roll(x, -1)))


def side_by_side(faces: tuple[np.ndarray, ...], face_page: np.ndarray, page_width_mm: float) -> list[np.ndarray]:
    """The net's faces with page ``i`` shifted right by ``i`` page widths (+ a gap): all pages in one picture."""
    return [f + np.array([(page_width_mm * 1.05) * int(p), 0.0]) for f, p in zip(faces, face_page)]


def label_quad(poly: Polyhedron, k: int, lift: float) -> list[list[list[float]]]:
    """Corners of a square label on face `k`, as a 2 x 2 grid (top row first) for a texture, model units.

    The square is centered on the face's vertex centroid, `lift` above the
    face, reads upright from outside (:func:`label_frame`), and its side is
    0.45 of the square root of the face's area.
    """
    pts = poly.vertices[np.asarray(poly.faces[k])]
    rot = label_frame(poly, k)
    right, up, n = rot[:, 0], rot[:, 1], rot[:, 2]
    area = 0.5 * float(np.linalg.norm(sum(np.cross(a, b) for a, b in zip(pts, np.roll(pts, -1, axis=0)))))
    half = 0.225 * np.sqrt(area)
    c = pts.mean(axis=0) + lift * n
    corner = [[c - half * right + half * up, c + half * right + half * up],
              [c - half * right - half * up, c + half * right - half * up]]  # fmt: skip
    return [[p.tolist() for p in row] for row in corner]
