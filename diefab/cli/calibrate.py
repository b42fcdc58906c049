"""``diefab calibrate``: fit the physics settings to dice with real rolls; write a physics profile."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from diefab.cli.common import (
    BOLD,
    PLAIN,
    check_resume_folder,
    console,
    design_inputs,
    emit_json,
    get_design,
    json_option,
    one_line_name,
    out_option,
    physics_file_option,
    refuse_options,
    run_logged,
)
from diefab.core.files import atomic_write, check_outputs, output_path, safe_name
from diefab.search.calibrate import DEFAULT_FREE, MIN_PRIOR_SD


def _parse_bounds(items: tuple[str, ...]) -> dict[str, tuple[float, float]]:
    """``("spin=0:20",)`` -> ``{"spin": (0.0, 20.0)}``."""
    out = {}
    for item in items:
        name, sep, rng = item.partition("=")
        lo, colon, hi = rng.partition(":")
        try:
            if not sep or not colon:
                raise ValueError
            bound = (float(lo), float(hi))
        except ValueError:
            raise click.BadParameter(f"{item!r} is not NAME=LOW:HIGH", param_hint="--bound") from None
        if name.strip() in out:
            raise click.BadParameter(f"{name.strip()} is bounded twice", param_hint="--bound")
        out[name.strip()] = bound
    return out


def _inputs(die_args, realrolls, physics_profile) -> list[Path]:
    """The files a fresh calibration reads: designs and their meshes and symbols, roll logs, real rolls, profile."""
    from diefab.core.errors import DiefabError
    from diefab.dice.design import load_design

    files = [Path(p) for p in realrolls]
    for spec, counts in die_args:
        try:
            files += design_inputs(spec, load_design(spec))
        except DiefabError:  # reported when the die is read
            files += [Path(spec)] if Path(spec).is_file() else []
        if Path(counts).is_file():
            files.append(Path(counts))
    if physics_profile is not None and Path(physics_profile).is_file():
        files.append(Path(physics_profile))
    return files


def _dice(die_args, realrolls):
    from diefab.search.calibrate import real_die, realrolls_die

    dice = []
    for spec, counts in die_args:
        d = get_design(spec)
        dice.append(real_die(d.name, d, counts))
    dice += [realrolls_die(path) for path in realrolls]
    names: dict[str, int] = {}
    out = []
    for die in dice:
        names[die.name] = names.get(die.name, 0) + 1
        if names[die.name] > 1:  # the same design with a second set of rolls
            from dataclasses import replace

            die = replace(die, name=f"{die.name}-{names[die.name]}")
        out.append(die)
    return out


@click.command()
@click.option("--die", "die_args", type=(str, str), multiple=True, metavar="DESIGN COUNTS",
              help="A die with real rolls: a design (template or TOML) and its counts per value, increasing "
              "(\"0,20,48,...\") or a roll log file (repeatable).")  # fmt: skip
@click.option("--realrolls", type=click.Path(exists=True, dir_okay=False, path_type=Path), multiple=True,
              metavar="FILE",
              help="A die of the real-rolls JSON format: geometry, mass and counts (repeatable).")  # fmt: skip
@click.option("--name", default="calibrated", show_default=True, callback=one_line_name,
              help="Name of the run and of the profile.")  # fmt: skip
@click.option("--free", default=",".join(DEFAULT_FREE), show_default=True,
              metavar="A,B,...", help="Physics parameters to fit: restitution, friction, rolling_friction, "
              "spinning_friction, spin (top of the spin range), speed (top of the speed range), "
              "drop_height, capture (quasi-static capture energy, units of m g L; searched on a square "
              "scale).")  # fmt: skip
@click.option("--bound", "bounds", multiple=True, metavar="NAME=LOW:HIGH", help="Range searched for a parameter.")
@click.option("--seed", type=int, default=0, show_default=True, help="Physics seed: common random numbers.")
@click.option("--sims-per-eval", type=int, default=1000, show_default=True,
              help="Drops of each die per evaluation at the start (doubled as it converges).")  # fmt: skip
@click.option("--max-sims-per-eval", type=int, default=None, help="Most drops of each die per evaluation (8x).")
@click.option("--budget", type=float, default=20.0, show_default=True, help="Wall-time budget, minutes.")
@click.option("--resume", type=click.Path(path_type=Path), default=None, metavar="RUN_DIR",
              help="Continue the interrupted calibration in RUN_DIR.")  # fmt: skip
@click.option("--method", type=click.Choice(["cma", "nm", "grid"]), default="cma", show_default=True,
              help="CMA-ES, Nelder-Mead, or a grid narrowed by successive halving (for one or two parameters "
              "with a switch-like effect, such as capture).")  # fmt: skip
@click.option(
    "--grid-points",
    type=int,
    default=11,
    show_default=True,
    help="Points per parameter of --method grid, evenly spaced on each parameter's search scale.",
)
@click.option("--sigma", type=float, default=0.2, show_default=True, help="Initial step, fraction of each range.")
@click.option("--prior", "prior_sd", type=float, default=None, metavar="SD",
              help="A normal prior toward the start (the default physics, or --physics), SD in units of each "
              "parameter's searched range on its search scale: a setting must earn its distance on the counts "
              "(default: none).")  # fmt: skip
@click.option("--max-evals", type=int, default=None, help="Stop after this many evaluations.")
@click.option("--workers", type=int, default=None, help="Worker processes (default all cores).")
@click.option("--scheduler", default=None, metavar="ADDRESS", help="Dask scheduler address.")
@physics_file_option
@out_option
@json_option
@click.pass_context
def calibrate(ctx, die_args, realrolls, name, free, bounds, seed, sims_per_eval, max_sims_per_eval, budget, resume,
              method, grid_points, sigma, prior_sd, max_evals, workers, scheduler, physics_profile, out_dir,
              as_json) -> None:  # fmt: skip
    """Fit the physics settings to dice with real rolls and write a physics profile.

    Maximizes the simulated likelihood of the real counts (common random
    numbers, CMA-ES); reports the fitted values with standard errors and
    the fit of every die.  The run is logged in OUT/NAME/ and can be
    resumed with --resume OUT/NAME; the profile OUT/NAME/NAME.toml is what
    validate and optimize take with --physics.
    """
    from dataclasses import replace

    from diefab.physics.profiles import load_profile
    from diefab.physics.simulate import PhysicsSettings
    from diefab.search.calibrate import CalibrationError, CalibrationLog, make_spec
    from diefab.search.simopt import RunError

    for value, hint in ((sims_per_eval, "--sims-per-eval"), (max_evals, "--max-evals"), (workers, "--workers")):
        if value is not None and value <= 0:
            raise click.BadParameter(f"{value} must be > 0", param_hint=hint)
    if resume is None and max_sims_per_eval is not None and max_sims_per_eval < sims_per_eval:
        raise click.BadParameter(f"{max_sims_per_eval} must be >= --sims-per-eval", param_hint="--max-sims-per-eval")
    if not (np.isfinite(budget) and budget > 0):
        raise click.BadParameter(f"{budget} must be a positive number of minutes", param_hint="--budget")
    if prior_sd is not None and not (np.isfinite(prior_sd) and prior_sd >= MIN_PRIOR_SD):
        raise click.BadParameter(f"{prior_sd} must be a standard deviation >= {MIN_PRIOR_SD:g}", param_hint="--prior")
    if scheduler is not None:
        refuse_options(ctx, ["workers"], "does not apply with --scheduler (the cluster's workers run the drops)")
    if resume is None:  # a resumed run keeps its stored method
        if method != "grid":
            refuse_options(ctx, ["grid_points"], "applies only to --method grid")
        else:
            refuse_options(ctx, ["sigma"], "applies only to --method cma or nm (a grid takes no step)")
    if not name or "/" in name or "\\" in name or name in (".", ".."):
        raise click.BadParameter(f"{name!r} must be a plain name (no folders)", param_hint="--name")
    warning = None
    if resume is not None:
        log = CalibrationLog(resume)
        log.lock()
        spec = log.spec()
        check_resume_folder(ctx, resume, out_dir)
        run_name = safe_name(Path(resume).resolve().name)
        if ctx.get_parameter_source("name").name == "COMMANDLINE" and name != run_name:
            raise click.UsageError(f"--name {name} differs from the folder of --resume {resume}", ctx=ctx)
        stored = {"seed": seed, "sims_per_eval": sims_per_eval, "method": method, "grid_points": grid_points,
                  "sigma0": sigma, "max_sims": max_sims_per_eval, "prior_sd": prior_sd}  # fmt: skip
        for key, value in stored.items():
            option = {"sigma0": "sigma", "max_sims": "max_sims_per_eval"}.get(key, key)
            source = ctx.get_parameter_source(option)
            if source is not None and source.name == "COMMANDLINE" and value != getattr(spec, key):
                flag = "--prior" if option == "prior_sd" else f"--{option.replace('_', '-')}"
                raise RunError(f"{flag} {value} differs from the run's {getattr(spec, key)} "
                               f"(stored in {log.spec_path})")  # fmt: skip
        for key, flag in (("die_args", "--die"), ("realrolls", "--realrolls"), ("free", "--free"),
                          ("bounds", "--bound"), ("physics_profile", "--physics")):  # fmt: skip
            source = ctx.get_parameter_source(key)
            if source is not None and source.name == "COMMANDLINE":
                raise RunError(f"a resumed run keeps the dice and settings stored in {log.spec_path}: leave out {flag}")
        history, warning = log.read()
        inputs = [path for die in spec.real_dice for path in design_inputs("", die.design)]
        check_outputs([output_path(log.folder, run_name, ".toml")], inputs)  # refused now, not at the first best
        changed = {}
        if ctx.get_parameter_source("budget").name == "COMMANDLINE" or spec.budget_minutes is None:
            changed["budget_minutes"] = float(budget)
        if max_evals is not None:
            changed["max_evaluations"] = max_evals
        if changed and any(getattr(spec, k) != v for k, v in changed.items()):
            spec = replace(spec, **changed)
            log.update(spec)
    else:
        if not die_args and not realrolls:
            raise CalibrationError("give at least one die with real rolls: --die DESIGN COUNTS or --realrolls FILE")
        run_name = name
        log = CalibrationLog(output_path(out_dir, run_name, ""))
        inputs = _inputs(die_args, realrolls, physics_profile)
        # every output, the profile too: refused now, not at the first best
        check_outputs([log.spec_path, log.path, log.identity_path, output_path(log.folder, run_name, ".toml")], inputs)
        dice = _dice(die_args, realrolls)
        names = [n.strip() for n in free.split(",") if n.strip()]
        base = load_profile(physics_profile) if physics_profile else PhysicsSettings()
        spec = make_spec(dice, free=names, base=base, bounds=_parse_bounds(bounds), seed=seed,
                         sims_per_eval=sims_per_eval, max_sims=max_sims_per_eval or 8 * sims_per_eval, method=method,
                         sigma0=sigma, grid_points=grid_points, budget_minutes=float(budget),
                         max_evaluations=max_evals, prior_sd=prior_sd)  # fmt: skip
        history = []
    budget, max_evals = spec.budget_minutes, spec.max_evaluations
    client = None
    if scheduler is not None:  # before the run folder exists: a wrong address leaves nothing behind
        from diefab.physics.simulate import dask_client

        client, _ = dask_client(scheduler)
    if resume is None:
        log.create(spec)
    if warning:
        click.echo(f"diefab: warning: {warning}", err=True)
    run(spec, log, run_name, history, budget, max_evals, workers, client, as_json, fresh=resume is None, inputs=inputs)


def run(spec, log, run_name, history, budget, max_evals, workers, client, as_json, fresh=False, inputs=()) -> None:
    """Run or continue the calibration in `log`; write the profile as it improves; print the report.

    `client` is a Dask client or None (local workers).  A `fresh` run that fails before its first
    evaluation leaves no run folder behind.
    """
    from diefab.cli.optimize import _simulation_view
    from diefab.physics.profiles import profile_to_toml
    from diefab.search.calibrate import calibrate as fit
    from diefab.search.calibrate import curvature, die_report, grid_interval, held_out
    from diefab.search.likelihood import predict_report

    dice = spec.real_dice
    profile_path = output_path(log.folder, run_name, ".toml")
    command = f"diefab calibrate (run {log.folder}; continue it with --resume)"
    live, update = _simulation_view(spec, budget * 60, history)
    records = list(history)
    names = ", ".join(d.name for d in dice)
    rolls = sum(d.n for d in dice)
    domain = {"fills": sorted({d.design.fill.kind for d in dice})}

    def summary(best):
        return {
            "deviance": best["deviance"],
            "deviance_per_roll": best["deviance"] / rolls,
            "drops_per_die": best["drops"],
            "seed": spec.seed,
            "dice": [d.name for d in dice],
            "rolls": [d.n for d in dice],
            **({"prior_sd": spec.prior_sd} if spec.prior_sd is not None else {}),
        }

    def write_profile(record, scores=None):
        text = profile_to_toml(spec.settings(record["x"]), name=run_name, calibration=summary(record) | (scores or {}),
                               domain=domain, comment=f"Written by: {command}",
                               description=f"physics calibrated to the real rolls of {names}")  # fmt: skip
        atomic_write(profile_path, text, inputs=inputs)

    def on_best(record):
        write_profile(record)
        if update:
            update(best=record)

    def on_evaluation(record):
        log.append(record)
        records.append(record)
        if update:
            update(record=record)

    result = run_logged(
        lambda: fit(spec, workers=workers, scheduler=client, history=history, on_evaluation=on_evaluation,
                    on_best=on_best, budget_seconds=budget * 60, max_evaluations=max_evals),
        log, live, client, f"diefab calibrate --resume {log.folder}",
        on_failure=(lambda: log.discard(profile_path)) if fresh else None,
    )  # fmt: skip
    best = result.best
    if best is None:
        from diefab.search.calibrate import CalibrationError

        if result.evaluations == 0:
            raise CalibrationError(f"the budget ran out before the first evaluation (--resume {log.folder})")
        raise CalibrationError(f"no candidate could be simulated in {result.evaluations} evaluations")
    fitted = curvature(records, spec, best)
    if spec.method == "grid":
        for name, interval in (grid_interval(records, spec, best) or {}).items():
            fitted[name]["interval"] = interval
    start = next((r for r in records if r.get("kind") == "start" and r.get("feasible")), None)
    per_die = []
    others = held_out(records, dice, x0=spec.x0, prior_sd=spec.prior_sd)
    for k, die in enumerate(dice):
        row = die_report(die, best["dice"][k]["counts"])
        if start is not None:
            row["start"] = die_report(die, start["dice"][k]["counts"])
        if others is not None:
            row["held_out"] = others[k]
        row["predict"] = predict_report(die)
        per_die.append(row)
    kind = None if others is None else ("grid" if spec.method == "grid" else "proposed")
    if others is not None:  # the profile keeps what it scores on its dice, fitted and each held out
        write_profile(best, {"tvd_fitted": [round(d["tvd"], 4) for d in per_die],
                             "tvd_held_out": [round(d["held_out"]["tvd"], 4) for d in per_die],
                             "held_out_candidates": kind})  # fmt: skip
    report = {
        "name": run_name,
        "fitted": fitted,
        "deviance": best["deviance"],
        "deviance_per_roll": best["deviance"] / rolls,
        "prior_sd": spec.prior_sd,
        "prior": best.get("prior"),
        "drops_per_die": best["drops"],
        "start_deviance": None if start is None else start["deviance"],
        "start_drops_per_die": None if start is None else start["drops"],
        "dice": per_die,
        "held_out_candidates": kind,
        "settings": spec.settings(best["x"]).as_dict(),
        "evaluations": result.evaluations,
        "replayed": result.replayed,
        "drops": result.drops * len(dice),
        "finished": result.finished,
        "run_folder": str(log.folder),
        "profile": str(profile_path),
    }
    if as_json:
        emit_json(report)
        return
    print_report(report)


#: How the held-out column chose each die's candidate, by the run's kind of candidates.
HELD_OUT = {
    "grid": "each at the grid point the other dice fit best",
    "proposed": "each at the evaluated point the other dice fit best, among points proposed with every die in view",
}


def print_report(report) -> None:
    """The human-readable calibration report."""
    from rich.table import Column, Table

    con = console()
    con.print(f"{BOLD}{report['name']}{PLAIN}: deviance {report['deviance']:.2f} "
              f"({report['deviance_per_roll']:.4f} per roll) at {report['drops_per_die']} drops per die"
              + ("" if report["prior_sd"] is None else
                 f"; prior sd {report['prior_sd']:g} toward the start, {report['prior']:.2f} at the fit")
              + ("" if report["start_deviance"] is None else
                 f"; at the start {report['start_deviance']:.2f} ({report['start_drops_per_die']} drops)"))  # fmt: skip
    gridded = any("interval" in fit for fit in report["fitted"].values())
    table = Table("parameter", "fitted", "grid points within ΔG² 1" if gridded else "standard error")
    for name, fit in report["fitted"].items():
        if gridded:
            spread = "{:.4g} – {:.4g}".format(*fit["interval"])
        else:
            spread = "not determined by the counts" if fit["se"] is None else f"{fit['se']:.3g}"
        table.add_row(name, f"{fit['value']:.4g}", spread)
    con.print(table)
    held = [d["held_out"] for d in report["dice"] if "held_out" in d]
    columns = ["die", "rolls", "fitted", *(["held out"] if held else []), "start", "predict", "noise", "p"]
    # a narrow terminal folds a long die name, never a figure
    dice = Table(Column(columns[0], overflow="fold"), *(Column(c, no_wrap=True) for c in columns[1:]))
    for d in report["dice"]:
        start, predicted = d.get("start"), d["predict"]["tvd"]
        dice.add_row(d["name"], str(d["rolls"]), f"{d['tvd']:.4f}", *([f"{d['held_out']['tvd']:.4f}"] if held else []),
                     "-" if start is None else f"{start['tvd']:.4f}", "-" if predicted is None else f"{predicted:.4f}",
                     f"{d['noise_tvd']:.4f}", f"{d['p_value']:.3g}")  # fmt: skip
    con.print(dice)
    models = "/".join(sorted({d["predict"]["model"] for d in report["dice"]}))
    con.print("TVD to the real rolls: fitted (in-sample)" + (", held out" if held else "") + ", at the start; "
              f"predict: what diefab predict gives ({models}, fitted on no real die); noise: what sampling alone "
              "gives; p: the fit's deviance against chi-squared")  # fmt: skip
    predicted, fitted = _mean_tvd([d["predict"] for d in report["dice"]]), _mean_tvd(report["dice"])
    if all(d["predict"]["tvd"] is not None for d in report["dice"]) and predicted < fitted:
        con.print(f"diefab predict, fitted on no real die, is closer to these rolls than the fitted physics (mean TVD "
                  f"{predicted:.4f} against {fitted:.4f} in-sample at {report['drops_per_die']} drops per die): the "
                  "profile does not improve on it for these dice")  # fmt: skip
    if held:
        rows = report["dice"]
        start = f", at the start {_mean_tvd([d['start'] for d in rows]):.4f}" if all("start" in d for d in rows) else ""
        con.print(f"mean TVD: fitted {_mean_tvd(rows):.4f} (in-sample), held out {_mean_tvd(held):.4f} "
                  f"({HELD_OUT[report['held_out_candidates']]}){start}; "
                  f"sampling alone {float(np.mean([d['noise_tvd'] for d in rows])):.4f}")  # fmt: skip
    state = "finished" if report["finished"] else "stopped by the budget or --max-evals (resume to continue)"
    con.print(f"{report['evaluations']} evaluations ({report['replayed']} replayed), {report['drops']:,} drops; "
              f"{state}\nlog {report['run_folder']}\nwrote {report['profile']}")  # fmt: skip


def _mean_tvd(rows) -> float:
    """Mean TVD of the rows that have one (nan if none)."""
    tvds = [r["tvd"] for r in rows if r["tvd"] is not None]
    return float(np.mean(tvds)) if tvds else float("nan")
