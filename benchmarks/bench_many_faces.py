"""A die of hundreds of faces through the command line: predict, validate, net and stl, timed.

The die is a rounded cube (the corners' spheres' hull: 6 faces it rests on,
the rest transitional), 142, 310 or 542 faces.  Each command runs as a
subprocess; wall time and the CPU time of the process and its children are
printed, with the net's pieces and the face count.

The die is stated as paper glued edge to edge (``[fill] kind = "paper",
tabs = false``): with 5 mm glue tabs weighed in, the tabs move this die's
centre of mass so far that it could rest on a transitional face, and
``diefab net`` says so (after writing the net).  The net runs through the
command line without tabs, and with 5 mm tabs through the library
(``design_net``).

Run: nice -n 10 python benchmarks/bench_many_faces.py [--counts 8,16] [--sims 200]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from test_transitional import _rounded_cube  # noqa: E402

from diefab.dice.design import design_to_toml  # noqa: E402
from diefab.made.mass import Fill  # noqa: E402


def timed(*args: str) -> tuple[dict, float, float]:
    """Run ``diefab ARGS --json``: its JSON, wall seconds and CPU seconds (children included)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "diefab", *args, "--json"], capture_output=True, text=True)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"diefab {' '.join(args)} failed: {proc.stderr.strip()}")
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return json.loads(proc.stdout), wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", default="16", help="uv-sphere segment counts (8: 142 faces, 16: 542).")
    parser.add_argument("--sims", type=int, default=200, help="Drops for validate.")
    args = parser.parse_args()
    print(f"{'faces':>5} {'command':<22} {'wall s':>8} {'cpu s':>8}  result")
    with tempfile.TemporaryDirectory() as tmp:
        for count in (int(c) for c in args.counts.split(",")):
            # glued edge to edge (no tabs drawn or weighed): with 5 mm tabs the paper die's tabs move its centre
            # of mass so far that it could rest on a transitional face, and `diefab net` says so
            design = replace(_rounded_cube(count), fill=Fill("paper", tabs=False))
            faces = len(design.polyhedron.faces)
            path = Path(tmp) / f"rounded{count}.toml"
            path.write_text(design_to_toml(design))
            runs = {
                "predict solid-angle": ("predict", str(path), "--model", "solid-angle"),
                "predict basins": ("predict", str(path), "--model", "basins"),
                "predict fast": ("predict", str(path), "--model", "fast"),
                f"validate {args.sims} drops": ("validate", str(path), "--sims", str(args.sims), "--workers", "1"),
                "net --tab-width 0": ("net", str(path), "--out", tmp, "--format", "svg", "--tab-width", "0"),
                "stl": ("stl", str(path), "--out", tmp),
            }
            for what, argv in runs.items():
                data, wall, cpu = timed(*argv)
                if what.startswith("net"):
                    result = f"{data['pieces']} pieces, {data['tabs']} tabs, {data['pages']} page(s)"
                elif what == "stl":
                    result = f"watertight {data.get('watertight')}, {data.get('volume_mm3', 0):.0f} mm3"
                elif what.startswith("validate"):
                    result = f"{data['landed']} landed, TVD {data.get('tvd', float('nan')):.3f}"
                else:
                    result = " ".join(f"{v:.3f}" for v in data["values"].values())
                print(f"{faces:>5} {what:<22} {wall:>8.1f} {cpu:>8.1f}  {result}", flush=True)
            # the layout with 5 mm glue tabs, in the library (a paper die's tabs also weigh: see the README)
            from diefab.fabricate.net import design_net

            wall, cpu = time.perf_counter(), time.process_time()
            net = design_net(design)
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
            what = "design_net, 5 mm tabs"
            print(f"{faces:>5} {what:<22} {wall:>8.1f} {cpu:>8.1f}  {net.n_pieces} pieces, {len(net.tabs)} tabs, "
                  f"{net.n_pages} page(s), {net.search['method']}", flush=True)  # fmt: skip
    print(f"{os.cpu_count()} cores (shared machine)")


if __name__ == "__main__":
    main()
