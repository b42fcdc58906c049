"""Run again the commands a saved benchmark output holds, and show where this commit's output differs.

    python benchmarks/rerun.py benchmarks/results/bench_throw_flat.txt           # differences only
    python benchmarks/rerun.py benchmarks/results/bench_throw_flat.txt --write   # and save the new output

A saved output names its commands on lines that start with ``$ `` (one or
several sections).  Each is run again from the repository's root and its
output compared with the saved section, line by line, with times (``12 s``,
``(3 s)``) and the machine's load masked, so that what remains is the
figures.  Exit status 0 when every section reproduces, 1 when one differs
(``--write`` then replaces the file, atomically, with the new output under
the same command lines).  Most benchmarks replay their simulations from
their caches, so a rerun takes seconds to minutes.  A command does what it
did when it was saved: one that records (``bench_realrolls.py --guard
--record``) records again, and one that keeps a record of its own (``*.json``
beside the output) rewrites it.
"""

from __future__ import annotations

import argparse
import difflib
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Wall times, load and what the cache held: they change from run to run and are not figures of the benchmark.
VOLATILE = re.compile(
    r"\d[\d,]*(\.\d+)?\s?(ms|s|seconds|minutes)\b|load( average)? \d+(\.\d+)?|[\d,]+ drops simulated|"
    r"\(\d+ replayed\)|[\d.]+ drops/s|wall time .*"
)


def sections(text: str) -> list[tuple[str, list[str]]]:
    """(command, output lines) for each ``$ `` line of a saved output."""
    found: list[tuple[str, list[str]]] = []
    for line in text.splitlines():
        if line.startswith("$ "):
            found.append((line[2:].strip(), []))
        elif found:
            found[-1][1].append(line)
    return found


def masked(lines: list[str]) -> list[str]:
    """The lines with times and load masked and blank lines at either end dropped."""
    out = [VOLATILE.sub("<t>", line.rstrip()) for line in lines]
    while out and not out[0]:
        out.pop(0)
    while out and not out[-1]:
        out.pop()
    return out


def run(command: str) -> list[str]:
    """The output (stdout and stderr) of one saved command, run by bash from the repository's root.

    ``python`` in it is this interpreter: the saved commands are shell lines (some are loops).
    """
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"}
    done = subprocess.run(["bash", "-c", command], cwd=ROOT, capture_output=True, text=True, env=env)
    return (done.stdout + done.stderr).splitlines()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("saved", type=Path, help="a saved output under benchmarks/results/")
    parser.add_argument("--write", action="store_true", help="replace the saved output when it differs")
    args = parser.parse_args()
    if not args.saved.is_file():
        parser.error(f"no file {args.saved}")
    found = sections(args.saved.read_text())
    if not found:
        parser.error(f"{args.saved} names no command (no line starting with '$ ')")

    differs, fresh = False, []
    for command, saved in found:
        print(f"$ {command}", flush=True)
        now = run(command)
        diff = list(difflib.unified_diff(masked(saved), masked(now), "saved", "this commit", lineterm="", n=0))
        print("\n".join(diff) if diff else "  reproduces", flush=True)
        differs |= bool(diff)
        fresh.append(f"$ {command}\n" + "\n".join(now).rstrip("\n") + "\n")
    if differs and args.write:
        part = args.saved.with_name(args.saved.name + ".part")
        part.write_text("\n".join(fresh))
        part.replace(args.saved)
        print(f"wrote {args.saved}")
    return 1 if differs else 0


if __name__ == "__main__":
    raise SystemExit(main())
