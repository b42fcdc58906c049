"""The ``diefab`` command line: parse, call the library, write files, print.

Every error a user can cause ends in one line on stderr and exit status 2;
Ctrl-C ends with status 130.  Outputs are written atomically.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

import click
import numpy as np

from .design import Design, format_value, load_design
from .errors import DiefabError
from .files import atomic_write, ensure_dir

# ----------------------------------------------------------------------
# shared plumbing


def _console(stderr: bool = False):
    from rich.console import Console

    return Console(stderr=stderr, highlight=False, soft_wrap=True)


def emit_json(obj: Any) -> None:
    """Print one JSON object on stdout."""
    click.echo(json.dumps(obj, indent=2, default=_json_default, ensure_ascii=False))


def _json_default(obj: Any):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"cannot serialize {type(obj).__name__}")


def note_fast_fill(d: Design, model: str, fill: str) -> None:
    """One line on stderr when the fast model's gem correction would be extrapolated to another fill."""
    if model == "fast" and d.family == "gem" and fill != "solid":
        click.echo(
            f"note: the fast model's gem correction was learned on solid gems; with a {fill} fill it is an "
            "extrapolation (README: the fast model), so check the die with diefab validate",
            err=True,
        )


def parse_params(items: tuple[str, ...]) -> dict[str, float]:
    """``("a=1.2", "b=0.5")`` -> ``{"a": 1.2, "b": 0.5}``."""
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise click.BadParameter(f"{item!r} is not NAME=VALUE", param_hint="--param")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise click.BadParameter(f"{item!r}: {value!r} is not a number", param_hint="--param") from None
    return out


def design_argument(func):
    """Add the DESIGN argument and ``--param NAME=VALUE`` overrides to a command."""
    func = click.option(
        "--param",
        "params",
        multiple=True,
        metavar="NAME=VALUE",
        help="Override a design parameter, e.g. --param a=1.2 (repeatable).",
    )(func)
    return click.argument("design", metavar="DESIGN")(func)


def get_design(spec: str, params: tuple[str, ...] = (), target: str | None = None) -> Design:
    """Load DESIGN (template name or TOML path) and apply overrides."""
    design = load_design(spec)
    if params:
        design = design.with_params(**parse_params(params))
    if target is not None:
        design = design.with_target(target)
    return design


def free_parameters(design: Design, free: str | None) -> list[str] | None:
    """``--free a,b,c`` -> the named parameters of the design's family (None when not given)."""
    if free is None:
        return None
    from .families import family

    names = [n.strip() for n in free.split(",") if n.strip()]
    known = [p.name for p in family(design.family).parameters]
    bad = [n for n in names if n not in known]
    if bad or not names:
        raise click.BadParameter(
            f"{free!r}: {bad[0] if bad else 'none'} is not a parameter of {design.family} ({','.join(known)})",
            param_hint="--free",
        )
    return names


def heading(design: Design, **settings: object) -> str:
    """``[bold]name[/bold]  a=1.18 b=0.52 ...  key=value ...``: the first line of a human report."""
    params = " ".join(f"{k}={v:g}" for k, v in design.params.items())
    return "  ".join([f"[bold]{design.name}[/bold]", params, *(f"{k}={v}" for k, v in settings.items())])


def values_dict(design: Design, probs: np.ndarray) -> dict[str, float]:
    """``{"-4": p, ...}`` keyed by the design's values."""
    return {str(v): float(p) for v, p in zip(design.support, probs)}


def out_option(func):
    return click.option(
        "--out",
        "out_dir",
        type=click.Path(file_okay=False, path_type=Path),
        default=Path("out"),
        show_default=True,
        help="Output folder.",
    )(func)


def json_option(func):
    return click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")(func)


def simulation_options(func):
    """Options of ``optimize --model simulation`` (implemented in :func:`optimize_simulation`)."""
    opts = [
        click.option("--sims-per-eval", type=int, default=1000, show_default=True,
                     help="[simulation] Drops per evaluation at the start (doubled as it converges)."),
        click.option("--max-sims-per-eval", type=int, default=None,
                     help="[simulation] Most drops per evaluation (default 16x --sims-per-eval)."),
        click.option("--budget", type=float, default=20.0, show_default=True,
                     help="[simulation] Wall-time budget of the whole run, minutes."),
        click.option("--resume", "resume", type=click.Path(path_type=Path), default=None, metavar="RUN_DIR",
                     help="[simulation] Continue the interrupted run in RUN_DIR."),
        click.option("--method", type=click.Choice(["cma", "nm"]), default="cma", show_default=True,
                     help="[simulation] CMA-ES or Nelder-Mead restarts."),
        click.option("--start", "start_model", type=click.Choice(["fast", "solid-angle", "design"]), default="fast",
                     show_default=True, help="[simulation] Start from this model's optimum or the design itself."),
        click.option("--sigma", type=float, default=0.1, show_default=True,
                     help="[simulation] Initial step, fraction of each parameter's range."),
        click.option("--max-evals", type=int, default=None, help="[simulation] Stop after this many evaluations."),
        click.option("--workers", type=int, default=None, help="[simulation] Worker processes (default all cores)."),
        click.option("--scheduler", default=None, metavar="ADDRESS", help="[simulation] Dask scheduler address."),
    ]  # fmt: skip
    for opt in reversed(opts):
        func = opt(func)
    return func


# ----------------------------------------------------------------------


@click.group(context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(package_name="diefab")
def cli() -> None:
    """Design, simulate and fabricate dice with unequal face probabilities."""


@cli.command()
@json_option
def templates(as_json: bool) -> None:
    """List the shipped design templates."""
    from .design import list_templates

    designs = list_templates()
    if as_json:
        emit_json({d.name: d.description for d in designs})
        return
    width = max(len(d.name) for d in designs)
    for d in designs:
        click.echo(f"{d.name:<{width}}  {d.description}")


@cli.command()
@design_argument
@click.option("--model", default="solid-angle", show_default=True, help="Landing model.")
@click.option(
    "--fill", type=click.Choice(["solid", "shell", "print"]), default=None, help="Override the design's fill."
)
@click.option("--target", default=None, help="Override the design's target distribution.")
@json_option
def predict(design: str, params, model: str, fill: str | None, target: str | None, as_json: bool) -> None:
    """Landing probabilities, centre of mass and stability margins of DESIGN."""
    from dataclasses import replace

    from .models import face_probabilities, to_values
    from .stats import jsd, pearson_divergence, tvd

    d = get_design(design, params, target)
    fill_model = replace(d.fill, kind=fill) if fill else d.fill
    d.check_stable(0.0, fill_model)
    note_fast_fill(d, model, fill_model.kind)
    poly = d.polyhedron
    faces = face_probabilities(d, model, fill_model)
    values = to_values(d, faces)
    goal = d.target_distribution.aligned(d.support)
    com = d.mass_properties(fill_model).center
    margins = d.margins(fill_model)
    result = {
        "design": d.name,
        "model": model,
        "fill": fill_model.kind,
        "params": dict(d.params),
        "target": d.target,
        "faces": [
            {
                "name": n,
                "value": d.values[n],
                "label_face": d.label_face[n],
                "probability": float(p),
                "margin": float(m),
            }
            for n, p, m in zip(poly.names, faces, margins)
        ],
        "values": values_dict(d, values),
        "target_values": values_dict(d, goal),
        "center_of_mass": com.tolist(),
        "margins": {n: float(m) for n, m in zip(poly.names, margins)},
        "min_margin": float(margins.min()),
        "objective": pearson_divergence(values, goal),
        "tvd": tvd(values, goal),
        "jsd": jsd(goal, values),
    }
    if as_json:
        emit_json(result)
        return
    from rich.table import Table

    con = _console()
    con.print(heading(d, model=model, fill=fill_model.kind))
    con.print(f"centre of mass: ({com[0]:.4f}, {com[1]:.4f}, {com[2]:.4f})  model units")
    table = Table("face", "value", "label on", "probability", "margin")
    for f in result["faces"]:
        table.add_row(
            f["name"],
            format_value(f["value"], min(d.support) < 0),
            f["label_face"] or "(vertex)",
            f"{f['probability']:.4f}",
            f"{f['margin']:.4f}",
        )
    con.print(table)
    table = Table("value", "predicted", "target", "difference")
    for v, p, q in zip(d.support, values, goal):
        table.add_row(str(v), f"{p:.4f}", f"{q:.4f}", f"{p - q:+.4f}")
    con.print(table)
    con.print(f"Eq. (2) objective {result['objective']:.5f}   TVD {result['tvd']:.4f}   JSD {result['jsd']:.5f}")


@cli.command()
@click.option("--counts", default=None, metavar="C1,C2,...", help="Counts of each value, in increasing value order.")
@click.option(
    "--rolls",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="Text or CSV log of rolled values.",
)
@click.option("--target", required=True, help="Target distribution, e.g. 4df or 1,4,10,16,19,16,10,4,1.")
@click.option("--alpha", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.05, show_default=True)
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the Monte-Carlo p-value.")
@json_option
def stats(counts: str | None, rolls: Path | None, target: str, alpha: float, seed: int, as_json: bool) -> None:
    """Test rolls against a target: chi2, G, TVD, JSD, intervals, power."""
    from .errors import StatsError
    from .stats import chi2_power, counts_from_rolls, goodness_of_fit, parse_counts, read_rolls, rolls_for_power
    from .targets import parse_target

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

    con = _console()
    table = Table("value", "count", "expected", "observed", f"{1 - alpha:.0%} simultaneous CI", "target")
    for v, c, e, o, (lo, hi), p in zip(goal.values, x, fit.expected, observed, fit.intervals, goal.probabilities):
        table.add_row(str(int(v)), str(int(c)), f"{e:.1f}", f"{o:.4f}", f"[{lo:.4f}, {hi:.4f}]", f"{p:.4f}")
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


@cli.command()
@design_argument
@click.option("--model", default="solid-angle", show_default=True,
              help="Landing model to fit: solid-angle, fast, or simulation (pybullet drops).")
@click.option("--target", default=None, help="Target distribution (default: the design's).")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the random starts.")
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
@click.option("--name", default=None, help="Name of the optimized design (default DESIGN-MODEL-opt).")
@simulation_options
@out_option
@json_option
@click.pass_context
def optimize(ctx, design, params, model, target, seed, min_margin, starts, free, objective, name, out_dir, as_json,
             **sim) -> None:  # fmt: skip
    """Fit DESIGN's parameters to its target; write the result as a template TOML.

    With --model simulation the objective uses pybullet drop frequencies
    (diefab validate's physics); the run is logged in OUT/NAME/ and can be
    resumed with --resume OUT/NAME.
    """
    from .design import design_to_toml
    from .optimize import optimize_design

    if model == "simulation":
        return optimize_simulation(ctx, design, params, target, seed, min_margin, starts, free, objective, name,
                                   out_dir, as_json, **sim)  # fmt: skip
    d = get_design(design, params, target)
    if not np.isfinite(min_margin) or min_margin < 0:
        raise click.BadParameter(f"{min_margin} must be a non-negative number", param_hint="--min-margin")
    names = free_parameters(d, free)
    ensure_dir(out_dir)
    note_fast_fill(d, model, d.fill.kind)
    result = optimize_design(
        d, model=model, objective=objective, names=names, min_margin=min_margin, starts=starts, seed=seed, name=name
    )
    best = result.design
    path = atomic_write(
        out_dir / f"{best.name}.toml",
        design_to_toml(best, comment=f"Written by: diefab optimize {design} --model {model} --seed {seed}"),
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
        "min_margin": float(margins.min()),
        "min_margin_mm": float(margins.min() * best.mm_per_unit),
        "binding_face": result.binding_face,
        "evaluations": result.evaluations,
        "starts": result.starts,
        "design_file": str(path),
    }
    if as_json:
        emit_json(report)
        return
    con = _console()
    con.print(
        f"[bold]{best.name}[/bold]  "
        + " ".join(f"{k}={v:.4f}" for k, v in best.params.items())
        + f"\n{objective} = {result.objective:.5f} under the {model} model "
        f"({result.evaluations} evaluations from {result.starts} starts)"
    )
    con.print(
        "value      "
        + " ".join(f"{v:>6d}" for v in best.support)
        + "\nmodel x81  "
        + " ".join(f"{81 * q:6.2f}" for q in result.values)
        + "\ntarget x81 "
        + " ".join(f"{81 * q:6.2f}" for q in goal)
    )
    con.print(
        f"smallest stability margin {margins.min():.4f} ({margins.min() * best.mm_per_unit:.2f} mm at "
        f"{best.size_mm:g} mm) on face {result.binding_face}; required {min_margin:g}"
    )
    con.print(f"wrote {path}")


@cli.command("stl")
@design_argument
@click.option("--size", "size_mm", type=float, default=None, help="Size in mm (2 model units along z).")
@click.option("--depth", "depth_mm", type=float, default=0.6, show_default=True, help="Engraving depth, mm.")
@click.option("--font", "font_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Font file (default DejaVu Sans Bold, shipped with matplotlib).")  # fmt: skip
@click.option("--round", "round_mm", type=float, default=0.0, show_default=True, help="Edge/corner radius, mm.")
@click.option("--emboss", is_flag=True, help="Raise the labels instead of engraving them.")
@click.option("--format", "formats", default="stl", show_default=True, metavar="stl,3mf", help="Output formats.")
@click.option("--min-stroke", type=float, default=0.6, show_default=True, help="Warn below this stroke width, mm.")
@click.option("--min-text-height", type=float, default=2.0, show_default=True, help="Smallest text height, mm.")
@click.option("--margin", "margin_mm", type=float, default=1.0, show_default=True, help="Text to face edge, mm.")
@click.option("--density", type=float, default=1.24, show_default=True, help="Material density, g/cm³ (PLA).")
@click.option("--infill", type=float, default=None, help="Infill fraction of the print (default design's or 0.15).")
@click.option("--wall", "wall_mm", type=float, default=None, help="Wall thickness of the print, mm (default 1.2).")
@click.option("--fit-each", is_flag=True, help="Size each value label to its face (default: one height for all).")
@click.option("--preview", is_flag=True, help="Also write DIR/<design>-preview.png.")
@out_option
@json_option
def stl(design, params, size_mm, depth_mm, font_file, round_mm, emboss, formats, min_stroke, min_text_height,
        margin_mm, density, infill, wall_mm, fit_each, preview, out_dir, as_json) -> None:  # fmt: skip
    """Printable STL/3MF of DESIGN with its values engraved; report volume, mass and balance."""
    from .errors import FabricationError
    from .fabricate.stl import build_solid, stl_bytes, threemf_bytes
    from .mass import Fill

    kinds = [f.strip().lower() for f in formats.split(",") if f.strip()]
    bad = [f for f in kinds if f not in ("stl", "3mf")]
    if bad or not kinds:
        raise click.BadParameter(f"{formats!r}: formats are stl and 3mf", param_hint="--format")
    d = get_design(design, params)
    base = d.fill if d.fill.kind == "print" else Fill("print")
    try:
        fill = Fill("print", base.wall_mm if wall_mm is None else wall_mm, base.infill if infill is None else infill)
    except DiefabError as exc:
        raise FabricationError(str(exc)) from exc
    ensure_dir(out_dir)
    solid = build_solid(
        d, size_mm=size_mm, depth_mm=depth_mm, font=font_file, round_mm=round_mm, emboss=emboss,
        min_stroke_mm=min_stroke, min_text_height_mm=min_text_height, margin_mm=margin_mm,
        density_g_cm3=density, print_fill=fill, uniform_height=not fit_each,
    )  # fmt: skip
    payloads = {f"{d.name}.{k}": (stl_bytes if k == "stl" else threemf_bytes)(solid) for k in dict.fromkeys(kinds)}
    if preview:
        from .fabricate.preview import render_preview

        payloads[f"{d.name}-preview.png"] = render_preview(solid)
    written = [str(atomic_write(out_dir / name, data)) for name, data in payloads.items()]
    for line in solid.warnings:
        click.echo(f"diefab: warning: {line}", err=True)
    report = {"file": written[0], "files": written, **solid.report}
    if as_json:
        emit_json(report)
        return
    r = solid.report
    click.echo(
        f"{d.name}: {r['size_mm']:g} mm, {len(r['labels'])} labels {'embossed' if emboss else 'engraved'} "
        f"{depth_mm:g} mm{f', edges rounded {round_mm:g} mm' if round_mm else ''}\n"
        f"volume {r['volume_mm3']:.1f} mm³ (uncut {r['uncut_volume_mm3']:.1f}, text "
        f"{r['engraved_volume_mm3']:.1f}); watertight {r['watertight']}, bodies {r['bodies']}, genus {r['genus']}\n"
        f"mass {r['mass_g']:.2f} g printed ({fill.wall_mm:g} mm walls, {fill.infill:.0%} infill), "
        f"{r['mass_solid_g']:.2f} g solid, at {density:g} g/cm³\n"
        f"centre of mass shift: engraving {r['com_shift_norm_mm'] * 1000:.1f} µm, "
        f"infill {r['infill_com_shift_norm_mm'] * 1000:.1f} µm"
    )
    before = r["probabilities"]["rounded" if round_mm else "sharp"]
    click.echo("value       " + " ".join(f"{v:>8s}" for v in before))
    for key in ("sharp", "rounded", "engraved", "printed"):
        if key in r["probabilities"]:
            click.echo(f"{key:<11s} " + " ".join(f"{p:8.5f}" for p in r["probabilities"][key].values()))
    for path in written:
        click.echo(f"wrote {path}")


@cli.command("net")
@design_argument
@click.option(
    "--size",
    "size_mm",
    type=float,
    default=None,
    help="Die size in mm (the design's size_mm: for the gem, the girdle short side).",
)
@click.option("--page", default="A4", show_default=True, help="A4, Letter, A3 or WxH in mm.")
@click.option(
    "--format", "formats", default="svg,pdf", show_default=True, metavar="svg,pdf,png", help="Output formats."
)
@click.option("--face-names", is_flag=True, help="Also print the small face names (f1, f2, ...).")
@click.option("--tab-width", type=float, default=5.0, show_default=True, help="Glue-tab width before narrowing, mm.")
@out_option
def net(design, params, size_mm, page, formats, face_names, tab_width, out_dir) -> None:  # fmt: skip
    """Unfolded, labelled, true-scale paper net of DESIGN with glue tabs (SVG/PDF/PNG)."""
    from .fabricate.net import design_net, parse_formats, render_net
    from .fabricate.unfold import parse_page
    from .files import atomic_write, ensure_dir

    kinds = parse_formats(formats)
    sheet = parse_page(page)
    d = get_design(design, params)
    ensure_dir(out_dir)
    the_net = design_net(d, size_mm=size_mm, page=sheet, tab_width=tab_width)
    rendered = render_net(d, the_net, kinds, face_names=face_names)
    written: list[Path] = []
    try:
        for kind in kinds:
            written.append(atomic_write(out_dir / f"{d.name}-net.{kind}", rendered[kind]))
    except DiefabError:
        for path in written:
            path.unlink(missing_ok=True)
        raise
    for path in written:
        click.echo(str(path))
    size = d.size_mm if size_mm is None else size_mm
    pieces = f"{the_net.n_pieces} piece{'s' * (the_net.n_pieces > 1)}"
    pages = f"{the_net.n_pages} {sheet.name} page{'s' * (the_net.n_pages > 1)}"
    click.echo(f"{d.name}: {size:g} mm die ({_size_note(d)}), {pieces} on {pages}, {len(the_net.tabs)} glue tabs")


def _size_note(design: Design) -> str:
    from .fabricate.net import size_note

    return size_note(design)


def _physics_options(func):
    """Options that override the design's [physics] table (see diefab.physics.PhysicsSettings)."""
    options = [
        ("--restitution", float, "Restitution of die and ground, in [0, 1] (default 0.3)."),
        ("--friction", float, "Friction of die and ground, >= 0 (default 0.8)."),
        ("--rolling-friction", float, "Rolling friction, >= 0 (default 0)."),
        ("--spinning-friction", float, "Spinning friction, >= 0 (default 0)."),
        ("--time-step", float, "Simulation step, seconds (default 1/240)."),
        ("--solver-iterations", int, "Constraint-solver iterations per step, fixed (default 5)."),
        ("--collision-margin", float, "Collision margin, model units (default 0.001)."),
        ("--drop-height", float, "Initial height of the centre of mass, model units (default 5)."),
        ("--height-jitter", float, "Height is uniform in drop-height +- this (default 0.5)."),
        ("--settle-time", float, "Seconds still on a face to count it (default 0.1)."),
        ("--time-limit", float, "Seconds before a moving die counts as unsettled (default 20)."),
        ("--face-tolerance", float, "Degrees from straight down for a face to count (default 3)."),
        ("--energy-fraction", float, "Early stop: a die in a face's basin with less than this fraction of "
         "the basin's barrier in energy has landed; 0 runs every die until still (default 0.95)."),
    ]
    for flag, kind, text in reversed(options):
        func = click.option(flag, type=kind, default=None, help=text)(func)
    func = click.option("--angular-velocity", type=(float, float), default=None, metavar="MIN MAX",
                        help="Range of the initial spin, rad/s (default 0 10).")(func)  # fmt: skip
    func = click.option("--linear-velocity", type=(float, float), default=None, metavar="MIN MAX",
                        help="Range of the initial horizontal speed, units/s (default 0 0).")(func)  # fmt: skip
    return func


@cli.command()
@design_argument
@click.option("--sims", type=int, default=10_000, show_default=True, help="Number of simulated drops.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed: the same seed gives the same counts.")
@click.option("--workers", type=int, default=None, help="Worker processes (default: all cores).")
@click.option("--scheduler", default=None, metavar="ADDRESS", help="Run on this Dask scheduler (tcp://host:8786).")
@click.option("--plot", "plot_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Write a bar chart to FILE (.png or .svg).")  # fmt: skip
@click.option(
    "--fill", type=click.Choice(["solid", "shell", "print"]), default=None, help="Override the design's fill."
)
@click.option("--target", default=None, help="Override the design's target distribution.")
@_physics_options
@json_option
def validate(design, params, sims, seed, workers, scheduler, plot_file, fill, target, as_json, **physics) -> None:
    """Drop DESIGN many times in pybullet and test the counts against its target."""
    import os
    from dataclasses import replace

    from .errors import PhysicsError
    from .files import atomic_write, ensure_dir
    from .models import value_probabilities
    from .physics import PhysicsSettings, SimulationInterrupted, plot_validation, simulate
    from .stats import goodness_of_fit

    d = get_design(design, params, target)
    if fill:
        d = replace(d, fill=replace(d.fill, kind=fill))
    settings = PhysicsSettings.from_mapping(d.physics, **physics)
    if plot_file is not None:
        if plot_file.suffix.lower() not in (".png", ".svg"):
            raise click.BadParameter(f"{plot_file} must end in .png or .svg", param_hint="--plot")
        ensure_dir(plot_file.parent)
    bar = None
    if sys.stderr.isatty():
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

        bar = Progress(TextColumn("drops"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn(),
                       console=_console(stderr=True), transient=True)  # fmt: skip
    try:
        if bar is None:
            result = simulate(d, sims, seed=seed, workers=workers, settings=settings, scheduler=scheduler)
        else:
            with bar:
                task = bar.add_task("drops", total=sims)
                result = simulate(d, sims, seed=seed, workers=workers, settings=settings, scheduler=scheduler,
                                  progress=lambda done, total: bar.update(task, completed=done))  # fmt: skip
    except SimulationInterrupted as exc:
        click.echo(f"diefab: interrupted after {exc.done} of {exc.total} drops had finished", err=True)
        raise click.exceptions.Exit(130) from None
    if result.landed == 0:
        raise PhysicsError(f"no drop came to rest on a face ({result.cocked} cocked, {result.unsettled} unsettled)")
    counts = result.value_counts(d)
    goal = d.target_distribution.aligned(d.support)
    fit = goodness_of_fit(counts, goal, seed=seed)
    model = value_probabilities(d, "solid-angle")
    keys = [str(v) for v in d.support]
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
        "cocked": result.cocked,
        "unsettled": result.unsettled,
        "chi2": fit.chi2,
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
    }
    if plot_file is not None:
        atomic_write(plot_file, plot_validation(d, result, fmt=plot_file.suffix.lower()[1:]))
    if as_json:
        emit_json(out)
        return
    from rich.table import Table

    con = _console()
    con.print(heading(d, fill=d.fill.kind, target=d.target))
    table = Table("value", "count", "simulated", "95% simultaneous CI", "target", "solid angle")
    signed = min(d.support) < 0
    for k, v in enumerate(d.support):
        lo, hi = fit.intervals[k]
        table.add_row(format_value(v, signed), str(counts[k]), f"{fit.observed[k]:.4f}", f"[{lo:.4f}, {hi:.4f}]",
                      f"{goal[k]:.4f}", f"{model[k]:.4f}")  # fmt: skip
    con.print(table)
    con.print("faces: " + "  ".join(f"{n}={c}" for n, c in zip(result.faces, result.face_counts)))
    con.print(
        f"{result.n} drops: {result.landed} on a face, {result.cocked} cocked, {result.unsettled} unsettled; "
        f"{result.seconds:.1f} s, {result.drops_per_second:,.0f} drops/s"
    )
    con.print(f"chi2 = {fit.chi2:.3f} (df {fit.df}), p = {fit.p_value:.4g} (Monte-Carlo {fit.p_value_mc:.4g})")
    con.print(f"TVD = {fit.tvd:.4f} (expected under the target {fit.expected_tvd:.4f})   "
              f"JSD = {fit.jsd:.5f} (expected {fit.expected_jsd:.5f})")  # fmt: skip
    if plot_file is not None:
        con.print(f"wrote {plot_file}")


# --- optimize --model simulation (issue 6) ------------------------------


def _simulation_view(spec, budget_s: float, history):
    """A rich live panel on stderr (None when stderr is not a terminal)."""
    con = _console(stderr=True)
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


def optimize_simulation(ctx, design, params, target, seed, min_margin, starts, free, objective, name, out_dir,
                        as_json, sims_per_eval, max_sims_per_eval, budget, resume, method, start_model, sigma,
                        max_evals, workers, scheduler) -> None:  # fmt: skip
    """``diefab optimize DESIGN --model simulation``: see :mod:`diefab.simopt`."""
    from .design import design_to_toml
    from .families import family
    from .physics import PhysicsSettings
    from .simopt import RunError, RunLog, RunSpec, best_design, optimize_by_simulation, start_point

    if not (np.isfinite(budget) and budget > 0):
        raise click.BadParameter(f"{budget} must be a positive number of minutes", param_hint="--budget")
    if sims_per_eval <= 0:
        raise click.BadParameter(f"{sims_per_eval} must be > 0", param_hint="--sims-per-eval")
    if max_sims_per_eval is not None and max_sims_per_eval < sims_per_eval:
        raise click.BadParameter(f"{max_sims_per_eval} must be >= --sims-per-eval", param_hint="--max-sims-per-eval")
    if max_evals is not None and max_evals <= 0:
        raise click.BadParameter(f"{max_evals} must be > 0", param_hint="--max-evals")
    if workers is not None and workers <= 0:
        raise click.BadParameter(f"{workers} must be > 0", param_hint="--workers")
    if objective not in ("eq2", "tvd"):
        raise click.BadParameter(f"{objective!r}: a simulation run minimizes eq2 or tvd", param_hint="--objective")
    if not np.isfinite(min_margin) or min_margin < 0:
        raise click.BadParameter(f"{min_margin} must be a non-negative number", param_hint="--min-margin")
    d = get_design(design, params, target)
    d.check_stable(0.0)
    warning = None
    if resume is not None:
        log = RunLog(resume)
        spec = log.spec()
        stored = spec.design
        if (stored.name, stored.family, dict(stored.values), stored.target) != (d.name, d.family, dict(d.values),
                                                                                 d.target):  # fmt: skip
            raise RunError(f"run {resume} optimizes design {stored.name!r} for {stored.target}, not {d.name!r} "
                           f"for {d.target}")  # fmt: skip
        given = {"seed": seed, "sims_per_eval": sims_per_eval, "objective": objective, "min_margin": min_margin,
                 "method": method}  # fmt: skip
        for key, value in given.items():
            source = ctx.get_parameter_source(key)
            if source is not None and source.name == "COMMANDLINE" and value != getattr(spec, key):
                raise RunError(f"--{key.replace('_', '-')} {value} differs from the run's {getattr(spec, key)} "
                               f"(stored in {log.spec_path})")  # fmt: skip
        history, warning = log.read()
        run_name = Path(resume).name
    else:
        names = free_parameters(d, free) or [p.name for p in family(d.family).parameters]
        run_name = name or f"{d.name}-simulation-opt"
        log = RunLog(out_dir / run_name)
        if log.path.exists():
            raise RunError(f"{log.folder} already holds a run: resume it with --resume {log.folder} or pick --name")
        physics = PhysicsSettings.from_mapping(d.physics)
        x0 = start_point(d, names, model=start_model, objective=objective, min_margin=min_margin, starts=starts,
                         seed=seed)  # fmt: skip
        spec = RunSpec(
            design_toml=design_to_toml(d), names=tuple(names), x0=tuple(float(v) for v in x0), objective=objective,
            min_margin=float(min_margin), seed=seed, sims_per_eval=sims_per_eval,
            max_sims=max_sims_per_eval or 16 * sims_per_eval, method=method, sigma0=sigma,
            physics=physics.as_dict(), start=start_model,
        )  # fmt: skip
        log.create(spec)
        history = []
    if warning:
        click.echo(f"diefab: warning: {warning}", err=True)
    client = None
    if scheduler is not None:
        from .physics import dask_client

        client, _ = dask_client(scheduler)
    best_path = log.folder / f"{run_name}.toml"
    command = f"diefab optimize {design} --model simulation --seed {spec.seed} (run {log.folder})"
    live, update = _simulation_view(spec, budget * 60, history)

    def on_best(record):
        best = best_design(spec, record, run_name)
        atomic_write(best_path, design_to_toml(best, comment=f"Written by: {command}"))
        if update:
            update(best=record)

    last = {"elapsed": history[-1].get("elapsed") if history else None}

    def on_evaluation(record):
        log.append(record)
        last["elapsed"] = record["elapsed"]
        if update:
            update(record=record)

    log.open()
    try:
        if live:
            live.start()
        result = optimize_by_simulation(
            spec, workers=workers, scheduler=client, history=history, on_evaluation=on_evaluation, on_best=on_best,
            budget_seconds=budget * 60, max_evaluations=max_evals,
        )  # fmt: skip
    except KeyboardInterrupt:
        if live:
            live.stop()
        log.close()
        click.echo(f"diefab: interrupted; resume with: diefab optimize {design} --model simulation --resume "
                   f"{log.folder}", err=True)  # fmt: skip
        sys.exit(130)
    finally:
        if live:
            live.stop()
        log.close()
        if client is not None:
            client.close()
    if result.best is None:
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
        "drops": result.drops,
        "finished": result.finished,
        "run_folder": str(log.folder),
        "design_file": str(best_path),
        "elapsed_seconds": last["elapsed"],
    }
    if as_json:
        emit_json(report)
        return
    con = _console()
    con.print(
        f"[bold]{run_name}[/bold]  " + " ".join(f"{k}={v:.4f}" for k, v in best["params"].items())
        + f"\n{spec.objective} = {best['objective']:.5f} at {best['drops']} drops (seed {spec.seed}); "
        f"{result.evaluations} evaluations ({result.replayed} replayed), {result.drops:,} drops; "
        f"min margin {best['min_margin']:.4f}"
    )
    con.print(f"log {log.path}\nwrote {best_path}")


# ----------------------------------------------------------------------


def _terminate(signum, frame) -> None:
    raise KeyboardInterrupt  # a kill (SIGTERM) stops a run as cleanly as Ctrl-C


def main(argv: list[str] | None = None) -> None:
    """Console entry point: one-line errors, exit status 2 on bad input."""
    import signal
    import threading

    previous = signal.getsignal(signal.SIGTERM)
    catch = previous is signal.SIG_DFL and threading.current_thread() is threading.main_thread()
    if catch:
        signal.signal(signal.SIGTERM, _terminate)
    try:
        _main(argv)
    finally:
        if catch:
            signal.signal(signal.SIGTERM, previous)


def _main(argv: list[str] | None) -> None:
    try:
        rv = cli.main(args=argv, prog_name="diefab", standalone_mode=False)
    except click.exceptions.Abort:
        click.echo("diefab: interrupted", err=True)
        sys.exit(130)
    except KeyboardInterrupt:
        click.echo("diefab: interrupted", err=True)
        sys.exit(130)
    except click.ClickException as exc:
        ctx = getattr(exc, "ctx", None)
        where = f"{ctx.command_path}: " if ctx is not None else "diefab: "
        click.echo(f"{where}error: {exc.format_message()}".replace("\n", " "), err=True)
        sys.exit(2)
    except DiefabError as exc:
        click.echo(f"diefab: error: {exc}".replace("\n", " "), err=True)
        sys.exit(2)
    except Exception as exc:  # a bug, not bad input: one line unless asked for the traceback
        if os.environ.get("DIEFAB_DEBUG"):
            raise
        click.echo(
            f"diefab: internal error: {type(exc).__name__}: {exc} (set DIEFAB_DEBUG=1 for a traceback)".replace(
                "\n", " "
            ),
            err=True,
        )
        sys.exit(1)
    sys.exit(rv if isinstance(rv, int) else 0)
