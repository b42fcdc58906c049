"""Printable solids: the die in millimetres with its values engraved, checked and measured.

:func:`build_solid` makes the die with manifold3d, in millimetres, from the
design's convex hull (optionally with rounded edges and corners), cuts (or
raises) every label with one batched boolean, checks the result after each
operation, verifies it with trimesh, and measures what the engraving and the
print's infill do to the centre of mass and to the landing prediction.
:func:`stl_bytes` and :func:`threemf_bytes` render the body; the CLI writes them.

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

Landing model of a rounded die
------------------------------
A rounded die can only rest on the flat parts of its faces; a die that lands
on a rounded edge rolls off onto one of them.  The rounded die's prediction is
the solid angle that each *flat* face polygon subtends at the centre of mass,
normalised by their sum (the rounded zones' share is spread in proportion).
Without rounding this is exactly the paper's solid-angle model.

Examples
--------
>>> from diefab.design import load_design
>>> solid = build_solid(load_design("d6").with_params(), size_mm=16)
>>> solid.watertight, solid.bodies, solid.genus
(True, 1, 0)
>>> abs(solid.volume_mm3 - (16**3 - solid.engraved_area_mm2 * 0.6)) < 0.005 * 16**3
True
"""

from __future__ import annotations

import io
import math
import zipfile
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .. import tolerances as tol
from ..design import Design
from ..errors import FabricationError
from ..geometry import Polyhedron
from ..mass import Fill, inset
from .labels import (
    MARK_FRACTION,
    design_axis,
    face_frame,
    fit_label,
    label_shape,
    mark_frame,
    placed_marks,
    small_die_warning,
)
from .text import Font, load_font, stroke_width, thin_fraction

__all__ = [
    "Label",
    "Solid",
    "bed_face",
    "build_solid",
    "cut_labels",
    "flat_face_probabilities",
    "inlay_stl_bytes",
    "mesh_moments",
    "stl_bytes",
    "threemf_bytes",
]

#: Height above the face the cutter starts at, mm (avoids coplanar booleans).
CUT_OVERSHOOT_MM = 0.2
#: Largest depth as a fraction of the die's thinnest width.
MAX_DEPTH_FRACTION = 0.1
#: Segments of the spheres that round edges and corners.
ROUND_SEGMENTS = 32
#: Share of a label's area that may be thinner than --min-stroke before a warning.
THIN_AREA_WARNING = 0.1
#: Gap kept between a value read at a corner or edge and the face's centred label, mm.
MARK_CLEARANCE_MM = 0.6
#: A value read at a corner or edge with less room than this (mm high) is left out, with a warning.
MIN_MARK_MM = 0.8


@dataclass(frozen=True, eq=False)
class Label:
    """One label placed on a face.

    Attributes
    ----------
    face : str
    text : str
    height_mm : float
        Digit height of the text.
    stroke_mm : float
        Mean stroke width (:func:`~diefab.fabricate.text.stroke_width`).
    thin_fraction : float
        Share of the text area in strokes thinner than ``min_stroke``.
    area_mm2 : float
        Area of the text outline (shapely), the engraved volume is ``area · depth``.
    center_mm : (3,) float
        Centre of the text on the face.
    centroid_mm : (3,) float
        Area centroid of the text outline on the face.
    baseline, up, normal : (3,) float
        The face frame: reading direction, up, outward normal (baseline × up = normal).
    origin_mm : (3,) float
        Origin of the face coordinates of `outline`.
    outline : shapely geometry
        The text in face coordinates (x along `baseline`, y along `up`), mm.
    face_outline : shapely geometry or None
        A value read at a corner or an edge: the text in the coordinates of
        the face's centred label (its frame turns toward that corner).
    """

    face: str
    text: str
    height_mm: float
    stroke_mm: float
    thin_fraction: float
    area_mm2: float
    center_mm: np.ndarray
    centroid_mm: np.ndarray
    baseline: np.ndarray
    up: np.ndarray
    normal: np.ndarray
    origin_mm: np.ndarray
    outline: Any = field(repr=False)
    face_outline: Any = field(default=None, repr=False)


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
        The labels as their own solid (what fills the pockets and what
        stands out of the faces): with `base` it makes up the finished die.
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
        return float(sum(label.area_mm2 for label in self.labels))

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


# ----------------------------------------------------------------------
# small pure helpers


def mesh_moments(vertices: np.ndarray, triangles: np.ndarray) -> tuple[float, np.ndarray]:
    """Volume and first moment ∫ x dV of a closed, outward-oriented triangle mesh.

    Returns
    -------
    volume : float
    first : (3,) float
        Divide by the volume for the centre of mass.
    """
    v = np.asarray(vertices, dtype=float)[np.asarray(triangles)]
    det = np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2]))
    return float(det.sum() / 6), (det[:, None] * v.sum(axis=1)).sum(axis=0) / 24


def _polygon_solid_angle(points: np.ndarray, center: np.ndarray) -> float:
    """Solid angle of a planar convex polygon (ordered ring, (k, 3)) seen from `center`."""
    r = points - center
    a = np.repeat(r[:1], len(r) - 2, axis=0)
    b, c = r[1:-1], r[2:]
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    triple = np.einsum("ij,ij->i", a, np.cross(b, c))
    denom = la * lb * lc + (a * b).sum(1) * lc + (a * c).sum(1) * lb + (b * c).sum(1) * la
    return float(abs((2 * np.arctan2(triple, denom)).sum()))


def flat_face_probabilities(flat_faces: list[np.ndarray | None], center: np.ndarray) -> np.ndarray:
    """(m,) float: solid angle of each flat face polygon at `center`, normalised to sum 1.

    `flat_faces` holds an ordered (k, 3) ring per face, or None where rounding
    left no flat part (probability 0).
    """
    omega = np.array([0.0 if f is None else _polygon_solid_angle(f, center) for f in flat_faces])
    return omega / omega.sum()


def _check(manifold, what: str):
    """Raise unless manifold3d reports success and a non-empty result."""
    import manifold3d

    status = manifold.status()
    if status != manifold3d.Error.NoError:
        raise FabricationError(f"manifold3d failed while {what}: {status.name}")
    if manifold.is_empty():
        raise FabricationError(f"manifold3d produced an empty solid while {what}")
    return manifold


def bed_face(poly: Polyhedron, overhang_deg: float = 45.0, *, avoid=(), strict: bool = False) -> int:
    """The face to print on: least overhanging area, then a face not in `avoid`, then the largest.

    With face k on the bed, a face whose outward normal is within
    `overhang_deg` of straight down (other than face k) needs support; its
    area counts as overhang.  `avoid` lists faces that carry a label: text on
    the bed face prints poorly, and raised text would stand the print on its
    letters.  With `strict`, any face outside `avoid` beats every face in it,
    whatever the overhang (embossed labels); when all faces are in `avoid`
    the usual choice stands and the caller engraves that face's label.
    """
    limit = math.cos(math.radians(overhang_deg))
    down = poly.normals @ poly.normals.T  # [k, j]: cos between face j's normal and "down" when k is on the bed
    overhang = np.where((down > limit + tol.TIE) & ~np.eye(len(poly.faces), dtype=bool), poly.areas[None, :], 0.0)
    cost = overhang.sum(axis=1)
    labelled = np.isin(np.arange(len(poly.faces)), list(avoid))
    pool = np.flatnonzero(~labelled) if strict and not labelled.all() else np.arange(len(poly.faces))
    best = pool[cost[pool] <= cost[pool].min() + tol.AREA]
    if not labelled[best].all():
        best = best[~labelled[best]]
    return int(best[np.argmax(poly.areas[best])])


def _rotation_to_down(normal: np.ndarray) -> np.ndarray:
    """(3, 3): the rotation taking unit vector `normal` to (0, 0, -1) (Rodrigues)."""
    target = np.array([0.0, 0.0, -1.0])
    axis = np.cross(normal, target)
    s, c = np.linalg.norm(axis), float(normal @ target)
    if s < 1e-12:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    k = axis / s
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * kx + (1 - c) * kx @ kx


def _min_width(poly: Polyhedron) -> float:
    """Thinnest width of the solid between a face and the opposite support plane."""
    heights = poly.offsets[:, None] - poly.normals @ poly.vertices.T
    return float(heights.max(axis=1).min())


def _max_cot_dihedral(poly: Polyhedron) -> np.ndarray:
    """(m,) float: largest cot of the interior dihedral angle at each face's edges (0 if all obtuse)."""
    out = np.zeros(len(poly.faces))
    for f0, f1 in poly.edge_faces:
        cos_interior = -float(poly.normals[f0] @ poly.normals[f1])
        theta = math.acos(max(-1.0, min(1.0, cos_interior)))
        cot = max(0.0, math.cos(theta) / max(math.sin(theta), 1e-12))
        out[f0] = max(out[f0], cot)
        out[f1] = max(out[f1], cot)
    return out


def _ring_order(points: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Points of a convex planar polygon in counter-clockwise order seen from outside, collinear dropped."""
    from scipy.spatial import ConvexHull

    u = np.cross(normal, [1.0, 0.0, 0.0])
    if np.linalg.norm(u) < 0.5:
        u = np.cross(normal, [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    w = np.cross(normal, u)
    hull = ConvexHull(np.column_stack([points @ u, points @ w]))
    return points[hull.vertices]  # scipy orders 2D hull vertices counter-clockwise in (u, w)


# ----------------------------------------------------------------------
# building


def _hull(points_mm: np.ndarray):
    import manifold3d

    return _check(manifold3d.Manifold.hull_points(np.ascontiguousarray(points_mm, dtype=float)), "building the hull")


def _rounded(poly: Polyhedron, scale: float, inset_mm: float, radius_mm: float, clip):
    """The polyhedron shrunk by `inset_mm`, grown back by spheres of `radius_mm`, clipped by `clip`."""
    import manifold3d

    core = inset(poly, inset_mm / scale) if inset_mm > 0 else poly
    if core is None:
        return None
    if radius_mm <= 0:
        return _hull(core.vertices * scale)
    # the sphere's polygon must cover the true sphere, so the flat faces land on the original planes
    cover = radius_mm / math.cos(math.pi / ROUND_SEGMENTS) ** 2
    sphere = manifold3d.Manifold.sphere(cover, ROUND_SEGMENTS).to_mesh64()
    sphere_pts = np.asarray(sphere.vert_properties)[:, :3]
    points = (core.vertices * scale)[:, None, :] + sphere_pts[None, :, :]
    body = _hull(points.reshape(-1, 3))
    return _check(body ^ clip, "clipping the rounded body to the face planes")


def _flat_faces(poly: Polyhedron, scale: float, round_mm: float) -> list[np.ndarray | None]:
    """The flat part of each face after rounding by `round_mm` (mm, ordered rings), None where none is left.

    Rounding is the die shrunk by the radius and grown back by a ball, so the
    flat part of face k is face k of the shrunk die moved out by the radius
    along its normal: exact, whatever the face's orientation.
    """
    rings = [poly.vertices[f] * scale for f in poly.faces]
    if round_mm <= 0:
        return rings
    core = inset(poly, round_mm / scale)
    if core is None:
        return [None] * len(poly.faces)
    out: list[np.ndarray | None] = []
    for k in range(len(poly.faces)):
        cos = core.normals @ poly.normals[k]
        j = int(np.argmax(cos))
        if cos[j] < 1 - tol.COPLANAR or core.areas[j] * scale**2 <= tol.AREA * scale**2:
            out.append(None)
            continue
        out.append(core.vertices[core.faces[j]] * scale + round_mm * poly.normals[k])
    return out


def _place_label(
    face: str,
    text: str,
    ring: np.ndarray,
    normal: np.ndarray,
    axis: np.ndarray,
    glyphs,
    margin_mm: float,
    min_height_mm: float,
    min_stroke_mm: float,
    max_height_mm: float = math.inf,
    avoid=None,
) -> Label:
    """Fit `text` centred on a face (ring, mm), clear of `avoid` (face coordinates: origin the ring's mean)."""
    from shapely.geometry import Polygon

    u, v = face_frame(ring, normal, axis)
    origin = ring.mean(axis=0)
    face2d = Polygon(np.column_stack([(ring - origin) @ u, (ring - origin) @ v]))
    inner = face2d.buffer(-margin_mm, join_style="mitre")
    if avoid is not None:
        inner = inner.difference(avoid)
    if inner.is_empty or inner.area <= 0:
        raise FabricationError(
            f"label {text!r} does not fit on face {face}: the face is narrower than twice the margin "
            f"({margin_mm:.2f} mm); use a larger --size"
        )
    fitted, cx, cy = fit_label(inner, glyphs)
    height = min(fitted, max_height_mm)
    if fitted < min_height_mm:
        raise FabricationError(
            f"label {text!r} does not fit on face {face}: at most {fitted:.2f} mm high, "
            f"below the minimum text height {min_height_mm:g} mm (use a larger --size or a shorter label)"
        )
    return _fitted_label(face, text, glyphs, height, cx, cy, origin, u, v, normal, min_stroke_mm)


def _fitted_label(face, text, glyphs, height, cx, cy, origin, baseline, up, normal, min_stroke_mm) -> Label:
    """The :class:`Label` of `glyphs` scaled to `height` at (cx, cy) in the frame (`origin`, `baseline`, `up`)."""
    from shapely import affinity

    outline = affinity.translate(affinity.scale(glyphs, height, height, origin=(0, 0)), cx, cy)
    c2 = outline.centroid
    return Label(
        face=face,
        text=text,
        height_mm=float(height),
        stroke_mm=float(stroke_width(glyphs) * height),
        thin_fraction=thin_fraction(outline, min_stroke_mm),
        area_mm2=float(outline.area),
        center_mm=origin + cx * baseline + cy * up,
        centroid_mm=origin + c2.x * baseline + c2.y * up,
        baseline=baseline,
        up=up,
        normal=np.asarray(normal, dtype=float),
        origin_mm=origin,
        outline=outline,
    )


def _place_mark(poly, m, flat, axis, font, texts, mark, pips, margin_mm, min_stroke_mm, scale) -> Label | None:
    """A value read at a corner or along an edge (:class:`~diefab.readings.Marking` `m`) on its face, as a Label.

    The text lies in the face shrunk toward that corner or the edge's middle
    (:func:`~.labels.mark_frame`), its top toward it, at most
    :data:`~.labels.MARK_FRACTION` of the face's inscribed diameter high;
    None where less than :data:`MIN_MARK_MM` fits.
    """
    from shapely import affinity
    from shapely.geometry import Polygon
    from shapely.ops import polylabel

    k = poly.face_index(m.face)
    ring = flat[k]
    if ring is None:
        raise FabricationError(f"value {m.text!r} does not fit on face {m.face}: rounding left no flat part")
    u, v = face_frame(ring, poly.normals[k], axis)
    origin = ring.mean(axis=0)
    ring2 = np.column_stack([(ring - origin) @ u, (ring - origin) @ v])
    # the named corners, on the flat part of a rounded face: its nearest corners
    at = tuple(int(np.argmin(np.linalg.norm(ring - poly.vertices[w] * scale, axis=1))) for w in m.at)
    zone, anchor, xa, ya = mark_frame(ring2, at)
    face2d = Polygon(ring2)
    region = zone.intersection(face2d.buffer(-margin_mm, join_style="mitre"))
    to_text = [xa[0], xa[1], ya[0], ya[1], -float(anchor @ xa), -float(anchor @ ya)]
    glyphs = label_shape(m.text, font, others=texts.values(), mark=mark, pips=pips)
    cap = MARK_FRACTION * 2 * face2d.exterior.distance(polylabel(face2d, 0.01))
    height, cx, cy = fit_label(affinity.affine_transform(region, to_text), glyphs, cap)
    if height < MIN_MARK_MM:
        return None
    baseline, up = xa[0] * u + xa[1] * v, ya[0] * u + ya[1] * v
    at_mm = origin + anchor[0] * u + anchor[1] * v
    label = _fitted_label(m.face, m.text, glyphs, height, cx, cy, at_mm, baseline, up, poly.normals[k], min_stroke_mm)
    face_outline = affinity.affine_transform(label.outline, [xa[0], ya[0], xa[1], ya[1], anchor[0], anchor[1]])
    return replace(label, face_outline=face_outline)


def _cutter(label: Label, depth_mm: float, emboss: bool):
    """The label's prism: into the face (engrave) or out of it (emboss), manifold3d."""
    import manifold3d

    contours = []
    for poly in getattr(label.outline, "geoms", [label.outline]):
        contours.append(np.asarray(poly.exterior.coords)[:-1])
        contours.extend(np.asarray(r.coords)[:-1] for r in poly.interiors)
    section = manifold3d.CrossSection(contours, manifold3d.FillRule.EvenOdd)
    prism = _check(manifold3d.Manifold.extrude(section, depth_mm + CUT_OVERSHOOT_MM), f"extruding label {label.face}")
    # engrave: from `depth` below the face to just above it; emboss: from just below to `depth` above
    prism = prism.translate((0.0, 0.0, -CUT_OVERSHOOT_MM if emboss else -depth_mm))
    matrix = np.column_stack([label.baseline, label.up, label.normal, label.origin_mm])
    return _check(prism.transform(matrix).as_original(), f"placing label {label.face}")


def cut_labels(body, cutters: list, *, emboss: bool = False, batched: bool = True):
    """Subtract (or add) the label prisms from `body`, checking manifold3d after every boolean.

    ``batched`` makes one boolean of all labels (manifold3d's batch
    boolean); otherwise each label is a separate boolean on the growing body,
    the straightforward baseline.
    """
    import manifold3d

    op = manifold3d.OpType.Add if emboss else manifold3d.OpType.Subtract
    verb = "embossing" if emboss else "engraving"
    if not cutters:
        return body
    if batched:
        return _check(manifold3d.Manifold.batch_boolean([body, *cutters], op), f"{verb} the labels")
    for k, cutter in enumerate(cutters):
        body = _check(body + cutter if emboss else body - cutter, f"{verb} label {k + 1}")
    return body


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
        (:func:`~.labels.placed_marks`, e.g. the gem's apex), in that corner
        or along that edge of every face that holds it.

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

    for name, value in (("size_mm", size_mm), ("depth_mm", depth_mm), ("round_mm", round_mm),
                        ("min_stroke_mm", min_stroke_mm), ("min_text_height_mm", min_text_height_mm),
                        ("margin_mm", margin_mm), ("density_g_cm3", density_g_cm3)):  # fmt: skip
        if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value)):
            raise FabricationError(f"{name}={value!r} is not a finite number")
    if size_mm is not None:
        if size_mm <= 0:
            raise FabricationError(f"size={size_mm:g} mm must be positive")
        design = replace(design, size_mm=float(size_mm))
    if depth_mm <= 0:
        raise FabricationError(f"depth={depth_mm:g} mm must be positive")
    if round_mm < 0:
        raise FabricationError(f"round={round_mm:g} mm must be >= 0")
    if density_g_cm3 <= 0:
        raise FabricationError(f"density={density_g_cm3:g} g/cm³ must be positive")
    if min_text_height_mm <= 0 or min_stroke_mm <= 0 or margin_mm < 0:
        raise FabricationError("min-text-height and min-stroke must be positive and margin >= 0")
    font = font if isinstance(font, Font) else load_font(font)
    poly = design.polyhedron
    scale = design.mm_per_unit
    width = _min_width(poly) * scale
    if depth_mm >= MAX_DEPTH_FRACTION * width:
        raise FabricationError(
            f"depth={depth_mm:g} mm is too deep for a die {width:.2f} mm thick at its thinnest "
            f"(must be < {MAX_DEPTH_FRACTION:g} of it, {MAX_DEPTH_FRACTION * width:.2f} mm)"
        )
    if print_fill is None:
        print_fill = design.fill if design.fill.kind == "print" else Fill("print")
    elif print_fill.kind != "print":
        raise FabricationError(f"print_fill must be a 'print' fill, got kind {print_fill.kind!r}")

    labelled = set(design.label_of)
    try:
        if bed is not None:
            bed_index = poly.face_index(bed)
        else:
            avoid = [poly.face_index(f) for f in labelled]
            bed_index = bed_face(poly, avoid=avoid, strict=emboss)
    except FabricationError:
        raise
    except Exception as exc:
        raise FabricationError(f"bed face: {exc}") from exc
    bed_name = poly.names[bed_index]
    warnings: list[str] = []
    small = small_die_warning(design)
    if small:
        warnings.append(small)
    sharp = _hull(poly.vertices * scale)
    if round_mm > 0:
        body = _rounded(poly, scale, round_mm, round_mm, sharp)
        if body is None:
            raise FabricationError(
                f"round={round_mm:g} mm is too large: the die is {width:.2f} mm thick at its thinnest"
            )
    else:
        body = sharp
    body_mesh = body.to_mesh64()
    body_vertices = np.asarray(body_mesh.vert_properties)[:, :3]
    flat = _flat_faces(poly, scale, round_mm)
    for k, ring in enumerate(flat):
        if ring is None:
            warnings.append(f"face {poly.names[k]} has no flat part left after rounding: the die cannot rest on it")

    # --- labels
    axis = design_axis(design)
    cots = _max_cot_dihedral(poly)
    texts = design.label_of
    shapes = {face: label_shape(t, font, others=texts.values(), mark=mark, pips=pips) for face, t in texts.items()}

    marks, placed = [], []
    for m in placed_marks(design) if with_marks else []:
        label = _place_mark(poly, m, flat, axis, font, texts, mark, pips,
                            margin_mm + depth_mm * cots[poly.face_index(m.face)], min_stroke_mm, scale)  # fmt: skip
        where = f"value {m.text!r} at {'its corner' if len(m.at) == 1 else 'its edge'} of face {m.face}"
        if label is None:
            warnings.append(f"{where} does not fit and is not engraved: use a larger --size")
            continue
        if label.height_mm < min_text_height_mm:
            warnings.append(
                f"{where} is {label.height_mm:.2f} mm high, under the minimum text height {min_text_height_mm:g} mm"
            )
        marks.append(label)
        placed.append(m)
    avoid: dict[str, Any] = {}
    for label in marks:
        keep_clear = label.face_outline.buffer(MARK_CLEARANCE_MM)
        avoid[label.face] = keep_clear if label.face not in avoid else avoid[label.face].union(keep_clear)
    labelled |= set(avoid)

    def place(face: str, text: str, cap: float = math.inf) -> Label:
        k = poly.face_index(face)
        if flat[k] is None:
            raise FabricationError(f"label {text!r} does not fit on face {face}: rounding left no flat part")
        return _place_label(
            face, text, flat[k], poly.normals[k], axis, shapes[face],
            margin_mm + depth_mm * cots[k], min_text_height_mm, min_stroke_mm, cap, avoid.get(face),
        )  # fmt: skip

    fitted = {face: place(face, text) for face, text in texts.items()}
    values = [face for face in fitted if face not in design.labels]  # computed value labels, not logos
    if uniform_height and values:
        common = min(fitted[face].height_mm for face in values)
        fitted.update({face: place(face, fitted[face].text, common) for face in values})
    labels = list(fitted.values()) + marks
    warnings.extend(_stroke_warnings(labels, min_stroke_mm))
    # embossed labels must not stand the print on its bed face: that one is engraved
    raised = [emboss and label.face != bed_name for label in labels]
    if emboss and bed_name in labelled:
        warnings.append(
            f"every face carries a label: the bed face {bed_name} ({texts[bed_name]!r}) is engraved, "
            "the others embossed, so the print stands flat"
        )
    cutters = [_cutter(label, depth_mm, up) for label, up in zip(labels, raised)]
    raised_cutters = [c for c, up in zip(cutters, raised) if up]
    sunk_cutters = [c for c, up in zip(cutters, raised) if not up]
    final = cut_labels(body, raised_cutters, emboss=True, batched=batched)
    final = cut_labels(final, sunk_cutters, emboss=False, batched=batched)
    if any(raised):
        warnings.append("embossed labels stand out of their faces: the die does not rest flat on them")

    # --- checks
    genus = int(final.genus())
    bodies = len(final.decompose())
    mesh = final.to_mesh64()
    vertices = np.asarray(mesh.vert_properties)[:, :3].copy()
    triangles = np.asarray(mesh.tri_verts, dtype=np.int64).copy()
    run_ids = np.asarray(mesh.run_original_id)
    run_tri = np.asarray(mesh.run_index) // 3
    cutter_ids = {c.original_id() for c in cutters}
    label_tri = np.zeros(len(triangles), dtype=bool)
    for rid, start, stop in zip(run_ids, run_tri[:-1], run_tri[1:]):
        label_tri[start:stop] = rid in cutter_ids
    inlay = _label_part(body, raised_cutters, sunk_cutters)
    base = cut_labels(body, sunk_cutters, emboss=False, batched=batched) if raised_cutters else final
    import trimesh

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
    uncut_volume, uncut_first = mesh_moments(body_vertices, np.asarray(body_mesh.tri_verts))
    volume, first = mesh_moments(vertices, triangles)
    if volume <= 0:
        raise FabricationError(f"the solid has non-positive volume {volume:.6g} mm³")
    expected_cut = sum(label.area_mm2 for label in labels) * depth_mm
    signed_cut = sum((1 if up else -1) * label.area_mm2 for label, up in zip(labels, raised)) * depth_mm
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
    com_uncut = uncut_first / uncut_volume
    com_solid = first / volume
    if round_mm == 0:  # walls, top and bottom skins and infill as the slicer lays them, labels included
        from ..mass import LabelMass, mass_properties

        label_mass = tuple(
            LabelMass(
                poly.face_index(lb.face),
                lb.area_mm2,
                lb.centroid_mm,
                lb.normal,
                depth_mm,
                up,
                lb.outline,
                lb.origin_mm,
                lb.baseline,
                lb.up,
            )  # fmt: skip
            for lb, up in zip(labels, raised)
        )
        printed = mass_properties(poly, print_fill, mm_per_unit=scale, bed=bed_index, labels=label_mass)
        print_volume, com_print = printed.mass * scale**3, printed.center * scale
        core = True
    else:  # rounded: walls of uniform thickness inside the rounded body
        core_inset = max(round_mm, print_fill.wall_thickness_mm)
        core_radius = max(0.0, round_mm - print_fill.wall_thickness_mm)
        core = _rounded(poly, scale, core_inset, core_radius, sharp)
        if core is None:  # walls meet: the print is solid
            core_volume, core_first = 0.0, np.zeros(3)
        else:
            core_mesh = core.to_mesh64()
            core_volume, core_first = mesh_moments(np.asarray(core_mesh.vert_properties)[:, :3], core_mesh.tri_verts)
        hollow = 1 - print_fill.infill
        print_volume = volume - hollow * core_volume
        com_print = (first - hollow * core_first) / print_volume
    if not all(raised) and depth_mm > print_fill.wall_thickness_mm and core is not None:
        warnings.append(
            f"depth {depth_mm:g} mm exceeds the print's wall {print_fill.wall_thickness_mm:g} mm: the slicer adds "
            "walls around the engraving, so the printed mass and centre of mass are approximate"
        )
    com_uncut, com_solid, com_print = com_uncut + body_offset, com_solid + body_offset, com_print + body_offset

    from ..models import solid_angle_model

    def model(center_mm: np.ndarray) -> np.ndarray:
        if round_mm > 0:
            return flat_face_probabilities(flat, center_mm)
        return solid_angle_model(poly, center_mm / scale)

    from ..models import to_values

    def per_value(center_mm: np.ndarray) -> dict[str, float]:
        return {str(v): float(p) for v, p in zip(design.support, to_values(design, model(center_mm)))}

    def sharp_per_value() -> dict[str, float]:
        p = solid_angle_model(poly, com_sharp / scale + body_offset / scale)
        return {str(v): float(p) for v, p in zip(design.support, to_values(design, p))}

    predictions = {"sharp": sharp_per_value()}
    if round_mm > 0:
        predictions["rounded"] = per_value(com_uncut)
    predictions["engraved"] = per_value(com_solid)
    predictions["printed"] = per_value(com_print)
    before = predictions["rounded" if round_mm > 0 else "sharp"]

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
        "watertight": watertight,
        "winding_consistent": winding,
        "bodies": bodies,
        "genus": genus,
        "triangles": int(len(triangles)),
        "density_g_cm3": float(density_g_cm3),
        "fill": {**print_fill.to_mapping(), "wall_mm": print_fill.wall_thickness_mm},
        "mass_g": float(print_volume * grams),
        "mass_solid_g": float(volume * grams),
        "center_of_mass_mm": {
            "uncut": com_uncut.tolist(),
            "engraved": com_solid.tolist(),
            "printed": com_print.tolist(),
        },
        "com_shift_mm": (com_solid - com_uncut).tolist(),
        "com_shift_norm_mm": float(np.linalg.norm(com_solid - com_uncut)),
        "infill_com_shift_mm": (com_print - com_solid).tolist(),
        "infill_com_shift_norm_mm": float(np.linalg.norm(com_print - com_solid)),
        "labels": {label.face: label.text for label in fitted.values()},
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
            for label in fitted.values()
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
            for label, m in zip(marks, placed)
        ],  # fmt: skip
        "landing_model": "solid-angle" if round_mm == 0 else "solid-angle of the flat faces",
        "probabilities": predictions,
        "probability_change": {
            "engraving": change(before, predictions["engraved"]),
            "infill": change(predictions["engraved"], predictions["printed"]),
        },
        "warnings": warnings,
    }
    if round_mm > 0:
        report["round_com_shift_mm"] = (com_uncut - com_sharp).tolist()
        report["probability_change"]["rounding"] = change(predictions["sharp"], predictions["rounded"])
        report["flat_face_area_mm2"] = {
            poly.names[k]: 0.0 if ring is None else _ring_area(ring) for k, ring in enumerate(flat)
        }
    report["bed_face"] = bed_name
    report["embossed"] = list(dict.fromkeys(label.face for label, up in zip(labels, raised) if up))
    report["engraved"] = list(dict.fromkeys(label.face for label, up in zip(labels, raised) if not up))
    return Solid(
        design, vertices, triangles, label_tri, tuple(labels), report, tuple(warnings),
        _rotation_to_down(poly.normals[bed_index]), _mesh_arrays(base), inlay,
    )  # fmt: skip


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
        pockets = _check(manifold3d.Manifold.batch_boolean(sunk, manifold3d.OpType.Add), "joining the labels")
        parts.append(_check(body ^ pockets, "measuring the engraved pockets"))
    if raised:
        relief = _check(manifold3d.Manifold.batch_boolean(raised, manifold3d.OpType.Add), "joining the labels")
        parts.append(_check(relief - body, "measuring the raised labels"))
    if not parts:
        return None
    return _mesh_arrays(_check(manifold3d.Manifold.batch_boolean(parts, manifold3d.OpType.Add), "joining labels"))


def _stroke_warnings(labels: list[Label], min_stroke_mm: float) -> list[str]:
    """One warning for the whole die when strokes are thinner than `min_stroke_mm`, naming the labels."""
    thin = [lb for lb in labels if lb.stroke_mm < min_stroke_mm]
    partly = [lb for lb in labels if lb.stroke_mm >= min_stroke_mm and lb.thin_fraction > THIN_AREA_WARNING]
    parts = []
    if thin:
        lo, hi = min(lb.stroke_mm for lb in thin), max(lb.stroke_mm for lb in thin)
        width = f"{lo:.2f}" if hi - lo < 0.005 else f"{lo:.2f}-{hi:.2f}"
        parts.append(f"{_which(thin, labels)} {'has' if len(thin) == 1 else 'have'} strokes about {width} mm wide")
    if partly:
        share = max(lb.thin_fraction for lb in partly)
        parts.append(f"{_which(partly, labels)} {'has' if len(partly) == 1 else 'have'} up to {share:.0%} of the "
                     "text in thinner strokes")  # fmt: skip
    if not parts:
        return []
    return [f"{'; '.join(parts)}, below --min-stroke {min_stroke_mm:g} mm (use a larger --size)"]


def _which(some: list[Label], labels: list[Label]) -> str:
    if len(some) == len(labels):
        return f"all {len(labels)} labels"
    if len(some) > 4:
        return f"{len(some)} of {len(labels)} labels"
    return ", ".join(f"{lb.text!r} (face {lb.face})" for lb in some)


def _ring_area(ring: np.ndarray) -> float:
    return float(0.5 * np.linalg.norm(np.cross(ring, np.roll(ring, -1, axis=0)).sum(axis=0)))


# ----------------------------------------------------------------------
# exporters


def stl_bytes(solid: Solid) -> bytes:
    """Binary STL of the body, millimetres, bed face down."""
    return _stl(solid.print_vertices, solid.triangles, f"diefab {solid.design.name} mm")


def inlay_stl_bytes(solid: Solid) -> bytes:
    """Binary STL of the labels alone (:attr:`Solid.inlay`), placed as on the body's print bed.

    Raises
    ------
    FabricationError
        If the die has no labels.
    """
    if solid.inlay is None:
        raise FabricationError(f"design {solid.design.name!r} has no labels to write as an inlay")
    vertices, triangles = solid.inlay
    return _stl(solid.on_bed(vertices), triangles, f"diefab {solid.design.name} labels mm")


def _stl(vertices: np.ndarray, triangles: np.ndarray, title: str) -> bytes:
    tri = vertices[triangles]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    record = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attr", "<u2")])
    data = np.zeros(len(tri), dtype=record)
    data["normal"] = normals
    data["vertices"] = tri
    header = title.encode("ascii", "replace")[:80].ljust(80, b" ")
    return header + np.uint32(len(tri)).tobytes() + data.tobytes()


_CONTENT_TYPES = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
    '<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
    '<Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>'
    "</Types>"
)
_RELS = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
    '<Relationship Target="/3D/3dmodel.model" Id="rel0" '
    'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>'
    "</Relationships>"
)


#: Display colours of the 3MF's two materials (sRGB with alpha).
BODY_COLOR = "#F2EBD9FF"
LABEL_COLOR = "#1F3373FF"


def threemf_bytes(solid: Solid) -> bytes:
    """3MF package (core specification, unit millimetre): the die as one object of two coloured parts.

    The body (pockets empty, no raised text) and the labels (:attr:`Solid.inlay`)
    are two closed shells of one object's mesh; every triangle names its base
    material (body or labels, each with a display colour), and PrusaSlicer's
    ``Metadata/Slic3r_PE_model.config`` names the two triangle ranges as the
    object's two parts, so a multi-material printer prints the values in a
    second colour.  A die without labels is one shell.
    """
    from xml.sax.saxutils import escape, quoteattr

    name = escape(solid.design.name)
    parts = (
        [("body", *solid.base), ("labels", *solid.inlay)]
        if solid.inlay is not None and solid.base
        else [("body", solid.vertices, solid.triangles)]
    )
    verts, tris, ranges, offset, first = [], [], [], 0, 0
    for index, (part, vertices, triangles) in enumerate(parts):
        verts.extend(f'<vertex x="{x:.6f}" y="{y:.6f}" z="{z:.6f}"/>' for x, y, z in solid.on_bed(vertices))
        tris.extend(
            f'<triangle v1="{a + offset}" v2="{b + offset}" v3="{c + offset}" pid="1" p1="{index}"/>'
            for a, b, c in triangles
        )
        ranges.append((part, first, first + len(triangles) - 1))
        offset, first = offset + len(vertices), first + len(triangles)
    materials = (
        f'<basematerials id="1"><base name="body" displaycolor={quoteattr(BODY_COLOR)}/>'
        f'<base name="labels" displaycolor={quoteattr(LABEL_COLOR)}/></basematerials>'
    )
    model = (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<model unit="millimeter" xml:lang="en-US" '
        'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02" '
        'xmlns:slic3rpe="http://schemas.slic3r.org/3mf/2017/06">'
        '<metadata name="slic3rpe:Version3mf">1</metadata>'
        f'<metadata name="Title">{name}</metadata>'
        '<metadata name="Application">diefab</metadata>'
        f'<resources>{materials}<object id="2" type="model" name="{name}" pid="1" pindex="0">'
        f"<mesh><vertices>{''.join(verts)}</vertices><triangles>{''.join(tris)}</triangles></mesh></object>"
        '</resources><build><item objectid="2"/></build></model>'
    )
    volumes = "".join(
        f'<volume firstid="{lo}" lastid="{hi}"><metadata type="volume" key="name" value="{name} {part}"/>'
        '<metadata type="volume" key="volume_type" value="ModelPart"/></volume>'
        for part, lo, hi in ranges
    )
    config = (
        '<?xml version="1.0" encoding="UTF-8"?>\n<config><object id="2" instances_count="1">'
        f'<metadata type="object" key="name" value="{name}"/>{volumes}</object></config>'
    )
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("[Content_Types].xml", _CONTENT_TYPES)
        zf.writestr("_rels/.rels", _RELS)
        zf.writestr("3D/3dmodel.model", model)
        zf.writestr("Metadata/Slic3r_PE_model.config", config)
    return buf.getvalue()
