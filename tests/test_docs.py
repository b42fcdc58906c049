"""The documentation builds, and every command it shows runs and prints the figures it quotes.

A command is *shown* in a ``console`` code block of the README or a page
under docs/: a line ``$ diefab ...`` followed by the output the docs quote
(``...`` stands for lines left out).  Each quoted line must appear in the
real output with the same words; its numbers must be equal, or, for commands
that simulate (Monte-Carlo), within a tolerance.  The blocks of one page run
in order in one temporary folder, so a page can use the files an earlier
command wrote.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
#: Commands whose figures come from drops (a budget in wall time or another platform may move them a little).
SIMULATING = ("validate", "design", "calibrate", "optimize")
#: Commands that take minutes: their pages are marked slow.
SLOW = ("design", "calibrate", "optimize", "validate")
NUMBER = re.compile(r"[−+-]?\d[\d,]*(?:\.\d+)?")
_SPEC = importlib.util.spec_from_file_location("rerun", ROOT / "benchmarks" / "rerun.py")
_RERUN = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(_RERUN)  # the console blocks are read as benchmarks/rerun.py --docs reads them


def console_blocks(page: Path) -> list[tuple[str, list[str]]]:
    """``[(command, quoted output lines), ...]`` of the page's console blocks, in order."""
    return _RERUN.console_sections(page.read_text(encoding="utf-8"))


def _skeleton(line: str) -> str:
    return " ".join(NUMBER.sub("#", line).split())


def _value(token: str) -> float:
    return float(token.replace("−", "-").replace(",", ""))


def check_quoted(quoted: list[str], actual: str, simulated: bool) -> None:
    """Every quoted line is a line of `actual` with the same words and (nearly) the same numbers."""
    lines = actual.splitlines()
    for line in quoted:
        if not line.strip() or line.strip() == "...":
            continue
        same = [a for a in lines if _skeleton(a) == _skeleton(line)]
        assert same, f"quoted line not in the output:\n{line}\n--- output ---\n{actual}"
        if not simulated:
            assert any(" ".join(a.split()) == " ".join(line.split()) for a in same), (line, same)
            continue
        want = [_value(t) for t in NUMBER.findall(line)]
        assert any(_close(a, want) for a in same), f"figures moved beyond the tolerance:\n{line}\n{same}"


def _close(line: str, want: list[float]) -> bool:
    """The numbers of `line` within 0.02 or 15 % of `want` (Monte-Carlo figures at the docs' sample sizes).

    A p-value (a number after ``p =`` or ``Monte-Carlo``) swings over its whole range between samples of a
    die that is near the target, so it is only checked to be a probability.
    """
    got = [_value(t) for t in NUMBER.findall(line)]
    before = [line[: m.start()].rstrip() for m in NUMBER.finditer(line)]
    pvalues = {k for k, text in enumerate(before) if text.endswith(("p =", "Monte-Carlo"))}
    return all((0 <= g <= 1) if k in pvalues else abs(g - w) <= max(0.02, 0.15 * abs(w))
               for k, (g, w) in enumerate(zip(got, want)))  # fmt: skip


def _is_slow(command: str) -> bool:
    """A command that simulates for minutes, or reads a file that such a command wrote (``out/...``)."""
    return command.split()[1] in SLOW or " out/" in command


def _pages_with_commands():
    """Per page: its quick commands (run in the quick suite), then all of them in order (slow)."""
    for page in PAGES:
        blocks = console_blocks(page)
        name = str(page.relative_to(ROOT))
        quick = [b for b in blocks if not _is_slow(b[0])]
        if quick:
            yield pytest.param(page, quick, id=f"{name}-quick")
        if len(quick) < len(blocks):
            yield pytest.param(page, blocks, id=f"{name}-all", marks=pytest.mark.slow)


def _run_shown(blocks, cwd: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    env.pop("COLUMNS", None)
    for command, quoted in blocks:
        args = command.split()[1:]
        proc = subprocess.run([sys.executable, "-m", "diefab", *args], cwd=cwd, env=env, capture_output=True,
                              text=True, encoding="utf-8", timeout=1800)  # fmt: skip
        assert proc.returncode == 0, f"{command} exited {proc.returncode}: {proc.stderr}"
        check_quoted(quoted, proc.stdout, simulated=args[0] in SIMULATING)


@pytest.mark.parametrize(("page", "blocks"), list(_pages_with_commands()))
def test_every_command_shown_runs_and_prints_what_the_docs_quote(page, blocks, tmp_path):
    _run_shown(blocks, tmp_path)


def test_the_docs_show_commands():
    assert any(console_blocks(p) for p in PAGES)


def test_quoted_figures_are_checked():
    """The checker itself: a changed figure fails, a Monte-Carlo figure within the tolerance passes."""
    check_quoted(["TVD 0.0390 as made", "..."], "x\nTVD 0.0390 as made\n", simulated=False)
    with pytest.raises(AssertionError):
        check_quoted(["TVD 0.0390 as made"], "TVD 0.0391 as made", simulated=False)
    check_quoted(["validated: 10000 drops, TVD 0.0119"], "validated: 10000 drops, TVD 0.0131", simulated=True)
    check_quoted(["TVD 0.0119, p = 0.247"], "TVD 0.0125, p = 0.031", simulated=True)
    with pytest.raises(AssertionError):
        check_quoted(["validated: 10000 drops, TVD 0.0119"], "validated: 10000 drops, TVD 0.0519", simulated=True)


def test_ci_runs_the_readme_s_install_and_test_commands():
    """What a new developer types is what CI runs: the README's developer install and its test command."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    tests = re.search(r"^## Tests\n+```sh\n(.+?)\n```", readme, flags=re.MULTILINE | re.DOTALL)
    assert tests is not None and "\n" not in tests[1], "the README's Tests section shows one command"
    ci = [line.strip() for line in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()]
    assert ci[-1] == tests[1]
    assert 'pip install ".[test]"' in readme and any(line.endswith('pip install ".[test]"') for line in ci)


def test_every_environment_variable_the_package_reads_is_documented():
    """A ``DIEFAB_*`` variable read anywhere in the package has its row in the command-line reference."""
    read = {m for path in (ROOT / "diefab").rglob("*.py")
            for m in re.findall(r"\b(DIEFAB_[A-Z_]+)\b", path.read_text(encoding="utf-8"))}  # fmt: skip
    documented = set(re.findall(r"^\| `(DIEFAB_[A-Z_]+)` \|", (ROOT / "docs" / "reference" / "cli.md").read_text(
        encoding="utf-8"), flags=re.MULTILINE))  # fmt: skip
    assert {"DIEFAB_DASK_STALL", "DIEFAB_DEBUG"} <= read
    assert read <= documented, sorted(read - documented)


def test_the_site_builds_strictly(tmp_path):
    pytest.importorskip("mkdocs")
    pytest.importorskip("material")
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
           "NO_MKDOCS_2_WARNING": "1"}  # fmt: skip
    command = ["mkdocs", "build", "--strict", "-q", "-f", str(ROOT / "mkdocs.yml"), "-d", str(tmp_path / "site")]
    proc = subprocess.run([sys.executable, "-m", *command], cwd=ROOT, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "site" / "reference" / "cli" / "index.html").is_file()
