"""Labels cut into a printed die: each placed label a prism, engraved or embossed with manifold3d.

Where each label goes is :mod:`diefab.made.placement`; here its outline is
extruded and cut, and every boolean is checked.
"""

from __future__ import annotations

import numpy as np

from diefab.core.errors import FabricationError
from diefab.made.placement import Label

__all__ = ["checked", "cut_labels", "cutter"]

#: Height above the face the cutter starts at, mm (avoids coplanar booleans).
CUT_OVERSHOOT_MM = 0.2


def checked(manifold, what: str):
    """Raise unless manifold3d reports success and a non-empty result."""
    import manifold3d

    status = manifold.status()
    if status != manifold3d.Error.NoError:
        raise FabricationError(f"manifold3d failed while {what}: {status.name}")
    if manifold.is_empty():
        raise FabricationError(f"manifold3d produced an empty solid while {what}")
    return manifold


def cutter(label: Label, depth_mm: float, emboss: bool):
    """The label's prism: into the face (engrave) or out of it (emboss), manifold3d."""
    import manifold3d

    contours = []
    for poly in getattr(label.outline, "geoms", [label.outline]):
        contours.append(np.asarray(poly.exterior.coords)[:-1])
        contours.extend(np.asarray(r.coords)[:-1] for r in poly.interiors)
    section = manifold3d.CrossSection(contours, manifold3d.FillRule.EvenOdd)
    prism = checked(manifold3d.Manifold.extrude(section, depth_mm + CUT_OVERSHOOT_MM), f"extruding label {label.face}")
    # engrave: from `depth` below the face to just above it; emboss: from just below to `depth` above
    prism = prism.translate((0.0, 0.0, -CUT_OVERSHOOT_MM if emboss else -depth_mm))
    matrix = np.column_stack([label.baseline, label.up, label.normal, label.origin_mm])
    return checked(prism.transform(matrix).as_original(), f"placing label {label.face}")


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
        return checked(manifold3d.Manifold.batch_boolean([body, *cutters], op), f"{verb} the labels")
    for k, prism in enumerate(cutters):
        body = checked(body + prism if emboss else body - prism, f"{verb} label {k + 1}")
    return body
