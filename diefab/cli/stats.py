"""``diefab stats``: test real rolls against a target."""

from __future__ import annotations

from pathlib import Path

import click

from diefab.cli.common import console, emit_json, json_option, seed_option
from diefab.dice.design import format_value


@click.command()
@click.option("--counts", default=None, metavar="C1,C2,...", help="Counts of each value, in increasing value order.")
@click.option(
    "--rolls",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="Text or CSV log of rolled values.",
)
@click.option("--target", required=True, help="Target distribution, e.g. 4df or 1,4,10,16,19,16,10,4,1.")
@click.option("--alpha", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.05, show_default=True)
@seed_option("Seed of the Monte-Carlo p-value.")
@json_option
def stats(counts: str | None, rolls: Path | None, target: str, alpha: float, seed: int, as_json: bool) -> None:
    """Test rolls against a target: chi2, G, TVD, JSD, intervals, power."""
    from diefab.core.errors import StatsError
    from diefab.dice.targets import parse_target
    from diefab.stats.goodness import (
        chi2_power,
        counts_from_rolls,
        goodness_of_fit,
        parse_counts,
        read_rolls,
        rolls_for_power,
    )

    if (counts is None) == (rolls is None):
        raise click.UsageError("give exactly one of --counts and --rolls")
    if counts is not None:
        x = parse_counts(counts)
        goal = parse_target(target)
        if len(x) != len(goal.values):
            raise StatsError(f"{len(x)} counts for the {len(goal.values)} values of target {target!r}")
    else:
        goal = parse_target(target)
        x = counts_from_rolls(read_rolls(rolls), goal.values)
    fit = goodness_of_fit(x, goal.probabilities, alpha=alpha, seed=seed)
    observed = fit.observed
    power_n = rolls_for_power(goal.probabilities, observed, method="monte-carlo", seed=seed)
    result = {
        "n": fit.n,
        "target": target,
        "values": [str(int(v)) for v in goal.values],
        "counts": {str(int(v)): int(c) for v, c in zip(goal.values, x)},
        "expected_counts": {str(int(v)): float(e) for v, e in zip(goal.values, fit.expected)},
        "chi2": fit.chi2,
        "df": fit.df,
        "p_value": fit.p_value,
        "p_value_mc": fit.p_value_mc,
        "small_expected_counts": fit.small_expected,
        "g": fit.g,
        "g_p_value": fit.g_p_value,
        "tvd": fit.tvd,
        "jsd": fit.jsd,
        "expected_tvd": fit.expected_tvd,
        "expected_tvd_exact": fit.expected_tvd_exact,
        "expected_jsd": fit.expected_jsd,
        "alpha": alpha,
        "intervals": {str(int(v)): [float(lo), float(hi)] for v, (lo, hi) in zip(goal.values, fit.intervals)},
        "power_at_n": chi2_power(goal.probabilities, observed, fit.n, alpha, method="monte-carlo", seed=seed),
        "power_at_n_noncentral": chi2_power(goal.probabilities, observed, fit.n, alpha),
        "rolls_for_80_percent_power": power_n,
        "rolls_for_80_percent_power_noncentral": rolls_for_power(goal.probabilities, observed),
    }
    if as_json:
        emit_json(result)
        return
    from rich.table import Table

    con = console()
    table = Table("value", "count", "expected", "observed", f"{1 - alpha:.0%} simultaneous CI", "target")
    signed = min(goal.values) < 0
    for v, c, e, o, (lo, hi), p in zip(goal.values, x, fit.expected, observed, fit.intervals, goal.probabilities):
        table.add_row(
            format_value(int(v), signed), str(int(c)), f"{e:.1f}", f"{o:.4f}", f"[{lo:.4f}, {hi:.4f}]", f"{p:.4f}"
        )
    con.print(table)
    con.print(
        f"n = {fit.n}   chi2 = {fit.chi2:.3f} (df {fit.df}), p = {fit.p_value:.4f} "
        f"(Monte-Carlo {fit.p_value_mc:.4f}){'  [some expected counts < 5]' if fit.small_expected else ''}"
    )
    con.print(f"G = {fit.g:.3f}, p = {fit.g_p_value:.4f}")
    con.print(
        f"TVD = {fit.tvd:.4f} (expected under the target {fit.expected_tvd_exact:.4f}; "
        f"the paper's sqrt((K-1)/(2 pi N)) gives {fit.expected_tvd:.4f})"
    )
    con.print(f"JSD = {fit.jsd:.5f} (expected under the target {fit.expected_jsd:.5f})")
    if power_n is not None:
        con.print(
            f"If the observed frequencies were the truth, the chi2 test would detect them with power "
            f"{result['power_at_n']:.2f} at n = {fit.n}, and 80% power needs {power_n} rolls."
        )
