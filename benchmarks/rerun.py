"""Run again the commands a saved benchmark output holds, and show where this commit's output differs.

    python benchmarks/rerun.py benchmarks/results/bench_throw_flat.txt           # differences only
    python benchmarks/rerun.py benchmarks/results/bench_throw_flat.txt --write   # and save the new output
    python benchmarks/rerun.py --docs                                            # the docs' console blocks

A saved output names its commands on lines that start with ``$ `` (one or
several sections).  Each is run again from the repository's root and its
output compared with the saved section, line by line, with times (``12 s``,
``(3 s)``) and the machine's load masked, so that what remains is the
figures.  Exit status 0 when every section reproduces, 1 when one differs
(``--write`` then replaces the file, atomically, with the new output under
the same command lines).  Most benchmarks replay their simulations from
their caches, so a rerun takes seconds to minutes.

``--docs`` does the same for the console blocks of the README and the docs
(``$ diefab ...`` and the lines the page quotes, ``...`` for lines left
out), page by page in a fresh folder: every quoted line must be a line of
this commit's output, figures and all.  The docs test allows simulated
figures a Monte-Carlo tolerance, so that another platform passes; this is
the check that the figures are this commit's.  A command does what it
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
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Wall times, load and what the cache held: they change from run to run and are not figures of the benchmark.
VOLATILE = re.compile(
    r"\d[\d,]*(\.\d+)?\s?(µs|us|ms|s|seconds|minutes)\b|load( average)? \d+(\.\d+)?|[\d,]+ drops simulated|"
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


def console_sections(page: str) -> list[tuple[str, list[str]]]:
    """(command, quoted lines) of each ``$ diefab`` line of a page's ``console`` code blocks, in order."""
    found: list[tuple[str, list[str]]] = []
    inside, current = False, None
    for line in page.splitlines():
        if line.startswith("```"):
            inside, current = line.strip() == "```console", None
        elif inside and line.startswith("$ "):
            current = (line[2:].strip(), [])
            found.append(current)
        elif inside and current is not None:
            current[1].append(line)
    return [(command, quoted) for command, quoted in found if command.startswith("diefab ")]


def masked(lines: list[str]) -> list[str]:
    """The lines with times and load masked and blank lines at either end dropped."""
    out = [VOLATILE.sub("<t>", line.rstrip()) for line in lines]
    while out and not out[0]:
        out.pop(0)
    while out and not out[-1]:
        out.pop()
    return out


def run(command: str, cwd: Path = ROOT) -> list[str]:
    """The output (stdout and stderr) of one saved command, run by bash in `cwd`.

    ``python`` in it is this interpreter and ``diefab`` this checkout's: the saved commands are shell
    lines (some are loops).
    """
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}",
           "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}  # fmt: skip
    env.pop("COLUMNS", None)
    if command.startswith("diefab "):
        command = "python -m " + command
    done = subprocess.run(["bash", "-c", command], cwd=cwd, capture_output=True, text=True, env=env)
    return (done.stdout + done.stderr).splitlines()


def check_docs(pages: list[Path]) -> int:
    """Run each page's console blocks in a fresh folder; print every quoted line this commit does not print."""
    differs = 0
    for page in pages:
        shown = console_sections(page.read_text(encoding="utf-8"))
        if not shown:
            continue
        with tempfile.TemporaryDirectory() as cwd:
            for command, quoted in shown:
                now = {" ".join(line.split()) for line in run(command, Path(cwd))}
                missing = [q for q in quoted if q.strip() not in ("", "...") and " ".join(q.split()) not in now]
                print(f"{page.relative_to(ROOT)}: $ {command}: " + (f"{len(missing)} quoted lines differ"
                      if missing else "reproduces"), flush=True)  # fmt: skip
                for line in missing:
                    print(f"    {line}")
                differs += bool(missing)
    return 1 if differs else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("saved", type=Path, nargs="?", help="a saved output under benchmarks/results/")
    parser.add_argument("--write", action="store_true", help="replace the saved output when it differs")
    parser.add_argument("--docs", action="store_true", help="check the console blocks of the README and docs/")
    args = parser.parse_args()
    if args.docs:
        if args.saved is not None or args.write:
            parser.error("--docs takes no saved output and no --write")
        return check_docs([ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))])
    if args.saved is None:
        parser.error("name a saved output, or --docs")
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
