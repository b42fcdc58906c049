"""Bodies as they are made: the paper die's glue tabs and the print's labels, for the mass model.

:func:`tab_shapes` reads the glue tabs off the net ``diefab net`` lays out
(their real trapezoids, moved from the page onto the faces they are glued
to); :func:`label_masses` weighs the labels ``diefab stl`` engraves, from
where they are placed (:func:`~diefab.made.placement.label_faces`: the same
regions the printed die's cutters are extruded from).  :func:`body_properties`
gives the mass properties with both, which is what
:meth:`diefab.dice.design.Design.mass_properties` returns.

Examples
--------
>>> from diefab.dice.design import load_design
>>> from diefab.made.fill import Fill
>>> from diefab.made.unfold import tab_shapes
>>> d6 = load_design("d6")
>>> len(tab_shapes(d6.polyhedron, d6.mm_per_unit, 5.0))  # a cube's net has 7 cut edges, one tab each
7
>>> body_properties(d6.polyhedron, Fill("solid"), mm_per_unit=d6.mm_per_unit).center.round(12).tolist()
[0.0, 0.0, 0.0]
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from diefab.core.errors import FabricationError
from diefab.geometry.moments import MassProperties
from diefab.geometry.polyhedron import Polyhedron
from diefab.made.fill import Fill, LabelMass
from diefab.made.mass import mass_properties
from diefab.made.placement import Label, LabelPlan, label_faces
from diefab.made.text import load_font

__all__ = [
    "ENGRAVE_DEPTH_MM",
    "MAX_DEPTH_FRACTION",
    "body_properties",
    "label_mass",
    "label_masses",
    "thinnest_width",
]

#: How ``diefab stl`` engraves by default: depth, margin, smallest text and stroke, mm.
ENGRAVE_DEPTH_MM = 0.6
ENGRAVE_MARGIN_MM = 1.0
ENGRAVE_MIN_TEXT_MM = 2.0
ENGRAVE_MIN_STROKE_MM = 0.6
#: Deepest engraving (or highest embossing) as a share of the die's thinnest width.
MAX_DEPTH_FRACTION = 0.1


def label_mass(poly: Polyhedron, label: Label, depth_mm: float, raised: bool) -> LabelMass:
    """One placed label as a prism of its outline, `depth_mm` into (or, `raised`, out of) its face."""
    return LabelMass(
        poly.face_index(label.face),
        label.area_mm2,
        np.asarray(label.centroid_mm),
        np.asarray(label.normal),
        depth_mm,
        raised,
        label.outline,
        np.asarray(label.origin_mm),
        np.asarray(label.baseline),
        np.asarray(label.up),
    )


def thinnest_width(poly: Polyhedron) -> float:
    """Thinnest width of the solid between a face and the opposite support plane, model units."""
    heights = poly.offsets[:, None] - poly.normals @ poly.vertices.T
    return float(heights.max(axis=1).min())


@lru_cache(maxsize=64)
def _labels_cached(key, plan: LabelPlan) -> tuple[LabelMass, ...]:
    poly, scale = plan.poly, plan.mm_per_unit
    if ENGRAVE_DEPTH_MM >= MAX_DEPTH_FRACTION * thinnest_width(poly) * scale:
        return ()  # too thin a die to engrave (diefab stl refuses it)
    flat = [poly.vertices[f] * scale for f in poly.faces]
    try:
        placed = label_faces(plan, flat, load_font(None), depth_mm=ENGRAVE_DEPTH_MM, margin_mm=ENGRAVE_MARGIN_MM,
                             min_text_height_mm=ENGRAVE_MIN_TEXT_MM, min_stroke_mm=ENGRAVE_MIN_STROKE_MM)  # fmt: skip
    except FabricationError:  # labels that do not fit are not engraved (diefab stl refuses such a die)
        return ()
    return tuple(label_mass(poly, label, ENGRAVE_DEPTH_MM, False) for label in placed.labels)


def label_masses(plan: LabelPlan | None) -> tuple[LabelMass, ...]:
    """The labels ``diefab stl`` engraves by default (0.6 mm deep, sharp edges); none if they do not fit."""
    if plan is None or not plan.texts:
        return ()
    key = (plan.poly.vertices.tobytes(), plan.mm_per_unit, plan.axis.tobytes(), tuple(plan.texts.items()),
           tuple((m.face, m.text, m.at) for m in plan.marks), plan.logos)  # fmt: skip
    return _labels_cached(key, plan)


def body_properties(
    poly: Polyhedron, fill: Fill, *, mm_per_unit: float, labels: LabelPlan | None = None
) -> MassProperties:
    """Mass properties of `poly` made with `fill`: a paper die's net tabs, a print's engraved `labels`.

    Parameters
    ----------
    poly : Polyhedron
        Model units.
    fill : Fill
    mm_per_unit : float
        Millimetres per model unit.
    labels : LabelPlan, optional
        What is printed on the faces; a print with ``fill.labels`` weighs them.
    """
    kwargs = {}
    if fill.kind == "print" and fill.labels:
        kwargs["labels"] = label_masses(labels)
    return mass_properties(poly, fill, mm_per_unit=mm_per_unit, **kwargs)
