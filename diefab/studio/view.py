"""Geometry the page draws: each face of the die as a flat plate, and the net as SVG polygons."""

from __future__ import annotations

from html import escape

import numpy as np

from diefab.geometry.polyhedron import Polyhedron


def face_frames(poly: Polyhedron) -> list[dict]:
    """Each face in its own plane: outline, rotation and centre to place it in the scene.

    Returns
    -------
    list of dict
        ``outline`` : (k, 2) list, the face's vertices in the face frame;
        ``rotation`` : (3, 3) list whose columns are the frame's axes
        (in-plane x, in-plane y, outward normal); ``center`` : (3,) list,
        the vertex centroid.  A frame point ``(x, y, z)`` lands at
        ``center + rotation @ (x, y, z)``, model units.
    """
    out = []
    for k, face in enumerate(poly.faces):
        pts = poly.vertices[np.asarray(face)]
        center = pts.mean(axis=0)
        n = poly.normals[k] / np.linalg.norm(poly.normals[k])
        e1 = pts[1] - pts[0]
        e1 = e1 - n * (e1 @ n)
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        rot = np.column_stack([e1, e2, n])
        local = (pts - center) @ rot
        out.append({"outline": local[:, :2].tolist(), "rotation": rot.tolist(), "center": center.tolist()})
    return out


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


def label_image(text: str, background: str = "#ffffff", px: int = 96) -> str:
    """A PNG of `text` (dark, bold, centered on a `background` square) as a ``data:`` URL."""
    import base64
    import io

    from matplotlib import font_manager
    from PIL import Image, ImageDraw, ImageFont

    font_file = font_manager.findfont(font_manager.FontProperties(family="DejaVu Sans", weight="bold"))
    img = Image.new("RGB", (px, px), background)
    draw = ImageDraw.Draw(img)
    size = px
    while size > 8:
        font = ImageFont.truetype(font_file, size)
        x0, y0, x1, y1 = draw.textbbox((0, 0), text, font=font)
        if x1 - x0 <= 0.92 * px and y1 - y0 <= 0.92 * px:
            break
        size -= 4
    draw.text(((px - (x1 - x0)) / 2 - x0, (px - (y1 - y0)) / 2 - y0), text, font=font, fill=(20, 20, 20))
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")
