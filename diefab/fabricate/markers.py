"""The die's fiducial markers as made: printed on the paper net, inlaid in the printed solid.

Both use the design's marker layout (:func:`~diefab.dice.markers.marker_layout`:
each face carries one marker of one ArUco dictionary, or a large face one
toward each corner, each square as large as its face allows beside the
value), so a folded or printed die is read by
``diefab read`` exactly as a die with the sticker sheet is.

* :func:`net_markers` maps each square onto its face of a paper net (page mm);
  the value label is then fitted around it.  Printed ink adds no mass the model
  could see (a few mg/m² of toner on 160 g/m² card), so the paper die's balance
  is that of the card and its tabs.
* :func:`solid_markers` places each square on the flat part of its face of the
  printed solid; the dark cells become pockets ``depth`` deep that a second
  material fills flush (the 3MF's second part), weighed as the engraved labels
  are (area × depth prisms, :func:`~diefab.made.inlays.inlay_masses`).

A marker whose cells would be finer than the medium draws (the printer's
stroke, :data:`MIN_PAPER_CELL_MM` on paper) is refused, naming the face, the
largest marker it fits and the size at which the die's markers would do.

Examples
--------
>>> from diefab.dice.design import load_design
>>> from diefab.fabricate.net import design_net
>>> d6 = load_design("d6")
>>> marks = net_markers(d6, design_net(d6))
>>> len(marks), [m.face for m in marks][:5], round(marks[0].side_mm, 2), round(marks[0].cell_mm, 2)
(24, ['f1', 'f1', 'f1', 'f1', 'f2'], 4.09, 0.68)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from diefab.core.errors import FabricationError
from diefab.dice.design import Design, design_axis
from diefab.dice.markers import marker_cells, marker_layout
from diefab.made.inlays import cell_outline, inlay_labels
from diefab.made.placement import Label

__all__ = [
    "MIN_PAPER_CELL_MM",
    "QUIET_CELLS",
    "NetMarker",
    "check_cells",
    "marked_body",
    "marker_json",
    "marker_report",
    "marker_summary",
    "net_markers",
    "solid_markers",
]

#: Smallest marker cell printed on paper, mm: finer cells are lost to a webcam at reading distance.
MIN_PAPER_CELL_MM = 0.5
#: Light border kept around each marker, in cells (ArUco needs a quiet zone round the black frame).
QUIET_CELLS = 1.0


@dataclass(frozen=True, eq=False)
class NetMarker:
    """One marker as printed on a net's face (page mm, y down, first copy).

    face : face name; marker_id : ArUco id; corners : (4, 2) float, TL, TR, BR, BL as
    seen on the printed side; outline : the dark cells (shapely); side_mm, cell_mm : sizes.
    """

    face: str
    marker_id: int
    corners: np.ndarray
    outline: Any
    side_mm: float
    cell_mm: float

    def keep_clear(self):
        """The square grown by its quiet zone: where no other print may go (shapely, page mm)."""
        from shapely.geometry import Polygon

        return Polygon(self.corners).buffer(QUIET_CELLS * self.cell_mm, join_style="mitre")


def check_cells(design: Design, size_mm: float, min_cell_mm: float, option: str) -> None:
    """Refuse a die whose smallest marker has cells under `min_cell_mm` at `size_mm` (one line, naming the face).

    Raises
    ------
    FabricationError
        Naming the face with the smallest marker, the largest marker it fits
        and the die size at which every marker's cells reach `min_cell_mm`.
    """
    layout = marker_layout(design)
    mm = design.mm_per_unit * size_mm / design.size_mm
    n = layout.bits + 2
    row = int(np.argmin(layout.sides))
    side = float(layout.sides[row]) * mm
    if side / n >= min_cell_mm:
        return
    need = size_mm * min_cell_mm * n / side
    face = design.polyhedron.names[int(layout.faces[row])]
    raise FabricationError(
        f"face {face} is too small for a readable marker at {size_mm:g} mm: the largest that fits beside its value "
        f"is {side:.2f} mm ({n}x{n} cells of {side / n:.2f} mm), under {option} {min_cell_mm:g} mm; "
        f"use --size {np.ceil(need * 10) / 10:g} or more"
    )


def _page_map(net, k: int, axis: np.ndarray):
    """Affine map (3D point, model units -> page mm) of face k of `net`, from its ring's page image."""
    poly = net.poly
    ring = poly.vertices[poly.faces[k]]
    from diefab.made.labels import face_frame

    u, v = face_frame(ring, poly.normals[k], axis)
    local = np.column_stack([(ring - ring[0]) @ u, (ring - ring[0]) @ v, np.ones(len(ring))])
    m, *_ = np.linalg.lstsq(local, net.faces[k], rcond=None)

    def to_page(points: np.ndarray) -> np.ndarray:
        rel = np.asarray(points, dtype=float) - ring[0]
        return np.column_stack([rel @ u, rel @ v, np.ones(len(rel))]) @ m

    return to_page


def net_markers(design: Design, net, *, min_cell_mm: float = MIN_PAPER_CELL_MM) -> list[NetMarker]:
    """The design's markers on the faces of `net` (its first copy), page mm.

    Raises
    ------
    FabricationError
        A marker whose cells would be under `min_cell_mm` (see :func:`check_cells`).
    """
    size = net.mm_per_unit * design.size_mm / design.mm_per_unit
    check_cells(design, size, min_cell_mm, "the smallest printable cell")
    layout = marker_layout(design)
    axis = design_axis(design)
    n = layout.bits + 2
    out = []
    for row, k in enumerate(layout.faces):
        quad = _page_map(net, int(k), axis)(layout.corners[row])
        cells = marker_cells(layout.dictionary, int(layout.ids[row]))
        side = float(np.linalg.norm(quad[1] - quad[0]))
        out.append(NetMarker(net.poly.names[int(k)], int(layout.ids[row]), quad, cell_outline(cells, quad), side,
                             side / n))  # fmt: skip
    return out


def solid_markers(
    design: Design, flat: list[np.ndarray | None], *, depth_mm: float, min_cell_mm: float
) -> tuple[tuple[Label, ...], dict[str, Any]]:
    """The design's markers on the flat faces of its printed solid (mm), and the regions labels keep clear of.

    Parameters
    ----------
    design : Design
        At the size being printed (``design.size_mm``).
    flat : list of (k, 3) float or None
        The flat part of each face, mm (:func:`~diefab.fabricate.stl.build_solid`'s rounding).
    depth_mm : float
        Depth of the dark cells' pockets.
    min_cell_mm : float
        Smallest cell the printer draws (``--min-stroke``).

    Returns
    -------
    markers : tuple of Label
        One per marked face, its outline the dark cells (text ``"marker <id>"``).
    keep_clear : dict face name -> shapely region
        Each marker's square grown by its quiet zone, in the face's label coordinates.
    """
    check_cells(design, float(design.size_mm), min_cell_mm, "--min-stroke")
    layout = marker_layout(design)
    poly, scale = design.polyhedron, design.mm_per_unit
    cells = [marker_cells(layout.dictionary, int(i)) for i in layout.ids]
    names = [f"marker {int(i)}" for i in layout.ids]
    labels = inlay_labels(poly, flat, design_axis(design), layout.faces, layout.corners * scale, cells,
                          depth_mm=depth_mm, names=names)  # fmt: skip
    # the black frame makes the dark cells' hull the whole square
    keep_clear: dict[str, Any] = {}
    for m in labels:
        square = m.outline.convex_hull.buffer(QUIET_CELLS * m.stroke_mm, join_style="mitre")
        keep_clear[m.face] = square.union(keep_clear[m.face]) if m.face in keep_clear else square
    return labels, keep_clear


def marker_json(placed: list[NetMarker]) -> dict[str, list[dict[str, Any]]]:
    """The markers of a net for its JSON report: face name -> its markers' ids and sizes (mm)."""
    out: dict[str, list[dict[str, Any]]] = {}
    for m in placed:
        out.setdefault(m.face, []).append({"id": m.marker_id, "side_mm": m.side_mm, "cell_mm": m.cell_mm})
    return out


def marker_summary(design: Design, sides_mm, cells_mm) -> str:
    """One line on the markers made: how many, which dictionary, their sides and cells, faces without one."""
    layout = marker_layout(design)
    lo, hi = float(min(sides_mm)), float(max(sides_mm))
    span = f"{lo:.1f}" if hi - lo < 0.05 else f"{lo:.1f}-{hi:.1f}"
    cell = float(min(cells_mm))
    bare = [n for k, n in enumerate(design.polyhedron.names) if k not in set(layout.faces.tolist())]
    rest = f"; faces {', '.join(bare)} too small for one" if bare else ""
    ids = [int(i) for i in layout.ids]
    run = len(ids) > 2 and ids == list(range(ids[0], ids[-1] + 1))
    named = f"{ids[0]}-{ids[-1]}" if run else ", ".join(map(str, ids))
    per_face = np.unique(layout.faces, return_counts=True)[1]
    several = f", {int(per_face.max())} on each face of {int(np.sum(per_face > 1))}" if per_face.max() > 1 else ""
    return (f"{len(layout.faces)} {layout.dictionary} markers (ids {named}{several}), "
            f"{span} mm, cells {cell:.2f} mm and up{rest}")  # fmt: skip


def marked_body(solid, fill):
    """Mass properties (model units, unit density) of the print of `solid` with its labels and markers as cut.

    The sharp die's walls, skins and infill (:func:`~diefab.made.mass.mass_properties`)
    with one prism per placed label (raised where `solid` embosses it) and per
    marker (always sunk), at the depth `solid` was cut to.
    """
    from diefab.made.bodies import label_mass
    from diefab.made.mass import mass_properties

    r = solid.report
    poly = solid.design.polyhedron
    raised = set(r["embossed"])
    prisms = [label_mass(poly, lb, r["depth_mm"], lb.face in raised) for lb in solid.labels]
    prisms += [label_mass(poly, m, r["depth_mm"], False) for m in solid.markers]
    return mass_properties(poly, fill, mm_per_unit=r["mm_per_unit"], bed=poly.face_index(r["bed_face"]),
                           labels=tuple(prisms))  # fmt: skip


def marker_report(markers: tuple[Label, ...], depth_mm: float, volume: float, first: np.ndarray) -> dict[str, Any]:
    """The inlaid markers for the solid's report, and how far their pockets move its centre of mass.

    `volume` (mm³) and `first` ((3,) mm⁴, its first moments) are the solid's as cut; the pockets are
    prisms of the markers' outlines, `depth_mm` deep, so the solid without them is known exactly.
    """
    cut = [m.area_mm2 * depth_mm for m in markers]
    moments = [v * (m.centroid_mm - 0.5 * depth_mm * m.normal) for v, m in zip(cut, markers)]
    uncut = (first + np.sum(moments, axis=0)) / (volume + sum(cut))
    shift = first / volume - uncut
    by_face: dict[str, list[dict[str, Any]]] = {}
    for m in markers:
        by_face.setdefault(m.face, []).append(
            {"id": int(m.text.split()[-1]), "side_mm": m.height_mm, "cell_mm": m.stroke_mm,
             "area_mm2": m.area_mm2, "center_mm": m.center_mm.tolist()}
        )  # fmt: skip
    return {
        "markers": by_face,
        "marker_volume_mm3": float(sum(cut)),
        "marker_com_shift_mm": shift.tolist(),
        "marker_com_shift_norm_mm": float(np.linalg.norm(shift)),
    }  # fmt: skip
