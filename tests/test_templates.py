"""Ready-made dice: a target's name takes the template designed for the fill it is made of."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from diefab.core.errors import DesignError
from diefab.dice.design import files, list_templates, load_design, template_for, template_name, template_path


@pytest.fixture
def shelf(tmp_path, monkeypatch):
    """A templates folder of the shipped 3d6, 3df and 3df-paper, and a 3d6 designed for print (a copy of 3d6)."""
    for name in ("3d6", "3df", "3df-paper", "uniform-5"):
        shutil.copy(Path(str(template_path(name))), tmp_path / f"{name}.toml")
    text = (tmp_path / "3d6.toml").read_text().replace('name = "3d6"', 'name = "3d6-print"')
    (tmp_path / "3d6-print.toml").write_text(text.replace('kind = "solid"', 'kind = "print"'))
    monkeypatch.setattr(files, "_templates_dir", lambda: tmp_path)
    return tmp_path


@pytest.mark.parametrize(
    ("spec", "made", "template"),
    [
        ("3dF", "paper", "3df-paper"),  # the target made of card: its die designed for card
        ("3dF", "print", "3df"),  # no 3dF designed for print: the plain die
        ("3dF", None, "3df"),
        ("3DF", "paper", "3df-paper"),
        ("3df", "paper", "3df"),  # a template's own name is that template
        ("3df-paper", None, "3df-paper"),
        ("3d6", "print", "3d6-print"),  # a template spelled as its target is the target
        ("3d6", "paper", "3d6"),
        ("3d6", None, "3d6"),
        ("3d6", "solid", "3d6"),
        ("uniform:5", "paper", "uniform-5"),
    ],  # fmt: skip
)
def test_a_target_takes_the_die_made_as_it_will_be(shelf, spec, made, template):
    assert template_name(spec, made) == template
    assert template_path(spec, made) == shelf / f"{template}.toml"
    assert template_for(spec, made) == template
    d = load_design(spec, made)
    assert d.name == template
    assert d.target_distribution.values.tolist() == sorted(set(d.values.values()))


def test_a_file_is_not_a_template(shelf):
    assert template_for(shelf / "3d6.toml", "print") is None
    assert load_design(shelf / "3d6.toml", "print").name == "3d6"


def test_an_unknown_name_points_to_design(shelf):
    with pytest.raises(DesignError, match="unknown template 'd7'.*3df-paper.*diefab design TARGET"):
        template_name("d7", "paper")


def _plain(target: str) -> str | None:
    try:
        return template_name(target)
    except DesignError:
        return None


def test_every_made_template_is_designed_for_its_fill():
    """A shipped target's die NAME-paper or NAME-print is made of that fill and rolls the plain NAME's target."""
    shipped = {d.name: d for d in list_templates()}
    made = [(name, kind) for name in shipped for kind in files.MADE_KINDS if name.endswith(f"-{kind}")]
    # the ready-made dice of targets (fudge-gem-paper is a variant of a named die, not of a target's)
    made = [(name, kind) for name, kind in made if _plain(shipped[name].target) == name.removesuffix(f"-{kind}")]
    assert ("3df-paper", "paper") in made
    for name, kind in made:
        d, plain = shipped[name], shipped[name.removesuffix(f"-{kind}")]
        assert d.fill.kind == kind
        assert d.target == plain.target
        assert template_name(plain.target, kind) == name


def test_net_of_a_target_names_the_template_it_used(run, tmp_path):
    code, out, err = run("net", "3dF", "--out", tmp_path, "--format", "svg")
    assert code == 0, err
    assert out.splitlines()[0] == "3dF: the ready-made die 3df-paper, designed to be made of card"
    assert (tmp_path / "3df-paper-net.svg").is_file()
    code, out, err = run("net", "3df", "--out", tmp_path, "--format", "svg", "--json")
    assert code == 0, err
    assert json.loads(out)["template"] == "3df"


def test_a_check_made_of_card_takes_the_die_designed_for_card(run):
    code, out, err = run("predict", "3dF", "--fill", "paper", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["design"] == "3df-paper" and data["fill"] == "paper"
    code, out, err = run("predict", "3dF", "--json")
    assert code == 0, err
    assert json.loads(out)["design"] == "3df"
