"""Printable solids: the die in millimetres with its values engraved, checked and measured.

:func:`build_solid` makes the die with manifold3d, in millimetres, from the
design's convex hull (optionally with rounded edges and corners), cuts (or
raises) every label with one batched boolean, checks the result after each
operation, verifies it with trimesh, and measures what the engraving and the
print's infill do to the centre of mass and to the landing prediction.
:mod:`.rounding` rounds the edges and predicts where a rounded die lands,
:mod:`.engrave` places and cuts the labels, :mod:`.formats` writes the body
as STL or 3MF.

Placement rules
---------------
* **Where**: a label sits at the centre of the largest circle inscribed in
  its face (shapely's ``polylabel``), after the face is shrunk by the margin;
  where that circle can slide (a rectangle, a trapezoid) at the middle of its
  track (the centroid of the centres within 10 % of the largest radius).
* **Size**: as large as fits, its convex hull inside the shrunk face; by
  default all value labels then take the smallest of those heights, so the
  die's numbers match (a logo from the design's ``labels`` table keeps its
  own).  The
  margin is ``margin_mm`` plus ``depth · cot θ`` for the sharpest dihedral
  angle θ at the face's edges, so the pocket never breaks through a
  neighbouring face.
* **Upright**: "up" in a face is the die's axis (+y, the gem's apex-to-top
  axis, for the gem family; +z otherwise) projected into the face plane, so
  every side label reads upright when the die is held axis vertical, top up.
  A face nearly perpendicular to the axis (projection shorter than
  ``AXIS_PROJECTION``, e.g. the gem's top) stands its text on its longest
  edge, reading along it.

Examples
--------
>>> from diefab.dice.design import load_design
>>> solid = build_solid(load_design("d6").with_params(), size_mm=16)
>>> solid.watertight, solid.bodies, solid.genus
(True, 1, 0)
>>> abs(solid.volume_mm3 - (16**3 - solid.engraved_area_mm2 * 0.6)) < 0.005 * 16**3
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from diefab.core import tolerances as tol
from diefab.core.errors import FabricationError
from diefab.dice.design import Design
from diefab.dice.notes import small_die_warning
from diefab.fabricate.engrave import checked, cut_labels, cutter
from diefab.fabricate.rounding import (
    flat_face_probabilities,
    flat_faces,
    hull_body,
    mesh_moments,
    rotation_to_down,
    rounded_body,
)
from diefab.made.bodies import MAX_DEPTH_FRACTION, label_mass, thinnest_width
from diefab.made.fill import Fill
from diefab.made.mass import bed_face, mass_properties
from diefab.made.placement import Label, Labelling, label_faces, stroke_warnings
from diefab.made.text import Font, load_font

__all__ = [
    "Label",
    "Solid",
    "bed_face",
    "build_solid",
    "cut_labels",
    "flat_face_probabilities",
    "mesh_moments",
]

#: Smallest edge rounding, mm (a printer resolves about 0.05 mm).
MIN_ROUND_MM = 0.01


@dataclass(frozen=True, eq=False)
class Solid:
    """A checked, printable die body in millimetres, with its report.

    Attributes
    ----------
    vertices : (n, 3) float, mm
    triangles : (t, 3) int, outward (counter-clockwise seen from outside)
    label_triangles : (t,) bool
        Triangles made by the label cutters (walls and floors of the engraving).
    labels : tuple of Label
    report : dict
        JSON-ready measurements (see :func:`build_solid`).
    warnings : tuple of str
    print_rotation : (3, 3) float
        Rotation that puts the print's bed face down (see :func:`bed_face`);
        the exporters write :attr:`print_vertices`.
    base : (vertices, triangles) or None
        The body without its labels' material: engraved pockets empty, no
        raised text (the first colour of a two-colour print).
    inlay : (vertices, triangles) or None
        The labels (and markers) as their own solid (what fills the pockets
        and what stands out of the faces): with `base` it makes up the finished die.
    markers : tuple of Label
        The inlaid markers' dark cells (:func:`~diefab.fabricate.markers.solid_markers`).
    """

    design: Design
    vertices: np.ndarray
    triangles: np.ndarray
    label_triangles: np.ndarray
    labels: tuple[Label, ...]
    report: dict[str, Any]
    warnings: tuple[str, ...]
    print_rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    base: tuple[np.ndarray, np.ndarray] | None = None
    inlay: tuple[np.ndarray, np.ndarray] | None = None
    markers: tuple[Label, ...] = ()

    def on_bed(self, vertices: np.ndarray) -> np.ndarray:
        """(n, 3) float, mm: `vertices` moved as the body is onto the print bed (see :attr:`print_vertices`)."""
        v = self.vertices @ self.print_rotation.T
        lo, hi = v.min(axis=0), v.max(axis=0)
        return vertices @ self.print_rotation.T - np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])

    @property
    def print_vertices(self) -> np.ndarray:
        """(n, 3) float, mm: the body on the print bed (z >= 0, bed face at z = 0, centred in x and y)."""
        return self.on_bed(self.vertices)

    @property
    def volume_mm3(self) -> float:
        return self.report["volume_mm3"]

    @property
    def engraved_area_mm2(self) -> float:
        return float(sum(label.area_mm2 for label in (*self.labels, *self.markers)))

    @property
    def watertight(self) -> bool:
        return self.report["watertight"]

    @property
    def bodies(self) -> int:
        return self.report["bodies"]

    @property
    def genus(self) -> int:
        return self.report["genus"]

    def to_trimesh(self):
        import trimesh

        return trimesh.Trimesh(self.vertices, self.triangles, process=True)


def build_solid(
    design: Design,
    *,
    size_mm: float | None = None,
    depth_mm: float = 0.6,
    font: Font | str | None = None,
    round_mm: float = 0.0,
    emboss: bool = False,
    min_stroke_mm: float = 0.6,
    min_text_height_mm: float = 2.0,
    margin_mm: float = 1.0,
    density_g_cm3: float = 1.24,
    print_fill: Fill | None = None,
    batched: bool = True,
    bed: str | None = None,
    uniform_height: bool = True,
    mark: str = "bar",
    pips: bool = False,
    with_marks: bool = True,
    markers: bool = False,
) -> Solid:
    """The printable die: hull (rounded if asked), labels engraved or embossed, checked and measured.

    Parameters
    ----------
    design : Design
    size_mm : float, optional
        Overrides ``design.size_mm`` (what it measures: ``design.size_note``).
    depth_mm : float
        Engraving depth (embossing height), mm; below ``MAX_DEPTH_FRACTION``
        of the die's thinnest width.
    font : Font or path, optional
        Default DejaVu Sans Bold.
    round_mm : float
        Radius of the edge and corner rounding, mm (0: sharp).
    emboss : bool
        Raise the labels instead of cutting them (the die then no longer
        rests flat on labelled faces).  The print never stands on raised
        text: the bed face is an unlabelled one if the die has one, else its
        label is engraved (a warning says so).
    min_stroke_mm : float
        Thinner strokes give a warning (what the printer's nozzle can draw).
    min_text_height_mm : float
        A label that fits only smaller than this is an error naming the face.
    margin_mm : float
        Free border between text and face edge (plus the depth allowance).
    density_g_cm3 : float
        Material density (PLA 1.24).
    print_fill : Fill, optional
        Walls and infill of the print; default the design's fill when it is a
        ``print`` fill, else the default print fill.
    batched : bool
        One batched boolean for all labels (see :func:`cut_labels`).
    uniform_height : bool
        Give every value label the height of the smallest one that fits, as
        on commercial dice (labels set in the design's ``labels`` table, like
        the gem's logo, keep their own fit); false sizes each to its face.
    bed : str, optional
        Face to print on (default :func:`bed_face`, avoiding labelled faces);
        the exported files are rotated so it lies on the bed.
    mark : {"bar", "period", "none"}
        How a label that reads as another label of the die upside down is
        marked (a 6 on a die that also has a 9).
    pips : bool
        Show value labels 1 to 9 as pips.
    with_marks : bool
        Also engrave the values read at a corner or along an edge
        (:func:`~diefab.dice.design.placed_marks`, e.g. the gem's apex), in that corner
        or along that edge of every face that holds it (:func:`~diefab.made.placement.label_faces`).
    markers : bool
        Inlay each face's ArUco markers (:func:`~diefab.fabricate.markers.solid_markers`): their dark
        cells cut `depth_mm` deep, flush once a second material fills them (the inlay part); the value
        labels keep out of each marker's quiet zone.  Cells under `min_stroke_mm` are an error.

    Returns
    -------
    Solid
        ``report`` holds ``volume_mm3``, ``uncut_volume_mm3``,
        ``engraved_volume_mm3`` (from manifold3d) and
        ``expected_engraved_volume_mm3`` (text area × depth, shapely),
        ``watertight``, ``winding_consistent``, ``bodies``, ``genus``,
        ``mass_g`` / ``mass_solid_g``, centres of mass and their shifts in mm
        (``com_shift_mm``: engraving; ``infill_com_shift_mm``: infill;
        ``round_com_shift_mm``: rounding), ``labels``, per-value landing
        predictions and their changes, and ``warnings``.

    Raises
    ------
    FabricationError
        Bad settings (depth, size, rounding, a label that does not fit, an
        unreadable font) or a failed/unsound boolean.
    """
    import manifold3d  # noqa: F401 -- fail early with ImportError if missing

    _check_settings(
        size_mm=size_mm,
        depth_mm=depth_mm,
        round_mm=round_mm,
        min_stroke_mm=min_stroke_mm,
        min_text_height_mm=min_text_height_mm,
        margin_mm=margin_mm,
        density_g_cm3=density_g_cm3,
    )
    if size_mm is not None:
        design = replace(design, size_mm=float(size_mm))
    font = font if isinstance(font, Font) else load_font(font)
    poly, scale = design.polyhedron, design.mm_per_unit
    width = thinnest_width(poly) * scale
    if depth_mm >= MAX_DEPTH_FRACTION * width:
        raise FabricationError(
            f"depth={depth_mm:g} mm is too deep for a die {width:.2f} mm thick at its thinnest "
            f"(must be < {MAX_DEPTH_FRACTION:g} of it, {MAX_DEPTH_FRACTION * width:.2f} mm)"
        )
    if print_fill is None:
        print_fill = design.fill if design.fill.kind == "print" else Fill("print")
    elif print_fill.kind != "print":
        raise FabricationError(f"print_fill must be a 'print' fill, got kind {print_fill.kind!r}")
    bed_index = _bed_index(design, bed, emboss)
    bed_name = poly.names[bed_index]
    warnings = [w for w in (small_die_warning(design),) if w]

    sharp = hull_body(poly.vertices * scale)
    body = sharp if round_mm == 0 else rounded_body(poly, scale, round_mm, round_mm, sharp)
    if body is None:
        raise FabricationError(f"round={round_mm:g} mm is too large: the die is {width:.2f} mm thick at its thinnest")
    flat = flat_faces(poly, scale, round_mm)
    warnings += [
        f"face {poly.names[k]} has no flat part left after rounding: the die cannot rest on it"
        for k, ring in enumerate(flat)
        if ring is None
    ]

    # --- markers, then the labels beside them
    inlays, keep_clear = (), None
    if markers:
        from diefab.fabricate.markers import solid_markers

        inlays, keep_clear = solid_markers(design, flat, depth_mm=depth_mm, min_cell_mm=min_stroke_mm)
    labelling = label_faces(design.label_plan, flat, font, depth_mm=depth_mm, margin_mm=margin_mm,
                            min_text_height_mm=min_text_height_mm, min_stroke_mm=min_stroke_mm, mark=mark, pips=pips,
                            uniform_height=uniform_height, with_marks=with_marks, keep_clear=keep_clear)  # fmt: skip
    warnings.extend(labelling.warnings)
    labels = labelling.labels
    warnings.extend(stroke_warnings(labels, min_stroke_mm))
    # embossed labels must not stand the print on its bed face: that one is engraved
    raised = [emboss and label.face != bed_name for label in labels]
    if emboss and bed_name in set(design.label_of) | labelling.faces:
        text = f" ({design.label_of[bed_name]!r})" if bed_name in design.label_of else ""
        warnings.append(
            f"every face carries a label: the bed face {bed_name}{text} is engraved, "
            "the others embossed, so the print stands flat"
        )
    cutters = [cutter(label, depth_mm, up) for label, up in zip(labels, raised)]
    cutters += [cutter(m, depth_mm, False) for m in inlays]  # markers stay flush: always cut
    cut, sunk = [*labels, *inlays], [*raised, *(False for _ in inlays)]
    raised_cutters = [c for c, up in zip(cutters, raised) if up]
    sunk_cutters = [c for c, up in zip(cutters, sunk) if not up]
    final = cut_labels(body, raised_cutters, emboss=True, batched=batched)
    final = cut_labels(final, sunk_cutters, emboss=False, batched=batched)
    if any(raised):
        warnings.append("embossed labels stand out of their faces: the die does not rest flat on them")

    # --- checks
    mesh = _sound_mesh(final, cutters)
    inlay = _label_part(body, raised_cutters, sunk_cutters)
    base = cut_labels(body, sunk_cutters, emboss=False, batched=batched) if raised_cutters else final
    uncut_volume, uncut_first = mesh_moments(*_mesh_arrays(body))
    volume, first = mesh_moments(mesh.vertices, mesh.triangles)
    if volume <= 0:
        raise FabricationError(f"the solid has non-positive volume {volume:.6g} mm³")
    expected_cut = sum(label.area_mm2 for label in cut) * depth_mm
    signed_cut = sum((1 if up else -1) * label.area_mm2 for label, up in zip(cut, sunk)) * depth_mm
    expected_volume = uncut_volume + signed_cut
    if abs(volume - expected_volume) > tol.STL_VOLUME_REL * expected_volume:
        raise FabricationError(
            f"volume {volume:.2f} mm³ differs from the expected {expected_volume:.2f} mm³ "
            f"(uncut {uncut_volume:.2f} {signed_cut:+.2f} text) by more than {tol.STL_VOLUME_REL:.1%}"
        )

    # --- mass and balance
    com_sharp = poly.centroid * scale
    # the real body's centre of mass (a stated one, a non-convex mesh's) is off the hull's by `body_offset`;
    # rounding, engraving and infill move it as they move the hull's
    body_offset = design.mass_properties(Fill("solid")).center * scale - com_sharp
    print_volume, com_print, hollow = _printed(design, print_fill, cut, sunk, depth_mm, bed_index, round_mm,
                                               sharp, volume, first)  # fmt: skip
    if not all(raised) and depth_mm > print_fill.wall_thickness_mm and hollow:
        warnings.append(
            f"depth {depth_mm:g} mm exceeds the print's wall {print_fill.wall_thickness_mm:g} mm: the slicer adds "
            "walls around the engraving, so the printed mass and centre of mass are approximate"
        )
    centers = {"uncut": uncut_first / uncut_volume, "engraved": first / volume, "printed": com_print}
    centers = {k: c + body_offset for k, c in centers.items()}
    predictions = _predictions(design, flat, round_mm, com_sharp + body_offset, centers)

    def change(a: dict[str, float], b: dict[str, float]) -> dict[str, float]:
        return {k: b[k] - a[k] for k in a}

    grams = density_g_cm3 / 1000.0
    report: dict[str, Any] = {
        "design": design.name,
        "size_mm": float(design.size_mm),
        "mm_per_unit": float(scale),
        "depth_mm": float(depth_mm),
        "emboss": bool(emboss),
        "round_mm": float(round_mm),
        "font": str(font.path),
        "volume_mm3": float(volume),
        "uncut_volume_mm3": float(uncut_volume),
        "hull_volume_mm3": float(poly.volume * scale**3),
        "engraved_volume_mm3": float(abs(uncut_volume - volume)),
        "expected_engraved_volume_mm3": float(expected_cut),
        "watertight": mesh.watertight,
        "winding_consistent": mesh.winding,
        "bodies": mesh.bodies,
        "genus": mesh.genus,
        "triangles": int(len(mesh.triangles)),
        "density_g_cm3": float(density_g_cm3),
        "fill": {**print_fill.to_mapping(), "wall_mm": print_fill.wall_thickness_mm},
        "mass_g": float(print_volume * grams),
        "mass_solid_g": float(volume * grams),
        "center_of_mass_mm": {k: c.tolist() for k, c in centers.items()},
        "com_shift_mm": (centers["engraved"] - centers["uncut"]).tolist(),
        "com_shift_norm_mm": float(np.linalg.norm(centers["engraved"] - centers["uncut"])),
        "infill_com_shift_mm": (centers["printed"] - centers["engraved"]).tolist(),
        "infill_com_shift_norm_mm": float(np.linalg.norm(centers["printed"] - centers["engraved"])),
        **_label_report(labelling),
        "landing_model": "solid-angle" if round_mm == 0 else "solid-angle of the flat faces",
        "probabilities": predictions,
        "probability_change": {
            "engraving": change(predictions["rounded" if round_mm > 0 else "sharp"], predictions["engraved"]),
            "infill": change(predictions["engraved"], predictions["printed"]),
        },
        "warnings": warnings,
    }
    if round_mm > 0:
        report["round_com_shift_mm"] = (centers["uncut"] - com_sharp - body_offset).tolist()
        report["probability_change"]["rounding"] = change(predictions["sharp"], predictions["rounded"])
        report["flat_face_area_mm2"] = {
            poly.names[k]: 0.0 if ring is None else _ring_area(ring) for k, ring in enumerate(flat)
        }
    if inlays:
        from diefab.fabricate.markers import marker_report

        report.update(marker_report(inlays, depth_mm, volume, first))
    report["bed_face"] = bed_name
    report["embossed"] = list(dict.fromkeys(label.face for label, up in zip(labels, raised) if up))
    report["engraved"] = list(dict.fromkeys(label.face for label, up in zip(labels, raised) if not up))
    return Solid(
        design, mesh.vertices, mesh.triangles, mesh.label_triangles, tuple(labels), report, tuple(warnings),
        rotation_to_down(poly.normals[bed_index]), _mesh_arrays(base), inlay, inlays,
    )  # fmt: skip


def _check_settings(**values: float | None) -> None:
    """Every setting a finite number (or None), in its range."""
    for name, value in values.items():
        if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value)):
            raise FabricationError(f"{name}={value!r} is not a finite number")
    if values["size_mm"] is not None and values["size_mm"] <= 0:
        raise FabricationError(f"size={values['size_mm']:g} mm must be positive")
    if values["depth_mm"] <= 0:
        raise FabricationError(f"depth={values['depth_mm']:g} mm must be positive")
    if values["round_mm"] < 0:
        raise FabricationError(f"round={values['round_mm']:g} mm must be >= 0")
    if 0 < values["round_mm"] < MIN_ROUND_MM:  # finer than any printer, and too fine for a sound boolean
        raise FabricationError(f"round={values['round_mm']:g} mm must be 0 (sharp) or at least {MIN_ROUND_MM:g} mm")
    if values["density_g_cm3"] <= 0:
        raise FabricationError(f"density={values['density_g_cm3']:g} g/cm³ must be positive")
    if values["min_text_height_mm"] <= 0 or values["min_stroke_mm"] <= 0 or values["margin_mm"] < 0:
        raise FabricationError("min-text-height and min-stroke must be positive and margin >= 0")


def _bed_index(design: Design, bed: str | None, emboss: bool) -> int:
    """The face the die is printed on: `bed` if named, else :func:`bed_face` avoiding the labelled faces."""
    poly = design.polyhedron
    try:
        if bed is not None:
            return poly.face_index(bed)
        return bed_face(poly, avoid=[poly.face_index(f) for f in design.label_of], strict=emboss)
    except FabricationError:
        raise
    except Exception as exc:
        raise FabricationError(f"bed face: {exc}") from exc


@dataclass(frozen=True, eq=False)
class _Mesh:
    """The finished body as triangles, with what trimesh and manifold3d say of it."""

    vertices: np.ndarray
    triangles: np.ndarray
    label_triangles: np.ndarray
    genus: int
    bodies: int
    watertight: bool
    winding: bool


def _sound_mesh(final, cutters: list) -> _Mesh:
    """The body's triangles (those the label cutters made flagged), checked: one watertight body of genus 0."""
    import trimesh

    genus = int(final.genus())
    bodies = len(final.decompose())
    mesh = final.to_mesh64()
    vertices = np.asarray(mesh.vert_properties)[:, :3].copy()
    triangles = np.asarray(mesh.tri_verts, dtype=np.int64).copy()
    run_tri = np.asarray(mesh.run_index) // 3
    cutter_ids = {c.original_id() for c in cutters}
    label_tri = np.zeros(len(triangles), dtype=bool)
    for rid, start, stop in zip(np.asarray(mesh.run_original_id), run_tri[:-1], run_tri[1:]):
        label_tri[start:stop] = rid in cutter_ids
    tm = trimesh.Trimesh(vertices, triangles, process=True)
    watertight, winding = bool(tm.is_watertight), bool(tm.is_winding_consistent)
    tm_bodies = int(tm.body_count)
    if bodies != 1 or tm_bodies != 1:
        raise FabricationError(f"the solid has {max(bodies, tm_bodies)} separate bodies, expected 1")
    if genus != 0:
        raise FabricationError(f"the solid has genus {genus}, expected 0 (a label cut a tunnel through the die)")
    if not (watertight and winding):
        raise FabricationError(
            f"the solid is not sound: watertight={watertight}, winding consistent={winding} (trimesh)"
        )
    return _Mesh(vertices, triangles, label_tri, genus, bodies, watertight, winding)


def _printed(design, print_fill, labels, raised, depth_mm, bed_index, round_mm, sharp, volume, first):
    """Volume (mm³) and centre (mm, of the hull's body) of the print as laid down, and whether its core is hollow.

    A sharp die: walls, top and bottom skins and infill as the slicer lays
    them, labels included (:func:`diefab.made.mass.mass_properties`).  A rounded
    one: walls of uniform thickness inside the rounded body around an infilled
    core (solid when the walls meet).
    """
    poly, scale = design.polyhedron, design.mm_per_unit
    if round_mm == 0:
        weighed = tuple(label_mass(poly, lb, depth_mm, up) for lb, up in zip(labels, raised))
        printed = mass_properties(poly, print_fill, mm_per_unit=scale, bed=bed_index, labels=weighed)
        return printed.mass * scale**3, printed.center * scale, True
    core_inset = max(round_mm, print_fill.wall_thickness_mm)
    core_radius = max(0.0, round_mm - print_fill.wall_thickness_mm)
    core = rounded_body(poly, scale, core_inset, core_radius, sharp)
    if core is None:  # walls meet: the print is solid
        core_volume, core_first = 0.0, np.zeros(3)
    else:
        core_volume, core_first = mesh_moments(*_mesh_arrays(core))
    hollow = 1 - print_fill.infill
    print_volume = volume - hollow * core_volume
    return print_volume, (first - hollow * core_first) / print_volume, core is not None


def _predictions(design, flat, round_mm, sharp_mm, centers) -> dict[str, dict[str, float]]:
    """Per-value landing probabilities (solid-angle model) of the sharp die and of each stage in `centers`."""
    from diefab.models.probabilities import solid_angle_model, to_values

    poly, scale = design.polyhedron, design.mm_per_unit

    def per_value(p: np.ndarray) -> dict[str, float]:
        return {str(v): float(q) for v, q in zip(design.support, to_values(design, p))}

    def model(center_mm: np.ndarray) -> np.ndarray:
        if round_mm > 0:
            return flat_face_probabilities(flat, center_mm)
        return solid_angle_model(poly, center_mm / scale)

    out = {"sharp": per_value(solid_angle_model(poly, sharp_mm / scale))}
    if round_mm > 0:
        out["rounded"] = per_value(model(centers["uncut"]))
    out["engraved"] = per_value(model(centers["engraved"]))
    out["printed"] = per_value(model(centers["printed"]))
    return out


def _label_report(labelling: Labelling) -> dict[str, Any]:
    """The labels and marks as the report lists them."""
    fitted = labelling.fitted.values()
    return {
        "labels": {label.face: label.text for label in fitted},
        "label_details": {
            label.face: {
                "text": label.text,
                "height_mm": label.height_mm,
                "stroke_mm": label.stroke_mm,
                "thin_fraction": label.thin_fraction,
                "area_mm2": label.area_mm2,
                "center_mm": label.center_mm.tolist(),
                "up": label.up.tolist(),
            }
            for label in fitted
        },
        "marks": [
            {
                "face": label.face,
                "text": label.text,
                "at": [int(v) for v in m.at],
                "height_mm": label.height_mm,
                "center_mm": label.center_mm.tolist(),
                "up": label.up.tolist(),
            }
            for label, m in zip(labelling.marks, labelling.placed)
        ],
    }


def _mesh_arrays(manifold) -> tuple[np.ndarray, np.ndarray]:
    mesh = manifold.to_mesh64()
    return np.asarray(mesh.vert_properties)[:, :3].copy(), np.asarray(mesh.tri_verts, dtype=np.int64).copy()


def _label_part(body, raised: list, sunk: list) -> tuple[np.ndarray, np.ndarray] | None:
    """The labels as their own solid: what the engraving removed plus what the embossing added.

    With the body as cut (engraved pockets, no raised text) it makes up the
    finished die: print it in a second colour, or paint-fill the pockets.
    """
    import manifold3d

    parts = []
    if sunk:
        pockets = checked(manifold3d.Manifold.batch_boolean(sunk, manifold3d.OpType.Add), "joining the labels")
        parts.append(checked(body ^ pockets, "measuring the engraved pockets"))
    if raised:
        relief = checked(manifold3d.Manifold.batch_boolean(raised, manifold3d.OpType.Add), "joining the labels")
        parts.append(checked(relief - body, "measuring the raised labels"))
    if not parts:
        return None
    return _mesh_arrays(checked(manifold3d.Manifold.batch_boolean(parts, manifold3d.OpType.Add), "joining labels"))


def _ring_area(ring: np.ndarray) -> float:
    return float(0.5 * np.linalg.norm(np.cross(ring, np.roll(ring, -1, axis=0)).sum(axis=0)))
