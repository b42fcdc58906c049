"""Paper nets: lengths, areas, overlaps, tabs, pages, CLI errors."""

from __future__ import annotations

import re
import shutil
import subprocess
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from diefab import Design, Polyhedron, load_design
from diefab.fabricate.net import design_net, render_net
from diefab.made.pages import PAGES, parse_page
from diefab.made.unfold import unfold

SVG = "{http://www.w3.org/2000/svg}"
DESIGN_DIR = Path(__file__).resolve().parent.parent / "templates"
INK = "{http://www.inkscape.org/namespaces/inkscape}"
OVERLAP_MM2 = 1e-6


def random_design(n_points: int = 12, seed: int = 3) -> Design:
    """A random convex polyhedron (20 triangles): too many spanning trees to enumerate."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n_points, 3))
    x /= np.linalg.norm(x, axis=1)[:, None]
    poly = Polyhedron.from_points(x)
    vertices = tuple(tuple(map(float, v)) for v in poly.vertices)
    faces = tuple(tuple(int(i) for i in f) for f in poly.faces)
    values = {n: k + 1 for k, n in enumerate(poly.names)}
    labels = {n: str(k + 1) for k, n in enumerate(poly.names)}
    return Design(
        "random", "convex", vertices=vertices, faces=faces, values=values, labels=labels,
        target=f"uniform:{len(values)}", size_mm=40,
    )  # fmt: skip


DESIGNS = {name: load_design(name) for name in ("fudge-gem", "d6", "d8")}
DESIGNS["random"] = random_design()


@pytest.fixture(scope="module", params=sorted(DESIGNS))
def made(request):
    design = DESIGNS[request.param]
    net = design_net(design)
    svg = render_net(design, net, ("svg",))["svg"].decode()
    return design, net, ET.fromstring(svg)


def parse_points(text: str) -> np.ndarray:
    return np.array([[float(v) for v in p.split(",")] for p in text.split()])


def svg_polygons(root, group: str, attr: str) -> dict[str, list[np.ndarray]]:
    g = root.find(f".//{SVG}g[@id='{group}']")
    out: dict[str, list[np.ndarray]] = {}
    for poly in g.iter(f"{SVG}polygon"):
        out.setdefault(poly.get(attr), []).append(parse_points(poly.get("points")))
    return out


def test_svg_is_true_scale_mm(made):
    design, net, root = made
    w, h = root.get("width"), root.get("height")
    assert w.endswith("mm") and h.endswith("mm")
    assert root.get("viewBox").split() == ["0", "0", w[:-2], h[:-2]]
    for group in ("faces", "tabs", "labels", "info"):
        assert root.find(f".//{SVG}g[@id='print']//{SVG}g[@id='{group}']") is not None
    layers = {g.get(f"{INK}label"): g for g in root.iter(f"{SVG}g") if g.get(f"{INK}groupmode") == "layer"}
    assert sorted(layers) == ["cut", "print", "score"]
    # cut and score differ in colour as well as dash; nothing but the outlines is on the cut layer
    assert layers["cut"].get("stroke") != layers["score"].get("stroke")
    assert layers["score"].get("stroke-dasharray") and not layers["cut"].get("stroke-dasharray")
    assert {el.tag for el in layers["cut"]} == {f"{SVG}path"}
    assert not root.findall(f".//{SVG}text")  # text is outlines: no font needed


def test_edge_lengths_and_area_survive_unfolding(made):
    design, net, root = made
    poly, scale = design.polyhedron, design.mm_per_unit
    faces = svg_polygons(root, "faces", "data-face")
    assert sorted(faces) == sorted(poly.names)
    total = 0.0
    for k, name in enumerate(poly.names):
        (flat,) = faces[name]
        ring = poly.vertices[poly.faces[k]]
        want = np.linalg.norm(np.roll(ring, -1, axis=0) - ring, axis=1) * scale
        got = np.linalg.norm(np.roll(flat, -1, axis=0) - flat, axis=1)
        np.testing.assert_allclose(got, want, atol=0.01)
        x, y = flat.T
        total += 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    assert total == pytest.approx(poly.surface_area * scale**2, rel=1e-4)  # SVG keeps 0.1 µm


def test_nothing_overlaps(made):
    from shapely.geometry import Polygon

    design, net, root = made
    faces = [(net.face_page[k], Polygon(p)) for k, p in enumerate(net.faces)]
    tabs = [(t.page, Polygon(t.polygon)) for t in net.tabs]
    shapes = faces + tabs
    for i in range(len(shapes)):
        for j in range(i + 1, len(shapes)):
            if shapes[i][0] == shapes[j][0]:
                assert shapes[i][1].intersection(shapes[j][1]).area < OVERLAP_MM2, (i, j)


def test_one_tab_per_cut_edge_and_folds_per_piece(made):
    design, net, root = made
    poly = design.polyhedron
    tabs = svg_polygons(root, "tabs", "data-tab")
    cut = set(range(len(poly.edges))) - set(net.fold_edges.tolist())
    assert sorted(t.edge for t in net.tabs) == sorted(cut)
    assert all(len(v) == 1 for v in tabs.values()) and len(tabs) == len(cut)
    assert {t.label for t in net.tabs} == set(tabs)
    for t in net.tabs:
        assert t.face in poly.edge_faces[t.edge]
    for piece in range(net.n_pieces):
        members = set(np.flatnonzero(net.face_piece == piece).tolist())
        folds = [e for e in net.fold_edges if set(poly.edge_faces[e].tolist()) <= members]
        assert len(folds) == len(members) - 1
    # every tab's letter is also printed on the face across its edge
    labels = [t.get("data-text") for t in root.find(f".//{SVG}g[@id='labels']").iter(f"{SVG}path")]
    for t in net.tabs:
        assert labels.count(t.label) >= 2


def test_tabs_are_narrow_trapezoids(made):
    design, net, root = made
    for t in net.tabs:
        base = np.linalg.norm(t.polygon[1] - t.polygon[0])
        d = t.polygon[1] - t.polygon[0]
        normal = np.array([-d[1], d[0]]) / base
        width = np.abs((t.polygon[2:] - t.polygon[0]) @ normal).max()
        assert width <= min(5.0, 0.5 * base) + 1e-9


def test_face_texts_are_the_design_labels(made):
    design, net, root = made
    paths = root.find(f".//{SVG}g[@id='labels']").iter(f"{SVG}path")
    texts = [t.get("data-text") for t in paths if t.get("class") == "face"]
    assert sorted(texts) == sorted(design.label_of.values())


def test_fudge_gem_fits_one_a4_page():
    net = design_net(load_design("fudge-gem"))
    assert net.n_pages == 1 and net.n_pieces == 1
    pw, ph = net.page.printable
    pts = np.concatenate(list(net.faces) + [t.polygon for t in net.tabs])
    assert pts.min() >= net.page.margin - 1e-9
    assert pts[:, 0].max() <= net.page.margin + pw + 1e-9 and pts[:, 1].max() <= net.page.margin + ph + 1e-9


def test_large_die_splits_into_pages():
    design = load_design("fudge-gem")
    net = design_net(design, size_mm=150)
    assert net.n_pieces > 1
    for piece in range(net.n_pieces):
        members = np.flatnonzero(net.face_piece == piece)
        assert len(set(net.face_page[members].tolist())) == 1


def test_mirror_free_unfolding():
    """Faces keep their orientation: counter-clockwise from outside reads clockwise in y-down page coordinates."""
    net = design_net(load_design("d8"))
    for p in net.faces:
        x, y = p.T
        assert np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)) < 0


@pytest.mark.parametrize("page", ["A4", "Letter"])
def test_pdf_page_size(page):
    design = load_design("d6")
    pdf = render_net(design, design_net(design, page=page), ("pdf",))["pdf"]
    boxes = re.findall(rb"/MediaBox\s*\[\s*([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s*\]", pdf)
    w, h = PAGES[page.upper()]
    assert boxes
    for box in boxes:
        x0, y0, x1, y1 = map(float, box)
        assert x1 - x0 == pytest.approx(w / 25.4 * 72, abs=0.01)
        assert y1 - y0 == pytest.approx(h / 25.4 * 72, abs=0.01)


def test_outputs_render(tmp_path):
    design = load_design("fudge-gem")
    out = render_net(design, design_net(design), ("svg", "pdf", "png"), face_names=True)
    assert out["png"][:8] == b"\x89PNG\r\n\x1a\n"
    (tmp_path / "n.svg").write_bytes(out["svg"])
    (tmp_path / "n.pdf").write_bytes(out["pdf"])
    if shutil.which("rsvg-convert"):
        subprocess.run(["rsvg-convert", str(tmp_path / "n.svg"), "-o", str(tmp_path / "s.png")], check=True)
        assert (tmp_path / "s.png").stat().st_size > 1000
    if shutil.which("pdftoppm"):
        subprocess.run(["pdftoppm", "-r", "30", "-png", str(tmp_path / "n.pdf"), str(tmp_path / "p")], check=True)
        assert list(tmp_path.glob("p*.png"))


def test_parse_page():
    assert parse_page("a3").width == 297.0
    assert parse_page("100x150").height == 150.0


def test_cube_has_eleven_distinct_net_shapes_all_valid():
    from diefab.geometry.trees import all_trees
    from diefab.made.flatten import count_overlaps, face_frames, hinges_of, homogeneous, place_trees

    cube = load_design("d6").polyhedron
    net = unfold(cube, 10.0)
    assert net.search["spanning_trees"] == 384
    local = face_frames(cube, 10.0)
    world, _ = place_trees(all_trees(cube), cube, hinges_of(cube, local), homogeneous(local))
    assert len(world) == 384 and not count_overlaps(world, [4] * 6).any()


# ----------------------------------------------------------------------
# command line


def test_cli_writes_files(tmp_path, run):
    code, out, err = run("net", "d6", "--out", tmp_path, "--format", "svg,pdf", "--face-names")
    assert code == 0, err
    assert (tmp_path / "d6-net.svg").is_file() and (tmp_path / "d6-net.pdf").is_file()
    assert "16 mm die" in out


@pytest.mark.parametrize(
    "args, words",
    [
        (["--size", "400"], "largest size that fits is"),
        (["--size", "0"], "positive"),
        (["--size", "-3"], "positive"),
        (["--page", "B5"], "page"),
        (["--format", "svg,gif"], "format"),
    ],
)
def test_cli_bad_input(tmp_path, bad, args, words):
    assert words in bad("net", "fudge-gem", "--out", tmp_path / "o", *args)
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def test_cli_unwritable_folder(tmp_path, bad):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    bad("net", "d6", "--out", blocker / "sub")


def test_size_error_names_a_size_that_works():
    design = load_design("fudge-gem")
    with pytest.raises(ValueError, match="largest size") as exc:
        design_net(design, size_mm=400)
    largest = float(re.search(r"fits is ([\d.]+) mm", str(exc.value)).group(1))
    assert design_net(replace(design, size_mm=largest)).n_pieces >= 1


# ----------------------------------------------------------------------
# labels like a real die, cutting machines, pages


def sheets_of(design, net, **kwargs):
    from diefab.dice.design import design_axis
    from diefab.fabricate.net import footer_texts
    from diefab.fabricate.sheet import layout_sheets, plan_footer
    from diefab.made.unfold import pack_copies

    plan = plan_footer(net.page.width, net.page.margin, *footer_texts(design, design.size_mm))
    values = [f for f in design.label_of if f not in design.labels]
    copies = kwargs.pop("copies", 1)
    return layout_sheets(
        pack_copies(net, copies), labels=design.label_of, axis=design_axis(design), plan=plan, values=values, **kwargs
    )


def _to_frame(design, net, k):
    """Affine map (page -> die frame of face k, mm), fitted from the face's corners alone."""
    from diefab.dice.design import design_axis
    from diefab.made.labels import face_frame

    poly = design.polyhedron
    ring = poly.vertices[poly.faces[k]] * net.mm_per_unit
    u, v = face_frame(ring, poly.normals[k], design_axis(design))
    origin = ring.mean(axis=0)
    want = np.column_stack([(ring - origin) @ u, (ring - origin) @ v])
    page = np.column_stack([net.faces[k], np.ones(len(ring))])
    m, *_ = np.linalg.lstsq(page, want, rcond=None)
    return m


def _apply(shape, m):
    from shapely import affinity

    return affinity.affine_transform(shape, [m[0, 0], m[1, 0], m[0, 1], m[1, 1], m[2, 0], m[2, 1]])


def _normalised(shape):
    from shapely import affinity

    x0, y0, x1, y1 = shape.bounds
    s = 1 / (y1 - y0)
    return affinity.scale(affinity.translate(shape, -(x0 + x1) / 2, -(y0 + y1) / 2), s, s, origin=(0, 0))


@pytest.mark.parametrize("name", ["fudge-gem", "d6", "d8"])
def test_net_labels_read_as_on_the_printed_die(name):
    """Carried back onto its face, each net label is the printed die's label: same turn, not mirrored."""
    from diefab.fabricate.stl import build_solid

    design = load_design(name)
    net = design_net(design)
    (sheet,) = sheets_of(design, net)
    solid = build_solid(design)
    printed = {label.face: label.outline for label in solid.labels if label.face_outline is None}
    faces = [t for t in sheet.texts if t.kind == "face"]
    assert sorted(t.face for t in faces) == sorted(printed)
    for t in faces:
        k = design.polyhedron.face_index(t.face)
        on_die = _normalised(_apply(t.shape, _to_frame(design, net, k)))
        want = _normalised(printed[t.face])
        assert on_die.symmetric_difference(want).area < 0.03 * want.area, t.face


@pytest.mark.parametrize("name", ["fudge-gem", "d6", "d8", "random"])
def test_value_labels_share_one_height_and_stay_inside_their_faces(name):
    from shapely.geometry import Polygon

    design = DESIGNS[name]
    net = design_net(design)
    sheets = sheets_of(design, net, face_names=True)
    texts = [t for s in sheets for t in s.texts]
    values = [t for t in texts if t.kind == "face" and t.face not in design.labels]
    heights = {round(t.height, 9) for t in values}
    assert len(heights) == (1 if name != "random" else 0)  # the random die's labels are all set by hand
    assert all(h > 1.0 for h in heights)
    for t in values:  # measured, in the die frame: the digits are that high
        if t.text.lstrip("+\u2212").isdigit():
            k = design.polyhedron.face_index(t.face)
            x0, y0, x1, y1 = _apply(t.shape, _to_frame(design, net, k)).bounds
            assert y1 - y0 == pytest.approx(t.height, rel=0.05), t.text  # a "1" is 4 % shorter than a "0"
    face_poly = {design.polyhedron.names[k]: Polygon(p) for k, p in enumerate(net.faces)}
    for t in texts:
        if t.kind in ("face", "name", "edge"):
            assert face_poly[t.face].contains(t.shape), (t.kind, t.text, t.face)
    for t in [t for t in texts if t.kind == "tab"]:
        tabs = [Polygon(tab.polygon) for tab in net.tabs if tab.label == t.text]
        assert any(p.contains(t.shape) for p in tabs), t.text
    # names never run into the value above them
    for t in [t for t in texts if t.kind == "name"]:
        for v in values:
            if v.face == t.face:
                assert not v.shape.intersects(t.shape)


def test_real_outlines_keep_a_wide_label_inside_its_face():
    design = replace(load_design("d6"), labels={"f2": "WWW"})
    net = design_net(design)
    (sheet,) = sheets_of(design, net)
    from shapely.geometry import Polygon

    (www,) = [t for t in sheet.texts if t.text == "WWW"]
    k = design.polyhedron.face_index(www.face)
    assert Polygon(net.faces[k]).buffer(-0.5).contains(www.shape)


def test_marks_only_where_a_label_reads_as_another():
    from diefab.made.labels import label_shape
    from diefab.made.text import load_font, text_polygons

    font = load_font()
    d20 = [str(v) for v in range(1, 21)]
    for text in ("10", "16", "18", "19"):
        assert label_shape(text, font, others=d20).equals(text_polygons(text, font))
    for text in ("6", "9"):
        assert label_shape(text, font, others=d20).area > text_polygons(text, font).area * 1.05
        assert not label_shape(text, font, others=d20, mark="none").equals(label_shape(text, font, others=d20))
    assert label_shape("6", font, others=[str(v) for v in range(1, 7)]).equals(text_polygons("6", font))


@pytest.mark.parametrize("copies", [1, 3])
def test_one_closed_cut_outline_per_piece(made, copies):
    from shapely.geometry import Polygon
    from shapely.ops import unary_union

    design, net, _ = made
    svg = render_net(design, net, ("svg",), copies=copies)["svg"].decode()
    root = ET.fromstring(svg)
    cut = root.find(f".//{SVG}g[@id='cut']")
    paths = cut.findall(f"{SVG}path")
    assert len(paths) == copies * net.n_pieces
    want = []
    for piece in range(net.n_pieces):
        members = np.flatnonzero(net.face_piece == piece)
        shapes = [Polygon(net.faces[f]) for f in members]
        shapes += [Polygon(t.polygon) for t in net.tabs if net.face_piece[t.face] == piece]
        want.append(unary_union([s.buffer(1e-7) for s in shapes]).area)
    got = []
    for p in paths:
        d = p.get("d")
        assert d.startswith("M") and d.endswith("Z") and d.count("M") == 1  # one closed ring
        ring = Polygon(np.array([[float(v) for v in xy.split(",")] for xy in re.split("[MLZ]", d) if xy]))
        assert ring.is_valid
        got.append(ring.area)
    np.testing.assert_allclose(sorted(got), sorted(want * copies), rtol=2e-5)  # the SVG keeps 0.1 µm
    # copies do not overlap each other
    faces = svg_polygons(root, "faces", "data-face")
    assert all(len(v) == copies for v in faces.values())


@pytest.mark.parametrize("page", ["A5", "A4", "Letter", "Legal", "A3"])
def test_footer_stays_on_the_page_and_off_the_net(page):
    from shapely.geometry import Polygon, box
    from shapely.ops import unary_union

    design = load_design("fudge-gem")
    size = 22.0 if page == "A5" else 30.0
    net = design_net(design, size_mm=size, page=page)
    pg = net.page
    assert pg.name.upper() == page.upper()
    sheets = sheets_of(design, net)
    for sheet in sheets:
        info = [t for t in sheet.texts if t.kind == "info"]
        assert any(t.text == f"page {sheet.number}/{sheet.pages}" for t in info)
        inside = box(pg.margin, pg.margin, pg.width - pg.margin, pg.height - pg.margin)
        net_area = unary_union([Polygon(p) for _, p in sheet.faces] + [Polygon(p) for _, p in sheet.tabs])
        shapes = [t.shape for t in info] + [Polygon(p).buffer(0) for style, p in sheet.legend if style == "swatch"]
        for s in shapes:
            assert inside.contains(s)
            assert not s.intersects(net_area)
        for a in range(len(info)):  # footer texts never overlap each other
            for b in range(a + 1, len(info)):
                assert not info[a].shape.intersects(info[b].shape), (info[a].text, info[b].text)


def test_tab_width_zero_means_no_tabs():
    design = load_design("d6")
    net = design_net(design, tab_width=0)
    assert net.tabs == ()
    cut = set(range(len(design.polyhedron.edges))) - set(net.fold_edges.tolist())
    assert set(net.edge_labels) == cut
    (sheet,) = sheets_of(design, net)
    letters = [t.text for t in sheet.texts if t.kind == "edge"]
    assert sorted(letters) == sorted(net.edge_labels[e] for e in cut for _ in range(2))  # both sides of each cut


def test_cli_copies_pages_and_reading(tmp_path, run):
    code, out, err = run("net", "fudge-gem", "--out", tmp_path, "--format", "svg", "--copies", "2", "--page", "A3")
    assert code == 0, err
    assert "2 dice" in out and "a point up means 0" in out
    code, out, err = run("net", "d6", "--out", tmp_path, "--format", "svg", "--size", "6", "--tab-width", "0")
    assert code == 0 and "no glue tabs" in out and "under about 8 mm" in err


def test_svg_symbol_on_a_face(tmp_path):
    """A symbol from an SVG file: holes kept, y flipped, found beside the design file, same place on paper and die."""
    pytest.importorskip("svgelements")
    from shapely.geometry import Polygon

    from diefab.made.labels import symbol_shape

    (tmp_path / "ring.svg").write_text(
        '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">'
        '<path d="M10,10 H90 V90 H10 Z M30,30 V70 H70 V30 Z"/><rect x="0" y="92" width="8" height="8"/></svg>'
    )
    shape = symbol_shape(str(tmp_path / "ring.svg"))
    assert shape.bounds[3] - shape.bounds[1] == pytest.approx(1.0)
    assert len(getattr(shape, "geoms", [shape])) == 2
    square = max(getattr(shape, "geoms", [shape]), key=lambda g: g.area)
    assert len(square.interiors) == 1
    # the small rect sits at the bottom left in the file (SVG y down): bottom left here too (y up)
    small = min(getattr(shape, "geoms", [shape]), key=lambda g: g.area)
    assert small.centroid.x < 0 and small.centroid.y < 0
    text = (tmp_path / "d6.toml").write_text((DESIGN_DIR / "d6.toml").read_text() + '\n[labels]\nf2 = "svg:ring.svg"\n')
    assert text
    design = load_design(tmp_path / "d6.toml")
    net = design_net(design)
    (sheet,) = sheets_of(design, net)
    (symbol,) = [t for t in sheet.texts if t.kind == "face" and t.text.startswith("svg:")]
    assert Polygon(net.faces[design.polyhedron.face_index(symbol.face)]).contains(symbol.shape)
    for bad in ("svg:missing.svg", "pips:12", "pips:x"):
        with pytest.raises(ValueError):
            design_net_labels = replace(design, labels={"f2": bad})
            render_net(design_net_labels, net, ("svg",))


def test_pips_on_the_net():
    design = load_design("d6")
    net = design_net(design)
    (sheet,) = sheets_of(design, net, pips=True)
    for t in [t for t in sheet.texts if t.kind == "face"]:
        assert len(getattr(t.shape, "geoms", [t.shape])) == int(t.text)
