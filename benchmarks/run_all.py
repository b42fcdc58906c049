"""Run every benchmark, one after the other, and print their figures.

    python benchmarks/run_all.py           # the full set (about an hour on 2 cores)
    python benchmarks/run_all.py --quick   # small sizes (a few minutes)

Each benchmark is also a command of its own; see its docstring.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).parent

#: (script, arguments of the full run, arguments of the quick run)
BENCHMARKS = [
    ("bench_core.py", [], ["--quick"]),
    ("bench_net.py", [], []),
    ("bench_stl.py", [], ["--repeat", "3"]),
    ("bench_validate.py", [], ["--n", "3000"]),
    ("bench_fastmodel.py", [], ["--designs", "4", "--drops", "3000"]),
    ("bench_families.py", ["--designs", "4", "--drops", "3000"], ["--designs", "1", "--drops", "500"]),
    ("bench_simopt.py", [], ["--budget", "1", "--validate", "3000"]),
    ("bench_shaped.py", [], ["--targets", "3df", "--seeds", "0"]),
    (
        "bench_calibrate.py",
        [],
        ["--drops", "100", "--slow-drops", "30", "--candidates", "3", "--predict-drops", "100", "--cache", "/dev/null"],
    ),
    (
        "bench_calibrate.py",
        "--free capture --grid 11 --drops 2000 --slow-drops 2000 --predict-drops 10000 --prior inf".split(),
        "--free capture --grid 3 --drops 100 --slow-drops 30 --predict-drops 100 --prior inf --cache /dev/null".split(),
    ),
    ("bench_realrolls.py", [], ["--sims", "200"]),
    ("bench_realrolls.py", ["--guard", "--sims", "400"], ["--guard", "--sims", "400"]),  # cached: the guard's figures
    ("bench_heldout.py", [], []),  # cached: prints in half a minute
    ("bench_throw.py", [], []),  # cached: prints in seconds
    ("fit_center_of_mass.py", [], ["--dice", "binom3,kitten_d3", "--evals", "40"]),
    ("fit_chain.py", [], ["--evals", "20"]),
    ("fit_cuboid_curves.py", ["--per-die"], ["--per-die"]),
    ("goal_floor.py", [], ["--samples", "200", "--drops", "1000,0"]),
    ("bench_coins.py", ["--rolling-friction", "0,0.01"], ["--sides", "16,128", "--drops", "100"]),
    (
        "bench_coins.py",
        ["--sides", "128", "--rolling-friction", "0,0.001,0.003,0.01,0.03"],
        ["--sides", "128", "--rolling-friction", "0.03", "--drops", "100"],
    ),
    ("bench_planes.py", [], ["--dice", "50", "--repeat", "1", "--no-design"]),
    ("bench_counting.py", [], ["--targets", "3d6", "--repeat", "1"]),
    ("bench_basins.py", [], []),
    ("bench_many_faces.py", [], ["--sims", "40"]),
    ("bench_fair_shapes.py", [], ["--faces", "22", "--sims", "600"]),
    ("robust_gem.py", [], ["--evals", "2", "--sims", "500"]),
    (
        "bench_read.py",
        ["--rests", "0", "--drops", "0", "--others", "50"],
        ["--rests", "0", "--drops", "0", "--others", "5"],
    ),
]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes")
    args = parser.parse_args()
    failed = []
    for script, full, quick in BENCHMARKS:
        cmd = [sys.executable, str(HERE / script), *(quick if args.quick else full)]
        print(f"\n=== {' '.join(cmd[1:])}", flush=True)
        start = time.perf_counter()
        if subprocess.run(cmd).returncode != 0:
            failed.append(script)
        print(f"=== {script}: {time.perf_counter() - start:.0f} s", flush=True)
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
