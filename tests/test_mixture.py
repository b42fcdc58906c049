"""Mixture of simulated set-ups: the fit recovers a known mixture, obeys its prior, and a held-out die stays out."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from diefab.core.errors import StatsError
from diefab.search.crossval import nested_choices
from diefab.search.mixture import fit_weights, mix, mixture_deviance, prior_penalty

GENTLE = np.array([0.6, 0.3, 0.1])
VIGOROUS = np.array([0.1, 0.3, 0.6])
MIDDLE = np.array([0.2, 0.6, 0.2])


def test_the_fit_recovers_a_known_weight_from_synthetic_counts():
    """Counts drawn from w * gentle + (1 - w) * vigorous: the fitted w is within a few standard errors."""
    rng = np.random.default_rng(7)
    probs = np.array([GENTLE, VIGOROUS])
    for w in (0.0, 0.3, 0.7, 1.0):
        dice = [rng.multinomial(20_000, mix(probs, [w, 1 - w])) for _ in range(3)]
        got = fit_weights(dice, [probs] * 3, np.zeros(2))
        # each die's 20,000 rolls pin w to about 0.004 (binomial); three dice, a bound of ~5 sd
        assert abs(got[0] - w) < 0.012
        assert got.sum() == pytest.approx(1.0) and np.all(got >= 0)


def test_the_fit_is_the_maximum_likelihood_mixture():
    """On a grid of the simplex no mixture has a lower deviance than the fitted one."""
    rng = np.random.default_rng(3)
    probs = np.array([GENTLE, MIDDLE, VIGOROUS])
    counts = [rng.multinomial(300, mix(probs, [0.2, 0.5, 0.3])), rng.multinomial(200, mix(probs, [0.1, 0.3, 0.6]))]
    w = fit_weights(counts, [probs] * 2, np.zeros(3))
    best = mixture_deviance(counts, [probs] * 2, w)
    grid = [(a, b, 1 - a - b) for a in np.linspace(0, 1, 41) for b in np.linspace(0, 1, 41) if a + b <= 1 + 1e-12]
    assert best <= min(mixture_deviance(counts, [probs] * 2, np.array(g)) for g in grid) + 1e-6


def test_the_prior_shrinks_the_mixture_toward_the_default():
    """Counts half gentle, half vigorous; a prior on the gentle set-up moves the weight toward the vigorous one."""
    probs = np.array([GENTLE, VIGOROUS])
    counts = [np.round(100 * mix(probs, [0.5, 0.5]))]
    free = fit_weights(counts, [probs], np.zeros(2))
    coords, x0 = np.array([[0.0], [1.0]]), np.array([1.0])
    weak, strong = (fit_weights(counts, [probs], prior_penalty(coords, x0, sd))[0] for sd in (0.5, 0.2))
    assert free[0] == pytest.approx(0.5, abs=1e-3)
    assert 0.0 <= strong < weak - 0.05 and weak < free[0] - 0.01  # a stronger prior shrinks further
    assert np.array_equal(fit_weights([], [], np.array([4.0, 0.0])), [0.0, 1.0])  # no die: the default alone


def test_a_pure_candidate_costs_what_the_grid_charges():
    coords, x0 = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.5]]), np.array([1.0, 0.0])
    assert np.allclose(prior_penalty(coords, x0, 0.5), [4.0, 0.0, 1.0])
    assert np.allclose(prior_penalty(coords, x0, np.inf), 0.0)
    with pytest.raises(StatsError, match="prior_sd"):
        prior_penalty(coords, x0, 0.0)


@pytest.mark.parametrize(
    "counts, probs, message",
    [
        ([np.array([1.0, 2.0])], [np.array([[0.5, 0.5, 0.0]])], "shape"),
        ([np.array([1.0, 2.0])], [np.array([[1.0, 0.0]])], "smoothed"),
        ([np.array([1.0, 2.0])], [], "dice"),
    ],
)
def test_bad_input_is_refused(counts, probs, message):
    with pytest.raises(StatsError, match=message):
        fit_weights(counts, probs, np.zeros(1))


def _methods(probs_of, counts_of):
    """Two methods over candidates (gentle, vigorous): the vigorous alone, and the fitted mixture."""

    def fixed(rows, target):
        return np.array([0.0, 1.0])

    def mixture(rows, target):
        return fit_weights([counts_of[j] for j in rows], [probs_of[j] for j in rows], np.zeros(2))

    return {"default": fixed, "mix": mixture}


def _loss(counts_of, probs_of):
    def loss(j, w):
        return 0.5 * float(np.abs(mix(probs_of[j], w) - counts_of[j] / counts_of[j].sum()).sum())

    return loss


def test_nested_choice_picks_the_mixture_when_every_die_is_mixed():
    rng = np.random.default_rng(11)
    probs_of = [np.array([GENTLE, VIGOROUS])] * 5
    counts_of = [rng.multinomial(2000, mix(probs_of[0], [0.6, 0.4])).astype(float) for _ in range(5)]
    got = nested_choices(5, _methods(probs_of, counts_of), _loss(counts_of, probs_of))
    assert [name for name, _, _ in got] == ["mix"] * 5
    assert all(abs(w[0] - 0.6) < 0.05 for _, w, _ in got)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 4), st.lists(st.integers(0, 400), min_size=3, max_size=3))
def test_a_held_out_die_never_moves_its_own_nested_choice(die, counts):
    """Whatever the held-out die's own counts, the method chosen for it and its weights are the same."""
    rng = np.random.default_rng(5)
    probs_of = [np.array([GENTLE, VIGOROUS])] * 5
    counts_of = [rng.multinomial(500, mix(probs_of[0], [w, 1 - w])).astype(float) for w in (0.1, 0.5, 0.9, 0.3, 0.7)]
    before = nested_choices(5, _methods(probs_of, counts_of), _loss(counts_of, probs_of))
    counts_of[die] = np.array(counts, dtype=float) + 1.0
    after = nested_choices(5, _methods(probs_of, counts_of), _loss(counts_of, probs_of))
    assert before[die][0] == after[die][0]
    assert np.allclose(before[die][1], after[die][1])


def test_nested_choice_needs_a_method():
    with pytest.raises(StatsError, match="no method"):
        nested_choices(3, {}, lambda j, w: 0.0)
