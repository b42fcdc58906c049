"""The installed package is the package: every subpackage and data file is named in pyproject.toml."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Files kept beside the package but read only by benchmarks/ (the fast model's training set).
NOT_INSTALLED = {"data/correction-training.jsonl"}
SETUP = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]


def test_every_subpackage_is_installed():
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "diefab").rglob("__init__.py")}
    assert found <= set(SETUP["packages"])


def test_every_data_file_is_installed():
    data = {f for f in (ROOT / "diefab").rglob("*") if f.is_file() and f.suffix not in (".py", ".pyc")}
    data = {f for f in data if "__pycache__" not in f.parts}
    data -= {ROOT / "diefab" / name for name in NOT_INSTALLED}
    covered = set()
    for package, patterns in SETUP["package-data"].items():
        base = ROOT / Path(*package.split("."))
        covered |= {f for pattern in patterns for f in base.glob(pattern)}
    assert data <= covered
