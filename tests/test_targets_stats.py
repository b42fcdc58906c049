"""Target distributions and the statistics of the paper's Section 3."""

from __future__ import annotations

import numpy as np
import pytest

from diefab.core.errors import StatsError, TargetError
from diefab.dice.targets import parse_target
from diefab.stats.goodness import (
    chi2_power,
    counts_from_rolls,
    expected_jsd,
    expected_tvd,
    expected_tvd_exact,
    goodman_intervals,
    goodness_of_fit,
    jsd,
    parse_counts,
    pearson_divergence,
    read_rolls,
    rolls_for_power,
    tvd,
)

TABLE2 = [0, 20, 48, 80, 89, 83, 66, 17, 2]


def test_named_targets():
    t = parse_target("4df")
    assert t.values.tolist() == list(range(-4, 5))
    np.testing.assert_allclose(t.probabilities * 81, [1, 4, 10, 16, 19, 16, 10, 4, 1])
    two = parse_target("2d6")
    assert two.values.tolist() == list(range(2, 13))
    np.testing.assert_allclose(two.probabilities * 36, [1, 2, 3, 4, 5, 6, 5, 4, 3, 2, 1])
    three = parse_target("3d6")
    assert three.probabilities[three.values.tolist().index(10)] == pytest.approx(27 / 216)
    b = parse_target("binomial:4")
    np.testing.assert_allclose(b.probabilities * 16, [1, 4, 6, 4, 1])
    np.testing.assert_allclose(parse_target("binomial:2:0.25").probabilities, [9 / 16, 6 / 16, 1 / 16])
    u = parse_target("uniform:6")
    assert u.values.tolist() == [1, 2, 3, 4, 5, 6]
    coins = parse_target("coins:10")
    np.testing.assert_allclose(coins.probabilities * 1024, [11, 45, 120, 210, 252, 210, 120, 45, 11])


def test_explicit_weights_follow_the_design_values():
    t = parse_target("1,4,10,16,19,16,10,4,1", values=range(-4, 5))
    np.testing.assert_allclose(t.probabilities, parse_target("4df").probabilities)
    pairs = parse_target("-1:1, 0:2, 1:1")
    assert pairs.values.tolist() == [-1, 0, 1]
    np.testing.assert_allclose(pairs.probabilities, [0.25, 0.5, 0.25])
    assert parse_target("\u22121:1,0:1").values.tolist() == [-1, 0]  # a typographic minus


@pytest.mark.parametrize(
    "spec",
    ["1,2,-3", "0,0,0", "1,nan,2", "1,inf,2", "", "7d", "binomial:0", "uniform:1", "coins:7", "1:1,2", "1:1,1:2", "x"],
)
def test_malformed_targets(spec):
    with pytest.raises(TargetError):
        parse_target(spec)


def test_target_must_fit_the_design_values():
    with pytest.raises(TargetError, match="9 values"):
        parse_target("1,2,3", values=range(-4, 5))
    with pytest.raises(TargetError, match="values"):
        parse_target("2d6", values=range(-4, 5))


def test_table2_reproduces_the_paper():
    fit = goodness_of_fit(TABLE2, parse_target("4df").probabilities)
    assert fit.n == 405
    assert fit.chi2 == pytest.approx(12.9414, abs=1e-4)  # the paper prints 12.97: see the README
    assert fit.p_value == pytest.approx(0.11, abs=0.005)
    assert fit.tvd == pytest.approx(0.047, abs=5e-4)
    assert fit.jsd == pytest.approx(0.0068, abs=5e-5)
    assert fit.expected_tvd == pytest.approx(0.056, abs=5e-4)
    assert fit.expected_jsd == pytest.approx(0.0025, abs=5e-5)
    assert fit.p_value_mc == pytest.approx(fit.p_value, abs=0.01)
    assert not fit.small_expected  # the smallest expected count is exactly 5


def test_coins_against_4df_as_in_the_paper():
    p = parse_target("4df").probabilities
    q = parse_target("coins:10").probabilities
    assert pearson_divergence(q, p) == pytest.approx(3.39e-3, abs=5e-6)
    power = chi2_power(p, q, 1000)
    assert power < 0.25  # "will not spot the difference in more than three-fourths of the cases"
    assert power > 0.05  # but it is above the test's size


def test_power_is_exact_at_the_rolls_it_asks_for():
    p = parse_target("4df").probabilities
    q = parse_target("coins:10").probabilities
    n = rolls_for_power(p, q, 0.8)
    assert chi2_power(p, q, n) >= 0.8 > chi2_power(p, q, n - 1)
    assert rolls_for_power(p, p) is None


def test_power_matches_simulation():
    p = parse_target("4df").probabilities
    q = parse_target("coins:10").probabilities
    from scipy.stats import chi2

    rng = np.random.default_rng(7)
    x = rng.multinomial(1000, q, size=20000)
    e = 1000 * p
    simulated = ((((x - e) ** 2) / e).sum(axis=1) > chi2.ppf(0.95, 8)).mean()
    assert chi2_power(p, q, 1000, method="monte-carlo", seed=1) == pytest.approx(simulated, abs=0.01)
    # the noncentral approximation is optimistic at 1000 rolls, accurate at 10 000
    assert chi2_power(p, q, 1000) > simulated
    assert chi2_power(p, q, 10_000) == pytest.approx(chi2_power(p, q, 10_000, method="monte-carlo"), abs=0.02)


def test_monte_carlo_rolls_for_power():
    p = parse_target("4df").probabilities
    q = parse_target("coins:10").probabilities
    n = rolls_for_power(p, q, 0.8, method="monte-carlo", samples=4000, seed=2)
    mc = lambda m: chi2_power(p, q, m, method="monte-carlo", samples=4000, seed=2)  # noqa: E731
    assert mc(n) >= 0.8 > mc(n - 1)
    assert n == pytest.approx(rolls_for_power(p, q, 0.8), rel=0.05)  # at 80 % power the approximation holds


def test_divergences():
    p = np.array([0.5, 0.5])
    assert tvd(p, [1, 0]) == pytest.approx(0.5)
    assert jsd(p, p) == 0
    assert jsd([1, 0], [0, 1]) == pytest.approx(np.log(2))
    assert expected_tvd(9, 405) == pytest.approx(np.sqrt(8 / (2 * np.pi * 405)))
    assert expected_jsd(9, 405) == pytest.approx(8 / (8 * 405))


def test_expected_tvd_and_jsd_match_sampling():
    p = parse_target("4df").probabilities
    rng = np.random.default_rng(3)
    n = 2000
    obs = rng.multinomial(n, p, size=4000) / n
    mean_tvd = np.mean([tvd(o, p) for o in obs])
    assert mean_tvd == pytest.approx(expected_tvd_exact(p, n), rel=0.02)
    assert mean_tvd < expected_tvd(9, n)  # the paper's formula is the uniform case: an upper bound
    uniform = np.full(9, 1 / 9)
    obs = rng.multinomial(n, uniform, size=4000) / n
    assert np.mean([tvd(o, uniform) for o in obs]) == pytest.approx(expected_tvd(9, n), rel=0.02)
    assert np.mean([jsd(p, o) for o in rng.multinomial(n, p, size=4000) / n]) == pytest.approx(
        expected_jsd(9, n), rel=0.03
    )


def test_goodman_intervals_cover_simultaneously():
    p = parse_target("4df").probabilities
    rng = np.random.default_rng(11)
    trials = 2000
    covered = 0
    for x in rng.multinomial(400, p, size=trials):
        ci = goodman_intervals(x, 0.05)
        covered += np.all((ci[:, 0] <= p) & (p <= ci[:, 1]))
    assert covered / trials >= 0.93  # nominal 95 %, conservative by construction


def test_small_expected_counts_use_monte_carlo():
    fit = goodness_of_fit([3, 0, 1], [0.6, 0.2, 0.2], mc_samples=50_000)
    assert fit.small_expected
    assert 0 < fit.p_value_mc <= 1


@pytest.mark.parametrize(
    ("counts", "target"),
    [([1, 2], [0.5, 0.3, 0.2]), ([1, -2, 3], [0.3, 0.3, 0.4]), ([0, 0], [0.5, 0.5]), ([1.5, 2], [0.5, 0.5])],
)
def test_bad_counts(counts, target):
    with pytest.raises(StatsError):
        goodness_of_fit(counts, target)


def test_parse_counts():
    assert parse_counts("0, 20 48;80").tolist() == [0, 20, 48, 80]
    for text in ("", "1,x", "1,-2", "1.5"):
        with pytest.raises(StatsError):
            parse_counts(text)


def test_read_rolls_formats(tmp_path):
    text = tmp_path / "rolls.txt"
    text.write_text("# session 1\n+2 -1 0\n\u22123, 4\n\n1 # last\n")
    assert read_rolls(text).tolist() == [2, -1, 0, -3, 4, 1]
    table = tmp_path / "rolls.csv"
    table.write_text("time,player,result\n10:01,ann,+1\n10:02,bob,-4\n")
    assert read_rolls(table).tolist() == [1, -4]
    assert counts_from_rolls([1, -4, 1], range(-4, 5)).tolist() == [1, 0, 0, 0, 0, 2, 0, 0, 0]


@pytest.mark.parametrize(
    ("content", "message"),
    [("", "empty"), ("# only a comment\n", "empty"), ("1 2 x3\n", ":1"), ("a,b\n1,2\n", "header"), ("1\n2.5\n", ":2")],
)
def test_bad_roll_logs(tmp_path, content, message):
    path = tmp_path / "log.txt"
    path.write_text(content)
    with pytest.raises(StatsError, match=message):
        read_rolls(path)
    with pytest.raises(StatsError, match="not a value"):
        counts_from_rolls([7], range(-4, 5))


def test_a_roll_off_the_target_is_named_by_its_place_and_file():
    with pytest.raises(StatsError, match=r"^log.csv: roll 3 of 4 is 7, not a value of the target \(1, 2\)$"):
        counts_from_rolls([1, 2, 7, 9], [1, 2], "log.csv")


def test_the_expected_tvd_is_a_mean_tvd_at_any_number_of_rolls():
    from diefab.stats.goodness import expected_tvd, goodness_of_fit

    target = np.array([1, 4, 10, 16, 19, 16, 10, 4, 1]) / 81
    one = goodness_of_fit(np.eye(9, dtype=int)[4], target)
    # one roll: the TVD is 1 - p of the value rolled, so its mean is 1 - sum p^2; the asymptotic figure is 1.13
    assert one.expected_tvd == pytest.approx(1 - (target**2).sum(), abs=0.01)
    assert expected_tvd(9, 1) > 1
    assert 0 < one.expected_jsd < np.log(2)
    many = goodness_of_fit(np.rint(target * 81_000).astype(int), target)
    assert many.expected_tvd == expected_tvd(9, many.n)  # every expected count at least 5: the paper's figure


def test_stats_weighs_the_design_s_values_with_a_bare_weight_list(run):
    import json

    code, out, err = run("stats", "--counts", "10,10,10,10,10,20", "--design", "d6", "--target", "1,1,1,1,1,2",
                         "--json")  # fmt: skip
    assert code == 0, err
    report = json.loads(out)
    assert report["values"] == ["1", "2", "3", "4", "5", "6"]  # the d6's values, not 0..5
    assert report["tvd"] == pytest.approx(0.0)
