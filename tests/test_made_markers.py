"""Markers on the made die: printed on the paper net, inlaid in the printed solid, weighed, and read back."""

from __future__ import annotations

import io
import json
import shutil
import subprocess
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

from diefab.core.errors import FabricationError
from diefab.dice.design import load_design
from diefab.dice.markers import MARGIN_FRACTION, marker_cells, marker_layout
from diefab.fabricate.formats import threemf_bytes, threemf_mesh
from diefab.fabricate.markers import MIN_PAPER_CELL_MM, QUIET_CELLS, check_cells, marked_body, net_markers
from diefab.fabricate.net import design_net, render_net
from diefab.fabricate.stl import build_solid, mesh_moments
from diefab.made.inlays import CELL_JOIN_MM, cell_outline

cv2 = pytest.importorskip("cv2")
shapely_geometry = pytest.importorskip("shapely.geometry")
Polygon = shapely_geometry.Polygon


@pytest.fixture(scope="module")
def d6():
    return load_design("d6")


@pytest.fixture(scope="module")
def d6_net(d6):
    return design_net(d6)


@pytest.fixture(scope="module")
def d6_solid(d6):
    return build_solid(d6, markers=True)


@pytest.fixture(scope="module")
def d6_plain(d6):
    return build_solid(d6)


def _inradius(ring: np.ndarray) -> float:
    from shapely.ops import polylabel

    face = Polygon(ring)
    return face.exterior.distance(polylabel(face, 1e-4))


# ----------------------------------------------------------------------
# the paper net


@pytest.mark.parametrize("name", ["d6", "d8", "fudge-gem", "d20"])
def test_net_markers_lie_inside_their_faces_with_a_margin(name):
    design = load_design(name)
    net = design_net(design)
    marks = net_markers(design, net)
    layout = marker_layout(design)
    assert [m.marker_id for m in marks] == layout.ids.tolist()
    for m in marks:
        ring = net.faces[net.poly.face_index(m.face)]
        square = Polygon(m.corners)
        # a square of the right side, the layout's margin (a share of the face's inscribed radius) from every edge
        sides = np.linalg.norm(np.roll(m.corners, -1, axis=0) - m.corners, axis=1)
        assert np.allclose(sides, m.side_mm, rtol=1e-9)
        assert np.dot(m.corners[1] - m.corners[0], m.corners[3] - m.corners[0]) == pytest.approx(0, abs=1e-9)
        margin = Polygon(ring).exterior.distance(square)
        assert margin >= MARGIN_FRACTION * _inradius(ring) * (1 - 1e-3)
        assert Polygon(ring).contains(square)
        # the dark cells are the marker's own cells, in its square
        cells = marker_cells(layout.dictionary, m.marker_id)
        assert m.outline.area == pytest.approx(cells.sum() * (m.side_mm / cells.shape[0]) ** 2, rel=1e-9)
        assert square.buffer(1e-9).contains(m.outline)


def test_d6_markers_are_as_large_as_the_face_allows_around_its_value(d6, d6_net):
    """A cube face of side s: one marker slid into each corner of the margin square, the value in the middle.

    The margin square's half side is a = s/2 - f·s/2.  Squares of side x in its corners, grown by a gap of a
    tenth of x, leave the middle a room reaching to their inner corners, √2·(a - 1.1·x) away: as large as the
    markers can be while that room is the label's share of the face's inradius s/2.
    """
    from diefab.dice.markers import CORNERS_LABEL_ROOM

    s = 16.0
    a = s / 2 - MARGIN_FRACTION * s / 2
    side = (a - CORNERS_LABEL_ROOM * (s / 2) / np.sqrt(2)) / 1.1
    marks = net_markers(d6, d6_net)
    assert len(marks) == 4 * 6
    for face in {m.face for m in marks}:
        ring = d6_net.faces[d6_net.poly.face_index(face)]
        mine = [m for m in marks if m.face == face]
        assert len(mine) == 4
        centre = np.mean(ring, axis=0)
        for m in mine:
            assert m.side_mm == pytest.approx(side, rel=1e-3)
            # in its corner: the margin from the face's edge, and as far from the middle as that allows
            margin = Polygon(ring).exterior.distance(Polygon(m.corners))
            assert margin == pytest.approx(MARGIN_FRACTION * s / 2, abs=1e-3)
            reach = np.linalg.norm(m.corners.mean(axis=0) - centre)
            assert reach == pytest.approx(np.sqrt(2) * (a - side / 2), rel=1e-3)
        # no two overlap
        assert all(not Polygon(p.corners).intersects(Polygon(q.corners)) for p in mine for q in mine if p is not q)


def test_net_labels_and_letters_keep_out_of_the_quiet_zone(d6, d6_net):
    from diefab.dice.design import design_axis
    from diefab.fabricate.net import footer_texts
    from diefab.fabricate.sheet import layout_sheets, plan_footer

    marks = net_markers(d6, d6_net)
    sheets = layout_sheets(d6_net, labels=d6.label_of, axis=design_axis(d6),
                           plan=plan_footer(210, 10, *footer_texts(d6, 16)), values=list(d6.label_of),
                           markers=marks)  # fmt: skip
    texts = [t for s in sheets for t in s.texts]
    zones: dict = {}
    for m in marks:
        zone = Polygon(m.corners).buffer(QUIET_CELLS * m.cell_mm * (1 - 1e-6), join_style="mitre")
        zones[m.face] = zone.union(zones[m.face]) if m.face in zones else zone
    values = [t for t in texts if t.kind == "face"]
    assert sorted(t.text for t in values) == sorted(d6.label_of.values())
    assert len([t for t in texts if t.kind == "marker"]) == len(marks) == 24
    for t in texts:
        if t.kind in ("face", "edge", "name", "corner", "along-edge"):
            assert not t.shape.intersects(zones[t.face]), (t.kind, t.text, t.face)
    assert min(t.height for t in values) > 3.0  # the value stays legible: over 3 mm on a 16 mm die


@pytest.mark.parametrize("name", ["d6", "fudge-gem"])
def test_rendered_net_is_read_back_by_the_camera_detector(name):
    """The net's PNG, decoded by the reader's own ArUco detector: every id found, on its own face, true scale."""
    from diefab.camera.pose import MarkerDetector

    design = load_design(name)
    net = design_net(design)
    marks = net_markers(design, net)
    png = render_net(design, net, ("png",), markers=marks)["png"]
    gray = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_GRAYSCALE)
    layout = marker_layout(design)
    ids, corners = MarkerDetector(layout).detect(gray)
    assert sorted(ids.tolist()) == layout.ids.tolist()
    px_per_mm = gray.shape[1] / net.page.width
    by_id = {m.marker_id: m for m in marks}
    for marker_id, found in zip(ids, corners / px_per_mm):
        m = by_id[int(marker_id)]
        face = layout.face_of(int(marker_id))
        assert m.face == design.polyhedron.names[face]
        assert Polygon(net.faces[face]).contains(Polygon(found))
        # ArUco's corner order is the layout's: not mirrored, not turned
        assert np.abs(found - m.corners).max() < 0.6


def test_paper_balance_is_unchanged_by_the_ink(run, tmp_path):
    code, out, err = run("net", "d6", "--out", tmp_path / "a", "--format", "svg", "--json")
    plain = json.loads(out)
    code2, out2, err2 = run("net", "d6", "--markers", "--out", tmp_path / "b", "--format", "svg", "--json")
    marked = json.loads(out2)
    assert code == code2 == 0
    assert set(marked["markers"]) == {f"f{k}" for k in range(1, 7)}
    assert all(len(on_face) == 4 for on_face in marked["markers"].values())
    assert {k: v for k, v in marked.items() if k not in ("files", "markers")} == {
        k: v for k, v in plain.items() if k != "files"
    }


def test_net_markers_cli_reports_them(run, tmp_path):
    code, out, err = run("net", "d6", "--markers", "--out", tmp_path, "--format", "svg")
    assert code == 0, err
    layout = marker_layout(load_design("d6"))
    side = layout.sides[0] * load_design("d6").mm_per_unit
    cells = f"cells {side / (layout.bits + 2):.2f} mm"
    # four markers on each face, one toward each corner
    assert f"markers: 24 {layout.dictionary} markers (ids 0-23, 4 on each face of 6), {side:.1f} mm, {cells}" in out
    svg = (tmp_path / "d6-net.svg").read_text()
    assert svg.count('class="marker"') == 24


# ----------------------------------------------------------------------
# the printed solid


def test_solid_markers_sit_in_their_faces(d6, d6_solid):
    layout = marker_layout(d6)
    poly, scale = d6.polyhedron, d6.mm_per_unit
    assert len(d6_solid.markers) == len(layout.ids) == 24
    for m, k, corners, marker_id in zip(d6_solid.markers, layout.faces, layout.corners, layout.ids):
        assert m.face == poly.names[k]
        # the outline in the face's frame is the layout's square, cell for cell
        square = np.column_stack([(corners * scale - m.origin_mm) @ m.baseline, (corners * scale - m.origin_mm) @ m.up])
        expected = cell_outline(marker_cells(layout.dictionary, int(marker_id)), square)
        assert m.outline.symmetric_difference(expected).area < 4 * CELL_JOIN_MM * expected.length
        assert np.allclose(np.cross(m.baseline, m.up), poly.normals[k])
    # the value labels keep out of the markers' quiet zone
    for label in d6_solid.labels:
        for m in (m for m in d6_solid.markers if m.face == label.face):
            assert not label.outline.intersects(m.outline.convex_hull.buffer(0.99 * m.stroke_mm, join_style="mitre"))


def test_marker_volume_is_the_dark_cells_times_depth(d6, d6_solid, d6_plain):
    """Σ (dark cells × cell²) × depth, analytic, against manifold3d's booleans."""
    layout = marker_layout(d6)
    depth = d6_solid.report["depth_mm"]
    side = layout.sides[0] * d6.mm_per_unit
    square = np.array([[0, side], [side, side], [side, 0], [0, 0]])
    cells = [marker_cells(layout.dictionary, int(i)) for i in layout.ids]
    dark = sum(int(c.sum()) for c in cells) * (side / (layout.bits + 2)) ** 2
    # each cell grown by CELL_JOIN_MM so corner-touching cells join: the outline's length times it, to first order
    grown = sum(cell_outline(c, square).length for c in cells) * CELL_JOIN_MM
    assert d6_solid.report["marker_volume_mm3"] == pytest.approx((dark + grown) * depth, rel=1e-3)
    assert grown < 0.03 * dark  # cells of 0.68 mm
    assert d6_plain.volume_mm3 - d6_solid.volume_mm3 == pytest.approx(
        d6_solid.report["marker_volume_mm3"] + (sum(lb.area_mm2 for lb in d6_solid.labels)
                                                - sum(lb.area_mm2 for lb in d6_plain.labels)) * depth,
        rel=1e-3,
    )  # fmt: skip
    assert d6_solid.watertight and d6_solid.genus == 0 and d6_solid.bodies == 1


def test_mass_with_markers_is_the_analytic_prism_sum(d6, d6_solid):
    """The engraved centre of mass: the uncut cube less one prism per label and marker (area × depth)."""
    r = d6_solid.report
    depth = r["depth_mm"]
    prisms = [*d6_solid.labels, *d6_solid.markers]
    volume = 16.0**3 - sum(p.area_mm2 for p in prisms) * depth
    first = -sum(p.area_mm2 * depth * (p.centroid_mm - 0.5 * depth * p.normal) for p in prisms)  # cube's own is 0
    assert r["volume_mm3"] == pytest.approx(volume, rel=1e-6)
    assert np.allclose(r["center_of_mass_mm"]["engraved"], first / volume, atol=1e-4)
    # the markers' own share of the shift
    markers = d6_solid.markers
    without = first + sum(p.area_mm2 * depth * (p.centroid_mm - 0.5 * depth * p.normal) for p in markers)
    volume_without = volume + sum(p.area_mm2 for p in markers) * depth
    assert np.allclose(r["marker_com_shift_mm"], first / volume - without / volume_without, atol=1e-6)


def test_printed_mass_model_weighs_the_marker_pockets(d6, d6_solid):
    """The print model removes each marker prism: it moves the printed centre as the solid's moments say."""
    from diefab.made.fill import Fill
    from diefab.made.inlays import inlay_masses
    from diefab.made.mass import mass_properties

    scale = d6.mm_per_unit
    depth = d6_solid.report["depth_mm"]
    bed = d6.polyhedron.face_index(d6_solid.report["bed_face"])
    fill = Fill("print")
    labels = inlay_masses(d6.polyhedron, d6_solid.labels, depth)
    markers = inlay_masses(d6.polyhedron, d6_solid.markers, depth)
    both = mass_properties(d6.polyhedron, fill, mm_per_unit=scale, bed=bed, labels=labels + markers)
    assert np.allclose(both.center * scale, d6_solid.report["center_of_mass_mm"]["printed"], atol=1e-9)
    assert both.mass * scale**3 * 1.24e-3 == pytest.approx(d6_solid.report["mass_g"], rel=1e-9)
    # the body the balance line weighs (its inertia too) is the same print
    assert np.allclose(marked_body(d6_solid, fill).center, both.center, atol=1e-12)
    alone = mass_properties(d6.polyhedron, fill, mm_per_unit=scale, bed=bed, labels=labels)
    assert not np.allclose(alone.center, both.center, atol=1e-6)  # the markers are in it


def test_3mf_carries_the_markers_as_its_second_part_in_the_face_planes(d6, d6_solid):
    package = threemf_bytes(d6_solid)
    zf = zipfile.ZipFile(io.BytesIO(package))
    verts, tris, part = threemf_mesh(package)
    assert set(part.tolist()) == {0, 1}
    config = ET.fromstring(zf.read("Metadata/Slic3r_PE_model.config"))
    extruders = [m.get("value") for v in config.iter("volume") for m in v if m.get("key") == "extruder"]
    assert extruders == ["1", "2"]
    second = tris[part == 1]
    assert mesh_moments(verts, second)[0] == pytest.approx(d6_solid.report["engraved_volume_mm3"], rel=1e-3)
    # back in the die's frame: every vertex of the second part within `depth` under a face plane
    poly, scale = d6.polyhedron, d6.mm_per_unit
    body = d6_solid.on_bed(d6_solid.vertices)
    shift = body.mean(axis=0) - d6_solid.vertices.mean(axis=0) @ d6_solid.print_rotation.T
    die = (verts - shift) @ d6_solid.print_rotation
    heights = die @ poly.normals.T - poly.offsets * scale  # ≤ 0 inside
    top = heights.max(axis=1)
    assert np.all(top <= 1e-6) and np.all(top >= -d6_solid.report["depth_mm"] - 1e-6)
    # flush: the second part's area in the face planes is the labels' and markers' area
    tri = die[second]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = 0.5 * np.linalg.norm(normals, axis=1)
    on_face = np.all(np.abs(heights.max(axis=1)[second]) < 1e-6, axis=1)
    expected = sum(p.area_mm2 for p in (*d6_solid.labels, *d6_solid.markers))
    assert area[on_face].sum() == pytest.approx(expected, rel=2e-3)


@pytest.mark.slow
def test_rendered_solid_preview_is_read_back_by_the_camera_detector(d6, d6_solid):
    from diefab.camera.pose import MarkerDetector
    from diefab.fabricate.preview import render_preview

    gray = cv2.imdecode(np.frombuffer(render_preview(d6_solid), np.uint8), cv2.IMREAD_GRAYSCALE)
    ids, _ = MarkerDetector(marker_layout(d6)).detect(gray)
    assert set(ids.tolist()) == set(marker_layout(d6).ids.tolist())


@pytest.mark.skipif(shutil.which("prusa-slicer") is None, reason="prusa-slicer is not installed")
@pytest.mark.slow
def test_prusa_slicer_slices_the_two_part_3mf(d6_solid, tmp_path):
    path = tmp_path / "d6.3mf"
    path.write_bytes(threemf_bytes(d6_solid))
    done = subprocess.run(
        ["prusa-slicer", "--export-gcode", str(path), "--output", str(tmp_path / "d6.gcode"),
         "--nozzle-diameter", "0.4,0.4", "--filament-diameter", "1.75,1.75", "--temperature", "215,215",
         "--first-layer-temperature", "215,215", "--wipe-tower", "--use-relative-e-distances"],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    gcode = (tmp_path / "d6.gcode").read_text()
    assert "\nT1" in gcode and "\nT0" in gcode  # both parts printed, each with its extruder


# ----------------------------------------------------------------------
# bad input


def test_too_small_a_marker_names_the_face_and_the_size_that_does(d6):
    layout = marker_layout(d6)
    n = layout.bits + 2
    cell = layout.sides.min() * d6.mm_per_unit / n
    need = np.ceil(16.0 * 1.1 * 10) / 10  # cells 10 % finer than asked for: the size 10 % larger, rounded up
    with pytest.raises(FabricationError, match=rf"face f\d is too small .* \({n}x{n} cells .*use --size {need:g} "):
        check_cells(d6, 16.0, 1.1 * cell, "--min-stroke")
    check_cells(d6, need, 1.1 * cell, "--min-stroke")  # the size it names does
    check_cells(d6, 16.0, cell, "--min-stroke")


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (("stl", "d20", "--markers"), "face f1 is too small for a readable marker at 22 mm"),
        (("stl", "d6", "--markers", "--round", "1"), "reaches 0.06 mm past the flat part"),
        (("net", "d6", "--markers", "--size", "3"), f"under the smallest printable cell {MIN_PAPER_CELL_MM:g} mm"),
    ],
)
def test_bad_marker_input_is_one_line_and_exit_2(run, tmp_path, args, match):
    code, out, err = run(*args, "--out", tmp_path)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("diefab: error:") and match in err
    assert "Traceback" not in err
