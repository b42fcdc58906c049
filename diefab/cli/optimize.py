"""``diefab optimize``: fit a design's parameters to its target (solid-angle, fast or simulation)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import click
import numpy as np

from diefab.cli.common import (
    BOLD,
    PLAIN,
    apply_fill,
    check_resume_folder,
    console,
    design_argument,
    design_inputs,
    emit_json,
    fill_options,
    free_parameters,
    get_design,
    json_option,
    note_fast_fill,
    one_line_name,
    out_option,
    physics_file_option,
    physics_settings,
    pop_fill,
    profile_inputs,
    refuse_options,
    run_logged,
    seed_option,
    simulation_options,
    values_dict,
)
from diefab.core.files import atomic_write, check_outputs, ensure_dir, output_path, safe_name
from diefab.dice.design import format_value


def _check_free(d) -> None:
    """Refuse, before any folder is made, a design whose family has nothing to optimize (convex, mesh)."""
    from diefab.core.errors import DesignError
    from diefab.dice.families import family

    if not family(d.family).free_names(d.params):
        raise DesignError(f"family {d.family!r} has no parameters to optimize")


@click.command()
@design_argument
@click.option(
    "--model",
    default="solid-angle",
    show_default=True,
    help="Landing model to fit: solid-angle, basins (quasi-static), fast, or simulation (pybullet drops).",
)
@click.option("--target", default=None, help="Target distribution (default: the design's).")
@seed_option("Seed of the random starts (and, with --model simulation, of the drops).")
@click.option(
    "--min-margin",
    type=float,
    default=0.05,
    show_default=True,
    help="Smallest stability margin of every face, model units (the girdle half-width is 1).",
)
@click.option("--starts", type=click.IntRange(0, 1000), default=6, show_default=True, help="Random starts.")
@click.option(
    "--free",
    default=None,
    metavar="A,B,...",
    help="Parameters to optimize (default: all of the family's, e.g. a,b,c,d,e for the gem).",
)
@click.option("--objective", type=click.Choice(["eq2", "tvd", "jsd"]), default="eq2", show_default=True)
@click.option("--name", default=None, callback=one_line_name,
              help="Name of the optimized design (default DESIGN-MODEL-opt).")  # fmt: skip
@fill_options("paper", "print")
@simulation_options
@click.option("--robust", is_flag=True,
              help="[simulation] Minimize the worst objective over the standard throws and tables (the shipped "
              "profiles soft-tray, wooden-table, hard-tray, low-spin, high-spin; each over --physics).")  # fmt: skip
@physics_file_option
@out_option
@json_option
@click.pass_context
def optimize(ctx, design, params, model, target, seed, min_margin, starts, free, objective, name, robust,
             physics_profile, out_dir, as_json, **sim) -> None:  # fmt: skip
    """Fit DESIGN's parameters to its target; write the result as a template TOML.

    With --model simulation the objective uses pybullet drop frequencies
    (diefab validate's physics); the run is logged in OUT/NAME/ and can be
    resumed with --resume OUT/NAME.  --physics PROFILE sets its physics.
    """
    from diefab.dice.design import design_to_toml
    from diefab.search.optimize import optimize_design

    fill = pop_fill(sim)
    if model == "simulation":
        return optimize_simulation(ctx, design, params, target, seed, min_margin, starts, free, objective, name,
                                   robust, physics_profile, out_dir, as_json, fill=fill, **sim)  # fmt: skip
    if robust:
        raise click.BadParameter("--robust needs --model simulation (the other models do not simulate)",
                                 param_hint="--robust")  # fmt: skip
    refuse_options(ctx, list(sim), "applies only to --model simulation")
    d = apply_fill(get_design(design, params, target), **fill)
    if physics_profile is not None:
        physics_settings(d, physics_profile)  # a bad profile is an error whatever the model
        click.echo(f"note: --physics only changes --model simulation; the {model} model does not simulate",
                   err=True)  # fmt: skip
    if not np.isfinite(min_margin) or min_margin < 0:
        raise click.BadParameter(f"{min_margin} must be a non-negative number", param_hint="--min-margin")
    names = free_parameters(d, free)
    _check_free(d)
    ensure_dir(out_dir)
    name = name or f"{d.name}-{model}-opt"
    inputs = design_inputs(design, d) + profile_inputs(physics_profile)
    path = output_path(out_dir, name, ".toml")
    check_outputs([path], inputs)
    note_fast_fill(d, model, d.fill.kind)
    result = optimize_design(
        d, model=model, objective=objective, names=names, min_margin=min_margin, starts=starts, seed=seed, name=name
    )
    best = result.design
    atomic_write(
        path,
        design_to_toml(best, comment=f"Written by: diefab optimize {design} --model {model} --seed {seed}"),
        inputs=inputs,
    )
    goal = best.target_distribution.aligned(best.support)
    margins = result.margins
    report = {
        "design": best.name,
        "model": model,
        "objective_name": objective,
        "objective": result.objective,
        "params": dict(best.params),
        "values": values_dict(best, result.values),
        "target_values": values_dict(best, goal),
        "margins": dict(zip(best.polyhedron.names, margins.tolist())),
        "min_margin": result.min_margin,
        "min_margin_mm": result.min_margin * best.mm_per_unit,
        "binding_face": result.binding_face,
        "evaluations": result.evaluations,
        "starts": result.starts,
        "design_file": str(path),
    }
    if as_json:
        emit_json(report)
        return
    con = console()
    con.print(
        f"{BOLD}{best.name}{PLAIN}  "
        + " ".join(f"{k}={v:.4f}" for k, v in best.params.items())
        + f"\n{objective} = {result.objective:.5f} under the {model} model "
        f"({result.evaluations} evaluations from {result.starts} starts)"
    )
    con.print(
        "value      "
        + " ".join(f"{format_value(v, min(best.support) < 0):>6s}" for v in best.support)
        + "\nmodel x81  "
        + " ".join(f"{81 * q:6.2f}" for q in result.values)
        + "\ntarget x81 "
        + " ".join(f"{81 * q:6.2f}" for q in goal)
    )
    con.print(
        f"smallest stability margin {result.min_margin:.4f} ({result.min_margin * best.mm_per_unit:.2f} mm at "
        f"{best.size_mm:g} mm) on face {result.binding_face}; required {min_margin:g}"
    )
    con.print(f"wrote {path}")


def _simulation_view(spec, budget_s: float, history):
    """A rich live panel on stderr (None when stderr is not a terminal)."""
    con = console(stderr=True)
    if not con.is_terminal:
        return None, None
    from rich.live import Live
    from rich.table import Table

    state = {
        "evals": len(history),
        "drops": sum(r["drops"] for r in history),
        "best": None,
        "elapsed": history[-1].get("elapsed", 0.0) if history else 0.0,
    }

    def render():
        t = Table.grid(padding=(0, 2))
        best = state["best"]
        left = max(budget_s - state["elapsed"], 0.0)
        t.add_row("evaluations", str(state["evals"]), "drops simulated", f"{state['drops']:,}")
        t.add_row(
            f"best {spec.objective}",
            "-" if best is None else f"{best['objective']:.5f} at {best['drops']} drops",
            "time left",
            f"{left / 60:.1f} min",
        )
        if best is not None:
            t.add_row("best params", " ".join(f"{k}={v:.4f}" for k, v in best["params"].items()), "", "")
        return t

    live = Live(render(), console=con, refresh_per_second=2, transient=False)

    def update(record=None, best=None):
        if record is not None:
            state["evals"] += 1
            state["drops"] += record["drops"]
            state["elapsed"] = record.get("elapsed", state["elapsed"])
        if best is not None:
            state["best"] = best
        live.update(render())

    return live, update


def optimize_simulation(ctx, design, params, target, seed, min_margin, starts, free, objective, name, robust,
                        physics_profile, out_dir, as_json, sims_per_eval, max_sims_per_eval, budget, resume, method,
                        start_model, sigma, max_evals, workers, scheduler, fill=None) -> None:  # fmt: skip
    """``diefab optimize DESIGN --model simulation``: see :mod:`diefab.search.simopt`."""
    from diefab.dice.design import design_to_toml
    from diefab.dice.families import family
    from diefab.search.runid import pinned_toml
    from diefab.search.runlog import RunLog
    from diefab.search.simopt import RunError, RunSpec, best_design, optimize_by_simulation, start_point

    if not (np.isfinite(budget) and budget > 0):
        raise click.BadParameter(f"{budget} must be a positive number of minutes", param_hint="--budget")
    if sims_per_eval <= 0:
        raise click.BadParameter(f"{sims_per_eval} must be > 0", param_hint="--sims-per-eval")
    from diefab.physics.simulate import MAX_DROPS

    for value, hint in ((sims_per_eval, "--sims-per-eval"), (max_sims_per_eval, "--max-sims-per-eval")):
        if value is not None and value > MAX_DROPS:
            raise click.BadParameter(f"{value} must be at most {MAX_DROPS:,} drops", param_hint=hint)
    if resume is None and max_sims_per_eval is not None and max_sims_per_eval < sims_per_eval:  # else: stored
        raise click.BadParameter(f"{max_sims_per_eval} must be >= --sims-per-eval", param_hint="--max-sims-per-eval")
    if max_evals is not None and max_evals <= 0:
        raise click.BadParameter(f"{max_evals} must be > 0", param_hint="--max-evals")
    if workers is not None and not 1 <= workers <= 1024:
        raise click.BadParameter(f"{workers} must be in [1, 1024]", param_hint="--workers")
    if scheduler is not None:
        refuse_options(ctx, ["workers"], "does not apply with --scheduler (the cluster's workers run the drops)")
    if objective not in ("eq2", "tvd"):
        raise click.BadParameter(f"{objective!r}: a simulation run minimizes eq2 or tvd", param_hint="--objective")
    if not np.isfinite(min_margin) or min_margin < 0:
        raise click.BadParameter(f"{min_margin} must be a non-negative number", param_hint="--min-margin")
    d = apply_fill(get_design(design, params, target), **(fill or {}))
    _check_free(d)
    d.check_stable(0.0)
    if method is None and resume is None:
        method = "correction" if robust else "cma"
    inputs = design_inputs(design, d) + profile_inputs(physics_profile)
    warning = None
    budget_given = ctx.get_parameter_source("budget").name == "COMMANDLINE"
    if resume is not None:
        refuse_options(ctx, ["name", "starts", "params"],
                       "does not apply with --resume (the run's design and start are in its run.json)")  # fmt: skip
        log = RunLog(resume)
        log.lock()
        spec = log.spec()
        check_resume_folder(ctx, resume, out_dir)
        stored = spec.design
        if (stored.name, stored.family, dict(stored.values), stored.target) != (d.name, d.family, dict(d.values),
                                                                                 d.target):  # fmt: skip
            raise RunError(f"run {resume} optimizes design {stored.name!r} for {stored.target}, not {d.name!r} "
                           f"for {d.target}")  # fmt: skip
        given = {  # option -> (value given, value stored)
            "seed": (seed, spec.seed), "sims_per_eval": (sims_per_eval, spec.sims_per_eval),
            "objective": (objective, spec.objective), "min_margin": (min_margin, spec.min_margin),
            "method": (method, spec.method), "start_model": (start_model, spec.start), "sigma": (sigma, spec.sigma0),
            "max_sims_per_eval": (max_sims_per_eval, spec.max_sims),
            "free": (",".join(free_parameters(d, free) or ()), ",".join(spec.names)),
        }  # fmt: skip
        for key, (value, kept) in given.items():
            source = ctx.get_parameter_source(key)
            if source is not None and source.name == "COMMANDLINE" and value != kept:
                flag = next(p.opts[0] for p in ctx.command.params if p.name == key)
                raise RunError(f"{flag} {value} differs from the run's {kept} (stored in {log.spec_path})")
        if any(v is not None for v in (fill or {}).values()) and d.fill != stored.fill:
            raise RunError(f"the fill given ({d.fill.describe()}) differs from the run's ({stored.fill.describe()}, "
                           f"stored in {log.spec_path})")  # fmt: skip
        if physics_profile is not None and physics_settings(d, physics_profile).as_dict() != spec.physics:
            raise RunError(f"--physics {physics_profile} differs from the run's physics (stored in {log.spec_path})")
        if ctx.get_parameter_source("robust").name == "COMMANDLINE" and robust != bool(spec.robust):
            raise RunError(f"--robust differs from the run's settings (stored in {log.spec_path})")
        history, warning = log.read()
        run_name = safe_name(Path(resume).resolve().name)
        best_path = output_path(log.folder, run_name, ".toml")
        check_outputs([best_path], inputs)
        changed = {}
        if budget_given or spec.budget_minutes is None:
            changed["budget_minutes"] = float(budget)
        if max_evals is not None:
            changed["max_evaluations"] = max_evals
        if changed:
            spec = replace(spec, **changed)
            log.update(spec)
        fresh = False
    else:
        names = free_parameters(d, free) or family(d.family).free_names(d.params)
        run_name = name or f"{d.name}-simulation-opt"
        log = RunLog(output_path(out_dir, run_name, ""))
        if log.holds_run():
            raise RunError(f"{log.folder} already holds a run: resume it with --resume {log.folder} or pick --name")
        best_path = output_path(log.folder, run_name, ".toml")
        check_outputs([log.spec_path, log.path, best_path], inputs)
        physics = physics_settings(d, physics_profile)
        throws = ()
        if robust:
            from diefab.physics.profiles import STANDARD, load_profile

            throws = tuple(load_profile(p, base=physics.as_dict()).as_dict() for p in STANDARD)
        x0 = start_point(d, names, model=start_model, objective=objective, min_margin=min_margin, starts=starts,
                         seed=seed)  # fmt: skip
        spec = RunSpec(
            design_toml=pinned_toml(d), names=tuple(names), x0=tuple(float(v) for v in x0), objective=objective,
            min_margin=float(min_margin), seed=seed, sims_per_eval=sims_per_eval,
            max_sims=max_sims_per_eval or 16 * sims_per_eval, method=method, sigma0=sigma,
            physics=physics.as_dict(), start=start_model, robust=throws, budget_minutes=float(budget),
            max_evaluations=max_evals,
        )  # fmt: skip
        history = []
        fresh = True
    budget = spec.budget_minutes
    max_evals = spec.max_evaluations
    client = None
    if scheduler is not None:  # before the run folder exists: a wrong address leaves nothing behind
        from diefab.physics.simulate import dask_client

        client, _ = dask_client(scheduler)
    if fresh:
        log.create(spec)
    if warning:
        click.echo(f"diefab: warning: {warning}", err=True)
    command = f"diefab optimize {design} --model simulation --seed {spec.seed} (run {log.folder})"
    live, update = _simulation_view(spec, budget * 60, history)

    def on_best(record):
        best = best_design(spec, record, run_name)
        atomic_write(best_path, design_to_toml(best, comment=f"Written by: {command}"), inputs=inputs)
        if update:
            update(best=record)

    last = {"elapsed": history[-1].get("elapsed") if history else None}

    def on_evaluation(record):
        log.append(record)
        last["elapsed"] = record["elapsed"]
        if update:
            update(record=record)

    result = run_logged(
        lambda: optimize_by_simulation(
            spec, workers=workers, scheduler=client, history=history, on_evaluation=on_evaluation, on_best=on_best,
            budget_seconds=budget * 60, max_evaluations=max_evals,
        ),
        log, live, client,
        f"diefab optimize {design} --model simulation --resume {log.folder} (the run keeps its budget of "
        f"{budget:g} minutes in all; --budget changes it)",
        # a run that failed before its first evaluation leaves no folder to block the corrected rerun
        on_failure=(lambda: log.discard(best_path)) if fresh else None,
    )  # fmt: skip
    if result.best is None:
        if result.evaluations == 0:
            again = f"diefab optimize {design} --model simulation --resume {log.folder} --budget MINUTES"
            raise RunError(f"the budget ran out before the first evaluation: resume with a larger one ({again})")
        raise RunError(f"no stable candidate was simulated in {result.evaluations} evaluations: "
                       "lower --min-margin or change the target")  # fmt: skip
    best = result.best
    report = {
        "design": run_name,
        "model": "simulation",
        "objective_name": spec.objective,
        "objective": best["objective"],
        "drops_per_evaluation": best["drops"],
        "params": best["params"],
        "min_margin": best["min_margin"],
        "evaluations": result.evaluations,
        "replayed": result.replayed,
        "drops": result.drops * max(len(spec.robust), 1),
        "finished": result.finished,
        "robust": bool(spec.robust),
        "objectives": best.get("objectives"),
        "run_folder": str(log.folder),
        "design_file": str(best_path),
        "elapsed_seconds": last["elapsed"],
    }
    if as_json:
        emit_json(report)
        return
    con = console()
    con.print(
        f"{BOLD}{run_name}{PLAIN}  "
        + " ".join(f"{k}={v:.4f}" for k, v in best["params"].items())
        + f"\n{spec.objective} = {best['objective']:.5f} at {best['drops']} drops (seed {spec.seed}); "
        f"{result.evaluations} evaluations ({result.replayed} replayed), {report['drops']:,} drops; "
        f"min margin {best['min_margin']:.4f}"
    )
    if spec.robust and best.get("objectives"):
        from diefab.physics.profiles import STANDARD

        con.print(f"worst over {len(spec.robust)} throws and tables; each: "
                  + "  ".join(f"{n} {o:.5f}" for n, o in zip(STANDARD, best["objectives"])))  # fmt: skip
    con.print(f"log {log.path}\nwrote {best_path}")
