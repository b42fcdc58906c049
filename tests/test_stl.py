"""The printable solid: soundness, volumes, balance, labels, exporters, CLI and slicer."""

from __future__ import annotations

import io
import math
import shutil
import subprocess
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import replace

import numpy as np
import pytest

from diefab.core.errors import FabricationError
from diefab.dice.design import load_design
from diefab.fabricate.engrave import cut_labels
from diefab.fabricate.formats import CORE_NS, inlay_stl_bytes, stl_bytes, threemf_bytes, threemf_mesh
from diefab.fabricate.stl import build_solid, flat_face_probabilities, mesh_moments
from diefab.geometry.polyhedron import solid_angles
from diefab.made.fill import Fill
from diefab.made.mass import inset, mass_properties
from diefab.made.text import MINUS, ambiguous, load_font, needs_underline, stroke_width, text_polygons


@pytest.fixture(scope="module")
def gem():
    return load_design("fudge-gem")


@pytest.fixture(scope="module")
def gem_solid(gem):
    return build_solid(gem, size_mm=30.0)


def _load_stl(data: bytes):
    import trimesh

    return trimesh.load(io.BytesIO(data), file_type="stl", process=True)


# ----------------------------------------------------------------------
# soundness and volume


def test_fudge_gem_stl_is_sound(gem_solid):
    r = gem_solid.report
    assert r["watertight"] and r["winding_consistent"]
    assert r["bodies"] == 1 and r["genus"] == 0  # '4', 'd' have counters: pockets, not tunnels
    mesh = _load_stl(stl_bytes(gem_solid))
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.is_volume
    assert mesh.body_count == 1
    assert mesh.volume == pytest.approx(r["volume_mm3"], rel=1e-5)  # float32 STL


def test_volume_is_hull_minus_text_area_times_depth(gem, gem_solid):
    """Independent: polyhedron volume in mm³ minus Σ (area of the text at its height) × depth."""
    font = load_font()
    scale = 30.0 / 2
    hull = gem.polyhedron.volume * scale**3
    text_area = sum(text_polygons(label.text, font).area * label.height_mm**2 for label in gem_solid.labels)
    expected = hull - text_area * 0.6
    assert gem_solid.volume_mm3 == pytest.approx(expected, rel=0.005)
    assert gem_solid.volume_mm3 < hull
    assert text_area * 0.6 == pytest.approx(gem_solid.report["engraved_volume_mm3"], rel=1e-4)


def test_labels_are_the_designs(gem, gem_solid):
    assert gem_solid.report["labels"] == gem.label_of
    assert gem_solid.report["labels"]["f5"] == "4dF"
    assert all(t.startswith(("+", MINUS)) for f, t in gem.label_of.items() if f != "f5")


def test_labels_are_upright_and_not_mirrored(gem, gem_solid):
    axis = np.array([0.0, 1.0, 0.0])
    for label in gem_solid.labels:
        assert np.allclose(np.cross(label.baseline, label.up), label.normal, atol=1e-12)
        assert abs(label.up @ label.normal) < 1e-12
        # side faces: text up points to the die's top (a value read at a corner points to that corner)
        if abs(label.normal @ axis) < 0.95 and label.face_outline is None:
            assert label.up @ axis > 0.3


def test_labels_fit_inside_their_faces(gem, gem_solid):
    from shapely.geometry import Polygon

    poly = gem.polyhedron
    for label in gem_solid.labels:
        ring = poly.vertices[poly.faces[poly.face_index(label.face)]] * 15.0
        rel = ring - label.origin_mm
        face = Polygon(np.column_stack([rel @ label.baseline, rel @ label.up]))
        assert label.outline.within(face.buffer(-1.0))
        assert label.height_mm >= 2.0


# ----------------------------------------------------------------------
# balance


def test_com_shift_equals_removed_prisms(gem_solid):
    """Each pocket is a right prism: area A_k, centroid c_k - (depth/2) n_k; the COM moves by exactly that."""
    r = gem_solid.report
    depth = r["depth_mm"]
    com0 = np.array(r["center_of_mass_mm"]["uncut"])
    v0 = r["uncut_volume_mm3"]
    removed = [(label.area_mm2 * depth, label.centroid_mm - 0.5 * depth * label.normal) for label in gem_solid.labels]
    vol = v0 - sum(v for v, _ in removed)
    predicted = (v0 * com0 - sum(v * c for v, c in removed)) / vol - com0
    assert np.allclose(r["com_shift_mm"], predicted, atol=1e-6)
    assert np.linalg.norm(predicted) > 1e-3  # the test would notice a zero shift


def test_uncut_com_is_the_solids_and_print_fill_matches_mass_module(gem):
    bare = replace(gem, labels={f: "" for f in gem.label_of})
    solid = build_solid(bare, size_mm=30.0, with_marks=False)
    assert solid.labels == ()
    r = solid.report
    assert np.allclose(r["center_of_mass_mm"]["uncut"], gem.polyhedron.centroid * 15.0, atol=1e-9)
    assert r["com_shift_norm_mm"] == pytest.approx(0.0, abs=1e-9)
    props = mass_properties(gem.polyhedron, Fill("print"), mm_per_unit=15.0)
    assert np.allclose(r["center_of_mass_mm"]["printed"], props.center * 15.0, atol=1e-9)
    assert r["mass_g"] == pytest.approx(props.mass * 15.0**3 * 1.24e-3, rel=1e-9)


def test_probabilities_follow_the_shifted_com(gem, gem_solid):
    from diefab.models.probabilities import to_values

    r = gem_solid.report
    com = np.array(r["center_of_mass_mm"]["engraved"]) / 15.0
    omega = solid_angles(gem.polyhedron, com)
    expected = to_values(gem, omega / omega.sum())
    got = np.array(list(r["probabilities"]["engraved"].values()))
    assert np.allclose(got, expected, atol=1e-12)
    for key in ("sharp", "engraved", "printed"):
        assert sum(r["probabilities"][key].values()) == pytest.approx(1.0)
    assert 0 < max(abs(x) for x in r["probability_change"]["engraving"].values()) < 1e-3


def test_flat_face_model_is_the_solid_angle_model_on_a_sharp_die(gem):
    poly = gem.polyhedron
    rings = [poly.vertices[f] for f in poly.faces]
    center = poly.centroid + np.array([0.01, -0.02, 0.03])
    omega = solid_angles(poly, center)
    assert np.allclose(flat_face_probabilities(rings, center), omega / omega.sum(), atol=1e-12)


# ----------------------------------------------------------------------
# rounding, embossing, batching


def test_rounded_volume_follows_steiners_formula(gem):
    """inset(P, r) ⊕ ball(r): V = V_Q + S_Q r + r² Σ_e L_e (π - θ_e) / 2 + 4/3 π r³."""
    bare = replace(gem, labels={f: "" for f in gem.label_of})
    r_mm = 2.0
    solid = build_solid(bare, size_mm=30.0, round_mm=r_mm)
    assert solid.watertight and solid.bodies == 1 and solid.genus == 0
    core = inset(gem.polyhedron, r_mm / 15.0).scaled(15.0)
    lengths = np.linalg.norm(np.diff(core.vertices[core.edges], axis=1)[:, 0], axis=1)
    n0, n1 = core.normals[core.edge_faces[:, 0]], core.normals[core.edge_faces[:, 1]]
    exterior = np.arccos(np.clip(np.einsum("ij,ij->i", n0, n1), -1, 1))  # π - interior dihedral
    steiner = core.volume + core.surface_area * r_mm + r_mm**2 * (lengths * exterior).sum() / 2
    steiner += 4 / 3 * math.pi * r_mm**3
    assert solid.volume_mm3 == pytest.approx(steiner, rel=0.005)
    assert solid.volume_mm3 < gem.polyhedron.volume * 15.0**3
    rep = solid.report
    assert rep["landing_model"] == "solid-angle of the flat faces"
    assert sum(rep["probabilities"]["rounded"].values()) == pytest.approx(1.0)
    assert max(abs(x) for x in rep["probability_change"]["rounding"].values()) > 1e-3


def test_rounded_and_engraved_gem_is_sound(gem):
    solid = build_solid(gem, size_mm=30.0, round_mm=1.5)
    assert solid.watertight and solid.bodies == 1 and solid.genus == 0
    r = solid.report
    assert r["volume_mm3"] == pytest.approx(r["uncut_volume_mm3"] - r["expected_engraved_volume_mm3"], rel=1e-4)


def test_emboss_adds_the_text_volume(gem):
    solid = build_solid(gem, size_mm=30.0, emboss=True)
    r = solid.report
    assert r["genus"] == 0 and r["bodies"] == 1
    area = {}
    for label in solid.labels:  # a face may hold a value read at a corner beside its own
        area[label.face] = area.get(label.face, 0.0) + label.area_mm2
    raised = sum(area[f] for f in set(r["embossed"])) * r["depth_mm"]
    sunk = sum(area[f] for f in set(r["engraved"])) * r["depth_mm"]
    assert r["volume_mm3"] == pytest.approx(r["uncut_volume_mm3"] + raised - sunk, rel=1e-4)
    assert any("emboss" in w for w in solid.warnings)


@pytest.mark.parametrize("name", ["d6", "fudge-gem"])
def test_emboss_never_stands_the_print_on_raised_text(name):
    """Every face carries a label: the bed face's is engraved, and nothing lies below the bed plane."""
    design = load_design(name)
    solid = build_solid(design, emboss=True)
    bed = solid.report["bed_face"]
    assert solid.report["engraved"] == [bed] and bed not in solid.report["embossed"]
    z = solid.print_vertices[:, 2]
    poly = design.polyhedron
    k = poly.face_index(bed)
    on_bed = np.abs(z) < 1e-6
    assert z.min() == pytest.approx(0.0, abs=1e-9) and on_bed.sum() >= len(poly.faces[k])
    assert any("engraved" in w for w in solid.warnings)


def test_emboss_picks_an_unlabelled_bed_face():
    design = replace(load_design("d6"), labels={"f2": ""})  # the face that showed 1 (resting on f1... ) is blank
    blank = [f for f in design.polyhedron.names if f not in design.label_of]
    solid = build_solid(design, emboss=True)
    assert solid.report["bed_face"] in blank and solid.report["engraved"] == []


def test_engraved_bed_face_avoids_labels():
    design = replace(load_design("d6"), labels={"f5": ""})
    assert build_solid(design).report["bed_face"] == "f5"


def test_batched_and_sequential_engraving_agree(gem_solid):
    import manifold3d

    from diefab.fabricate.engrave import cutter
    from diefab.fabricate.rounding import hull_body

    body = hull_body(gem_solid.design.polyhedron.vertices * 15.0)
    cutters = [cutter(label, 0.6, False) for label in gem_solid.labels]
    one = cut_labels(body, cutters, batched=True)
    many = cut_labels(body, cutters, batched=False)
    assert one.status() == manifold3d.Error.NoError and many.status() == manifold3d.Error.NoError
    assert one.volume() == pytest.approx(many.volume(), rel=1e-9)
    assert one.volume() == pytest.approx(gem_solid.volume_mm3, rel=1e-9)


def test_mesh_moments_of_a_box():
    import trimesh

    box = trimesh.creation.box(extents=(2, 3, 4), transform=trimesh.transformations.translation_matrix([1, 2, 3]))
    volume, first = mesh_moments(box.vertices, box.faces)
    assert volume == pytest.approx(24.0)
    assert np.allclose(first / volume, [1, 2, 3])


def test_print_orientation_rests_on_a_face(gem_solid):
    v = gem_solid.print_vertices
    assert v[:, 2].min() == pytest.approx(0.0, abs=1e-12)
    poly = gem_solid.design.polyhedron
    bed = poly.face_index(gem_solid.report["bed_face"])
    down = gem_solid.print_rotation @ poly.normals[bed]
    assert np.allclose(down, [0, 0, -1], atol=1e-12)
    assert np.allclose(gem_solid.print_rotation @ gem_solid.print_rotation.T, np.eye(3), atol=1e-12)


# ----------------------------------------------------------------------
# text


def test_text_readability_rules():
    font = load_font()
    assert needs_underline("6") and needs_underline("9") and needs_underline("+6") and needs_underline("66")
    assert not needs_underline("8") and not needs_underline("69") and not needs_underline("−3")
    assert ambiguous("6", ["6", "9"]) and not ambiguous("6", ["1", "6"]) and not ambiguous("16", ["16", "19"])
    six = text_polygons("6", font, "bar")
    assert six.bounds[3] - six.bounds[1] > 1.2  # digit height 1 plus the bar below
    dotted = text_polygons("6", font, "period")
    plain = text_polygons("6", font)
    assert dotted.bounds[2] - dotted.bounds[0] > plain.bounds[2] - plain.bounds[0] + 0.1
    assert dotted.bounds[3] - dotted.bounds[1] == pytest.approx(1.0, abs=0.01)  # the period sits on the line
    assert text_polygons("-3", font).equals(text_polygons(MINUS + "3", font))
    minus = text_polygons(MINUS, font)
    plus = text_polygons("+", font)
    assert minus.bounds[2] - minus.bounds[0] == pytest.approx(plus.bounds[2] - plus.bounds[0], rel=0.05)
    zero = text_polygons("0", font)
    assert len(zero.interiors) == 1 and 0.1 < stroke_width(zero) < 0.3


def test_thin_strokes_warn(gem):
    solid = build_solid(gem, size_mm=12.0)
    thin = [w for w in solid.warnings if "--min-stroke" in w]
    assert len(thin) == 1  # one warning for the die, not one per face
    assert solid.watertight and solid.genus == 0


def test_3mf_package(gem_solid):
    package = threemf_bytes(gem_solid)
    zf = zipfile.ZipFile(io.BytesIO(package))
    assert {"[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model"} <= set(zf.namelist())
    root = ET.fromstring(zf.read("3D/3dmodel.model"))
    ns = {"m": CORE_NS}
    assert root.get("unit") == "millimeter"
    colors = [base.get("displaycolor") for base in root.iterfind(".//m:basematerials/m:base", ns)]
    names = [base.get("name") for base in root.iterfind(".//m:basematerials/m:base", ns)]
    assert names == ["body", "labels"] and colors[0] != colors[1]
    verts, tris, part = threemf_mesh(package)
    volumes = {names[k]: mesh_moments(verts, tris[part == k])[0] for k in (0, 1)}
    # PrusaSlicer's config names the same two triangle ranges as the object's parts
    config = ET.fromstring(zf.read("Metadata/Slic3r_PE_model.config"))
    ranges = [(int(v.get("firstid")), int(v.get("lastid"))) for v in config.iter("volume")]
    assert ranges == [(0, int((part == 0).sum()) - 1), (int((part == 0).sum()), len(part) - 1)]
    # the body with empty pockets, and the labels filling them: together the uncut die
    assert volumes["body"] == pytest.approx(gem_solid.volume_mm3, rel=1e-6)
    assert volumes["labels"] == pytest.approx(gem_solid.report["engraved_volume_mm3"], rel=1e-3)
    assert volumes["body"] + volumes["labels"] == pytest.approx(gem_solid.report["uncut_volume_mm3"], rel=1e-6)


@pytest.mark.parametrize("name", ['a "quoted" die', "<x>&]]><!--", "gem 'v2'"])
def test_3mf_keeps_any_design_name_as_xml(gem_solid, name):
    from dataclasses import replace

    solid = replace(gem_solid, design=replace(gem_solid.design, name=name))
    zf = zipfile.ZipFile(io.BytesIO(threemf_bytes(solid)))
    root = ET.fromstring(zf.read("3D/3dmodel.model"))
    ns = {"m": CORE_NS}
    assert root.find(".//m:object", ns).get("name") == name
    assert root.find("m:metadata[@name='Title']", ns).text == name
    config = ET.fromstring(zf.read("Metadata/Slic3r_PE_model.config"))
    assert [m.get("value") for m in config.iter("metadata") if m.get("key") == "name"][:2] == [name, f"{name} body"]


def test_inlay_stl_fills_the_pockets(gem_solid):
    mesh = _load_stl(inlay_stl_bytes(gem_solid))
    assert mesh.is_watertight and mesh.volume == pytest.approx(gem_solid.report["engraved_volume_mm3"], rel=1e-3)
    body = _load_stl(stl_bytes(gem_solid))
    # placed as on the body's print bed: inside its bounding box
    assert np.all(mesh.bounds[0] >= body.bounds[0] - 1e-6) and np.all(mesh.bounds[1] <= body.bounds[1] + 1e-6)


# ----------------------------------------------------------------------
# bad input


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"size_mm": 0.0}, "size=0"),
        ({"size_mm": -3.0}, "size=-3"),
        ({"depth_mm": 3.0}, "too deep"),
        ({"depth_mm": 0.0}, "depth=0"),
        ({"size_mm": 8.0}, "does not fit on face f1"),
        ({"round_mm": 40.0}, "too large"),
        ({"font": "/nonexistent/font.ttf"}, "does not exist"),
    ],
)
def test_bad_settings_raise(gem, kwargs, match):
    with pytest.raises(FabricationError, match=match):
        build_solid(gem, **kwargs)


def test_cli_writes_stl_and_3mf(tmp_path, run):
    import json

    code, out, err = run("stl", "fudge-gem", "--format", "stl,3mf", "--out", tmp_path, "--json")
    assert code == 0, err
    report = json.loads(out)
    for key in ("file", "volume_mm3", "watertight", "com_shift_mm", "labels", "mass_g"):
        assert key in report
    assert report["labels"]["f4"] == "+2"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fudge-gem.3mf", "fudge-gem.stl"]
    mesh = _load_stl((tmp_path / "fudge-gem.stl").read_bytes())
    assert mesh.is_watertight and mesh.volume == pytest.approx(report["volume_mm3"], rel=1e-5)


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (["--depth", "3"], "too deep"),
        (["--size", "0"], "size=0"),
        (["--size", "8"], "face f1"),
        (["--format", "obj"], "--format"),
        (["--infill", "1.5"], "infill"),
    ],
)
def test_cli_bad_input(tmp_path, bad, args, match):
    out_dir = tmp_path / "out"
    assert match in bad("stl", "fudge-gem", "--out", out_dir, *args)
    assert not out_dir.exists() or not any(out_dir.iterdir())


def test_cli_unreadable_font_and_unwritable_folder(tmp_path, bad):
    bad_font = tmp_path / "font.ttf"
    bad_font.write_bytes(b"not a font")
    out_dir = tmp_path / "out"
    assert "font" in bad("stl", "fudge-gem", "--font", bad_font, "--out", out_dir)
    assert not out_dir.exists() or not any(out_dir.iterdir())
    blocker = tmp_path / "file"
    blocker.write_text("x")
    bad("stl", "fudge-gem", "--out", blocker / "sub")
    assert blocker.read_text() == "x"


def test_cli_label_too_long_names_the_face(tmp_path, bad):
    text = (tmp_path / "long.toml").write_text(
        'name = "long"\nfamily = "gem"\n[params]\na = 1.18\nb = 0.52\nc = 0.72\nd = 1.41\n'
        "[values]\nf1 = 3\nf2 = 4\nf3 = -3\nf4 = -4\nf5 = 0\nf6 = 1\nf7 = 2\nf8 = -1\nf9 = -2\n"
        '[labels]\nf5 = "Fudge dice are great fun"\n'
    )
    assert text > 0
    assert "face f5" in bad("stl", tmp_path / "long.toml", "--out", tmp_path / "o")
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


# ----------------------------------------------------------------------
# slicer


@pytest.mark.skipif(shutil.which("prusa-slicer") is None, reason="prusa-slicer is not installed")
def test_prusa_slicer_slices_without_repair(gem_solid, tmp_path):
    stl = tmp_path / "fudge-gem.stl"
    stl.write_bytes(stl_bytes(gem_solid))
    info = subprocess.run(["prusa-slicer", "--info", str(stl)], capture_output=True, text=True, timeout=120)
    text = info.stdout + info.stderr
    assert info.returncode == 0
    assert "manifold = yes" in text
    for repaired in ("open_edges", "facets_removed", "facets_reversed", "backwards_edges", "edges_fixed"):
        assert repaired not in text
    assert "number_of_parts =  1" in text or "number_of_parts = 1" in text
    gcode = tmp_path / "fudge-gem.gcode"
    run = subprocess.run(
        ["prusa-slicer", "--export-gcode", str(stl), "--output", str(gcode)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    log = "\n".join(
        line for line in (run.stdout + run.stderr).splitlines() if "[trace]" not in line and "[debug]" not in line
    )
    assert run.returncode == 0, log
    assert "repair" not in log.lower() and "warning" not in log.lower()
    assert gcode.is_file() and gcode.stat().st_size > 10_000


# ----------------------------------------------------------------------
# every die: rounding, size, pips


def icosahedron(rotation_seed: int | None = None, size_mm: float = 22.0):
    """A d20 (opposite faces sum to 21), optionally rotated at random."""
    from scipy.spatial.transform import Rotation

    from diefab import Design, Polyhedron

    p = (1 + 5**0.5) / 2
    v = np.array([c for a in (-1, 1) for b in (-p, p) for c in ((0, a, b), (a, b, 0), (b, 0, a))], dtype=float)
    if rotation_seed is not None:
        v = v @ Rotation.random(random_state=rotation_seed).as_matrix().T
    poly = Polyhedron.from_points(v)
    values: dict[str, int] = {}
    for i, name in enumerate(poly.names):
        if name not in values:
            j = int(np.argmin(poly.normals @ poly.normals[i]))
            values[name], values[poly.names[j]] = len(values) // 2 + 1, 20 - len(values) // 2
    return Design(
        "d20", "convex", vertices=tuple(map(tuple, poly.vertices.tolist())),
        faces=tuple(tuple(int(i) for i in f) for f in poly.faces), values=values, target="uniform:20",
        size_mm=size_mm,
    )  # fmt: skip


@pytest.mark.parametrize("name", ["d8", "d20"])
def test_rounding_works_on_faces_not_aligned_with_the_axes(name):
    design = icosahedron(1) if name == "d20" else load_design(name)
    solid = build_solid(design, round_mm=1.0)
    assert solid.watertight and solid.bodies == 1 and solid.genus == 0
    assert len(solid.labels) == len(design.polyhedron.faces)
    flat = solid.report["flat_face_area_mm2"]
    assert all(a > 0 for a in flat.values())
    assert not any("no flat part" in w for w in solid.warnings)
    # a fair die stays fair: every flat face the same area
    assert max(flat.values()) == pytest.approx(min(flat.values()), rel=1e-6)


def test_size_is_face_to_face_whatever_the_rotation():
    edges = []
    for seed in (None, 1, 2, 3):
        design = icosahedron(seed, size_mm=22.0)
        poly = design.polyhedron
        width = (poly.offsets + poly.offsets[np.argmin(poly.normals @ poly.normals.T, axis=1)]).max()
        assert width * design.mm_per_unit == pytest.approx(22.0)
        e = poly.vertices[poly.edges]
        edges.append(np.linalg.norm(e[:, 0] - e[:, 1], axis=1).mean() * design.mm_per_unit)
    # a d20 22 mm across its faces has edges 22 / (phi^2 / sqrt 3) = 14.55 mm
    assert np.allclose(edges, 22.0 * 3**0.5 / ((1 + 5**0.5) / 2) ** 2)
    assert load_design("d6").size_note == "face to face" and load_design("fudge-gem").size_note == "girdle short side"


def test_pips_on_a_d6():
    solid = build_solid(load_design("d6"), pips=True)
    assert solid.watertight and solid.genus == 0
    for label in solid.labels:
        parts = getattr(label.outline, "geoms", [label.outline])
        assert len(parts) == int(label.text)  # one round pip per unit
    # equal pips: every pip the same area
    areas = [p.area for label in solid.labels for p in getattr(label.outline, "geoms", [label.outline])]
    assert max(areas) == pytest.approx(min(areas), rel=1e-6)


def test_small_die_warns():
    solid = build_solid(load_design("d6"), size_mm=7.5, min_text_height_mm=1.0)
    assert any("under about 8 mm" in w for w in solid.warnings)
    assert not any("under about 8 mm" in w for w in build_solid(load_design("d6")).warnings)


def test_cli_inlay_pips_bed_and_reading(tmp_path, run):
    import json

    code, out, err = run(
        "stl", "d6", "--pips", "--emboss", "--inlay", "--format", "stl,3mf", "--out", tmp_path, "--json"
    )  # fmt: skip
    assert code == 0, err
    report = json.loads(out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d6-inlay.stl", "d6.3mf", "d6.stl"]
    assert report["reading"] == "read the face on top" and report["engraved"] == [report["bed_face"]]
    inlay = _load_stl((tmp_path / "d6-inlay.stl").read_bytes())
    assert inlay.is_watertight and inlay.body_count == 21  # 1 + 2 + ... + 6 pips
    code, out, err = run("stl", "fudge-gem", "--bed", "f1", "--out", tmp_path / "b")
    assert code == 0 and "printed on face f1" in out and "a point up means 0" in out
    assert "−4" in out and "+4" in out  # one value format: a true minus and a plus sign
