"""``diefab validate``: drop the die in pybullet and test the counts."""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

import click
import numpy as np

from diefab.cli.common import (
    apply_fill,
    console,
    design_argument,
    design_inputs,
    emit_json,
    fill_options,
    get_design,
    heading,
    json_option,
    physics_file_option,
    physics_options,
    physics_settings,
    pop_fill,
    profile_inputs,
    refuse_options,
    report_option,
    seed_option,
    values_dict,
)
from diefab.dice.design import format_value


@click.command()
@design_argument
@click.option("--sims", type=int, default=10_000, show_default=True, help="Number of simulated drops.")
@seed_option("Seed: the same seed gives the same counts.")
@click.option("--workers", type=int, default=None, help="Worker processes (default: all cores).")
@click.option("--scheduler", default=None, metavar="ADDRESS", help="Run on this Dask scheduler (tcp://host:8786).")
@click.option("--plot", "plot_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Write a bar chart to FILE (.png or .svg).")  # fmt: skip
@report_option
@fill_options("paper", "print")
@click.option("--target", default=None, help="Override the design's target distribution.")
@click.option("--delta", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.03, show_default=True,
              help="Tolerance in TVD of the verdict: within it of the target, or off by at least it.")  # fmt: skip
@click.option("--rolls", "rolls_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              metavar="FILE",
              help="Real rolls of the die as made (a roll log or CSV, as diefab stats reads): also score the "
              "simulation against them, the physics held out on them if they took no part in fitting it.")  # fmt: skip
@click.option("--checkpoint", type=click.Path(dir_okay=False, path_type=Path), default=None, metavar="FILE",
              help="Keep every finished drop in FILE (.npz): the same command with the same FILE continues a "
              "stopped validation, and with more --sims adds drops to it.")  # fmt: skip
@click.option("--sensitivity", is_flag=True,
              help="Validate under each standard throw and table (the shipped profiles soft-tray, wooden-table, "
              "hard-tray, low-spin, high-spin) and report the TVD to the target of each and the worst.")  # fmt: skip
@physics_file_option
@physics_options
@json_option
@click.pass_context
def validate(ctx, design, params, sims, seed, workers, scheduler, plot_file, report_file, target, delta, rolls_file,
             checkpoint, sensitivity, physics_profile, as_json, **physics) -> None:  # fmt: skip
    """Drop DESIGN many times in pybullet and test the counts against its target.

    With --sensitivity, drop it under each standard throw and table instead
    (each over --physics and the design's [physics] table; the physics
    options override all of them).
    """
    import os

    from diefab.core.errors import PhysicsError
    from diefab.core.files import check_outputs, ensure_dir, write_files
    from diefab.models.choice import best_model
    from diefab.models.probabilities import value_probabilities
    from diefab.physics.simulate import SimulationInterrupted, plot_validation, simulate
    from diefab.stats.goodness import goodness_of_fit
    from diefab.stats.sequential import sequential_counts
    from diefab.stats.verdict import target_label, verdict

    fill = pop_fill(physics)
    if scheduler is not None:
        refuse_options(ctx, ["workers"], "does not apply with --scheduler (the cluster's workers run the drops)")
    made = fill.get("fill_kind")  # a target's name made of card or printed takes the die designed so
    d = apply_fill(get_design(design, params, target, made), **fill)
    inputs = design_inputs(design, d, made) + profile_inputs(physics_profile)  # no output may replace them
    settings = physics_settings(d, physics_profile, **physics)
    real = None
    if rolls_file is not None:  # read before any drop: a bad log is refused at once
        from diefab.stats.goodness import counts_from_rolls, read_roll_column

        rolls = read_roll_column(rolls_file)[0]  # an empty log is refused there
        real = counts_from_rolls(rolls, d.support, rolls_file, of="the die")
        inputs = [*inputs, rolls_file]
    if sensitivity:
        if plot_file is not None or report_file is not None or rolls_file is not None or checkpoint is not None:
            raise click.BadParameter("--plot, --report, --rolls and --checkpoint go with one validation, not "
                                     "--sensitivity", param_hint="--plot/--report/--rolls/--checkpoint")  # fmt: skip
        return _sensitivity(d, settings, sims, seed, workers, scheduler, as_json, physics)
    if plot_file is not None:
        if plot_file.suffix.lower() not in (".png", ".svg"):
            raise click.BadParameter(f"{plot_file} must end in .png or .svg", param_hint="--plot")
        ensure_dir(plot_file.parent)
        check_outputs([plot_file], inputs)
    if report_file is not None:
        ensure_dir(report_file.parent)
        check_outputs([report_file, *([plot_file] if plot_file else [])], inputs)
    drops = None if checkpoint is None else _checkpoint(checkpoint, d, settings, seed, sims, inputs)
    bar = None
    if sys.stderr.isatty():
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

        bar = Progress(TextColumn("drops"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn(),
                       console=console(stderr=True), transient=True)  # fmt: skip
    run = {"workers": workers, "scheduler": scheduler}
    try:
        with bar if bar is not None else contextlib.nullcontext():
            if bar is not None:
                task = bar.add_task("drops", total=sims, completed=0 if drops is None else drops.held)
                run["progress"] = lambda done, total: bar.update(task, completed=done)
            result = simulate(d, sims, seed=seed, settings=settings, **run) if drops is None else drops.run(**run)
    except SimulationInterrupted as exc:  # a checkpoint has kept the drops that finished
        kept = "" if drops is None else f"; they are kept in {checkpoint}: run the same command again to continue"
        click.echo(f"diefab: interrupted after {exc.done} of {exc.total} drops had finished{kept}", err=True)
        raise click.exceptions.Exit(130) from None
    if result.landed == 0:
        raise PhysicsError(f"no drop came to rest on a face ({result.cocked} cocked, {result.unsettled} unsettled)")
    counts = result.value_counts(d)
    goal = d.target_distribution.aligned(d.support)
    fit = goodness_of_fit(counts, goal, seed=seed)
    seq = sequential_counts(counts, goal, delta)
    said = verdict(counts, goal, target_label(d.target), p_value=fit.p_value, sequential=seq)
    choice = best_model(d)
    model = value_probabilities(d, "solid-angle")
    predicted = model if choice.name == "solid-angle" else value_probabilities(d, choice.name)
    keys = [str(v) for v in d.support]
    # values the target never rolls, rolled: counted and reported (they reject the target outright)
    unexpected = {k: int(c) for k, c, g in zip(keys, counts, goal) if g == 0 and c > 0}
    out = {
        "design": d.name,
        "params": dict(d.params),
        "fill": d.fill.kind,
        "target": d.target,
        "n": result.n,
        "landed": result.landed,
        "counts": dict(zip(keys, counts.tolist())),
        "face_counts": dict(zip(result.faces, result.face_counts.tolist())),
        "probabilities": values_dict(d, fit.observed),
        "intervals": {k: [float(lo), float(hi)] for k, (lo, hi) in zip(keys, fit.intervals)},
        "target_probabilities": values_dict(d, goal),
        "solid_angle": values_dict(d, model),
        "model": choice.name,
        "predicted": values_dict(d, predicted),
        "cocked": result.cocked,
        "unsettled": result.unsettled,
        "zero_weight_rolls": unexpected,
        "transitional": list(d.transitional_faces),
        "chi2": fit.chi2 if np.isfinite(fit.chi2) else None,
        "df": fit.df,
        "p_value": fit.p_value,
        "p_value_mc": fit.p_value_mc,
        "tvd": fit.tvd,
        "expected_tvd": fit.expected_tvd,
        "jsd": fit.jsd,
        "expected_jsd": fit.expected_jsd,
        "seed": seed,
        "workers": "dask" if scheduler else (workers or os.cpu_count()),
        "seconds": result.seconds,
        "drops_per_second": result.drops_per_second,
        "settings": settings.as_dict(),
        "sequential": seq.as_dict(),
        "verdict": said.text,
    }
    if drops is not None:
        out["checkpoint"] = {"file": str(checkpoint), "resumed": result.resumed}
    if real is not None:
        out["real_rolls"] = real_rolls_score(d, real, counts, rolls_file)
    files = {}  # the plot and the report: both written or neither
    if plot_file is not None:
        files[plot_file] = plot_validation(d, result, fmt=plot_file.suffix.lower()[1:], model=choice.name)
    if report_file is not None:
        files[report_file] = _report_page(d, fit, result, said.text, settings)
    if files:
        write_files(files, inputs=inputs)
    if as_json:
        emit_json(out)
        return
    from rich.table import Table

    con = console()
    con.print(heading(d, fill=d.fill.kind, target=d.target))
    table = Table("value", "count", "simulated", "95% simultaneous CI", "target", f"{choice.name} model",
                  title=f"Values: {result.n} pybullet drops against the target and the {choice.name} model",
                  title_justify="left")  # fmt: skip
    signed = min(d.support) < 0
    for k, v in enumerate(d.support):
        lo, hi = fit.intervals[k]
        table.add_row(format_value(v, signed), str(counts[k]), f"{fit.observed[k]:.4f}", f"[{lo:.4f}, {hi:.4f}]",
                      f"{goal[k]:.4f}", f"{predicted[k]:.4f}")  # fmt: skip
    con.print(table)
    shown = [f"{n}={c}" for n, c in zip(result.faces, result.face_counts) if n in d.values]
    more = f"  ... ({len(shown) - 40} more; --json lists all)" if len(shown) > 40 else ""
    con.print("faces: " + "  ".join(shown[:40]) + more)
    con.print(
        f"{result.n} drops: {result.landed} on a face, {result.cocked} cocked, {result.unsettled} unsettled; "
        f"{result.seconds:.1f} s, {result.drops_per_second:,.0f} drops/s"
    )
    if drops is not None:
        before = f" ({result.resumed} of them from before)" if result.resumed else ""
        con.print(f"drops kept in {checkpoint}{before}")
    if unexpected:
        con.print("rolled values with target weight 0: " + "  ".join(f"{k} x{c}" for k, c in unexpected.items())
                  + " (impossible under the target: p = 0)")  # fmt: skip
    con.print(f"chi2 = {fit.chi2:.3f} (df {fit.df}), p = {fit.p_value:.4g} (Monte-Carlo {fit.p_value_mc:.4g})")
    con.print(f"TVD = {fit.tvd:.4f} (expected under the target {fit.expected_tvd:.4f})   "
              f"JSD = {fit.jsd:.5f} (expected {fit.expected_jsd:.5f})")  # fmt: skip
    con.print(f"verdict: {said.text}")
    if real is not None:
        r = out["real_rolls"]
        con.print(f"real rolls: {r['n']} in {rolls_file}: TVD {r['tvd']:.4f} to this simulation (sampling noise of "
                  f"{r['n']} rolls {r['noise_tvd']:.4f}), p = {r['p_value']:.3g} (the simulation's own noise "
                  f"not counted)")  # fmt: skip
    for written in (plot_file, report_file):
        if written is not None:
            con.print(f"wrote {written}")


def _checkpoint(path: Path, d, settings, seed: int, sims: int, inputs):
    """``--checkpoint``: the drops the drop file at `path` holds for this die, kept there as new ones finish."""
    from diefab.core.files import check_outputs, ensure_dir
    from diefab.physics.checkpoint import Checkpoint
    from diefab.physics.dropfile import DropFile

    if path.suffix.lower() != ".npz":
        raise click.BadParameter(f"{path} must end in .npz", param_hint="--checkpoint")
    ensure_dir(path.parent)
    check_outputs([path], inputs)  # locked until the command ends: one process per file
    return Checkpoint(DropFile(path), d, settings, seed, sims)


def real_rolls_score(d, real, simulated, path) -> dict:
    """How well `simulated` value counts of design `d` predict its `real` rolls (read from `path`)."""
    from diefab.search.likelihood import die_report
    from diefab.search.realdie import real_die

    report = die_report(real_die(d.name, d, real), simulated)
    return {"file": str(path), "n": int(real.sum()), "counts": dict(zip(map(str, d.support), real.tolist())),
            "tvd": report["tvd"], "noise_tvd": report["noise_tvd"], "deviance": report["deviance"],
            "df": report["df"], "p_value": report["p_value"]}  # fmt: skip


def _report_page(d, fit, result, verdict, settings) -> bytes:
    """The HTML page of ``--report``."""
    from diefab.fabricate.report import DieReport, die_pictures, render_report

    report = DieReport(
        design=d, title=f"diefab validate {d.name}", verdict=verdict, probabilities=fit.observed,
        intervals=np.asarray(fit.intervals), source=f"{result.landed} pybullet drops",
        lines=[f"{result.n} drops: {result.landed} on a face, {result.cocked} cocked, {result.unsettled} unsettled",
               f"chi2 = {fit.chi2:.3f} (df {fit.df}), p = {fit.p_value:.4g}; TVD {fit.tvd:.4f} (expected under "
               f"the target {fit.expected_tvd:.4f})",
               "physics: " + ", ".join(f"{k}={v}" for k, v in settings.as_dict().items())],
        pictures=die_pictures(d),
    )  # fmt: skip
    return render_report(report).encode("utf-8")


def _sensitivity(d, base, sims, seed, workers, scheduler, as_json, overrides) -> None:
    """``validate --sensitivity``: the TVD to the target under each standard profile."""
    from dataclasses import replace

    from diefab.physics.profiles import STANDARD, sensitivity
    from diefab.physics.simulate import SimulationInterrupted

    try:
        rows = sensitivity(replace(d, physics=base.as_dict()), STANDARD, sims, seed=seed, workers=workers,
                           scheduler=scheduler, **overrides)  # fmt: skip
    except SimulationInterrupted as exc:
        click.echo(f"diefab: interrupted after {exc.done} of {exc.total} drops of one profile", err=True)
        raise click.exceptions.Exit(130) from None
    worst = max(rows, key=lambda r: r["tvd"])
    out = {"design": d.name, "params": dict(d.params), "fill": d.fill.kind, "target": d.target, "n": sims,
           "seed": seed, "profiles": rows, "worst_profile": worst["profile"], "worst_tvd": worst["tvd"]}  # fmt: skip
    if as_json:
        emit_json(out)
        return
    from rich.table import Table

    con = console()
    con.print(heading(d, fill=d.fill.kind, target=d.target))
    table = Table(
        "profile",
        "TVD to target",
        "expected (noise)",
        "chi2 p",
        "cocked",
        "unsettled",
        "seconds",
        title=f"pybullet simulation under each profile ({sims} drops each)",
        title_justify="left",
    )
    for r in rows:
        table.add_row(r["profile"], f"{r['tvd']:.4f}", f"{r['expected_tvd']:.4f}", f"{r['p_value']:.3g}",
                      str(r["cocked"]), str(r["unsettled"]), f"{r['seconds']:.1f}")  # fmt: skip
    con.print(table)
    con.print(f"worst: {worst['profile']}, TVD {worst['tvd']:.4f} ({sims} drops per profile, seed {seed})")
