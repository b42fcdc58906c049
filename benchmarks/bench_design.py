"""Benchmark: ``diefab design TARGET`` with default options, then validate, net and stl on what it wrote.

Run:  python benchmarks/bench_design.py [--targets "2d6;3df;..."] [--sims 30000] [--seed 424242] [--budget MIN]

For each target (default: 2d6, 3dF, binomial:4, the loaded d6
1:3,2:3,3:3,4:3,5:3,6:5 and uniform:3) it times ``diefab design TARGET``
(default options unless --budget is given), validates the die it wrote at
--sims drops on --seed (a seed the design step never used; solid fill),
and runs ``diefab net`` and ``diefab stl`` on it.  The baseline in the same
run is the die the fast model alone designs: the design step's first
simulation, before any correction by simulation (for a two-class die, the
distribution its first tuning drops give at the fast model's shape; a fair
die needs no correction).  Prints one row per target and writes the rows so
far to --results after each.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGETS = ["2d6", "3df", "binomial:4", "1:3,2:3,3:3,4:3,5:3,6:5", "uniform:3"]
HERE = Path(__file__).parent


def _run(*args: str) -> tuple[subprocess.CompletedProcess, float]:
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "diefab", *args], capture_output=True, text=True)
    return proc, time.perf_counter() - t0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--targets", default=";".join(TARGETS), help="targets separated by ;")
    parser.add_argument("--sims", type=int, default=30_000)
    parser.add_argument("--seed", type=int, default=424242)
    parser.add_argument("--budget", type=float, default=None, help="design --budget (default: the command's)")
    parser.add_argument("--out", type=Path, default=None, help="keep the designs here (default: a temp folder)")
    parser.add_argument("--results", type=Path, default=HERE / "results" / "design.json", help="JSON rows")
    args = parser.parse_args()
    targets = [t for t in args.targets.split(";") if t]
    out = args.out or Path(tempfile.mkdtemp(prefix="bench-design-"))
    print(f"design then validate ({args.sims} drops, seed {args.seed}, solid fill), net, stl; "
          f"{os.cpu_count()} cores; output in {out}", flush=True)  # fmt: skip
    print(f"{'target':26s} {'family':14s} {'method':9s} {'faces':>5s} {'design s':>9s} {'fast-only TVD':>13s} "
          f"{'TVD':>7s} {'p':>8s} {'net':>4s} {'stl':>4s}", flush=True)  # fmt: skip
    rows = []
    for target in targets:
        extra = ["--budget", str(args.budget)] if args.budget else []
        proc, seconds = _run("design", target, "--out", str(out), "--json", *extra)
        if proc.returncode != 0:
            print(f"{target:26s} design failed: {proc.stderr.strip()}", flush=True)
            rows.append({"target": target, "error": proc.stderr.strip(), "design_seconds": seconds})
            _save(rows, args.results)
            continue
        report = json.loads(proc.stdout)
        path = report["design_file"]
        val, _ = _run("validate", path, "--sims", str(args.sims), "--seed", str(args.seed), "--fill", "solid",
                      "--json")  # fmt: skip
        fit = json.loads(val.stdout) if val.returncode == 0 else {"tvd": float("nan"), "p_value": float("nan")}
        net, _ = _run("net", path, "--out", str(out))
        stl, _ = _run("stl", path, "--out", str(out))
        steps = report.get("refinement") or []
        baseline = steps[0]["simulated_tvd"] if steps else float("nan")
        row = {
            "target": target, "family": report["family"], "method": report.get("method", "shaped"),
            "faces": len(report["values"]),
            "transitional": len(report["faces"]) - len(report["values"]), "design_seconds": seconds,
            "fast_only_tvd": baseline, "tvd": fit["tvd"], "p_value": fit["p_value"], "drops": args.sims,
            "seed": args.seed, "net_ok": net.returncode == 0, "stl_ok": stl.returncode == 0,
            "net_error": net.stderr.strip()[-300:] if net.returncode else "",
            "stl_error": stl.stderr.strip()[-300:] if stl.returncode else "",
            "params": report["params"], "values": report["values"], "design_file": path,
        }  # fmt: skip
        rows.append(row)
        _save(rows, args.results)
        print(f"{target:26s} {row['family']:14s} {row['method']:9s} {row['faces']:5d} {seconds:9.0f} {baseline:13.4f} "
              f"{row['tvd']:7.4f} {row['p_value']:8.3g} {'ok' if row['net_ok'] else 'FAIL':>4s} "
              f"{'ok' if row['stl_ok'] else 'FAIL':>4s}", flush=True)  # fmt: skip
    _save(rows, args.results)
    return 0


def _save(rows: list[dict], path: Path) -> None:
    """Write the rows so far (an interrupted run keeps the targets it finished)."""
    from diefab.core.files import atomic_write

    path.parent.mkdir(exist_ok=True)
    atomic_write(path, json.dumps(rows, indent=2) + "\n")


if __name__ == "__main__":
    sys.exit(main())
