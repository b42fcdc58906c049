"""Nets and prints as makers use them: measured geometry, timings and the README's figures.

    python benchmarks/bench_makers.py [--figures benchmarks/figures]

Prints, for the shipped dice: the net's value-label heights, text kept inside
its face, one closed cut outline per piece, Inkscape layers, the footer on
every page size, --copies packing; the STL's rounding on faces not aligned
with the axes (d8, d20, a randomly rotated d20), size under rotation (face
to face against the old bounding-box rule), --emboss bed face, the 3MF's two
parts.  Writes a net PDF page (rendered with pdftoppm when installed) and
STL previews as PNG under --figures.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from diefab import Design, load_design  # noqa: E402
from diefab.dice.design import design_axis  # noqa: E402
from diefab.fabricate.formats import threemf_bytes, threemf_mesh  # noqa: E402
from diefab.fabricate.net import design_net, footer_texts, render_net  # noqa: E402
from diefab.fabricate.sheet import layout_sheets, plan_footer  # noqa: E402
from diefab.fabricate.stl import build_solid, mesh_moments  # noqa: E402
from diefab.made.unfold import pack_copies  # noqa: E402

SVG = "{http://www.w3.org/2000/svg}"
INK = "{http://www.inkscape.org/namespaces/inkscape}"


def rotated(design: Design, seed: int) -> Design:
    from scipy.spatial.transform import Rotation

    v = np.asarray(design.vertices) @ Rotation.random(random_state=seed).as_matrix().T
    return replace(design, vertices=tuple(map(tuple, v.tolist())))


def sheets(design, net, copies=1):
    plan = plan_footer(net.page.width, net.page.margin, *footer_texts(design, design.size_mm))
    values = [f for f in design.label_of if f not in design.labels]
    return layout_sheets(pack_copies(net, copies), labels=design.label_of, axis=design_axis(design), plan=plan,
                         values=values)  # fmt: skip


def nets() -> None:
    from shapely.geometry import Polygon

    render_net(load_design("d6"), design_net(load_design("d6")), ("svg", "pdf"))  # imports and font caches
    print("nets (A4, default size): time for design_net + SVG + PDF, value-label height, texts inside their face")
    print(f"{'die':10s} {'s':>6s} {'heights mm':>12s} {'inside':>8s} {'cut paths':>9s} {'pieces':>6s} layers")
    for name in ("fudge-gem", "d6", "d8", "d20"):
        d = load_design(name)
        t0 = time.perf_counter()
        net = design_net(d)
        out = render_net(d, net, ("svg", "pdf"))
        seconds = time.perf_counter() - t0
        (sheet,) = sheets(d, net)
        values = [t for t in sheet.texts if t.kind == "face" and t.face not in d.labels]
        heights = sorted({round(t.height, 3) for t in values})
        faces = {d.polyhedron.names[k]: Polygon(p) for k, p in enumerate(net.faces)}
        on_face = [t for t in sheet.texts if t.kind in ("face", "name", "edge")]
        inside = sum(faces[t.face].contains(t.shape) for t in on_face)
        root = ET.fromstring(out["svg"])
        layers = sorted(g.get(f"{INK}label") for g in root.iter(f"{SVG}g") if g.get(f"{INK}groupmode") == "layer")
        cut = [p.get("d") for p in root.find(f".//{SVG}g[@id='cut']")]
        closed = all(p.count("M") == 1 and p.endswith("Z") for p in cut)
        print(
            f"{name:10s} {seconds:6.2f} {'/'.join(f'{h:g}' for h in heights):>12s} {inside:>3d}/{len(on_face):<4d} "
            f"{len(cut):>5d} {'closed' if closed else 'OPEN'} {net.n_pieces:>4d}   {','.join(layers)}"
        )
    print("\npages (fudge-gem; A5 at 22 mm): footer rows and height, texts overlapping the net or each other")
    from shapely.geometry import box
    from shapely.ops import unary_union

    for page in ("A5", "A4", "Letter", "Legal", "A3"):
        d = load_design("fudge-gem")
        net = design_net(d, page=page, size_mm=22.0 if page == "A5" else None)
        plan = plan_footer(net.page.width, net.page.margin, *footer_texts(d, d.size_mm))
        (sheet,) = sheets(d, net)
        info = [t.shape for t in sheet.texts if t.kind == "info"]
        area = unary_union([Polygon(p) for _, p in sheet.faces] + [Polygon(p) for _, p in sheet.tabs])
        pg = net.page
        inside = box(pg.margin, pg.margin, pg.width - pg.margin, pg.height - pg.margin)
        clashes = sum(s.intersects(area) for s in info) + sum(
            info[i].intersects(info[j]) for i in range(len(info)) for j in range(i + 1, len(info))
        )
        off = sum(not inside.contains(s) for s in info)
        rows = f"{len(plan.rows)} rows, footer {plan.height:4.1f} mm"
        print(f"  {page:7s} {rows}: {clashes} overlaps, {off} off the page")
    d = load_design("d6")
    for page, copies in (("A5", 6), ("A4", 12), ("Letter", 12), ("A3", 30)):
        net = design_net(d, page=page)
        packed = pack_copies(net, copies)
        print(f"  d6 x{copies:<3d} on {page:6s}: {max(n.n_pages for n in packed)} page(s)")


def solids() -> None:
    print("\nstl --round 1 on faces not aligned with the axes (was: 'rounding left no flat part')")
    d20 = load_design("d20")
    for name, d in (("d8", load_design("d8")), ("d20", d20), ("d20 rotated", rotated(d20, 7))):
        t0 = time.perf_counter()
        s = build_solid(d, round_mm=1.0)
        seconds = time.perf_counter() - t0
        flat = np.array(list(s.report["flat_face_area_mm2"].values()))
        print(
            f"  {name:12s} watertight {s.watertight}, genus {s.genus}, {len(s.labels)} labels, flat faces "
            f"{flat.min():.3f}-{flat.max():.3f} mm², {seconds:.2f} s"
        )
    print("\nsize 22 mm on a d20 turned at random: edge length, face to face now vs the old bounding-box rule")
    p = (1 + 5**0.5) / 2
    for seed in (None, 1, 2, 3):
        d = d20 if seed is None else rotated(d20, seed)
        poly = d.polyhedron
        edge = np.linalg.norm(np.diff(poly.vertices[poly.edges], axis=1)[:, 0], axis=1).mean()
        old = 22.0 / float(np.ptp(poly.vertices, axis=0).max())
        print(f"  rotation {seed!s:4s}: {edge * d.mm_per_unit:6.3f} mm now, {edge * old:6.3f} mm by the old rule")
    print(f"  (a d20 22 mm across its faces has {22 * 3**0.5 / p**2:.3f} mm edges)")
    print("\n--emboss: the print stands on a flat face")
    for name in ("d6", "fudge-gem"):
        s = build_solid(load_design(name), emboss=True)
        r = s.report
        print(f"  {name:10s} bed {r['bed_face']}, engraved {r['engraved']}, {len(r['embossed'])} embossed")
    s = build_solid(replace(load_design("d6"), labels={"f2": ""}), emboss=True)
    print(f"  d6 with a blank face: bed {s.report['bed_face']}, engraved {s.report['engraved']}")
    print("\n3MF: body and labels as two coloured parts of one object (fudge-gem, 30 mm)")
    s = build_solid(load_design("fudge-gem"))
    v, t, part = threemf_mesh(threemf_bytes(s))
    for k, name in enumerate(("body", "labels")):
        print(f"  {name:22s} {mesh_moments(v, t[part == k])[0]:9.2f} mm³")
    print(f"  uncut die              {s.report['uncut_volume_mm3']:9.2f} mm³")
    if shutil.which("prusa-slicer"):
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "fudge-gem.3mf"
            path.write_bytes(threemf_bytes(s))
            info = subprocess.run(["prusa-slicer", "--info", str(path)], capture_output=True, text=True).stdout
            print("  prusa-slicer --info:", ", ".join(re.findall(r"(manifold = \w+|volume = [\d.]+)", info)))


def figures(folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    from diefab.fabricate.preview import render_preview

    written = []
    for name, size in (("fudge-gem", None), ("d20", None)):
        d = load_design(name)
        pdf = render_net(d, design_net(d, size_mm=size), ("pdf", "png"))
        target = folder / f"{name}-net.png"
        if shutil.which("pdftoppm"):
            with tempfile.TemporaryDirectory() as tmp:
                (Path(tmp) / "net.pdf").write_bytes(pdf["pdf"])
                subprocess.run(["pdftoppm", "-png", "-r", "110", "-singlefile", "net.pdf", "page"], cwd=tmp, check=True)
                shutil.copy(Path(tmp) / "page.png", target)
        else:
            target.write_bytes(pdf["png"])
        written.append(target)
    for name, kwargs in (("d20", {"round_mm": 1.0, "mark": "period"}), ("d6", {"pips": True, "emboss": True})):
        target = folder / f"{name}-stl{'-pips' if kwargs.get('pips') else ''}.png"
        target.write_bytes(render_preview(build_solid(load_design(name), **kwargs), dpi=70))
        written.append(target)
    print("\nfigures: " + ", ".join(str(p) for p in written))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figures", type=Path, default=None, help="also write the README's figures here")
    args = parser.parse_args()
    print("timings on a shared 2-core machine\n")
    nets()
    solids()
    if args.figures:
        figures(args.figures)


if __name__ == "__main__":
    main()
