"""Model optimizations kept beside a search's drops: taken again exactly, or made again where the models differ."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from diefab.core.errors import DesignError
from diefab.dice.design import load_design
from diefab.search import memo as memo_module
from diefab.search.memo import OptimizationMemo
from diefab.search.optimize import optimize_design

OPTIONS = {"model": "solid-angle", "starts": 1, "seed": 2, "max_evaluations": 60, "budget": 120}


def _never(*args, **kwargs):
    raise AssertionError("an optimization was made again")


def _same(a, b) -> None:
    assert list(a.design.params.items()) == list(b.design.params.items())  # the same numbers, in the same order
    assert a.objective == b.objective and np.array_equal(a.values, b.values) and np.array_equal(a.margins, b.margins)
    assert (a.design.name, a.design.description, a.evaluations) == (b.design.name, b.design.description, b.evaluations)


def test_a_kept_optimization_is_taken_exactly_and_not_made_again(tmp_path, monkeypatch):
    gem = load_design("fudge-gem")
    first = OptimizationMemo(tmp_path).optimize(gem, **OPTIONS)
    _same(first, optimize_design(gem, **OPTIONS))
    monkeypatch.setattr(memo_module, "optimize_design", _never)
    again = OptimizationMemo(tmp_path)
    _same(again.optimize(gem, **OPTIONS), first)
    assert (again.found, again.made) == (1, 0)
    with pytest.raises(AssertionError, match="made again"):  # other options are another optimization
        again.optimize(gem, **{**OPTIONS, "seed": 3})


def test_a_kept_result_the_models_no_longer_give_is_made_again(tmp_path):
    gem = load_design("fudge-gem")
    first = OptimizationMemo(tmp_path).optimize(gem, **OPTIONS)
    (path,) = (tmp_path / "optimized").glob("*.json")
    kept = json.loads(path.read_text())
    for change in ({"objective": (first.objective * 1.5).hex()}, {"params": "not a list"}, {"pad": "x" * 2**20},
                   None):  # fmt: skip
        path.write_text("{ not json" if change is None else json.dumps(kept | change))
        again = OptimizationMemo(tmp_path)
        _same(again.optimize(gem, **OPTIONS), first)
        assert (again.found, again.made) == (0, 1)


def test_a_failed_optimization_is_kept_as_its_message(tmp_path, monkeypatch):
    gem = load_design("fudge-gem")
    with pytest.raises(DesignError) as made:
        OptimizationMemo(tmp_path).optimize(gem, **OPTIONS, min_margin=5.0)
    monkeypatch.setattr(memo_module, "optimize_design", _never)
    again = OptimizationMemo(tmp_path)
    with pytest.raises(DesignError) as found:
        again.optimize(gem, **OPTIONS, min_margin=5.0)
    assert str(found.value) == str(made.value) and again.found == 1


def test_an_optimization_with_a_wall_time_deadline_is_neither_kept_nor_taken(tmp_path):
    memo = OptimizationMemo(tmp_path)
    memo.optimize(load_design("fudge-gem"), **OPTIONS, deadline=time.monotonic() + 600)
    assert not (tmp_path / "optimized").exists() and memo.made == memo.found == 0


def test_a_search_run_again_on_its_store_makes_no_optimization_and_finds_the_same_die(tmp_path, monkeypatch):
    from diefab.dice.targets import parse_target
    from diefab.physics.checkpoint import DropStore
    from diefab.search.synthesis import synthesize

    def search():
        return synthesize(parse_target("uniform:3"), family="cuboid", model="simulation", max_drops=1200, seed=3,
                          workers=1, store=DropStore(tmp_path))  # fmt: skip

    first = search()
    assert list((tmp_path / "optimized").glob("*.json"))
    monkeypatch.setattr(memo_module, "optimize_design", _never)
    again = search()
    assert list(again.design.params.items()) == list(first.design.params.items()) and again.steps == first.steps
