"""Bodies as they are made: the paper die's glue tabs and the print's labels, for the mass model.

:func:`tab_shapes` reads the glue tabs off the net ``diefab net`` lays out
(their real trapezoids, moved from the page onto the faces they are glued
to); :func:`label_masses` reads the labels off the solid ``diefab stl``
builds.  :func:`body_properties` gives a design's mass properties with both,
which is what :meth:`diefab.dice.design.Design.mass_properties` returns.

Examples
--------
>>> from diefab.dice.design import load_design
>>> d6 = load_design("d6")
>>> tabs = tab_shapes(d6.polyhedron, d6.mm_per_unit, 5.0)
>>> len(tabs)  # a cube's net has 7 cut edges, one tab each
7
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from diefab.made.mass import Fill, LabelMass, MassProperties, TabShape, mass_properties

if TYPE_CHECKING:
    from diefab.dice.design import Design
    from diefab.fabricate.stl import Solid
    from diefab.geometry.polyhedron import Polyhedron
    from diefab.made.unfold import Net

__all__ = ["body_properties", "label_masses", "net_tab_shapes", "solid_label_masses", "tab_shapes"]


def net_tab_shapes(net: Net) -> tuple[TabShape, ...]:
    """The tabs of a laid-out net, as :class:`~diefab.made.mass.TabShape` on the die's edges."""
    poly = net.poly
    out = []
    for tab in net.tabs:
        ring = net.faces[tab.face]
        p, q, far_q, far_p = tab.polygon
        i = int(np.argmin(np.linalg.norm(ring - p, axis=1)))
        n = len(ring)
        a, b = int(poly.faces[tab.face][i]), int(poly.faces[tab.face][(i + 1) % n])
        u = (q - p) / np.linalg.norm(q - p)
        normal = np.array([-u[1], u[0]])
        width = abs(float((far_p - p) @ normal))
        lean_a = float((far_p - p) @ u) / width
        lean_b = float((q - far_q) @ u) / width
        faces = poly.edge_faces[tab.edge]
        glued = int(faces[0] if faces[1] == tab.face else faces[1])
        out.append(TabShape(a, b, glued, width, lean_a, lean_b))
    return tuple(out)


@lru_cache(maxsize=64)
def _tabs_cached(key: bytes, faces: tuple, poly: Polyhedron, mm_per_unit: float, tab_mm: float):
    from diefab.made.unfold import unfold

    return net_tab_shapes(unfold(poly, mm_per_unit, tab_width=tab_mm))


def tab_shapes(poly: Polyhedron, mm_per_unit: float, tab_mm: float) -> tuple[TabShape, ...]:
    """The glue tabs of the net of `poly` that ``diefab net`` lays out on A4 (none when `tab_mm` is 0)."""
    if tab_mm == 0:
        return ()
    faces = tuple(tuple(int(v) for v in f) for f in poly.faces)
    return _tabs_cached(poly.vertices.tobytes(), faces, poly, float(mm_per_unit), float(tab_mm))


def solid_label_masses(solid: Solid) -> tuple[LabelMass, ...]:
    """The labels of a built solid, as :class:`~diefab.made.mass.LabelMass` (mm, the die's coordinates)."""
    poly = solid.design.polyhedron
    depth, raised = solid.report["depth_mm"], set(solid.report.get("embossed", ()))
    return tuple(
        LabelMass(
            poly.face_index(lb.face),
            lb.area_mm2,
            np.asarray(lb.centroid_mm),
            np.asarray(lb.normal),
            depth,
            lb.face in raised,
            lb.outline,
            np.asarray(lb.origin_mm),
            np.asarray(lb.baseline),
            np.asarray(lb.up),
        )  # fmt: skip
        for lb in solid.labels
    )


@lru_cache(maxsize=64)
def _labels_cached(key, design: Design) -> tuple[LabelMass, ...]:
    from diefab.core.errors import FabricationError
    from diefab.fabricate.stl import build_solid

    try:
        return solid_label_masses(build_solid(design, print_fill=Fill("print")))
    except FabricationError:  # labels that do not fit are not engraved (diefab stl refuses such a die)
        return ()


def label_masses(design: Design) -> tuple[LabelMass, ...]:
    """The labels ``diefab stl`` engraves on `design` by default (0.6 mm deep); none if they do not fit."""
    if not design.label_of:
        return ()
    key = (design.polyhedron.vertices.tobytes(), design.size_mm, design.family, tuple(design.label_of.items()))
    return _labels_cached(key, design)


def body_properties(design: Design, fill: Fill | None = None) -> MassProperties:
    """Mass properties of `design` made with `fill` (default its own): the net's tabs, the print's labels."""
    fill = fill or design.fill
    kwargs = {}
    if fill.kind == "print" and fill.labels:
        kwargs["labels"] = label_masses(design)
    return mass_properties(design.polyhedron, fill, mm_per_unit=design.mm_per_unit, **kwargs)
