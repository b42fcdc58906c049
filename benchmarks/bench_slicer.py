"""Benchmark: the print fill model against a real slicer (PrusaSlicer), mass and centre of mass.

Run:  python benchmarks/bench_slicer.py [--design fudge-gem] [--size 30] [--infill 0.15 ...]

Builds the engraved STL of the design (``diefab stl``'s body, bed face down),
slices it with ``prusa-slicer`` at the fill's settings (nozzle, perimeters,
layer height, top and bottom layers, infill; no skirt, no brim, the first
layer as thick and wide as the others), and reads the G-code back: every
extruding move deposits ``ΔE x filament cross-section`` of material spread
evenly along its segment, centred half a layer below the nozzle.  The
deposited volume and its centre of mass, turned back into the die's frame,
are compared with :func:`diefab.made.mass.mass_properties` for the same fill, bed
face and labels (the fill model), and with the simpler models beside it: a
uniform wall of the same thickness in every direction, and the solid die.
Skips (exit 0) when ``prusa-slicer`` is not on the PATH.
"""

from __future__ import annotations

import argparse
import math
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from diefab.dice.design import load_design
from diefab.fabricate.stl import build_solid, stl_bytes
from diefab.made.bodies import solid_label_masses
from diefab.made.mass import Fill, mass_properties

FILAMENT_MM = 1.75
_WORD = re.compile(r"([GXYZEM])(-?\d*\.?\d+)")


def slicer_options(fill: Fill, center: tuple[float, float]) -> list[str]:
    """PrusaSlicer command-line settings for `fill` (every width 1.125 x nozzle, as the fill model assumes)."""
    width = 1.125 * fill.nozzle_mm
    return [
        f"--nozzle-diameter={fill.nozzle_mm}",
        f"--filament-diameter={FILAMENT_MM}",
        f"--layer-height={fill.layer_mm}",
        f"--first-layer-height={fill.layer_mm}",
        f"--extrusion-width={width}",
        f"--first-layer-extrusion-width={width}",
        f"--perimeters={fill.perimeters}",
        f"--top-solid-layers={fill.top_layers}",
        f"--bottom-solid-layers={fill.bottom_layers}",
        f"--fill-density={fill.infill * 100:g}%",
        "--skirts=0",
        "--brim-width=0",
        f"--center={center[0]},{center[1]}",
    ]


def extrusions(gcode: str, layer_mm: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Start points (n, 3), end points (n, 3) and filament length (n,) of every extruding move.

    Handles absolute (M82) and relative (M83) E and G92 resets; moves that
    extrude without moving in x, y (primes after a retraction) and negative
    E (retractions, wipes) deposit nothing.  z is the bead's centre: half a
    layer below the nozzle.
    """
    pos = np.zeros(3)
    e_abs, relative = 0.0, False
    starts, ends, lengths = [], [], []
    for raw in gcode.splitlines():
        line = raw.split(";", 1)[0].strip()
        if not line:
            continue
        words = dict(_WORD.findall(line))
        g, m = words.get("G"), words.get("M")
        if m == "82":
            relative = False
        elif m == "83":
            relative = True
        if g == "92" and "E" in words:
            e_abs = float(words["E"])
            continue
        if g not in ("0", "1"):
            continue
        new = pos.copy()
        for k, axis in enumerate("XYZ"):
            if axis in words:
                new[k] = float(words[axis])
        de = 0.0
        if "E" in words:
            e = float(words["E"])
            de = e if relative else e - e_abs
            e_abs = e_abs + e if relative else e
        if de > 0 and np.hypot(*(new[:2] - pos[:2])) > 0:
            starts.append(pos.copy())
            ends.append(new.copy())
            lengths.append(de)
        pos = new
    a, b = np.array(starts), np.array(ends)
    a[:, 2] -= layer_mm / 2
    b[:, 2] -= layer_mm / 2
    return a, b, np.array(lengths)


def uniform_wall_center(design, fill: Fill) -> np.ndarray:
    """Centre of mass (mm) with a wall of the fill's side-wall thickness in every direction (no skins, no labels)."""
    from diefab.made.mass import inset

    poly, scale = design.polyhedron, design.mm_per_unit
    core = inset(poly, fill.wall_thickness_mm / scale)
    outer = mass_properties(poly, Fill("solid"))
    inner = mass_properties(core, Fill("solid"))
    hollow = 1 - fill.infill
    return (outer.mass * outer.center - hollow * inner.mass * inner.center) / (outer.mass - hollow * inner.mass) * scale


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--design", default="fudge-gem")
    parser.add_argument("--size", type=float, default=30.0)
    parser.add_argument("--infill", type=float, default=0.15)
    parser.add_argument("--perimeters", type=int, default=2)
    parser.add_argument("--top-layers", type=int, default=4)
    parser.add_argument("--bottom-layers", type=int, default=4)
    parser.add_argument("--layer", type=float, default=0.2)
    parser.add_argument("--nozzle", type=float, default=0.4)
    parser.add_argument(
        "--slicer-arg",
        action="append",
        default=[],
        metavar="--KEY=VALUE",
        help="Extra PrusaSlicer setting (repeatable), e.g. --slicer-arg=--perimeter-generator=classic",
    )
    args = parser.parse_args()
    exe = shutil.which("prusa-slicer")
    if exe is None:
        print("skipped: prusa-slicer is not on the PATH (apt-get install prusa-slicer)")
        return 0
    help_text = subprocess.run([exe, "--help"], capture_output=True, text=True).stdout
    version = next((line.split(" based on")[0] for line in help_text.splitlines() if "PrusaSlicer-" in line), "")

    fill = Fill(
        "print", nozzle_mm=args.nozzle, perimeters=args.perimeters, layer_mm=args.layer,
        top_layers=args.top_layers, bottom_layers=args.bottom_layers, infill=args.infill,
    )  # fmt: skip
    design = replace(load_design(args.design), size_mm=args.size, fill=fill)
    solid = build_solid(design, print_fill=fill)
    scale = design.mm_per_unit
    rot = solid.print_rotation
    placed = solid.vertices @ rot.T
    lo, hi = placed.min(axis=0), placed.max(axis=0)
    shift = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])  # print_vertices = v R^T - shift
    center = (100.0, 100.0)

    with tempfile.TemporaryDirectory() as tmp:
        stl = Path(tmp) / f"{design.name}.stl"
        stl.write_bytes(stl_bytes(solid))
        out = Path(tmp) / f"{design.name}.gcode"
        t0 = time.perf_counter()
        run = subprocess.run(
            [exe, "--export-gcode", *slicer_options(fill, center), *args.slicer_arg, "--output", str(out), str(stl)],
            capture_output=True, text=True,
        )  # fmt: skip
        seconds = time.perf_counter() - t0
        if run.returncode != 0 or not out.exists():
            print(run.stdout[-2000:], run.stderr[-2000:], file=sys.stderr)
            return 1
        gcode = out.read_text()
    a, b, de = extrusions(gcode, fill.layer_mm)
    volume = de * math.pi * (FILAMENT_MM / 2) ** 2
    mid = 0.5 * (a + b)
    # the print's frame -> the die's frame (mm): p = v R^T - shift + (cx, cy, 0)
    offset = np.array([center[0], center[1], 0.0])
    g_center_print = (volume[:, None] * mid).sum(axis=0) / volume.sum()
    g_center = (g_center_print - offset + shift) @ rot
    bbox_gcode = np.ptp(np.concatenate([a, b]), axis=0)

    labels = solid_label_masses(solid)
    bed = design.polyhedron.face_index(solid.report["bed_face"])
    model = mass_properties(design.polyhedron, fill, mm_per_unit=scale, bed=bed, labels=labels)
    m_center, m_volume = model.center * scale, model.mass * scale**3
    uniform = uniform_wall_center(design, fill)
    solid_center = np.asarray(solid.report["center_of_mass_mm"]["engraved"])

    print(f"{design.name} at {args.size:g} mm, {fill.describe()}; {version}")
    print(f"sliced in {seconds:.1f} s: {len(de)} extruding moves, extents {np.round(bbox_gcode, 2).tolist()} mm")
    print(f"bed face {solid.report['bed_face']}; centres in the die's frame, mm (y: the gem's axis)")
    print(f"{'':22s} {'volume mm3':>11s} {'x':>8s} {'y':>8s} {'z':>8s} {'|diff| mm':>10s}")
    rows = [
        ("G-code (PrusaSlicer)", volume.sum(), g_center),
        ("fill model", m_volume, m_center),
        ("uniform wall", float("nan"), uniform),
        ("solid", solid.report["volume_mm3"], solid_center),
    ]
    for name, vol, c in rows:
        d = np.linalg.norm(c - g_center)
        print(f"{name:22s} {vol:11.1f} {c[0]:8.4f} {c[1]:8.4f} {c[2]:8.4f} {d:10.4f}")
    diff = float(np.linalg.norm(m_center - g_center))
    print(f"fill model vs slicer: centre of mass {diff:.4f} mm apart (goal <= 0.1), "
          f"volume {m_volume / volume.sum() - 1:+.1%}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
