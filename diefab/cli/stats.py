"""``diefab stats``: test real rolls against a target."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

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
@click.option(
    "--target",
    default=None,
    help="Target distribution, e.g. 4df or 1,4,10,16,19,16,10,4,1 (default: the --design's target).",
)
@click.option(
    "--design",
    "design_spec",
    default=None,
    metavar="DESIGN",
    help="The die rolled (a template name or design file): also score each landing model's prediction "
    "of it against the rolls.",
)
@click.option("--alpha", type=click.FloatRange(1e-9, 0.5), default=0.05, show_default=True,
              help="Significance level of the tests and intervals, 1e-9 to 0.5.")  # fmt: skip
@click.option("--delta", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.03, show_default=True,
              help="Tolerance in TVD of the verdict: within it of the target, or off by at least it.")  # fmt: skip
@click.option("--sequential", is_flag=True,
              help="Only the anytime-valid verdict (valid however often the log was checked).")  # fmt: skip
@seed_option("Seed of the Monte-Carlo p-value.")
@json_option
def stats(counts: str | None, rolls: Path | None, target: str | None, design_spec: str | None, alpha: float,
          delta: float, sequential: bool, seed: int, as_json: bool) -> None:  # fmt: skip
    """Test rolls against a target: chi2, G, TVD, JSD, intervals, power, and a plain verdict.

    The verdict is anytime-valid: a roll log (--rolls) is checked after
    every roll, so it may be run while rolling and stopped when it decides.
    With --design, each landing model's prediction of the die is scored
    against the same rolls: the real rolls judge the models.
    """
    from diefab.core.errors import StatsError
    from diefab.dice.targets import parse_target
    from diefab.stats.goodness import (
        chi2_power,
        counts_from_rolls,
        goodness_of_fit,
        parse_counts,
        read_roll_column,
        rolls_for_power,
    )
    from diefab.stats.sequential import sequential_counts, sequential_test
    from diefab.stats.verdict import target_label, verdict

    if (counts is None) == (rolls is None):
        raise click.UsageError("give exactly one of --counts and --rolls")
    die = None
    if design_spec is not None:
        from diefab.cli.common import get_design

        die = get_design(design_spec)
        target = target or die.target
    if target is None:
        raise click.UsageError("give --target, or --design for the die's own target")
    column = None
    support = None if die is None else list(die.support)  # a bare weight list weighs the die's values
    if counts is not None:
        x = parse_counts(counts)
        goal = parse_target(target, support)
        if len(x) != len(goal.values):
            raise StatsError(f"{len(x)} counts for the {len(goal.values)} values of target {target!r}")
        seq = sequential_counts(x, goal.probabilities, delta, alpha)
    else:
        goal = parse_target(target, support)
        values, column = read_roll_column(rolls)
        x = counts_from_rolls(values, goal.values, rolls)  # a roll off the target is one line, before any note
        seq = sequential_test(np.searchsorted(goal.values, values), goal.probabilities, delta, alpha)
        if not as_json:
            note = f"read column {column!r} of {rolls}" if column else f"read {len(values)} rolls of {rolls}"
            if _cut_short(rolls):
                note += "; its last line has no line end and is left out, as a roll cut short by a crash"
            click.echo(note, err=True)
    if sequential:
        return _sequential(seq, target, column, as_json)
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
        "column": column,
        "sequential": seq.as_dict(),
    }
    said = verdict(x, goal.probabilities, target_label(target), p_value=fit.p_value, sequential=seq, alpha=alpha)
    result["verdict"] = said.text
    if die is not None:
        result["design"] = die.name
        result["models"] = model_scores(die, goal.values, x, alpha, seed)
    if as_json:
        emit_json(result)
        return
    from rich.table import Table

    con = console()
    table = Table("value", "count", "expected", "observed", f"{100 * (1 - alpha):.10g} % simultaneous CI", "target")
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
    if fit.small_expected:
        con.print(f"TVD = {fit.tvd:.4f} (expected under the target {fit.expected_tvd:.4f}, over draws of {fit.n})")
    else:
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
    con.print(f"verdict: {said.text}")
    if die is not None:
        _print_models(con, die.name, result["models"])


def model_scores(die, values, counts, alpha: float, seed: int) -> dict[str, dict]:
    """Each landing model's prediction of `die` scored against `counts` of `values` (the rolls of the die)."""
    from diefab.core.errors import StatsError
    from diefab.search.fidelity import landing_model_scores
    from diefab.search.realdie import real_die

    if list(die.support) != [int(v) for v in values]:
        raise StatsError(f"the rolls' values {[int(v) for v in values]} are not the values {list(die.support)} "
                         f"of design {die.name!r}")  # fmt: skip
    return landing_model_scores(real_die(die.name, die, counts), alpha=alpha, seed=seed)


def _print_models(con, name: str, models: dict[str, dict]) -> None:
    from rich.table import Table

    table = Table("model", "TVD to the rolls", "noise", "p")
    for model, m in models.items():
        noise = "-" if m["expected_tvd"] is None else f"{m['expected_tvd']:.4f}"
        table.add_row(model + (" (the one to trust)" if m["to_trust"] else ""), f"{m['tvd']:.4f}", noise,
                      f"{m['p_value']:.3g}")  # fmt: skip
    con.print(f"how well each landing model predicted {name} (noise: the TVD the rolls would show if the model "
              "were right; p: chi-squared of the rolls against the model):")  # fmt: skip
    con.print(table)


def _sequential(seq, target: str, column: str | None, as_json: bool) -> None:
    """``stats --sequential``: the anytime-valid verdict alone."""
    from diefab.stats.verdict import sequential_line, target_label

    out = {"target": target, "column": column, **seq.as_dict()}
    if as_json:
        emit_json(out)
        return
    console().print(sequential_line(seq, target_label(target)))


def _cut_short(path) -> bool:
    """Whether `path` is a roll log whose last line has no line end (which reading it leaves out)."""
    from diefab.core.errors import StatsError
    from diefab.stats.rolllog import read_log

    try:
        with open(path, "rb") as f:  # only a file without a final line end is read again
            f.seek(-1, 2)
            if f.read(1) == b"\n":
                return False
        return read_log(path).torn
    except (OSError, StatsError):  # not a roll log (every line of it was read), or nothing to look at
        return False
