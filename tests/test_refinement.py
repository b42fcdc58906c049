"""The shaped die's refinement: each step drops the die enough to measure its error, and no more."""

import numpy as np
import pytest
from scipy.stats import binom

from diefab.search.refinement import MIN_REFINE_DROPS, REFINE_DROPS, refinement_drops


def expected_tvd(values: int, drops: int) -> float:
    """Exact expected TVD between `drops` drops of a fair die of `values` values and its distribution."""
    p = 1.0 / values
    x = np.arange(drops + 1)
    return 0.5 * values * float(np.sum(binom.pmf(x, drops, p) * np.abs(x / drops - p)))


@pytest.mark.parametrize("values", [3, 6, 9, 16])
@pytest.mark.parametrize("best", [0.3, 0.1, 0.05, 0.03, 0.01])
def test_a_step_measures_the_error_to_about_a_seventh_of_the_best_tvd(values, best):
    drops = refinement_drops(best, values)
    assert MIN_REFINE_DROPS <= drops <= REFINE_DROPS
    noise = expected_tvd(values, drops)
    if drops < REFINE_DROPS:  # at the floor the noise is smaller still
        assert noise < best / 5
    if MIN_REFINE_DROPS < drops < REFINE_DROPS:
        assert best / 9 < noise


def test_the_drops_grow_as_the_die_nears_its_target():
    counts = [refinement_drops(d, 7) for d in (0.5, 0.2, 0.1, 0.05, 0.02, 0.01)]
    assert counts == sorted(counts)
    assert counts[0] == MIN_REFINE_DROPS and counts[-1] == REFINE_DROPS
    assert refinement_drops(0.0, 7) == REFINE_DROPS
