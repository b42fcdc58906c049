"""The package's structure holds by itself: layers import downward only, no module imports itself back."""

from __future__ import annotations

import functools
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@functools.cache
def _graph():
    grimp = pytest.importorskip("grimp")
    sys.path.insert(0, str(ROOT))
    try:
        return grimp.build_graph("diefab", include_external_packages=False)
    finally:
        sys.path.remove(str(ROOT))


def test_layers_contract_is_kept():
    pytest.importorskip("importlinter")
    code = "from importlinter.cli import lint_imports; raise SystemExit(lint_imports())"
    env = {"PYTHONPATH": str(ROOT), "PATH": ""}
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, env=env)
    assert run.returncode == 0, run.stdout + run.stderr


def test_no_module_imports_itself_back():
    graph = _graph()
    circles = sorted(
        (a, b)
        for a in graph.modules
        for b in graph.find_modules_directly_imported_by(a)
        if a < b and graph.find_shortest_chain(importer=b, imported=a)
    )
    assert circles == []


def test_imports_are_not_deferred_to_hide_a_layer():
    """An import inside a function is for a heavy optional library, never for a module of a higher layer."""
    graph = _graph()
    contract = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"][0]
    rank = {
        name.strip().removeprefix("diefab."): -k
        for k, layer in enumerate(contract["layers"])
        for name in layer.split("|")
    }
    upward = []
    for importer in graph.modules:
        for imported in graph.find_modules_directly_imported_by(importer):
            a, b = importer.split(".")[1:2], imported.split(".")[1:2]
            if a and b and a[0] in rank and b[0] in rank and rank[b[0]] > rank[a[0]]:
                upward.append((importer, imported))
    assert upward == []


def test_package_imports_without_heavy_libraries():
    code = "import sys, diefab; print(sorted({'pybullet', 'manifold3d', 'matplotlib', 'trimesh'} & set(sys.modules)))"
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    assert run.stdout.strip() == "[]"
