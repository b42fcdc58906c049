"""Outputs that tell the truth: the model to trust, named models, one face meaning, whole numbers, extras."""

from __future__ import annotations

import json
import sys
import tomllib
from html.parser import HTMLParser

import numpy as np
import pytest

from diefab import design_to_toml, load_design, parse_design
from diefab.core.errors import MissingExtraError
from diefab.core.extras import require
from diefab.models.choice import best_model


def test_best_model_is_fast_for_rigid_drops_and_basins_under_capture():
    assert best_model(load_design("fudge-gem-paper")).name == "fast"
    assert best_model(load_design("d6")).name == "fast"
    choice = best_model(load_design("fudge-gem-print-table"))  # its [physics] has capture_energy 0.81
    assert choice.name == "basins" and "capture" in choice.reason


def test_predict_defaults_to_the_model_to_trust(run):
    code, out, _ = run("predict", "fudge-gem-paper", "--json")
    auto = json.loads(out)
    assert code == 0 and auto["model"] == "fast" and "model_reason" in auto
    _, out, _ = run("predict", "fudge-gem-paper", "--model", "fast", "--json")
    assert json.loads(out)["values"] == auto["values"]
    _, out, _ = run("predict", "fudge-gem-print-table", "--json")
    assert json.loads(out)["model"] == "basins"


def test_predict_tables_name_their_model_and_say_rests_on_and_label_on(run):
    code, out, _ = run("predict", "fudge-gem-paper", "--model", "solid-angle")
    assert code == 0
    assert "Resting faces, solid-angle model" in out and "Values, solid-angle model" in out
    assert "rests on" in out and "label on" in out
    table = out[out.index("Values, solid-angle model") :]
    assert "-0." not in table and "\u22120." in table  # differences carry a true minus sign, as values do


def test_label_faces_are_an_involution_on_the_gem():
    """Resting on fN shows the label on fM, and resting on fM shows the label on fN (the gem's faces pair up)."""
    d = load_design("fudge-gem")
    pairs = {rest: up for rest, up in d.label_face.items() if up is not None}
    assert all(pairs.get(up) == rest for rest, up in pairs.items())


@pytest.mark.parametrize("name", ["d6", "fudge-gem-paper", "fudge-gem-print"])
def test_toml_writes_whole_numbers_as_integers_and_round_trips(name):
    d = load_design(name)
    text = design_to_toml(d)
    data = tomllib.loads(text)
    assert isinstance(data["size_mm"], int)
    for table in ("fill", "physics"):
        for value in data.get(table, {}).values():
            assert not (isinstance(value, float) and value.is_integer())
    again = parse_design(text)
    assert np.allclose(again.polyhedron.vertices, d.polyhedron.vertices)
    assert again.params == pytest.approx(d.params) and again.fill == d.fill


def test_a_missing_extra_is_one_line_naming_it():
    with pytest.raises(MissingExtraError, match=r"pip install 'diefab\[dask\]'"):
        require("a_module_that_is_not_installed", "dask", "--scheduler")
    with pytest.raises(ValueError):
        require("math", "no-such-extra")


def test_validate_scheduler_without_dask_names_the_extra(bad, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if Dask were not installed
    line = bad("validate", "d6", "--sims", "10", "--scheduler", "tcp://127.0.0.1:1")
    assert "diefab[dask]" in line and "internal error" not in line


class _Links(HTMLParser):
    def __init__(self):
        super().__init__()
        self.sources: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.sources += [v for k, v in attrs if k in ("src", "href") and v]


def test_validate_report_is_one_offline_page(run, tmp_path):
    report, plot = tmp_path / "d6.html", tmp_path / "d6.png"
    code, _, err = run("validate", "d6", "--sims", "200", "--seed", "3", "--report", report, "--plot", plot)
    assert code == 0, err
    page = report.read_text(encoding="utf-8")
    links = _Links()
    links.feed(page)
    assert len(links.sources) >= 3  # the distribution, the die, the net
    assert all(src.startswith("data:image/") for src in links.sources)  # nothing to fetch: it opens offline
    assert "not distinguishable from uniform:6" in page or "distinguishable from uniform:6" in page
    assert plot.read_bytes().startswith(b"\x89PNG")


def test_report_refuses_a_file_that_is_not_html(bad, tmp_path):
    assert "--report" in bad("validate", "d6", "--sims", "10", "--report", tmp_path / "r.txt")


def test_a_spreadsheet_roll_log_is_read_from_its_result_column(tmp_path, run):
    from diefab.stats.goodness import read_roll_column

    sheet = tmp_path / "rolls.csv"
    sheet.write_text("Roll #,Die A,Die B,Result\n1,2,3,5\n2,1,1,2\n3,6,6,12\n# a pause\n4,3,4,7\n")
    rolls, column = read_roll_column(sheet)
    assert rolls.tolist() == [5, 2, 12, 7] and column == "Result"
    totals = tmp_path / "totals.csv"
    totals.write_text("Throw,Total\n1,7\n2,8\n")
    assert read_roll_column(totals)[1] == "Total"
    plain = tmp_path / "plain.txt"
    plain.write_text("1 2 3  # the first three\n4\n")
    assert read_roll_column(plain)[0].tolist() == [1, 2, 3, 4] and read_roll_column(plain)[1] is None
    code, _, err = run("stats", "--rolls", sheet, "--target", "2d6")
    assert code == 0 and "column 'Result'" in err


def test_a_bad_roll_is_named_with_its_line(tmp_path, bad):
    log = tmp_path / "rolls.csv"
    log.write_text("value\n1\n2\nx3\n")
    line = bad("stats", "--rolls", log, "--target", "1d6")
    assert "rolls.csv:4" in line and "'x3'" in line


def test_design_report_is_one_offline_page(run, tmp_path):
    page = tmp_path / "u6.html"
    # 200 drops cannot show TVD 0.02: a wide tolerance, so the report (not the verdict) is what is tested
    code, out, err = run("design", "uniform:6", "--model", "fast", "--validate-sims", "200", "--tolerance", "0.5",
                         "--report", page, "--out", tmp_path)  # fmt: skip
    assert code == 0, err
    links = _Links()
    links.feed(page.read_text(encoding="utf-8"))
    assert len(links.sources) >= 3 and all(src.startswith("data:image/") for src in links.sources)
    assert f"wrote {page}" in out
