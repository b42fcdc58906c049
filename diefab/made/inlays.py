"""Square cell patterns inlaid in a die's faces (fiducial markers), as placed regions and as masses.

A marker is a square grid of cells, some of them dark.  On a print the dark
cells are cut into the face as shallow pockets that a second material fills
flush (:func:`cell_outline` gives their outline, :func:`inlay_labels` places
them on the flat part of their faces as :class:`~diefab.made.placement.Label`
objects, so the engraving, the two-colour part and the mass model treat them
exactly as the value labels: area × depth prisms).  Which cells are dark and
where each square goes is decided above this layer (the marker layout); here
the squares are plain arrays.

Examples
--------
>>> cells = np.array([[1, 1, 1], [1, 0, 1], [1, 1, 1]], dtype=bool)
>>> square = np.array([[0.0, 3.0], [3.0, 3.0], [3.0, 0.0], [0.0, 0.0]])  # TL, TR, BR, BL
>>> round(cell_outline(cells, square).area, 9)  # eight unit cells, the middle one left light
8.0
"""

from __future__ import annotations

import numpy as np

from diefab.core import tolerances as tol
from diefab.core.errors import FabricationError
from diefab.geometry.polyhedron import Polyhedron
from diefab.made.bodies import label_mass
from diefab.made.fill import LabelMass
from diefab.made.labels import face_frame
from diefab.made.placement import Label, max_cot_dihedral

__all__ = ["CELL_JOIN_MM", "cell_outline", "inlay_labels", "inlay_masses", "square_frames"]

#: Dark cells are grown by this much before they are joined, so cells that touch only at a corner make one
#: sound outline (a pocket with no edge shared by four faces), mm; far below what a printer draws.
CELL_JOIN_MM = 0.01


def cell_outline(cells: np.ndarray, corners: np.ndarray, grow: float = 0.0):
    """The dark cells of a square pattern as one shapely outline, mapped onto a quadrilateral.

    Parameters
    ----------
    cells : (n, n) bool
        Dark cells, row 0 along the top edge (TL -> TR), column 0 along the left edge.
    corners : (4, 2) float
        The square's corners in the target plane: top-left, top-right, bottom-right, bottom-left.
    grow : float
        Grow each cell by this distance (target units, square corners kept) before joining.
    """
    from shapely import affinity
    from shapely.geometry import box
    from shapely.ops import unary_union

    cells = np.asarray(cells, dtype=bool)
    n = cells.shape[0]
    corners = np.asarray(corners, dtype=float)
    tl, tr, _, bl = corners
    x, y = (tr - tl) / n, (bl - tl) / n
    rows, cols = np.nonzero(cells)
    unit = unary_union([box(c, r, c + 1, r + 1) for r, c in zip(rows, cols)])
    shape = affinity.affine_transform(unit, [x[0], y[0], x[1], y[1], float(tl[0]), float(tl[1])])
    return shape.buffer(grow, join_style="mitre") if grow > 0 else shape


def square_frames(poly: Polyhedron, faces: np.ndarray, flat: list[np.ndarray | None], axis: np.ndarray):
    """Face frames of the flat part of `faces`: (origin (3,), baseline (3,), up (3,)) each, mm.

    The frame is the one value labels are placed in (:func:`~diefab.made.placement.label_faces`):
    origin at the mean of the flat ring, baseline and up from :func:`~diefab.made.labels.face_frame`.
    """
    out = []
    for k in faces:
        ring = flat[int(k)]
        if ring is None:
            out.append(None)
            continue
        u, v = face_frame(ring, poly.normals[int(k)], axis)
        out.append((ring.mean(axis=0), u, v))
    return out


def inlay_labels(
    poly: Polyhedron,
    flat: list[np.ndarray | None],
    axis: np.ndarray,
    faces: np.ndarray,
    corners_mm: np.ndarray,
    cells: list[np.ndarray],
    *,
    depth_mm: float,
    names: list[str] | None = None,
) -> tuple[Label, ...]:
    """The dark cells of square patterns on the flat part of their faces, as placed labels (mm).

    Parameters
    ----------
    poly : Polyhedron
        The die (its faces' normals and dihedral angles).
    flat : list of (k, 3) float or None
        The flat part of each face, mm, counter-clockwise from outside (None: rounded away).
    axis : (3,) float
        The die's up axis.
    faces : (n,) int
        The face of each square.
    corners_mm : (n, 4, 3) float
        Each square's corners on its face, mm: top-left, top-right, bottom-right, bottom-left from outside.
    cells : list of (m, m) bool
        Each square's dark cells, row 0 on top.
    depth_mm : float
        Depth of the pockets; each square must keep ``depth · cot θ`` from the edges of its flat face
        (θ the face's sharpest dihedral angle), so no pocket breaks through a neighbouring face.
    names : list of str, optional
        Text of each label (default ``"square i"``).

    Raises
    ------
    FabricationError
        A square that does not lie on the flat part of its face with that margin, naming the face.
    """
    from shapely.geometry import Point, Polygon

    cots = max_cot_dihedral(poly)
    frames = square_frames(poly, faces, flat, axis)
    out = []
    for i, (k, frame) in enumerate(zip(faces, frames)):
        k = int(k)
        text = names[i] if names else f"square {i}"
        if frame is None:
            raise FabricationError(f"{text} does not fit on face {poly.names[k]}: rounding left no flat part")
        origin, u, v = frame
        rel = np.asarray(corners_mm[i], dtype=float) - origin
        square = np.column_stack([rel @ u, rel @ v])
        ring = flat[k]
        face2d = Polygon(np.column_stack([(ring - origin) @ u, (ring - origin) @ v]))
        margin = depth_mm * cots[k]
        room = face2d.buffer(-margin, join_style="mitre") if margin > tol.NET_OVERLAP_MM else face2d
        if not room.buffer(tol.NET_OVERLAP_MM).contains(Polygon(square)):
            over = max(room.distance(Point(c)) for c in square) if not room.is_empty else np.inf
            raise FabricationError(
                f"{text} ({np.linalg.norm(square[1] - square[0]):.2f} mm) on face {poly.names[k]} reaches "
                f"{over:.2f} mm past the flat part that keeps a {depth_mm:g} mm deep pocket inside the die: "
                "use less --round or --depth, or a larger --size"
            )
        outline = cell_outline(cells[i], square, CELL_JOIN_MM)
        side = float(np.linalg.norm(square[1] - square[0]))
        c2, mid = outline.centroid, square.mean(axis=0)
        out.append(
            Label(
                face=poly.names[k],
                text=text,
                height_mm=side,
                stroke_mm=side / len(cells[i]),
                thin_fraction=0.0,
                area_mm2=float(outline.area),
                center_mm=origin + mid[0] * u + mid[1] * v,
                centroid_mm=origin + c2.x * u + c2.y * v,
                baseline=u,
                up=v,
                normal=np.asarray(poly.normals[k], dtype=float),
                origin_mm=origin,
                outline=outline,
            )
        )
    return tuple(out)


def inlay_masses(poly: Polyhedron, labels: tuple[Label, ...], depth_mm: float) -> tuple[LabelMass, ...]:
    """The pockets of :func:`inlay_labels` as masses for :func:`~diefab.made.mass.mass_properties`.

    Each is a prism of its outline, `depth_mm` into its face: material taken
    away from the print (a second material filling it is not weighed, as an
    engraved label's paint is not).
    """
    return tuple(label_mass(poly, label, depth_mm, False) for label in labels)
