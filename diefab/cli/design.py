"""``diefab design``: from a target distribution to a die that predict, validate, net and stl take."""

from __future__ import annotations

import contextlib
import re
import shlex
import time
import unicodedata
from pathlib import Path

import click
import numpy as np

from diefab.cli.common import (
    BOLD,
    FILL_OPTIONS,
    PLAIN,
    check_fill_options,
    check_size,
    console,
    emit_json,
    fill_options,
    json_option,
    named_folder,
    out_option,
    physics_file_option,
    profile_inputs,
    report_option,
    seed_option,
)

_METHOD = {
    "fair": "a fair die, its faces counted out to the target",
    "fair-nearest": "a fair die, its faces counted out as near the target as its face count allows",
    "two-class": "two classes of faces counted out to the target, one share tuned",
    "two-class-nearest": "two classes of faces counted out as near the target as they allow, one share tuned",
    "shaped": "shape optimized",
}
#: Exit status of a die written whose closing check is further from its target than --tolerance.
EXIT_ABOVE_TOLERANCE = 3


def _slug(text: str) -> str:
    text = unicodedata.normalize("NFKC", text)  # as the target is read: a fullwidth 2d6 is 2d6
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-") or "target"


@click.command()
@click.argument("target", metavar="TARGET")
@click.option("--faces", type=click.IntRange(2, 120), default=None, help="Resting faces of the die (default: chosen).")
@click.option("--family", "family_name", default="auto", show_default=True,
              help="Die family (ngem, prism, bipyramid, trapezohedron, icosahedral, cuboid, freeform, gem) "
              "or auto.")  # fmt: skip
@fill_options("paper", "print")
@click.option("--model", type=click.Choice(["fast", "solid-angle", "basins", "simulation"]), default="simulation",
              show_default=True,
              help="Model optimized; simulation refines the fast model's die against pybullet drops.")  # fmt: skip
@click.option("--max-drops", type=click.IntRange(1, 100_000_000), default=64_000, show_default=True,
              help="Drops the search may spend (tuning or refinement; the closing check comes on top). The same "
              "seed and options give the same die.")  # fmt: skip
@click.option(
    "--budget",
    type=float,
    default=None,
    help="Wall-time cap of the search, minutes (default none). A run it ends is not reproducible.",
)
@click.option("--tolerance", type=float, default=0.02, show_default=True,
              help="Largest validated TVD of a die that rolls like its target; above it the die is written and "
              "the exit status is 3.")  # fmt: skip
@click.option("--name", default=None, help="Design name (default FAMILY-TARGET).")
@seed_option("Seed of starts and drops.")
@click.option("--size", "size_mm", type=float, default=30.0, show_default=True,
              help="Size in mm of the family's reference length (see the design file's description).")  # fmt: skip
@click.option("--min-margin", type=float, default=0.05, show_default=True,
              help="Smallest stability margin of every resting face, model units.")  # fmt: skip
@click.option("--validate-sims", type=click.IntRange(0, 10_000_000), default=10_000, show_default=True,
              help="Drops of the closing check (on a seed the search never used); 0 skips it.")  # fmt: skip
@click.option("--workers", type=click.IntRange(1, 256), default=None, help="Worker processes (default all cores).")
@click.option("--scheduler", default=None, metavar="ADDRESS", help="Run the drops on this Dask scheduler.")
@click.option("--checkpoint", "checkpoint", type=click.Path(file_okay=False), default=None, callback=named_folder,
              metavar="DIR",
              help="Keep every drop of the search and the closing check in DIR; the same command with the same DIR "
              "drops only what it had not, and writes the same die (without --budget).")  # fmt: skip
@physics_file_option
@click.option("--flat-faces", is_flag=True,
              help="Simulate the faces the die rests on flat where the engine's one hull folds them (slower; "
              "kept in the design's [physics] table).")  # fmt: skip
@click.option("--robust", is_flag=True,
              help="Refine and check against every standard throw and table (the shipped profiles soft-tray, "
              "wooden-table, hard-tray, low-spin, high-spin; each over --physics), judged by the worst.")  # fmt: skip
@out_option
@report_option
@json_option
@click.pass_context
def design(ctx, target, faces, family_name, model, max_drops, budget, tolerance, name, seed, size_mm, min_margin,
           validate_sims, workers, scheduler, checkpoint, physics_profile, flat_faces, robust, out_dir, report_file,
           as_json, fill_kind, **fill_settings) -> None:  # fmt: skip
    """Design a die that rolls like TARGET (2d6, 3dF, binomial:4, uniform:3, 1:3,2:3,...).

    Picks a family and face count that can carry the target's values,
    assigns values to faces, optimizes the shape, checks it by simulation on
    a fresh seed, and writes OUT/NAME.toml.  With --fill paper or print (and
    their settings) the die is designed as it will be made.  With --physics
    the die is refined and checked under that profile, which the design file
    keeps as its [physics] table; with --robust, under each standard throw
    and table at once.

    With --checkpoint DIR, a search that is stopped (Ctrl-C, a signal, a
    dead worker) keeps the drops it made in DIR, and the same command run
    again with DIR continues it: the drops it holds are not run again, and
    the die written is the die an uninterrupted run writes (unless --budget
    cut a stage short).

    Exit status: 0 when the closing check's TVD is within --tolerance, 3 when
    it is not (the die is still written, and stderr says what limits it), 2
    on bad input, 130 when interrupted.
    """
    from dataclasses import replace

    from diefab.cli.common import note_profile_domain, refuse_options
    from diefab.core.files import atomic_write, check_outputs, ensure_dir, hold_lock, output_path
    from diefab.dice.design import design_to_toml
    from diefab.dice.targets import parse_target
    from diefab.made.fill import Fill
    from diefab.physics.profiles import STANDARD, load_profile
    from diefab.physics.simulate import PhysicsSettings
    from diefab.search.synthesis import synthesize
    from diefab.search.verdict import closing_check, fast_agreement, judge
    from diefab.stats.goodness import pearson_divergence, tvd

    t0 = time.monotonic()
    goal = parse_target(target)
    check_fill_options(fill_kind or "solid", fill_settings)
    changes = {FILL_OPTIONS[k][0]: v for k, v in fill_settings.items() if v is not None}
    made = Fill(kind=fill_kind or "solid", **changes)  # a setting out of range: DesignError, one line
    if budget is not None and not (np.isfinite(budget) and budget > 0):
        raise click.BadParameter(f"{budget} must be a positive number of minutes", param_hint="--budget")
    if not (np.isfinite(tolerance) and 0 < tolerance < 1):
        raise click.BadParameter(f"{tolerance} must be a number in (0, 1)", param_hint="--tolerance")
    if not (np.isfinite(size_mm) and size_mm > 0):
        raise click.BadParameter(f"{size_mm} must be a positive number of millimetres", param_hint="--size")
    check_size(size_mm)
    if not (np.isfinite(min_margin) and min_margin >= 0):
        raise click.BadParameter(f"{min_margin} must be a non-negative number", param_hint="--min-margin")
    if name is not None and not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._-]{0,99}", name):
        raise click.BadParameter(f"{name!r}: use letters, digits, '.', '_' and '-'", param_hint="--name")
    if robust and model != "simulation":
        raise click.BadParameter("--robust needs --model simulation (the other models do not simulate)",
                                 param_hint="--robust")  # fmt: skip
    if scheduler is not None:
        refuse_options(ctx, ["workers"], "does not apply with --scheduler (the cluster's workers run the drops)")
    physics = {} if physics_profile is None else load_profile(physics_profile).as_dict()
    if physics_profile is not None:
        note_profile_domain(physics_profile, made.kind)
    if flat_faces:
        physics = PhysicsSettings.from_mapping(physics, flat_faces=True).as_dict()
    throws = [load_profile(p, base=physics).as_dict() for p in STANDARD] if robust else []
    family = None if family_name == "auto" else family_name
    ensure_dir(out_dir)
    # one process per design: its outputs (refused now if they cannot be written), or, before the die's family
    # names it, its target in this folder
    outputs = [] if report_file is None else [report_file]
    if name is not None:
        outputs.append(output_path(out_dir, name, ".toml"))
    # the target too, named or not: a run without --name and one naming its default name exclude each other
    hold_lock(Path(out_dir) / f"design-{_slug(target)}", f"design {target} into {out_dir}")
    inputs = profile_inputs(physics_profile)
    check_outputs(outputs, inputs)
    store = None if checkpoint is None else _store(checkpoint)
    err = console(stderr=True)
    say = (lambda text: err.print(text, markup=False)) if not as_json else None
    with _kept(store), _Stages(err if not as_json else None) as stages:
        found = synthesize(
            goal, faces=faces, family=family, fill=made, model=model,
            budget_seconds=None if budget is None else budget * 60, max_drops=max_drops, tolerance=tolerance,
            seed=seed, name=name or "die", size_mm=size_mm, min_margin=min_margin, workers=workers,
            scheduler=scheduler, progress=say, ticker=stages.tick, settings=PhysicsSettings.from_mapping(physics),
            throws=throws, store=store,
        )  # fmt: skip
    d = replace(
        found.design,
        physics=physics,
        name=name or f"{found.design.family}-{_slug(target)}",
        description=f"designed for {target}{f' made as {made.describe()},' * (made.kind != 'solid')} "
        f"by diefab design: {_METHOD[found.method]} "
        f"({found.model} model, seed {seed})",
    )
    smallest = float(np.min(np.where(d.resting_mask(), d.margins(), np.inf)))
    if smallest <= min_margin:  # a fair or counted die's shape is fixed by its counts, not by the margin asked
        click.echo(f"diefab: note: the die's smallest stability margin is {smallest:.4f}, not above --min-margin "
                   f"{min_margin:g}: a die whose faces are counted out takes the shape its counts give",
                   err=True)  # fmt: skip
    given = {"size_mm": "--size", "min_margin": "--min-margin", "tolerance": "--tolerance"}
    how = "".join(f" --{k.replace('_', '-')} {v}" for k, v in fill_settings.items() if v is not None)
    how += "".join(f" {flag} {ctx.params[k]}" for k, flag in given.items()
                   if ctx.get_parameter_source(k) is not click.core.ParameterSource.DEFAULT)  # fmt: skip
    how += f" --physics {shlex.quote(str(physics_profile))}" if physics_profile else ""
    how += (" --robust" if robust else "") + (" --flat-faces" if flat_faces else "")
    how += (f" --family {family_name}" if family_name != "auto" else "") + (f" --faces {faces}" if faces else "")
    # written before the closing check, which may take long: an interrupted check keeps the die it found
    path = atomic_write(
        output_path(out_dir, d.name, ".toml"),
        design_to_toml(
            d,
            comment=f"Written by: diefab design {target} --model {model} --seed {seed} --max-drops {max_drops}"
            + (f" --fill {made.kind}" if made.kind != "solid" else "")
            + how,
        ),
        inputs=inputs,
    )  # fmt: skip
    aligned = goal.aligned(d.support)
    validated, verdict, agreement = None, None, None
    if validate_sims:
        with _kept(store), _Stages(err if not as_json else None) as stages:
            tell = lambda done, total: stages.tick("closing check", done, total)  # noqa: E731
            validated = closing_check(d, validate_sims, seed, throws=throws, workers=workers, scheduler=scheduler,
                                      progress=tell, store=store)  # fmt: skip
        agreement = fast_agreement(d, validated["probabilities"])
        verdict = judge(goal, validated, tolerance, method=found.method, nearest=found.nearest,
                        simulated_tvd=found.simulated_tvd, drops=found.drops,
                        max_drops=max_drops if model == "simulation" else None)  # fmt: skip
        if throws:
            worst = max(range(len(throws)), key=lambda i: validated["throws"][i]["tvd"])
            validated = {**validated, "profiles": dict(zip(STANDARD, validated.pop("throws"))),
                         "worst_profile": STANDARD[worst]}  # fmt: skip
    said = None
    if validated is not None and "profiles" not in validated:  # the plain verdict on the closing check's drops
        from diefab.stats.sequential import sequential_counts
        from diefab.stats.verdict import target_label
        from diefab.stats.verdict import verdict as plain_verdict

        counts = np.rint(np.asarray(validated["probabilities"]) * validated["landed"]).astype(int)
        said = plain_verdict(counts, aligned, target_label(target), p_value=validated["p_value"],
                             sequential=sequential_counts(counts, aligned, tolerance)).text  # fmt: skip
    report = {
        "design_file": str(path),
        "family": d.family,
        "params": dict(d.params),
        "faces": list(d.polyhedron.names),
        "values": dict(d.values),
        "predicted": {str(v): float(p) for v, p in zip(d.support, found.predicted)},
        "target": {str(v): float(p) for v, p in zip(d.support, aligned)},
        "model": found.model,
        "method": found.method,
        "objective": float(pearson_divergence(found.predicted, aligned)),
        "tvd": float(tvd(found.predicted, aligned)),
        "simulated_tvd": found.simulated_tvd,
        "fast": None if agreement is None else {
            "predicted": {str(v): float(p) for v, p in zip(d.support, agreement["fast"])},
            "tvd": float(tvd(agreement["fast"], aligned)),
            "tvd_to_simulation": agreement["tvd_between"],
            "trusted": agreement["trusted"],
        },
        "nearest_counted": None if found.nearest is None else {
            "kind": found.nearest.kind, "faces": found.nearest.faces, "tvd": float(found.nearest.tvd)},
        "validated": validated,
        "tolerance": tolerance,
        "smallest_margin": smallest,
        "min_margin": min_margin,
        "within_tolerance": None if verdict is None else verdict.met,
        "verdict": None if verdict is None else verdict.why,
        "plain_verdict": said,
        "max_drops": max_drops,
        "drops": found.drops,
        "reproducible": not found.capped,
        "physics": physics_profile,
        "robust": robust,
        "tried": found.tried,
        "refinement": found.steps,
        "seconds": time.monotonic() - t0,
    }  # fmt: skip
    if store is not None:
        report["checkpoint"] = {"folder": str(checkpoint), "drops": store.drops, "resumed": store.resumed}
    if report_file is not None:
        from diefab.fabricate.report import design_report, render_report

        page = render_report(design_report(d, found.predicted, found.model, validated))
        report["report"] = str(atomic_write(report_file, page.encode("utf-8"), inputs=[*inputs, path]))
    if as_json:
        emit_json(report)
    else:
        _print_report(d, report, path)
        if store is not None:
            console().print(f"drops kept in {checkpoint} ({store.resumed:,} of {store.drops:,} from before)",
                            markup=False)  # fmt: skip
        if report_file is not None:
            console().print(f"wrote {report['report']}")
    if found.capped:
        click.echo(f"diefab: note: the --budget wall-time cap of {budget:g} minutes ended the search early: this "
                   "die depends on the machine's speed and is not reproducible from the seed and options; drop "
                   "--budget (or lower --max-drops) for a reproducible run", err=True)  # fmt: skip
    if verdict is not None and not verdict.met:
        click.echo(f"diefab: {verdict.why}. The die is written to {path}, but it does not roll like {target} "
                   f"within --tolerance {tolerance:g} (exit status {EXIT_ABOVE_TOLERANCE})", err=True)  # fmt: skip
        raise click.exceptions.Exit(EXIT_ABOVE_TOLERANCE)
    if validated is None:
        click.echo("diefab: note: --validate-sims 0 skips the closing check, so nothing checked the die against "
                   "--tolerance", err=True)  # fmt: skip


@contextlib.contextmanager
def _kept(store):
    """On a stop with --checkpoint, say how many drops are kept and where (one line, exit status 130)."""
    try:
        yield
    except KeyboardInterrupt:
        if store is None:
            raise
        held = store.held()
        kept = (f"{held:,} drop{'s are' if held != 1 else ' is'} kept in {store.folder}: run the same command again "
                "to continue") if held else f"no drop was made yet, so {store.folder} holds none"  # fmt: skip
        click.echo(f"diefab: interrupted; {kept}", err=True)
        raise click.exceptions.Exit(130) from None


def _store(folder: Path):
    """``--checkpoint``: the drop store in `folder`, held by this process until it ends."""
    from diefab.core.files import ensure_dir, hold_lock
    from diefab.physics.checkpoint import DropStore
    from diefab.search.memo import OptimizationMemo

    if folder.exists() and not folder.is_dir():
        raise click.BadParameter(f"{folder} exists and is not a folder", param_hint="--checkpoint")
    kept = folder / OptimizationMemo.FOLDER
    if kept.exists() and not kept.is_dir():
        raise click.BadParameter(f"{kept} (where the search keeps its optimizations) is not a folder",
                                 param_hint="--checkpoint")  # fmt: skip
    ensure_dir(folder)
    hold_lock(folder, f"design checkpoint {folder}")
    return DropStore(folder)


class _Stages:
    """A progress bar with an ETA per stage of the search (on a terminal only)."""

    def __init__(self, con) -> None:
        import sys

        self.bar = None
        self.tasks: dict[str, int] = {}
        if con is not None and sys.stderr.isatty():
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

            self.bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                                TimeRemainingColumn(), console=con, transient=True)  # fmt: skip

    def __enter__(self) -> _Stages:
        if self.bar is not None:
            self.bar.start()
        return self

    def __exit__(self, *exc) -> None:
        if self.bar is not None:
            self.bar.stop()

    def tick(self, stage: str, done: int, total: int) -> None:
        if self.bar is None:
            return
        if stage not in self.tasks:
            self.tasks[stage] = self.bar.add_task(stage, total=total)
        self.bar.update(self.tasks[stage], completed=done, total=total)


def _print_report(d, report: dict, path: Path) -> None:
    from rich.table import Table

    from diefab.dice.design import format_value

    con = console()
    con.print(f"{BOLD}{d.name}{PLAIN}  family {d.family}  " + " ".join(f"{k}={v:.4g}" for k, v in d.params.items()))
    con.print(_METHOD[report["method"]])
    table = Table("value", "rests on", "predicted", "target", title=f"Values, {report['model']} model",
                  title_justify="left")  # fmt: skip
    faces_of: dict[int, list[str]] = {}
    for face, value in d.values.items():
        faces_of.setdefault(value, []).append(face)
    for v in d.support:
        table.add_row(
            format_value(v, min(d.support) < 0),
            " ".join(faces_of[v]),
            f"{report['predicted'][str(v)]:.4f}",
            f"{report['target'][str(v)]:.4f}",
        )
    con.print(table)
    con.print(f"Eq. (2) {report['objective']:.5f}, TVD {report['tvd']:.4f} under the {report['model']} model")
    fast = report["fast"]
    if fast is not None:
        trust = "" if fast["trusted"] else f" {BOLD}not trusted for this die{PLAIN}"
        con.print(f"fast model: TVD {fast['tvd']:.4f} to the target, {fast['tvd_to_simulation']:.4f} from the "
                  f"closing check's drops{trust}")  # fmt: skip
    if report["nearest_counted"] is not None and report["method"] == "shaped":
        n = report["nearest_counted"]
        con.print(f"nearest counted die: {n['faces']}-face {n['kind']}, TVD {n['tvd']:.4f} (exact)")
    v = report["validated"]
    if v and "profiles" in v:
        for profile, c in v["profiles"].items():
            con.print(f"validated under {profile}: {c['n']} drops (seed {c['seed']}), TVD {c['tvd']:.4f}, "
                      f"p = {c['p_value']:.3g}")  # fmt: skip
        con.print(f"worst: {v['worst_profile']}, TVD {v['tvd']:.4f}")
    elif v:
        under = f" under {report['physics']}" if report["physics"] else ""
        con.print(f"validated{under}: {v['n']} drops (seed {v['seed']}), TVD {v['tvd']:.4f}, p = {v['p_value']:.3g}")
    if report["plain_verdict"]:
        con.print(f"verdict: {report['plain_verdict']}")
    con.print(f"wrote {path} ({report['seconds']:.0f} s)")
