"""The limit of what diefab design can do, measured over a wide set of targets.

    nice -n 10 python benchmarks/bench_targets.py                 # every target not yet measured
    nice -n 10 python benchmarks/bench_targets.py 2d6 3d6         # only these
    nice -n 10 python benchmarks/bench_targets.py --drops 10000   # a quicker closing check

For each target, at default options but for the closing check's size
(``python -m diefab design TARGET --seed 1 --validate-sims 30000 --json``),
it records the die (family, face count, how it carries the target), the
wall time of the design and its closing check, the TVD of that check (30,000
drops on a seed the search never used), the exit status and stderr of
``design`` (status 3 and a plain verdict when the TVD is above the default
tolerance 0.02), the commit it ran on, and the best TVD any fair or
two-class die of at most 60 steady faces reaches by exact arithmetic
(:func:`diefab.search.counting.nearest_dice`).  Rows measured before the
closing check took 30,000 drops were validated by ``python -m diefab
validate DIE --sims 30000 --seed 7`` instead (their ``check`` says so).
Each target's row is written to ``benchmarks/results/targets.json`` as it
finishes, so the run resumes where it stopped; ``--table`` prints the
Markdown table of what is there.
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

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
RESULTS = ROOT / "benchmarks" / "results" / "targets.json"
TEMPLATES = ROOT / "benchmarks" / "results" / "templates.json"
TARGETS = [
    "2d4", "2d6", "3d6", "2d8", "2d10", "4dF", "3dF",
    *(f"binomial:{n}" for n in range(3, 9)),
    *(f"uniform:{n}" for n in range(3, 13)),
    "1:3,2:3,3:3,4:3,5:3,6:5",  # a loaded d6
    "1:32,2:16,3:8,4:4,5:2,6:1",  # geometric, ratio 1/2
    "1:4,2:2,3:1,4:1,5:2,6:4",  # bimodal
    "1:1,2:2,3:3,4:4,5:5,6:6",
]  # fmt: skip
SEED = 1
CHECK_SEED = 7


def _diefab(args: list[str]) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "diefab", *args], cwd=ROOT, capture_output=True, text=True)


def counted(target: str) -> dict | None:
    """The fair or two-class die of at most 60 steady faces nearest `target`, by exact arithmetic."""
    from diefab.dice.targets import parse_target
    from diefab.search.counting import nearest_dice

    best = nearest_dice(parse_target(target))
    if not best:
        return None
    family = best[0].plan.family if best[0].plan is not None else None
    return {"kind": best[0].kind, "faces": best[0].faces, "tvd": float(best[0].tvd), "family": family}


def commit() -> str:
    """The commit this checkout is on, ``+dirty`` when tracked files other than results have changes."""
    git = lambda *a: subprocess.run(["git", *a], cwd=ROOT, capture_output=True, text=True).stdout.strip()  # noqa: E731
    changed = git("status", "--porcelain", "-uno", "--", ".", ":!benchmarks/results")
    return git("rev-parse", "--short", "HEAD") + ("+dirty" if changed else "")


def measure(target: str, drops: int, nearest: dict | None = None) -> dict:
    """Design `target` at default options with a closing check of `drops` drops; `nearest` as from :func:`counted`."""
    nearest = nearest or counted(target)
    row = {"target": target, "nearest_counted": nearest, "cpus": os.cpu_count(), "commit": commit(),
           "load_average": round(os.getloadavg()[0], 1)}  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.monotonic()
        done = _diefab(["design", target, "--seed", str(SEED), "--validate-sims", str(drops), "--out", tmp, "--json"])
        seconds = round(time.monotonic() - t0, 1)
    stderr = done.stderr.strip()
    if done.returncode not in (0, 3):
        return {**row, "error": (stderr.splitlines() or ["?"])[-1], "design_seconds": seconds}
    report = json.loads(done.stdout)
    v = report["validated"]
    return {
        **row,
        "family": report["family"],
        "faces": len(report["values"]),
        "method": report["method"],
        "design_seconds": seconds,
        "check": f"design closing check, {drops} drops",
        "validated_drops": v["n"],
        "validated_tvd": v["tvd"],
        "expected_tvd": v.get("expected_tvd"),
        "exit": done.returncode,
        "verdict": report["verdict"],
        "stderr": stderr,
    }


def from_templates(results: dict) -> list[str]:
    """Copy into `results` the templates designed at this benchmark's options (same command, same die)."""
    made = json.loads(TEMPLATES.read_text()) if TEMPLATES.is_file() else {}
    copied = []
    for r in made.values():
        target = r.get("target")
        same = f"python -m diefab design {target} --seed {SEED} --validate-sims 30000 --name "
        if target not in TARGETS or "family" in results.get(target, {}) or not r.get("command", "").startswith(same):
            continue
        if len(r["command"][len(same) :].split()) != 1:  # more options than the name
            continue
        results[target] = {**results.get(target, {}), "target": target, "commit": r.get("commit"),
                           "family": r["family"], "faces": r["faces"], "method": r["method"],
                           "design_seconds": r["design_seconds"], "check": "design closing check, 30000 drops "
                           "(benchmarks/make_templates.py)", "validated_drops": r["validated_drops"],
                           "validated_tvd": r["validated_tvd"], "exit": r["exit"],
                           "verdict": r.get("verdict")}  # fmt: skip
        copied.append(target)
    return copied


def _save(results: dict) -> None:
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    part = RESULTS.with_suffix(".json.part")
    part.write_text(json.dumps(results, indent=2) + "\n")
    part.replace(RESULTS)


def table(results: dict) -> str:
    rows = ["| target | die | faces | design s | validated TVD (drops) | exit | commit "
            "| nearest counted die (exact TVD) |", "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for target in TARGETS:
        r = results.get(target)
        if r is None:
            continue
        n = r.get("nearest_counted")
        shape = f" {n['family']}" if n and n.get("family") == "icosahedral" else ""
        near = f"{n['faces']}-face{shape} {n['kind']}, {n['tvd']:.4f}" if n else "none"
        if "family" not in r and "error" not in r:
            rows.append(f"| {target} | not yet measured | | | | | | {near} |")
            continue
        if "error" in r:
            rows.append(f"| {target} | refused: {r['error']} | | {r['design_seconds']:.0f} | | 2 "
                        f"| {r.get('commit', '—')} | {near} |")  # fmt: skip
            continue
        tvd = "—" if r["validated_tvd"] is None else f"{r['validated_tvd']:.4f} ({r['validated_drops']})"
        rows.append(f"| {target} | {r['family']} ({r['method']}) | {r['faces']} | {r['design_seconds']:.0f} | {tvd} "
                    f"| {r.get('exit', '—')} | {r.get('commit', '—')} | {near} |")  # fmt: skip
    return "\n".join(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("targets", nargs="*", help="Targets to measure (default: all not yet measured)")
    parser.add_argument("--drops", type=int, default=30_000, help="Drops of the validation (default 30000)")
    parser.add_argument("--force", action="store_true", help="Measure again targets already measured")
    parser.add_argument("--table", action="store_true", help="Print the Markdown table of the results and stop")
    parser.add_argument("--from-templates", action="store_true",
                        help="Copy the rows of templates designed at these options and stop")  # fmt: skip
    parser.add_argument("--counted-only", action="store_true",
                        help="Only the nearest counted die of each target (exact arithmetic, no drops)")  # fmt: skip
    args = parser.parse_args()
    results = json.loads(RESULTS.read_text()) if RESULTS.is_file() else {}
    if args.table:
        print(table(results))
        return
    if args.from_templates:
        copied = from_templates(results)
        _save(results)
        print(table({t: results[t] for t in copied}))
        return
    if args.counted_only:
        for target in args.targets or TARGETS:
            results.setdefault(target, {"target": target})["nearest_counted"] = counted(target)
            print(table({target: results[target]}).splitlines()[-1], flush=True)
        _save(results)
        return
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}; validation at {args.drops} drops",
          flush=True)  # fmt: skip
    for target in args.targets or TARGETS:
        if ("family" in results.get(target, {}) or "error" in results.get(target, {})) and not args.force:
            continue
        results[target] = measure(target, args.drops, results.get(target, {}).get("nearest_counted"))
        _save(results)
        print(table({target: results[target]}).splitlines()[-1], flush=True)
    print(table(results))


if __name__ == "__main__":
    main()
