"""Property: any corruption of a run folder ends in a correct resume or one line and exit 2, never exit 1.

Random byte edits (replace, insert, cut, truncate) and JSON edits (any value at any place) of
``run.json``, ``identity.json`` and ``evaluations.jsonl``; half the ``run.json`` edits also rewrite
the identity, as someone who edits both files would, so that what lies behind the identity check
(the run's own validation) is fuzzed too.
"""

from __future__ import annotations

import contextlib
import importlib.util
import json
import os
import shutil
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from diefab.search.runid import identity_text

_SPEC = importlib.util.spec_from_file_location("resume_sweep", Path(__file__).parent.parent / "benchmarks" /
                                               "resume_sweep.py")  # fmt: skip
sweep = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(sweep)
places, put, _run = sweep.places, sweep.put, sweep.run  # the places the exhaustive sweep edits, and how it runs

FILES = ["run.json", "identity.json", "evaluations.jsonl"]
COMMON = ["--workers", "1", "--json"]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Two finished runs of two evaluations each: a calibration and an optimization."""
    root = tmp_path_factory.mktemp("runs")
    code, _, err = _run("calibrate", "--die", "d6", "10,11,9,10,12,8", "--free", "restitution", "--sims-per-eval",
                        "20", "--max-evals", "2", "--name", "c", "--out", root, *COMMON)  # fmt: skip
    assert code == 0, err
    code, _, err = _run("optimize", "fudge-gem", "--model", "simulation", "--start", "design", "--sims-per-eval", "16",
                        "--max-evals", "2", "--name", "o", "--out", root, *COMMON)  # fmt: skip
    assert code == 0, err
    return {"calibrate": (root / "c", ["calibrate"]),
            "optimize": (root / "o", ["optimize", "fudge-gem", "--model", "simulation"])}  # fmt: skip


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(min_value=-(10**30), max_value=10**30)
    | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=12)
    | st.sampled_from([10**20, 10**29, -1, 0, 1e308, "\udcff", "{x}[/bold]", "../../x", ""]),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
    max_leaves=6,
)  # fmt: skip


@st.composite
def mutations(draw):
    """(file, function bytes -> bytes, rewrite the identity too)."""
    name = draw(st.sampled_from(FILES))
    kind = draw(st.sampled_from(["replace", "insert", "cut", "truncate", "json", "json"]))
    seed = draw(st.integers(0, 2**32 - 1))
    value = draw(JSON_VALUES)
    data = draw(st.binary(min_size=1, max_size=8))
    resign = draw(st.booleans())

    def mutate(raw: bytes) -> bytes:
        n = max(len(raw), 1)
        at = seed % n
        if kind == "replace":
            return raw[:at] + data + raw[at + len(data) :]
        if kind == "insert":
            return raw[:at] + data + raw[at:]
        if kind == "cut":
            return raw[:at] + raw[at + 1 + seed % 7 :]
        if kind == "truncate":
            return raw[:at]
        lines = raw.split(b"\n") if name.endswith(".jsonl") else [raw]
        line = (seed // n) % max(len(lines), 1)
        try:
            tree = json.loads(lines[line])
        except ValueError:
            return raw + data
        where = list(places(tree))
        lines[line] = json.dumps(put(tree, where[(seed // 7) % len(where)], value)).encode("utf-8", "surrogatepass")
        return b"\n".join(lines)

    return name, kind, mutate, resign


def _check(folder: Path, command: list[str], tmp: Path, mutation) -> None:
    name, kind, mutate, resign = mutation
    copy = tmp / folder.name
    shutil.rmtree(copy, ignore_errors=True)
    shutil.copytree(folder, copy)
    target = copy / name
    target.write_bytes(mutate(target.read_bytes()))
    if resign and name == "run.json":
        with contextlib.suppress(Exception):  # text that is no JSON object has no identity
            (copy / "identity.json").write_text(identity_text(target.read_bytes().decode("utf-8")))
    code, out, err = _run(*command, "--resume", copy, "--max-evals", "2", *COMMON)
    event(f"exit {code}")
    assert code in (0, 2), f"{name} {kind}: exit {code}: {err}"
    assert "Traceback" not in err and "internal error" not in err, err
    if code == 2:
        assert len(err.strip().splitlines()) == 1, err
    else:
        report = json.loads(out)
        assert report["evaluations"] == 2 and report["replayed"] <= 2


@pytest.mark.parametrize("kind", ["calibrate", "optimize"])
@settings(
    max_examples=int(os.environ.get("DIEFAB_FUZZ_EXAMPLES", "60")),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(mutation=mutations())
def test_any_corruption_of_a_run_resumes_or_is_one_line(runs, tmp_path, kind, mutation):
    folder, command = runs[kind]
    _check(folder, command, tmp_path, mutation)
