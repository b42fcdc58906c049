"""How a die is read: what points up when it rests on each face, and what must be printed there.

Real dice use three conventions, and a die is readable when every resting
face has one of them:

``face``
    a face points up (its normal within :data:`FACE_ANGLE` of straight up and
    clearly closer than any other): the value is printed on it, as on a d6;
``vertex``
    no face does but one vertex is clearly highest: the value is printed in
    the corner at that vertex of every face around it, as on a d4 -- and as
    the gem's apex, which points up when the gem rests on its top;
``edge``
    two vertices are clearly highest: the value is printed along that edge
    on both faces that share it, as on a triangular-prism d3.

Two resting faces that would print in the same place (the same face, the
same corner or the same edge) with different values make the die unreadable.

Examples
--------
>>> from diefab.dice.design import load_design
>>> d6 = load_design("d6")
>>> {r.kind for r in readings(d6.polyhedron, d6.polyhedron.centroid)}
{'face'}
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from diefab.core.errors import DesignError
from diefab.geometry.polyhedron import Polyhedron

__all__ = ["FACE_ANGLE", "KINDS", "Marking", "Reading", "markings", "readings", "unreadable"]

#: Largest angle (degrees) between straight up and a face that is read as "the face on top".
FACE_ANGLE = 40.0
#: Smallest difference (degrees) between the top face and the next for the top face to be clear.
FACE_MARGIN = 5.0
#: Smallest height difference, as a fraction of the die's size, that makes a vertex clearly highest.
VERTEX_MARGIN = 0.05


@dataclass(frozen=True)
class Reading:
    """What shows the value when the die rests on one face.

    ``kind`` is ``face`` (``face`` is the index of the face on top), ``vertex``
    (``vertices`` holds the highest vertex) or ``edge`` (the two highest).
    """

    kind: str
    face: int | None = None
    vertices: tuple[int, ...] = ()

    @property
    def place(self) -> tuple:
        """Where the value is printed, comparable between resting faces."""
        return (self.kind, self.face) if self.kind == "face" else (self.kind, tuple(sorted(self.vertices)))


@dataclass(frozen=True)
class Marking:
    """One text that net and stl print: ``text`` on face ``face``, centred, at a corner or along an edge.

    ``at`` is ``()`` for the face's centre, ``(v,)`` for its corner at vertex
    v, ``(v, w)`` for its edge from v to w.
    """

    face: str
    text: str
    at: tuple[int, ...] = ()


def readings(poly: Polyhedron, center: np.ndarray | None = None) -> list[Reading | None]:
    """For each face, how the die is read when resting on it (None: no convention applies).

    `center` is not needed by the rule (what points up depends only on the
    face's normal); it is accepted so callers can pass the centre of mass
    uniformly with other per-face functions.
    """
    normals, vertices = poly.normals, poly.vertices
    size = float(np.ptp(vertices, axis=0).max())
    cos_read = np.cos(np.radians(FACE_ANGLE))
    out: list[Reading | None] = []
    for k in range(len(poly.faces)):
        up = -normals[k]
        angles = np.degrees(np.arccos(np.clip(normals @ up, -1, 1)))
        angles[k] = np.inf
        order = np.argsort(angles)
        if normals[order[0]] @ up >= cos_read and angles[order[1]] - angles[order[0]] >= FACE_MARGIN:
            out.append(Reading("face", int(order[0])))
            continue
        heights = vertices @ up
        top = np.argsort(heights)[::-1]
        gap = (heights[top[0]] - heights[top[1:4]]) / size
        if gap[0] >= VERTEX_MARGIN:
            out.append(Reading("vertex", vertices=(int(top[0]),)))
        elif gap[1] >= VERTEX_MARGIN and _is_edge(poly, int(top[0]), int(top[1])):
            out.append(Reading("edge", vertices=(int(top[0]), int(top[1]))))
        else:
            out.append(None)
    return out


def _is_edge(poly: Polyhedron, v: int, w: int) -> bool:
    return bool(np.any(np.all(poly.edges == sorted((v, w)), axis=1)))


#: The reading conventions, in the order :func:`readings` tries them.
KINDS = ("face", "vertex", "edge")


def unreadable(
    poly: Polyhedron, values: Mapping[str, int], labelled: Sequence[str] = (), read_by: Sequence[str] = KINDS
) -> str | None:
    """Why `poly` with these resting-face `values` cannot be read, or None when it can.

    Faces in `labelled` have their text set by hand (a design's ``labels``):
    two resting faces may share such a face on top.  `read_by` lists the
    conventions allowed (a subset of :data:`KINDS`): a die whose net marks
    only faces and the apex is designed with ``("face", "vertex")``.
    """
    found = readings(poly)
    where: dict[tuple, str] = {}
    for name, value in values.items():
        r = found[poly.face_index(name)]
        if r is None:
            return f"resting on {name}, neither a face, a vertex nor an edge clearly points up"
        if r.kind not in read_by:
            return f"resting on {name}, it is read from {'an' if r.kind[0] in 'ae' else 'a'} {r.kind}"
        if r.kind == "face" and poly.names[r.face] in labelled:
            continue
        other = where.setdefault(r.place, name)
        if other != name and values[other] != value:
            return f"resting on {other} and on {name} shows the same {r.kind} on top, with different values"
    return None


def markings(poly: Polyhedron, values: Mapping[str, int], texts: Mapping[str, str]) -> list[Marking]:
    """What net and stl print: one :class:`Marking` per place, for the resting faces in `values`.

    Parameters
    ----------
    values : resting face name -> value
    texts : resting face name -> the printed text of its value

    Raises
    ------
    DesignError
        If the die is not readable (see :func:`unreadable`).
    """
    why = unreadable(poly, values)
    if why:
        raise DesignError(f"the die cannot be read: {why}")
    found = readings(poly)
    out: dict[tuple, Marking] = {}
    for name in values:
        r = found[poly.face_index(name)]
        if r.kind == "face":
            out[("face", r.face)] = Marking(poly.names[r.face], texts[name])
            continue
        for j in _faces_at(poly, r.vertices):
            out[(j, r.vertices)] = Marking(poly.names[j], texts[name], _oriented(poly, j, r.vertices))
    return list(out.values())


def _faces_at(poly: Polyhedron, vertices: Sequence[int]) -> list[int]:
    """The faces that hold every one of `vertices` (a corner's faces, or an edge's two)."""
    return [j for j, f in enumerate(poly.faces) if all(v in f for v in vertices)]


def _oriented(poly: Polyhedron, face: int, vertices: tuple[int, ...]) -> tuple[int, ...]:
    """`vertices` in the face's counter-clockwise order (an edge runs the way the face goes round)."""
    if len(vertices) == 1:
        return vertices
    ring = list(poly.faces[face])
    v, w = vertices
    return (v, w) if ring[(ring.index(v) + 1) % len(ring)] == w else (w, v)
