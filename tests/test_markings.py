"""Values read at a corner or along an edge: net and stl print each on the geometry it names."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import LineString, Point, Polygon

from diefab.dice.design import load_design
from diefab.fabricate.net import design_net
from diefab.fabricate.sheet import _die_texts
from diefab.made.labels import design_axis, mark_frame, placed_marks
from diefab.made.text import load_font

#: A gem that reads +4 and -4 from an edge and 0 from its apex; the plain gem 0 from its apex.
EDGE_GEM = dict(
    params={"a": 1.096142057017725, "b": 0.6992907133500326, "c": 0.7971155905815607, "d": 1.1880515442696602,
            "e": 0.8939678614309613},
    values={"f1": 3, "f2": 4, "f3": -3, "f4": -4, "f5": 0, "f6": 1, "f7": 2, "f8": -1, "f9": -2},
    labels={"f5": "4dF"},
)  # fmt: skip
DESIGNS = ("edge-gem", "fudge-gem")


def _design(name: str):
    if name == "edge-gem":
        from diefab.dice.design import Design

        return Design("edge-gem", "gem", **EDGE_GEM)
    return load_design(name)


def _nearest_place(ring: np.ndarray, ids: list[int], point: np.ndarray, edge: bool) -> tuple[int, ...]:
    """The corner (or edge, as a sorted vertex pair) of a face ring nearest to `point`."""
    if not edge:
        return (ids[int(np.argmin(np.linalg.norm(ring - point, axis=1)))],)
    d = [LineString([ring[i], ring[(i + 1) % len(ring)]]).distance(Point(point)) for i in range(len(ring))]
    i = int(np.argmin(d))
    return tuple(sorted((ids[i], ids[(i + 1) % len(ring)])))


@pytest.mark.parametrize("name", DESIGNS)
def test_every_marking_is_printed_on_the_net_at_its_corner_or_edge(name):
    design = _design(name)
    marks = placed_marks(design)
    assert marks, "the gem is read at its apex"
    assert any(len(m.at) == 2 for m in marks) == (name == "edge-gem")
    net = design_net(design)
    fonts = {"font": load_font(bold=False), "bold": load_font()}
    texts = _die_texts(net, design.label_of, design_axis(design), face_names=False, mark="bar", pips=False,
                       values=set(design.label_of), marks=marks, **fonts)  # fmt: skip
    poly = design.polyhedron
    printed = [t for t in texts if t.kind in ("corner", "along-edge")]
    assert len(printed) == len(marks)
    for m, t in zip(marks, printed):
        k = poly.face_index(m.face)
        ring, ids = net.faces[k], poly.faces[k].tolist()
        assert t.face == m.face and t.text == m.text
        assert t.shape.within(Polygon(ring))
        centre = np.asarray(t.shape.centroid.coords[0])
        assert _nearest_place(ring, ids, centre, len(m.at) == 2) == tuple(sorted(m.at))
        # nearer its corner or edge than the face's centre is
        anchor = ring[[ids.index(v) for v in m.at]].mean(axis=0)
        assert np.linalg.norm(centre - anchor) < np.linalg.norm(np.mean(ring, axis=0) - anchor)


@pytest.mark.parametrize("name", DESIGNS)
def test_every_marking_is_engraved_at_its_corner_or_edge(name):
    from diefab.fabricate.stl import build_solid

    design = _design(name)
    marks = placed_marks(design)
    solid = build_solid(design, size_mm=30.0)
    scale = design.mm_per_unit
    poly = design.polyhedron
    engraved = [lb for lb in solid.labels if lb.face_outline is not None]
    assert len(engraved) == len(marks) == len(solid.report["marks"])
    for m, label in zip(marks, engraved):
        k = poly.face_index(m.face)
        ids = poly.faces[k].tolist()
        ring = poly.vertices[poly.faces[k]] * scale
        assert label.face == m.face and label.text == m.text
        assert abs((label.centroid_mm - ring[0]) @ poly.normals[k]) < 1e-9  # in the face's plane
        assert np.allclose(np.cross(label.baseline, label.up), poly.normals[k], atol=1e-12)  # not mirrored
        # inside the face, and nearest the corner or edge it names
        rel = ring - label.origin_mm
        assert label.outline.within(Polygon(np.column_stack([rel @ label.baseline, rel @ label.up])))
        flat = np.column_stack([rel @ label.baseline, rel @ label.up])
        centre = np.array([label.outline.centroid.x, label.outline.centroid.y])
        assert _nearest_place(flat, ids, centre, len(m.at) == 2) == tuple(sorted(m.at))
        # the text's top points toward that corner or edge
        anchor = ring[[ids.index(v) for v in m.at]].mean(axis=0)
        assert (anchor - label.centroid_mm) @ label.up > 0


def test_mark_frame_points_up_toward_the_corner_and_is_not_mirrored():
    square = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]])
    zone, origin, x, up = mark_frame(square, (2,))
    assert np.allclose(origin, [4, 4]) and np.allclose(up, np.array([1, 1]) / np.sqrt(2))
    assert x[0] * up[1] - x[1] * up[0] > 0 and zone.within(Polygon(square).buffer(1e-9))
    _, origin, x, up = mark_frame(square, (0, 1), y_down=True)
    assert np.allclose(origin, [2, 0]) and np.allclose(up, [0, -1]) and x[0] * up[1] - x[1] * up[0] < 0
