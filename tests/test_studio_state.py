"""The studio's state and geometry without a browser: evaluation, undo/redo, colors, face frames, jobs."""

from __future__ import annotations

import time

import numpy as np
import pytest

from diefab import DesignError, load_design, value_probabilities
from diefab.studio.state import Session, evaluate, face_colors, parameters
from diefab.studio.view import die_data, face_at, label_quad, net_svg


def test_evaluation_is_the_library_fast_model():
    d = load_design("fudge-gem")
    ev = evaluate(d)
    np.testing.assert_allclose(ev["probabilities"], value_probabilities(d, "fast"), atol=1e-12)
    assert sum(f["probability"] for f in ev["faces"]) == pytest.approx(1.0)
    np.testing.assert_allclose([f["margin"] for f in ev["faces"]], d.margins())
    assert ev["stable"] and ev["min_margin"] > 0
    # every resting face is read from the face its design says
    assert {f["name"]: f["read_from"] for f in ev["faces"]} == d.label_face


def test_a_cube_is_uniform():
    ev = evaluate(load_design("d6"))
    np.testing.assert_allclose(ev["probabilities"], np.full(6, 1 / 6), atol=1e-9)


def test_parameters_within_family_bounds():
    for p in parameters(load_design("fudge-gem")):
        assert p["lower"] <= p["value"] <= p["upper"]


def test_one_slider_drag_is_one_undo_step():
    s = Session(load_design("fudge-gem"))
    a0 = s.design.params["a"]
    for a in (1.2, 1.21, 1.22):
        s.edit(key=("param", "a"), params={"a": a})
    s.edit(key=("param", "b"), params={"b": 0.55})
    assert len(s.undo_stack) == 2
    assert s.undo() and s.design.params["b"] != 0.55 and s.design.params["a"] == 1.22
    assert s.undo() and s.design.params["a"] == a0
    assert not s.undo()
    assert s.redo() and s.redo() and s.design.params["b"] == 0.55
    assert not s.redo()


def test_bad_edit_changes_nothing():
    s = Session(load_design("fudge-gem"))
    with pytest.raises(DesignError):
        s.edit(key=("param", "a"), params={"a": 99.0})
    assert s.design.params["a"] == 1.18 and not s.undo_stack


def test_evaluations_are_cached():
    s = Session(load_design("fudge-gem"))
    assert s.evaluation() is s.evaluation()


def test_colors_darken_with_probability():
    colors = face_colors(np.array([0.0, 0.1, 0.2]))
    lum = [sum(int(c[i : i + 2], 16) for i in (1, 3, 5)) for c in colors]
    assert lum[0] > lum[1] > lum[2]


def test_die_data_draws_every_face_with_its_label_inside_it():
    poly = load_design("fudge-gem").polyhedron
    m = len(poly.faces)
    data = die_data(poly, ["#fff"] * m, [str(k) for k in range(m)], lift=0.0)
    v = np.array(data["vertices"])
    for k, face in enumerate(data["faces"]):
        pts = v[face]
        # every face lies in its plane and winds counter-clockwise seen from outside
        np.testing.assert_allclose(pts @ poly.normals[k], poly.offsets[k], atol=1e-5)
        assert np.cross(pts[1] - pts[0], pts[2] - pts[0]) @ poly.normals[k] > 0
        quad = np.array(data["quads"][k])
        # the label lies in the face's plane, inside the face, and is upright: top edge above the bottom one
        np.testing.assert_allclose(quad @ poly.normals[k], poly.offsets[k], atol=1e-5)
        assert np.all(poly.normals @ quad.T <= poly.offsets[:, None] + 1e-5)
        up = label_quad(poly, k, 0.0)
        np.testing.assert_allclose(quad, np.array(up).reshape(4, 3), atol=1e-5)


def test_a_click_finds_the_face_under_it():
    poly = load_design("fudge-gem").polyhedron
    for k, face in enumerate(poly.faces):
        centroid = poly.vertices[np.asarray(face)].mean(axis=0)
        assert face_at(poly, centroid) == k
        assert face_at(poly, centroid - 0.01 * poly.normals[k]) == k  # an engraved label's floor


def test_net_svg_has_one_polygon_per_face():
    import xml.etree.ElementTree as ET

    faces = [np.array([[0, 0], [10, 0], [0, 10]], float), np.array([[10, 0], [10, 10], [0, 10]], float)]
    root = ET.fromstring(net_svg(faces, ["f1", "f2"], {"f1": "6"}, ["#fff", "#000"]))
    groups = root.findall("{http://www.w3.org/2000/svg}g")
    assert [g.get("data-face") for g in groups] == ["f1", "f2"]


def _ended(process, timeout: float = 10.0) -> bool:
    """True once a worker `process` has ended (another thread reaps it: ask until it says so)."""
    end = time.monotonic() + timeout
    while process.is_alive() and time.monotonic() < end:
        time.sleep(0.05)
    return not process.is_alive()


def test_job_reports_and_cancels():
    from diefab.studio.jobs import Job

    job = Job(_count_to, 3)

    end = time.monotonic() + 60
    while not job.poll() and time.monotonic() < end:
        time.sleep(0.05)
    assert job.result == 3 and job.done == 3 and job.error is None
    slow = Job(_sleep_forever)
    slow.cancel()  # returns at once: the page's event loop never waits for the worker
    assert slow.error == "cancelled" and slow.finished
    assert _ended(slow.process)  # SIGTERM now, SIGKILL 2 s later


def _count_to(n, *, report):
    for i in range(n + 1):
        report("progress", i, n)
    return n


def _sleep_forever(*, report):

    while True:
        time.sleep(1)


def test_studio_command_refuses_bad_input_in_one_line(bad, tmp_path):
    import socket

    assert "unknown template" in bad("studio", "no-such-die", "--no-browser", "--out", tmp_path)
    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        held.listen()
        port = held.getsockname()[1]
        assert "cannot serve on 127.0.0.1" in bad("studio", "d6", "--no-browser", "--port", port, "--out", tmp_path)


def test_provisional_evaluation_is_the_solid_body_of_the_same_shape():
    from dataclasses import replace

    from diefab.made.fill import Fill
    from diefab.studio.state import made_body_is_slow, provisional_evaluation

    paper = replace(load_design("fudge-gem"), fill=Fill("paper"))
    assert made_body_is_slow(paper) and not made_body_is_slow(load_design("fudge-gem"))
    ev = provisional_evaluation(paper)
    assert ev["provisional"] and ev["fill"] == "paper"
    solid = replace(paper, fill=Fill())
    np.testing.assert_allclose(ev["probabilities"], value_probabilities(solid, "fast"), atol=1e-12)
    np.testing.assert_allclose([f["margin"] for f in ev["faces"]], solid.margins())
    assert not evaluate(solid)["provisional"]


def test_evaluator_worker_gives_the_library_evaluation_and_stops():
    from dataclasses import replace

    from diefab.core.errors import DiefabError
    from diefab.made.fill import Fill
    from diefab.studio.jobs import Evaluator

    printed = replace(load_design("d6"), fill=Fill("print", infill=0.2))
    worker = Evaluator()
    try:
        ev = worker.evaluate(printed)
        np.testing.assert_allclose(ev["probabilities"], evaluate(printed)["probabilities"], atol=1e-12)
        np.testing.assert_allclose([f["margin"] for f in ev["faces"]], printed.margins(), atol=1e-12)
        with pytest.raises(DiefabError, match="internal error"):  # not a design: one line, and the worker lives on
            worker.evaluate(None)
        assert worker.evaluate(printed)["probabilities"] == ev["probabilities"]
    finally:
        worker.stop()
    assert _ended(worker.process)


def test_made_mesh_gives_each_triangle_its_face():
    from diefab.studio.view import made_mesh

    poly = load_design("fudge-gem").polyhedron
    triangles, owner = [], []
    for k, face in enumerate(poly.faces):
        for i in range(1, len(face) - 1):
            triangles.append([face[0], face[i], face[i + 1]])
            owner.append(k)
    engraved = np.zeros(len(triangles), bool)
    data = made_mesh(poly, poly.vertices, np.array(triangles), engraved)
    assert data["face_of"] == owner
    # a triangle sunk into a face (an engraving's floor) still belongs to that face
    k = 3
    floor = poly.vertices[np.asarray(poly.faces[k][:3])] * 0.9 + 0.1 * poly.vertices[poly.faces[k]].mean(axis=0)
    floor = floor - 0.02 * poly.normals[k]
    sunk = made_mesh(poly, floor, np.array([[0, 1, 2]]), np.array([True]))
    assert sunk["face_of"] == [k] and sunk["engraved"] == [1]


def test_charts_and_live_verdict():
    from diefab.studio.chart import counts_options, live_verdict, margin_rows, validation_options

    d = load_design("d6")
    counts, sequential, plain = live_verdict(d, [1, 1, 6, 7], delta=0.03)  # 7 is not a value of the die: left out
    assert counts == [2, 0, 0, 0, 0, 1]
    assert sequential.startswith("3 rolls: TVD") and plain
    opts = counts_options(["1", "2", "3", "4", "5", "6"], counts, [1 / 6] * 6)
    assert sum(opts["series"][0]["data"]) == pytest.approx(1.0)
    assert live_verdict(d, [], delta=0.03)[2] == ""
    r = {"observed": [0.5, 0.5], "target": [0.5, 0.5], "intervals": [[0.4, 0.6], [0.3, 0.7]]}
    series = {s["name"]: s["data"] for s in validation_options(["1", "2"], r)["series"]}
    assert series["interval low"] == [0.4, 0.3] and series["interval high"] == [0.6, 0.7]
    rows = margin_rows(evaluate(d))
    assert [row["state"] for row in rows] == ["stable"] * 6


def test_upload_checks(tmp_path):
    from diefab.dice.design import design_to_toml
    from diefab.studio.files import MAX_UPLOAD, parse_upload

    d6 = load_design("d6")
    text = design_to_toml(d6).encode()
    assert parse_upload(text, "d6.toml", tmp_path).name == d6.name
    with pytest.raises(DesignError, match="larger than"):
        parse_upload(b" " * (MAX_UPLOAD + 1), "big.toml", tmp_path)
    with pytest.raises(DesignError, match="UTF-8"):
        parse_upload(b"\xff\xfe", "bin.toml", tmp_path)
    outside = b'name = "m"\nfamily = "mesh"\nmesh = "/etc/passwd"\nvalues = {}\n'
    with pytest.raises(DesignError, match="read only in"):
        parse_upload(outside, "m.toml", tmp_path)
    missing = outside.replace(b"/etc/passwd", b"/nonexistent/secret.stl")
    with pytest.raises(DesignError, match="read only in"):  # refused before it is opened: says nothing of the file
        parse_upload(missing, "m.toml", tmp_path)
    with pytest.raises(DesignError, match="nested too deeply"):
        parse_upload(b"a = " + b"[" * 5000, "deep.toml", tmp_path)


def test_the_studio_never_replaces_the_files_it_read(tmp_path):
    from diefab.core.errors import OutputError
    from diefab.dice.design import design_to_toml, parse_design
    from diefab.studio.make import write_design, write_solid

    write_solid(load_design("d6"), tmp_path)
    mesh = tmp_path / "m.stl"
    (tmp_path / "d6.stl").rename(mesh)
    text = 'name = "m"\nfamily = "mesh"\nmesh = "m.stl"\ntarget = "1d6"\n'
    text += "values = {" + ", ".join(f"f{i} = {i}" for i in range(1, 7)) + "}\n"
    design = parse_design(text, base=tmp_path, within=tmp_path)
    before = mesh.read_bytes()
    with pytest.raises(OutputError, match="input"):
        write_solid(design, tmp_path)  # m.stl, the design's own mesh
    assert mesh.read_bytes() == before
    opened = tmp_path / "m.toml"
    opened.write_text(design_to_toml(design))
    with pytest.raises(OutputError, match="input"):
        write_design(design, tmp_path, inputs=(opened,))


def test_make_tab_writes_the_net_and_the_solid_with_markers(tmp_path):
    """The Make tab's writers with markers: every id read back from the net, the solid's pockets measured."""
    cv2 = pytest.importorskip("cv2")
    from diefab.camera.pose import MarkerDetector
    from diefab.dice.markers import marker_layout
    from diefab.studio.make import write_net, write_solid

    design = load_design("d6")
    (png,) = write_net(design, tmp_path, formats=("png",), markers=True)
    gray = cv2.imdecode(np.fromfile(png, np.uint8), cv2.IMREAD_GRAYSCALE)
    layout = marker_layout(design)
    ids, _ = MarkerDetector(layout).detect(gray)
    assert sorted(ids.tolist()) == layout.ids.tolist()
    _, plain = write_solid(design, tmp_path / "plain")
    _, marked = write_solid(design, tmp_path / "marked", markers=True)
    assert marked["watertight"] and len(marked["markers"]) == len(design.polyhedron.faces)
    assert marked["marker_volume_mm3"] > 0 and not plain.get("marker_volume_mm3")


def test_validate_job_notes_a_die_outside_the_profiles_dice():
    from diefab.dice.design import load_design
    from diefab.studio.jobs import validate_job

    paper = load_design("fudge-gem-paper")
    r = validate_job(paper, 10, 0, "printed-table", report=lambda *a: None)
    assert sum(r["counts"]) + r["cocked"] + r["unsettled"] == 10 and "this die is paper" in r["note"]
    assert validate_job(paper, 10, 0, None, report=lambda *a: None)["note"] is None
