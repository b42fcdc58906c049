"""Benchmark: build and engrave the fudge-gem, one batched boolean vs one boolean per label.

Run:  python benchmarks/bench_stl.py [--repeat N]

Prints the median time of (1) the engraving step alone (body minus the nine
label prisms) and (2) the whole :func:`build_solid` (hull, label layout,
engraving, checks, mass and balance report), for manifold3d's batched
boolean and for the straightforward baseline that subtracts each label with
its own boolean, and the ratio baseline / batched.  Both give the same solid.
"""

from __future__ import annotations

import argparse
import statistics
import time

from diefab.dice.design import load_design
from diefab.fabricate.engrave import cut_labels, cutter
from diefab.fabricate.rounding import hull_body
from diefab.fabricate.stl import build_solid


def _median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--design", default="fudge-gem")
    parser.add_argument("--size", type=float, default=30.0)
    args = parser.parse_args()

    design = load_design(args.design)
    t0 = time.perf_counter()
    solid = build_solid(design, size_mm=args.size)  # warms imports and caches
    first = time.perf_counter() - t0
    scale = solid.report["mm_per_unit"]
    depth = solid.report["depth_mm"]

    def engrave(batched: bool):
        # the cutters are rebuilt each time: manifold3d evaluates lazily and caches results
        body = hull_body(design.polyhedron.vertices * scale)
        cutters = [cutter(label, depth, False) for label in solid.labels]
        out = cut_labels(body, cutters, batched=batched)
        out.num_tri()  # force evaluation
        return out

    v_batch = engrave(True).volume()
    v_seq = engrave(False).volume()
    assert abs(v_batch - v_seq) <= 1e-9 * v_batch, (v_batch, v_seq)

    e_batch = _median_time(lambda: engrave(True), args.repeat)
    e_seq = _median_time(lambda: engrave(False), args.repeat)
    b_batch = _median_time(lambda: build_solid(design, size_mm=args.size, batched=True), args.repeat)
    b_seq = _median_time(lambda: build_solid(design, size_mm=args.size, batched=False), args.repeat)

    print(f"{args.design} at {args.size:g} mm: {len(solid.labels)} labels, {solid.report['triangles']} triangles")
    print(f"first build_solid (imports, font cache):        {first * 1000:8.1f} ms")
    print(f"engrave step, one batched boolean (median):     {e_batch * 1000:8.2f} ms")
    print(f"engrave step, one boolean per label (baseline): {e_seq * 1000:8.2f} ms   ratio {e_seq / e_batch:5.2f}x")
    print(f"build_solid, batched (median):                  {b_batch * 1000:8.1f} ms")
    print(f"build_solid, per-label booleans (baseline):     {b_seq * 1000:8.1f} ms   ratio {b_seq / b_batch:5.2f}x")


if __name__ == "__main__":
    main()
