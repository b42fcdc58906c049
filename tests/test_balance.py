"""Every output checks itself: the made die's distribution against its target, and the material settings."""

from __future__ import annotations

import json

import numpy as np
import pytest

from diefab.dice.design import load_design
from diefab.models.balance import TVD_SLACK, made_balance


def test_a_symmetric_die_stays_balanced_and_a_shifted_centre_warns():
    d6 = load_design("d6")
    fine = made_balance(d6, d6.polyhedron.centroid, "print", "defaults")
    assert fine.predicted_tvd == pytest.approx(0.0, abs=1e-12) and fine.warning is None
    off = made_balance(d6, d6.polyhedron.centroid + [0.0, 0.0, 0.3], "print", "defaults", "d6")
    assert off.predicted_tvd > off.design_tvd + TVD_SLACK
    assert "diefab design uniform:6 --fill print" in off.warning  # a cube has nothing to optimize
    assert f"TVD {off.predicted_tvd:.3f}" in off.warning and "fast model" in off.warning
    assert sum(off.predicted.values()) == pytest.approx(1.0)
    gem = load_design("fudge-gem")
    tilted = made_balance(gem, gem.polyhedron.centroid + [0.2, 0.0, 0.0], "paper", "160 g/m² card", "fudge-gem")
    assert "diefab optimize fudge-gem --fill paper --model simulation" in tilted.warning


def test_net_of_a_solid_design_warns_once_and_json_carries_the_prediction(run, tmp_path):
    code, out, err = run("net", "fudge-gem-sim", "--out", tmp_path, "--json")
    assert code == 0
    report = json.loads(out)
    assert report["model"] == "fast" and set(report["predicted"]) == {str(v) for v in range(-4, 5)}
    assert report["predicted_tvd"] > report["design_tvd"] + TVD_SLACK  # paper with tabs: the apex end gets heavier
    warnings = [line for line in err.splitlines() if line.startswith("diefab: warning:")]
    assert len(warnings) == 1 and "--fill paper" in warnings[0]
    # heavier card of the same thickness scales faces and tabs alike: the centre stays
    code, out, _ = run("net", "fudge-gem-sim", "--out", tmp_path, "--json", "--card", "300", "--card-thickness", "0.2")
    assert json.loads(out)["predicted_tvd"] == pytest.approx(report["predicted_tvd"], abs=1e-9)


def test_stl_reports_the_print_it_writes(run, tmp_path):
    code, out, err = run("stl", "d6", "--out", tmp_path, "--json", "--infill", "0.5")
    assert code == 0
    report = json.loads(out)
    assert report["model"] == "fast" and report["fill"]["infill"] == 0.5
    assert np.isclose(sum(report["predicted"].values()), 1.0)
    assert "warning" not in err  # a cube printed any way rolls nearly fair
    code, out, err = run("stl", "d6", "--out", tmp_path)
    assert "fast model" in out and "as made" in out


@pytest.mark.parametrize(
    "args, word",
    [
        (("stl", "d6", "--perimeters", "0"), "perimeters"),
        (("stl", "d6", "--layer-height", "0.6"), "layer_mm"),
        (("net", "d6", "--card", "nan"), "card_g_m2"),
        (("predict", "d6", "--fill", "print", "--infill", "2"), "infill"),
        (("validate", "d6", "--fill", "paper", "--glue", "-1", "--sims", "10"), "glue_g_m2"),
    ],
)
def test_bad_material_settings_are_one_line_errors(bad, tmp_path, args, word):
    line = bad(*args, *(("--out", tmp_path) if args[0] in ("stl", "net") else ()))
    assert word in line
