"""Cross-validation over real dice: a held-out die never takes part in its own choice, and the prior shrinks."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from diefab.core.errors import StatsError
from diefab.search.crossval import RULES, held_out_choices, pick_candidate, training_rows

COORDS = np.array([[1.0, 0.0], [0.0, 0.0], [1.0, 1.0]])  # the default first
X0 = np.array([1.0, 0.0])
NAMES = ["a1", "a2", "b1", "s1"]
FAMILY = {"a1": "a", "a2": "a", "b1": "b", "s1": "s"}.get
SURFACE = {"s1": "stone"}


def surface(name: str) -> str:
    return SURFACE.get(name, "table")


def test_no_prior_picks_the_least_total_deviance():
    dev = np.array([[3.0, 1.0, 2.0], [3.0, 2.0, 0.5]])
    assert pick_candidate(dev, [0], COORDS, X0, np.inf) == 1
    assert pick_candidate(dev, [0, 1], COORDS, X0, np.inf) == 2  # 5, 3, 2.5


def test_the_prior_shrinks_toward_the_default():
    """Candidate 1 is 1 coordinate unit from the default: with sd s it costs 1 / s**2 of deviance."""
    dev = np.array([[3.0, 2.0, 9.0]])
    assert pick_candidate(dev, [0], COORDS, X0, 2.0) == 1  # 3 vs 2 + 0.25
    assert pick_candidate(dev, [0], COORDS, X0, 0.5) == 0  # 3 vs 2 + 4
    assert pick_candidate(dev, [], COORDS, X0, 0.5) == 0  # no data: the default


@pytest.mark.parametrize("sd", [0.0, -1.0, float("nan")])
def test_a_bad_prior_is_refused(sd):
    with pytest.raises(StatsError, match="prior_sd"):
        pick_candidate(np.zeros((1, 3)), [0], COORDS, X0, sd)


def test_the_surface_rules_fall_back_to_the_default_alone_on_a_surface():
    dev = np.array([[5.0, 0.0, 5.0], [5.0, 0.0, 5.0], [5.0, 0.0, 5.0], [0.0, 5.0, 5.0]])
    got = held_out_choices(NAMES, dev, COORDS, X0, np.inf, FAMILY, surface)
    assert set(got) == set(RULES)
    assert got["loo"] == [1, 1, 1, 1]  # s1 is outvoted by the three table dice
    assert got["loo-surface"][3] == 0  # no other die on stone: the default
    assert got["loo-surface"][:3] == [1, 1, 1]


def test_leave_one_family_out_ignores_the_family():
    # a1 and a2 love candidate 2; b1 and s1 candidate 1
    dev = np.array([[30.0, 30.0, 0.0], [30.0, 30.0, 0.0], [9.0, 0.0, 9.0], [9.0, 0.0, 9.0]])
    got = held_out_choices(NAMES, dev, COORDS, X0, np.inf, FAMILY, surface)
    assert got["lofo"][:2] == [1, 1]  # a1 held out with its family: only b1 and s1 speak
    assert got["loo"][0] == 2  # a2 still speaks for a1 when only a1 is out (candidate 2: 0 + 9 + 9 = 18 vs 30)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0, 50), min_size=12, max_size=12), st.integers(0, 3), st.floats(0, 1000))
def test_a_held_out_die_never_moves_its_own_choice(values, die, change):
    """Whatever the held-out die's own deviances are, every rule picks the same candidate for it."""
    dev = np.array(values).reshape(4, 3)
    before = held_out_choices(NAMES, dev, COORDS, X0, 0.5, FAMILY, surface)
    dev[die] += np.array([change, 0.0, -change / 3])
    after = held_out_choices(NAMES, dev, COORDS, X0, 0.5, FAMILY, surface)
    assert all(before[r][die] == after[r][die] for r in RULES)


def test_training_rows_never_hold_the_die_and_stay_among_the_given_rows():
    for rule in RULES:
        for i in range(len(NAMES)):
            rows = training_rows(NAMES, i, rule, FAMILY, surface)
            assert i not in rows
            assert set(training_rows(NAMES, i, rule, FAMILY, surface, among=[0, 3])) <= {0, 3} - {i}
    assert training_rows(NAMES, 0, "lofo", FAMILY, surface) == [2, 3]  # a2 is a1's family
    assert training_rows(NAMES, 3, "loo-surface", FAMILY, surface) == []  # alone on stone
    with pytest.raises(StatsError, match="rule"):
        training_rows(NAMES, 0, "all", FAMILY, surface)
