"""A PNG preview of a printable solid: overviews and each labelled face seen straight on.

Orthographic views drawn with matplotlib's 2D PolyCollection (painter's
algorithm, back faces culled, Lambert shading); triangles cut by the labels
are drawn dark so the engraving reads at any light.  Every camera is
right-handed (screen right = up × towards-viewer), so mirrored text would
show as mirrored.
"""

from __future__ import annotations

import io

import numpy as np

from diefab.fabricate.stl import Solid
from diefab.made.labels import design_axis, reading_note

__all__ = ["render_preview"]

_BODY = np.array([0.93, 0.90, 0.80])
_LABEL = np.array([0.10, 0.20, 0.45])


def _camera(toward_viewer: np.ndarray, up_hint: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    d = toward_viewer / np.linalg.norm(toward_viewer)
    up = up_hint - (up_hint @ d) * d
    if np.linalg.norm(up) < 1e-6:
        up = np.cross(d, [1.0, 0.0, 0.0])
    up /= np.linalg.norm(up)
    return np.cross(up, d), up, d


def _draw(ax, solid: Solid, right: np.ndarray, up: np.ndarray, d: np.ndarray, title: str) -> None:
    from matplotlib.collections import PolyCollection

    tri = solid.vertices[solid.triangles]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    visible = normals @ d > 1e-9
    depth = tri.mean(axis=1) @ d
    order = np.argsort(depth[visible])
    idx = np.flatnonzero(visible)[order]
    light = d + 0.6 * up - 0.4 * right
    light /= np.linalg.norm(light)
    shade = 0.35 + 0.65 * np.clip(normals[idx] @ light, 0, 1)
    base = np.where(solid.label_triangles[idx, None], _LABEL, _BODY)
    colors = np.clip(base * shade[:, None], 0, 1)
    pts = np.stack([tri[idx] @ right, tri[idx] @ up], axis=-1)
    ax.add_collection(PolyCollection(pts, facecolors=colors, edgecolors=colors, linewidths=0.2))
    all_pts = solid.vertices @ np.column_stack([right, up])
    lo, hi = all_pts.min(axis=0), all_pts.max(axis=0)
    pad = 0.05 * (hi - lo).max()
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title(title, fontsize=10)


def render_preview(solid: Solid, *, dpi: int = 110) -> bytes:
    """PNG bytes: two overviews (die axis vertical) and one straight-on view per label.

    Parameters
    ----------
    solid : Solid
    dpi : int
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    axis = design_axis(solid.design)
    other = np.array([1.0, 0.0, 0.0])
    side = np.cross(axis, other)
    views = [
        (_camera(side + 0.45 * axis + 0.6 * other, axis), "overview, axis up"),
        (_camera(-side - 0.6 * axis - 0.8 * other, axis), "overview from below"),
    ]
    for label in solid.labels:
        views.append(((np.cross(label.up, label.normal), label.up, label.normal), f"{label.face}: {label.text}"))
    cols = 4
    rows = -(-len(views) // cols)
    fig = Figure(figsize=(3 * cols, 3 * rows))
    for k, ((right, up, d), title) in enumerate(views):
        _draw(fig.add_subplot(rows, cols, k + 1), solid, right, up, d, title)
    r = solid.report
    rounded = f", round {r['round_mm']:g} mm" if r["round_mm"] else ""
    fig.suptitle(
        f"{r['design']}  {r['size_mm']:g} mm, depth {r['depth_mm']:g} mm{rounded}: volume {r['volume_mm3']:.0f} mm³, "
        f"COM shift {r['com_shift_norm_mm'] * 1000:.1f} µm\nto read it: {reading_note(solid.design)}",
        fontsize=11,
    )
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.75 / fig.get_figheight()))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()
