"""What a die's maker is told in words: how to read the die, and when it is too small to handle.

Examples
--------
>>> from diefab.dice.design import load_design
>>> reading_note(load_design("fudge-gem"))
'read the face on top; a point up means 0'
>>> reading_note(load_design("d6"))
'read the face on top'
"""

from __future__ import annotations

import numpy as np

from diefab.dice.design import Design, format_value

__all__ = ["SMALL_DIE_MM", "reading_note", "small_die_warning"]

#: Dice smaller than this (in their size convention) are hard to handle and to read, mm.
SMALL_DIE_MM = 8.0


def reading_note(design: Design) -> str:
    """How to read the die: the face on top, and what a point or an edge on top means."""
    poly = design.polyhedron
    extra = []
    for rest, up in design.label_face.items():
        if up is not None or rest not in design.value_of:  # a transitional face: the die never rests on it
            continue
        k = poly.face_index(rest)
        heights = poly.vertices @ -poly.normals[k]
        top = int(np.sum(heights > heights.max() - 1e-6 * max(1.0, float(np.ptp(heights)))))
        what = "a point" if top == 1 else "an edge" if top == 2 else "a small face"
        value = design.value_of[rest]
        extra.append(f"{what} up means {format_value(value, min(design.support) < 0)}")
    return "; ".join(["read the face on top", *dict.fromkeys(extra)])


def small_die_warning(design: Design, size_mm: float | None = None) -> str | None:
    """A warning for a die under about ``SMALL_DIE_MM``, else None."""
    size = design.size_mm if size_mm is None else size_mm
    if size >= SMALL_DIE_MM:
        return None
    return (
        f"a {size:g} mm die ({design.size_note}) is under about {SMALL_DIE_MM:g} mm: "
        "hard to handle, fold or read; consider a larger --size"
    )
