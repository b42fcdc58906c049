"""Every place of a stored run, every hostile value: a resume ends in exit 0 or one line and exit 2.

The property test (``tests/test_resume_fuzz.py``) draws random corruptions;
this sweep is exhaustive over a grid instead.  It makes one finished
calibration run and one finished optimization run (two evaluations each, in
a temporary folder), then, for every place in their ``run.json`` and in each
line of their log (each key and list entry, at any depth, and the whole
document) and each value of :data:`VALUES`, writes that value there (in
``run.json`` with and without rewriting ``identity.json`` to match, as
someone who edits both files would), resumes the run in-process and records
the exit status.  Any exit status other than 0 or 2,
an "internal error" or more than one line on stderr is printed and makes the
exit status 1::

    python benchmarks/resume_sweep.py                    # both runs, about a minute
    python benchmarks/resume_sweep.py --runs calibrate
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import shutil
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

#: What is written at each place: wrong types, the ends of the number line, and text that is markup or a path.
VALUES = [
    None, True, False, 0, 1, -1, 0.5, 10**20, -(10**20), 10**30, 2**63, -(2**63), 9.3e18, 1e16, 1e308, -1e308,
    float("nan"), float("inf"), "", "x", "5", "{x}[/bold]", "../../x", [], {}, [1, 2], [1e308], [float("nan")],
]  # fmt: skip
COMMON = ["--workers", "1", "--json"]
#: The run's log of evaluations.
LOG = "evaluations.jsonl"


def run(*args) -> tuple[int, str, str]:
    """``diefab ARGS...`` in-process: (exit status, stdout, stderr)."""
    from diefab.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main([str(a) for a in args])
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        else:
            code = 0
    return code, out.getvalue(), err.getvalue()


def places(node, prefix=()):
    """Every place in a JSON tree, as a tuple of keys and indices (the root first)."""
    yield prefix
    if isinstance(node, dict):
        for key, value in node.items():
            yield from places(value, (*prefix, key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from places(value, (*prefix, i))


def put(tree, place, value):
    """`tree` with `value` at `place` (a copy)."""
    if not place:
        return value
    tree = json.loads(json.dumps(tree))
    parent = tree
    for key in place[:-1]:
        parent = parent[key]
    parent[place[-1]] = value
    return tree


def make_runs(root: Path) -> dict[str, tuple[Path, list[str]]]:
    """A finished calibration and optimization run of two evaluations each, and the command that resumes each."""
    code, _, err = run("calibrate", "--die", "d6", "10,11,9,10,12,8", "--free", "restitution", "--sims-per-eval",
                       "20", "--max-evals", "2", "--name", "c", "--out", root, *COMMON)  # fmt: skip
    if code != 0:
        raise SystemExit(f"resume_sweep: the calibration run failed: {err.strip()}")
    code, _, err = run("optimize", "fudge-gem", "--model", "simulation", "--start", "design", "--sims-per-eval", "16",
                       "--max-evals", "2", "--name", "o", "--out", root, *COMMON)  # fmt: skip
    if code != 0:
        raise SystemExit(f"resume_sweep: the optimization run failed: {err.strip()}")
    return {"calibrate": (root / "c", ["calibrate"]),
            "optimize": (root / "o", ["optimize", "fudge-gem", "--model", "simulation"])}  # fmt: skip


def edits(folder: Path):
    """(file, place, value, new text, new identity or None) for every place and value of run.json and each log line."""
    from diefab.search.runid import identity_text

    tree = json.loads((folder / "run.json").read_text())
    for place in places(tree):
        for value in VALUES:
            text = json.dumps(put(tree, place, value))
            yield "run.json", place, value, text, None
            try:
                identity = identity_text(text)
            except Exception:  # what is no JSON object has no identity to write
                continue
            yield "run.json", place, value, text, identity
    lines = (folder / LOG).read_text().splitlines()
    for number, line in enumerate(lines):
        record = json.loads(line)
        for place in places(record):
            for value in VALUES:
                edited = [*lines[:number], json.dumps(put(record, place, value)), *lines[number + 1 :]]
                yield LOG, (f"line {number + 1}", *place), value, "\n".join(edited) + "\n", None


def sweep(folder: Path, command: list[str], scratch: Path) -> tuple[Counter, list[str]]:
    """Exit statuses over every edit of :func:`edits`, and the edits that broke the promise."""
    statuses: Counter = Counter()
    broken = []
    for name, place, value, text, identity in edits(folder):
        copy = scratch / folder.name
        shutil.rmtree(copy, ignore_errors=True)
        shutil.copytree(folder, copy)
        (copy / name).write_text(text)
        if identity is not None:
            (copy / "identity.json").write_text(identity)
        code, _, err = run(*command, "--resume", copy, "--max-evals", "2", *COMMON)
        statuses[name, code] += 1
        lines = err.strip().splitlines()
        if code not in (0, 2) or "internal error" in err or (code == 2 and len(lines) != 1):
            where = "/".join(map(str, place)) or "(root)"
            how = " (identity rewritten)" if identity is not None else ""
            broken.append(f"{name}: {where} = {value!r}{how}: exit {code}: {lines[-1:]}")
    return statuses, broken


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", default="calibrate,optimize", help="which runs to sweep (default: both)")
    args = ap.parse_args(argv)
    kinds = [k for k in args.runs.split(",") if k]
    if not kinds or any(k not in ("calibrate", "optimize") for k in kinds):
        print(f"resume_sweep: --runs {args.runs!r} must name calibrate and/or optimize", file=sys.stderr)
        return 2
    failed = False
    with tempfile.TemporaryDirectory(prefix="diefab-sweep-") as tmp:
        runs = make_runs(Path(tmp) / "runs")
        for kind in kinds:
            start = time.monotonic()
            folder, command = runs[kind]
            statuses, broken = sweep(folder, command, Path(tmp))
            for name in ("run.json", LOG):
                counts = {code: n for (file, code), n in sorted(statuses.items()) if file == name}
                shares = ", ".join(f"exit {c}: {n:,}" for c, n in counts.items())
                print(f"{kind} run, {name} edited: {sum(counts.values()):,} resumes ({shares})", flush=True)
            print(f"{kind} run: broken {len(broken)} ({time.monotonic() - start:.0f} s)", flush=True)
            for line in broken:
                print(f"  {line}")
            failed |= bool(broken)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
