"""Labels placed on a die's faces: where each text goes, how high, which way up, as 2D regions.

Every value label is centred on its face (the widest inscribed circle of the
face shrunk by a margin, :func:`~diefab.made.labels.fit_label`), as high as
fits, its up along the die's axis; a value read at a corner or along an edge
(the gem's apex) goes into that corner of every face that holds it.  The
margin grows by ``depth · cot θ`` for the sharpest dihedral angle θ at the
face's edges, so a pocket never breaks through a neighbouring face.  The
printed die engraves these regions (:mod:`diefab.fabricate.engrave`); the mass
model weighs them (:mod:`diefab.made.bodies`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from diefab.core.errors import FabricationError
from diefab.geometry.polyhedron import Polyhedron
from diefab.made.labels import MARK_FRACTION, face_frame, fit_label, label_shape, mark_frame
from diefab.made.text import Font, stroke_width, thin_fraction

__all__ = ["Label", "LabelPlan", "Labelling", "label_faces", "max_cot_dihedral", "stroke_warnings"]

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
        Mean stroke width (:func:`~diefab.made.text.stroke_width`).
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


def max_cot_dihedral(poly: Polyhedron) -> np.ndarray:
    """(m,) float: largest cot of the interior dihedral angle at each face's edges (0 if all obtuse)."""
    out = np.zeros(len(poly.faces))
    for f0, f1 in poly.edge_faces:
        cos_interior = -float(poly.normals[f0] @ poly.normals[f1])
        theta = math.acos(max(-1.0, min(1.0, cos_interior)))
        cot = max(0.0, math.cos(theta) / max(math.sin(theta), 1e-12))
        out[f0] = max(out[f0], cot)
        out[f1] = max(out[f1], cot)
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
    """A value read at a corner or along an edge (:class:`~diefab.dice.readings.Marking` `m`) on its face, as a Label.

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


def stroke_warnings(labels: list[Label], min_stroke_mm: float) -> list[str]:
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


@dataclass(frozen=True, eq=False)
class Labelling:
    """The labels of a die as placed on its faces.

    Attributes
    ----------
    fitted : dict face name -> Label
        Each labelled face's centred label.
    marks : tuple of Label
        The values read at a corner or along an edge, in the corners or
        along the edges of the faces that hold them.
    placed : tuple of Marking
        The marking of each of `marks`.
    warnings : tuple of str
        Marks left out or smaller than the minimum text height.
    """

    fitted: dict[str, Label]
    marks: tuple[Label, ...]
    placed: tuple[Any, ...]
    warnings: tuple[str, ...]

    @property
    def labels(self) -> list[Label]:
        """Every label: the centred ones, then the marks."""
        return [*self.fitted.values(), *self.marks]

    @property
    def faces(self) -> set[str]:
        """The faces that carry a label or a mark."""
        return {label.face for label in self.labels}


@dataclass(frozen=True, eq=False)
class LabelPlan:
    """What is printed on a die's faces, in the die's own frame: all that placing its labels needs.

    Attributes
    ----------
    poly : Polyhedron
        The die, model units.
    mm_per_unit : float
        Millimetres per model unit.
    axis : (3,) float
        The die's up axis: a label's up points along it where the face allows.
    texts : dict face name -> str
        The centred label of each labelled face.
    marks : tuple of Marking
        Values read at a corner or along an edge (:class:`~diefab.dice.readings.Marking`
        with a place), in order.
    logos : frozenset of str
        Faces whose text is set by hand (a logo): they keep their own fit
        when value labels share one height.
    """

    poly: Polyhedron
    mm_per_unit: float
    axis: np.ndarray
    texts: dict[str, str]
    marks: tuple[Any, ...] = ()
    logos: frozenset[str] = frozenset()


def label_faces(
    plan: LabelPlan,
    flat: list[np.ndarray | None],
    font: Font,
    *,
    depth_mm: float,
    margin_mm: float,
    min_text_height_mm: float,
    min_stroke_mm: float,
    mark: str = "bar",
    pips: bool = False,
    uniform_height: bool = True,
    with_marks: bool = True,
    keep_clear: dict[str, Any] | None = None,
) -> Labelling:
    """Place every label of `plan` on the flat part of its face (`flat`: ordered rings, mm; None: no flat part).

    The marks (values read at a corner or edge) go first; each face's
    centred label then keeps :data:`MARK_CLEARANCE_MM` from them.  With
    `uniform_height` every value label takes the height of the smallest
    (a logo from the design's ``labels`` table keeps its own).  The options
    are those of :func:`~diefab.fabricate.stl.build_solid`; `keep_clear` maps
    a face name to a region (shapely, the face's label coordinates: origin at
    the mean of its flat ring, :func:`~.labels.face_frame` axes, mm) the
    centred label must stay out of, such as the face's marker.

    Raises
    ------
    FabricationError
        A centred label that does not fit its face at `min_text_height_mm`.
    """
    poly, scale, axis = plan.poly, plan.mm_per_unit, plan.axis
    cots = max_cot_dihedral(poly)
    texts = plan.texts
    shapes = {face: label_shape(t, font, others=texts.values(), mark=mark, pips=pips) for face, t in texts.items()}

    warnings, marks, placed = [], [], []
    for m in plan.marks if with_marks else []:
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
    avoid: dict[str, Any] = dict(keep_clear or {})
    for label in marks:
        zone = label.face_outline.buffer(MARK_CLEARANCE_MM)
        avoid[label.face] = zone if label.face not in avoid else avoid[label.face].union(zone)

    def place(face: str, text: str, cap: float = math.inf) -> Label:
        k = poly.face_index(face)
        if flat[k] is None:
            raise FabricationError(f"label {text!r} does not fit on face {face}: rounding left no flat part")
        return _place_label(
            face, text, flat[k], poly.normals[k], axis, shapes[face],
            margin_mm + depth_mm * cots[k], min_text_height_mm, min_stroke_mm, cap, avoid.get(face),
        )  # fmt: skip

    fitted = {face: place(face, text) for face, text in texts.items()}
    values = [face for face in fitted if face not in plan.logos]  # computed value labels, not logos
    if uniform_height and values:
        common = min(fitted[face].height_mm for face in values)
        fitted.update({face: place(face, fitted[face].text, common) for face in values})
    return Labelling(fitted, tuple(marks), tuple(placed), tuple(warnings))
