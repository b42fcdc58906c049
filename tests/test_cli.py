"""The command line: outputs, JSON keys, and one-line errors with exit status 2."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from diefab.dice.design import load_design

TABLE2 = "0,20,48,80,89,83,66,17,2"


def test_templates_lists_every_template(run):
    code, out, _ = run("templates")
    assert code == 0
    assert "fudge-gem " in out and "fudge-gem-solid-angle" in out


def test_predict_json(run):
    code, out, _ = run("predict", "fudge-gem", "--json")
    assert code == 0
    data = json.loads(out)
    assert [f["name"] for f in data["faces"]] == [f"f{k}" for k in range(1, 10)]
    assert set(data["values"]) == {str(v) for v in range(-4, 5)}
    assert sum(data["values"].values()) == pytest.approx(1)
    assert len(data["center_of_mass"]) == 3 and set(data["margins"]) == {f"f{k}" for k in range(1, 10)}
    assert data["objective"] > 0


def test_predict_param_override_and_fill(run):
    _, out, _ = run("predict", "fudge-gem", "--param", "a=1.3", "--fill", "shell", "--json")
    data = json.loads(out)
    assert data["params"]["a"] == 1.3 and data["fill"] == "shell"


def test_predict_human_output(run):
    code, out, _ = run("predict", "fudge-gem-solid-angle")
    assert code == 0 and "Eq. (2) objective" in out


def test_stats_on_table2(run):
    code, out, _ = run("stats", "--counts", TABLE2, "--target", "4df", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["n"] == 405
    assert data["chi2"] == pytest.approx(12.94, abs=0.01)
    assert data["p_value"] == pytest.approx(0.11, abs=0.01)
    assert data["tvd"] == pytest.approx(0.047, abs=0.001)
    assert data["jsd"] == pytest.approx(0.0068, abs=0.0001)
    assert data["expected_tvd"] == pytest.approx(0.056, abs=0.001)
    assert data["expected_jsd"] == pytest.approx(0.0025, abs=0.0001)
    assert set(data["intervals"]) == {str(v) for v in range(-4, 5)}
    for key in ("g", "p_value_mc", "rolls_for_80_percent_power"):
        assert key in data


def test_stats_from_a_roll_log(run, tmp_path):
    log = tmp_path / "rolls.txt"
    log.write_text("\n".join(["0"] * 19 + ["1"] * 16 + ["-1"] * 16 + ["2"] * 10 + ["-2"] * 10 + ["3", "-3"] * 4))
    code, out, _ = run("stats", "--rolls", log, "--target", "4df", "--json")
    assert code == 0
    assert json.loads(out)["n"] == 79


def test_stats_scores_each_landing_model_of_the_design_against_the_rolls(run):
    from diefab.models.probabilities import value_probabilities

    die = load_design("fudge-gem")
    fast = value_probabilities(die, "fast")
    counts = np.round(fast * 100_000).astype(int)  # rolls that follow the fast model to within rounding
    code, out, err = run("stats", "--counts", ",".join(map(str, counts)), "--design", "fudge-gem", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["target"] == "4df" and data["design"] == "fudge-gem"  # the design's own target
    models = data["models"]
    assert set(models) == {"solid-angle", "basins", "fast"} and sum(m["to_trust"] for m in models.values()) == 1
    assert models["fast"]["tvd"] < 1e-4 and models["fast"]["p_value"] > 0.99
    assert models["solid-angle"]["tvd"] > 0.1 and models["solid-angle"]["p_value"] < 1e-6
    for m in models.values():  # each TVD is the one between the frequencies and the model's prediction
        predicted = np.array(m["predicted"])
        assert m["tvd"] == pytest.approx(0.5 * np.abs(counts / counts.sum() - predicted).sum())
        assert 0 < m["expected_tvd"] < 0.01  # the noise of 100,000 rolls


def test_validate_scores_the_simulation_against_real_rolls(run, tmp_path):
    log = tmp_path / "rolls.txt"
    log.write_text("\n".join(str(v) for v in [1, 2, 3, 4, 5, 6] * 5 + [6] * 10))
    code, out, err = run("validate", "d6", "--sims", "60", "--workers", "1", "--rolls", log, "--json")
    assert code == 0, err
    data = json.loads(out)
    real = data["real_rolls"]
    assert real["n"] == 40 and real["counts"] == {"1": 5, "2": 5, "3": 5, "4": 5, "5": 5, "6": 15}
    simulated = np.array([data["counts"][k] for k in map(str, range(1, 7))], dtype=float)
    frequencies = np.array(list(real["counts"].values())) / 40
    assert real["tvd"] == pytest.approx(0.5 * np.abs(frequencies - simulated / simulated.sum()).sum())
    assert 0 < real["noise_tvd"] < 0.3 and 0 <= real["p_value"] <= 1 and real["df"] == 5
    (tmp_path / "seven.txt").write_text("7\n")
    code, _, err = run("validate", "d6", "--sims", "60", "--workers", "1", "--rolls", tmp_path / "seven.txt")
    assert code == 2 and "seven.txt: roll 1 of 1 is 7, not a value of the die" in err
    assert "drops" not in err  # refused before any drop


def test_optimize_writes_a_loadable_template(run, tmp_path):
    code, out, _ = run("optimize", "fudge-gem", "--model", "solid-angle", "--seed", "1", "--out", tmp_path, "--json")
    assert code == 0
    data = json.loads(out)
    assert data["objective"] <= 0.02
    assert set(data["values"]) == {str(v) for v in range(-4, 5)}
    design = load_design(data["design_file"])
    assert design.params == pytest.approx(data["params"])
    design.check_stable(0.0)
    assert [p.name for p in tmp_path.iterdir()] == [os.path.basename(data["design_file"])]


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (("predict", "fudge-gem", "--param", "b=1.3"), "b=1.3 is outside [0.3, 0.9]"),
        (("predict", "fudge-gem", "--param", "a=nan"), "a=nan"),
        (("predict", "fudge-gem", "--param", "a"), "NAME=VALUE"),
        (("predict", "fudge-gem", "--param", "a=1.5"), "unstable"),
        (("predict", "no-such-die"), "unknown template"),
        (("predict", "fudge-gem", "--target", "1,2,3"), "9 values"),
        (("predict", "fudge-gem", "--target", "1,-1,1,1,1,1,1,1,1"), "negative"),
        (("predict", "fudge-gem", "--model", "tea-leaves"), "unknown model"),
        (("stats", "--counts", "1,2,3", "--target", "4df"), "3 counts"),
        (("stats", "--counts", "1,-2,3,1,1,1,1,1,1", "--target", "4df"), "negative"),
        (("stats", "--target", "4df"), "exactly one"),
        (("stats", "--counts", "1,2"), "give --target, or --design"),
        (("stats", "--counts", "1,1,1", "--target", "uniform:3", "--design", "fudge-gem"), "the design's values are"),
        (("stats", "--counts", "1,1,1", "--design", "no-such-die"), "unknown template"),
        (("stats", "--counts", "1,2", "--target", "nonsense"), "unknown target"),
        (("optimize", "fudge-gem", "--min-margin", "-1"), "non-negative"),
        (("optimize", "fudge-gem", "--free", "a,q"), "q is not a parameter"),
        (("optimize", "d6"), "no parameters"),
        (("frobnicate",), "No such command"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(bad, args, needle):
    assert needle in bad(*args)


def test_bad_files(bad, tmp_path):
    broken = tmp_path / "broken.toml"
    broken.write_text('name = "x"\nfamily = "gem"\n[params\n')
    assert "line 3" in bad("predict", broken)
    nonconvex = tmp_path / "dent.toml"
    nonconvex.write_text(
        'name = "dent"\nfamily = "convex"\ntarget = "uniform:4"\n'
        "vertices = [[1,1,1],[1,-1,-1],[-1,1,-1],[-1,-1,1],[0,0,0]]\n"
    )
    assert "convex" in bad("predict", nonconvex)
    flat = tmp_path / "flat.toml"
    flat.write_text(
        'name = "flat"\nfamily = "convex"\ntarget = "uniform:4"\nvertices = [[0,0,0],[1,0,0],[0,1,0],[1,1,0]]\n'
    )
    assert "degenerate" in bad("predict", flat) or "volume" in bad("predict", flat)
    family = tmp_path / "family.toml"
    family.write_text('name = "x"\nfamily = "blob"\n')
    assert "unknown family" in bad("predict", family)
    assert "does not exist" in bad("predict", tmp_path / "missing.toml")
    empty = tmp_path / "empty.txt"
    empty.write_text("")
    assert "empty" in bad("stats", "--rolls", empty, "--target", "4df")
    garbled = tmp_path / "garbled.txt"
    garbled.write_text("1 2 3\n4 five 6\n")
    assert ":2" in bad("stats", "--rolls", garbled, "--target", "4df")


@pytest.mark.skipif(os.geteuid() == 0, reason="root can write anywhere")
def test_unwritable_output_folder_as_user(bad, tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    assert "not writable" in bad("optimize", "fudge-gem", "--out", locked / "sub")


def test_output_folder_that_is_a_file(bad, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    line = bad("optimize", "fudge-gem", "--starts", "1", "--out", blocker / "sub")
    assert "output folder" in line
    assert blocker.read_text() == "x"


def test_unwritable_output_folder_even_for_root(bad):
    # /proc refuses new folders whoever asks, root included
    line = bad("optimize", "fudge-gem", "--starts", "1", "--out", "/proc/diefab-out")
    assert "cannot create output folder /proc/diefab-out" in line


def test_fast_model_on_a_fill_without_its_correction_says_it_extrapolates(run, monkeypatch):
    import diefab.models.fills

    code, _, err = run("predict", "fudge-gem", "--model", "fast", "--fill", "print")
    assert code == 0 and "learned on solid gems" not in err  # every made fill has its own correction
    monkeypatch.setattr(diefab.models.fills, "fill_discrepancy", lambda kind: None)
    code, out, err = run("predict", "fudge-gem", "--model", "fast", "--fill", "print", "--json")
    assert code == 0
    assert json.loads(out)["fill"] == "print"
    assert "learned on solid gems" in err and len(err.strip().splitlines()) == 1
    code, _, err = run("predict", "fudge-gem", "--model", "fast")
    assert code == 0 and "learned on solid gems" not in err


def test_a_bare_diefab_prints_its_help(run):
    code, out, err = run()
    assert code == 0 and not err
    assert out.startswith("Usage: diefab") and "Commands:" in out
