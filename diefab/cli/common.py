"""Shared plumbing of the command line: the DESIGN argument, common options, output helpers."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import click
import numpy as np

from diefab.core.errors import OutputError
from diefab.dice.design import Design, load_design

#: Start and end of bold in text printed through :func:`console` (control characters no name may hold).
BOLD, PLAIN = "\x01", "\x02"


def console(stderr: bool = False):
    """A rich console that prints every string as it is: no markup from names, paths or values.

    Rich reads ``[...]`` as markup, so a design named ``{x}[/bold]`` would
    fail and ``[link=file:///etc/passwd]`` would become a link.  Strings are
    escaped; the only styling is bold between :data:`BOLD` and :data:`PLAIN`.
    Table cells are plain text too (markup is off).
    """
    from rich.console import Console
    from rich.markup import escape
    from rich.text import Text

    class PlainConsole(Console):
        def print(self, *objects, **kwargs) -> None:
            texts = [Text.from_markup(escape(o).replace(BOLD, "[bold]").replace(PLAIN, "[/bold]"))
                     if isinstance(o, str) else o for o in objects]  # fmt: skip
            super().print(*texts, **kwargs)

    return PlainConsole(stderr=stderr, highlight=False, soft_wrap=True, markup=False)


def emit_json(obj: Any) -> None:
    """Print one JSON object on stdout, as strict JSON: a value that is not a finite number is null."""
    click.echo(json.dumps(_strict(obj), indent=2, default=_json_default, ensure_ascii=False, allow_nan=False))


def _strict(obj: Any) -> Any:
    """`obj` with NaN and infinities, in containers and arrays too, replaced by None."""
    if isinstance(obj, dict):
        return {k: _strict(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_strict(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _strict(obj.tolist())
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def _json_default(obj: Any):
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"cannot serialize {type(obj).__name__}")


def note_fast_fill(d: Design, model: str, fill: str) -> None:
    """One line on stderr when the fast model's gem correction would be extrapolated to another fill."""
    from diefab.models.fills import fill_discrepancy

    if model == "fast" and d.family == "gem" and fill != "solid" and fill_discrepancy(fill) is None:
        click.echo(
            f"diefab: note: the fast model's gem correction was learned on solid gems and has none learned for a "
            f"{fill} fill, so there it is an extrapolation (README: the fast model); check the die with "
            "diefab validate",
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


def get_design(spec: str, params: tuple[str, ...] = (), target: str | None = None, made: str | None = None) -> Design:
    """Load DESIGN (template or target name, or TOML path; a target's die designed `made`) and apply overrides."""
    design = load_design(spec, made)
    if params:
        design = design.with_params(**parse_params(params))
    if target is not None:
        design = design.with_target(target)
    return design


#: How a die made as each fill is said in a command's output.
MADE_WORDS = {"paper": "made of card", "print": "printed"}


def template_note(spec: str, design: Design, made: str) -> tuple[str | None, str | None]:
    """The template a net or STL of SPEC is made from (None for a file), and a line naming it for a target's name."""
    from diefab.dice.design import template_for

    name = template_for(spec, made)
    if name is None or name == spec:
        return name, None
    how = f", designed to be {MADE_WORDS[made]}" if design.fill.kind == made else ""
    return name, f"{spec}: the ready-made die {name}{how}"


def design_inputs(spec: str, design: Design, made: str | None = None) -> list[Path]:
    """The files DESIGN was read from (design file or template, mesh, SVG symbols): no output may replace them."""
    from diefab.core.errors import DiefabError
    from diefab.dice.design import files_read, template_path

    files = []
    if Path(spec).is_file():
        files.append(Path(spec))
    else:
        try:
            files.append(Path(str(template_path(spec, made))))
        except DiefabError:
            pass
    return files + files_read(design.mesh, design.labels)  # its mesh and SVG symbols


#: Sizes of a die the commands that make one accept, millimetres (a marble to a beach ball).
SIZE_RANGE_MM = (1.0, 1000.0)


def check_size(size_mm: float | None) -> None:
    """Refuse a ``--size`` outside :data:`SIZE_RANGE_MM` (None: the design's own)."""
    lo, hi = SIZE_RANGE_MM
    if size_mm is not None and not (np.isfinite(size_mm) and lo <= size_mm <= hi):
        raise click.BadParameter(f"{size_mm:g} mm is outside [{lo:g}, {hi:g}] mm, the sizes of dice diefab makes",
                                 param_hint="--size")  # fmt: skip


def refuse_options(ctx: click.Context, names: list[str], why: str) -> None:
    """Raise a usage error if any of the named parameters was given on the command line."""
    for name in names:
        source = ctx.get_parameter_source(name)
        if source is not None and source.name in ("COMMANDLINE", "ENVIRONMENT"):
            param = next(p for p in ctx.command.params if p.name == name)
            raise click.UsageError(f"{param.opts[0]} {why}", ctx=ctx)


def one_line_name(ctx, param, value: str | None) -> str | None:
    """Click callback: a name that a design or profile file can hold (one line, no control characters)."""
    from diefab.core.errors import DesignError
    from diefab.dice.schema import word

    if value is not None:
        try:
            word("name", value)
        except DesignError as exc:
            raise click.BadParameter(str(exc).removeprefix("name = "), ctx=ctx, param=param) from None
    return value


def seed_option(help_text: str):
    """``--seed``: a non-negative integer (NumPy seeds cannot be negative)."""
    return click.option("--seed", type=click.IntRange(0, 2**63 - 1), default=0, show_default=True, help=help_text)


def free_parameters(design: Design, free: str | None) -> list[str] | None:
    """``--free a,b,c`` -> the named parameters of the design's family (None when not given)."""
    if free is None:
        return None
    from diefab.dice.families import family

    names = [n.strip() for n in free.split(",") if n.strip()]
    known = [p.name for p in family(design.family).parameters if not p.integer]
    bad = [n for n in names if n not in known]
    if bad or not names:
        raise click.BadParameter(
            f"{free!r}: {bad[0] if bad else 'none'} is not a parameter of {design.family} ({','.join(known)})",
            param_hint="--free",
        )
    return names


def heading(design: Design, **settings: object) -> str:
    """``name`` (bold) ``  a=1.18 b=0.52 ...  key=value ...``: the first line of a human report."""
    params = " ".join(f"{k}={v:g}" for k, v in design.params.items())
    return "  ".join([f"{BOLD}{design.name}{PLAIN}", params, *(f"{k}={v}" for k, v in settings.items())])


def values_dict(design: Design, probs: np.ndarray) -> dict[str, float]:
    """``{"-4": p, ...}`` keyed by the design's values."""
    return {str(v): float(p) for v, p in zip(design.support, probs)}


def named_folder(ctx, param, value: str | Path | None) -> Path | None:
    """An output folder's option as a path; an empty name is refused rather than read as the current folder."""
    if value is None:
        return None
    if not str(value).strip():
        raise click.BadParameter("name a folder ('.' for this one)", param_hint=f"'{param.opts[0]}'")
    return Path(value)


def out_option(func):
    return click.option(
        "--out",
        "out_dir",
        type=click.Path(file_okay=False),
        default="out",
        show_default=True,
        callback=named_folder,
        help="Output folder.",
    )(func)


def _html_file(ctx, param, value: Path | None) -> Path | None:
    if value is not None and value.suffix.lower() not in (".html", ".htm"):
        raise click.BadParameter(f"{value} must end in .html", param_hint="--report")
    return value


def report_option(func):
    """``--report FILE.html``: one self-contained page of the die, its net, its distribution and the verdict."""
    return click.option(
        "--report",
        "report_file",
        type=click.Path(dir_okay=False, path_type=Path),
        default=None,
        callback=_html_file,
        help="Also write one self-contained HTML page to FILE: the die, its net, its distribution, the verdict.",
    )(func)


def json_option(func):
    return click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")(func)


def simulation_options(func):
    """Options of ``optimize --model simulation``."""
    opts = [
        click.option("--sims-per-eval", type=int, default=1000, show_default=True,
                     help="[simulation] Drops per evaluation at the start (doubled as it converges)."),
        click.option("--max-sims-per-eval", type=int, default=None,
                     help="[simulation] Most drops per evaluation (default 16x --sims-per-eval)."),
        click.option("--budget", type=float, default=20.0, show_default=True,
                     help="[simulation] Wall-time budget of the whole run, minutes."),
        click.option("--resume", "resume", type=click.Path(path_type=Path), default=None, metavar="RUN_DIR",
                     help="[simulation] Continue the interrupted run in RUN_DIR."),
        click.option("--method", type=click.Choice(["cma", "nm", "correction"]), default=None,
                     help="[simulation] CMA-ES, Nelder-Mead restarts, or defect correction (the fast model "
                     "corrected per throw by each round's drops, minimized in between) [default: cma; "
                     "correction with --robust]."),
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


def physics_file_option(func):
    """``--physics PROFILE``: a shipped physics profile's name or a TOML file with a [physics] table."""
    return click.option(
        "--physics",
        "physics_profile",
        default=None,
        metavar="PROFILE",
        help="Physics profile: a TOML file with a [physics] table (e.g. from diefab calibrate) or a shipped "
        "profile's name; it overrides the design's [physics] table, the physics options override it.",
    )(func)


def profile_inputs(profile: str | None) -> list[Path]:
    """A ``--physics`` profile given as a file (none for a shipped profile's name): no output may replace it."""
    return [Path(profile)] if profile is not None and Path(profile).is_file() else []


def physics_settings(design: Design, profile: str | None = None, **overrides):
    """The design's [physics] table, then `profile` (a name or file), then the command-line `overrides`."""
    from diefab.physics.profiles import load_profile
    from diefab.physics.simulate import PhysicsSettings

    if profile is None:
        return PhysicsSettings.from_mapping(design.physics, **overrides)
    settings = load_profile(profile, base=design.physics, **overrides)
    note_profile_domain(profile, design.fill.kind)
    return settings


def note_profile_domain(profile: str, fill: str) -> None:
    """One line on stderr when a die of `fill` lies outside the dice physics `profile` was fitted on."""
    from diefab.physics.profiles import domain_note

    note = domain_note(profile, fill)
    if note is not None:
        click.echo(f"diefab: note: {note}: see its held-out figures in docs/reference/profiles.md",
                   err=True)  # fmt: skip


def physics_options(func):
    """Options that override the design's [physics] table (see diefab.physics.simulate.PhysicsSettings)."""
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
        (
            "--energy-fraction",
            float,
            "Early stop: a die in a face's basin with less than this fraction of "
            "the basin's barrier in energy has landed; 0 runs every die until still (default 0.95).",
        ),
        (
            "--capture-energy",
            float,
            "Quasi-static capture: a die in a face's basin with less energy above rest than this, in units "
            "of mass x gravity x the die's radius, has landed there (real dice lose energy faster than a "
            "rigid hull); 0 is the rigid simulation (default 0).",
        ),
    ]
    for flag, kind, text in reversed(options):
        func = click.option(flag, type=kind, default=None, help=text)(func)
    func = click.option("--flat-faces/--no-flat-faces", default=None,
                        help="Hold the faces the die rests on flat in the engine, whose one hull folds some "
                        "(slower; see the validation docs) (default: the one hull).")(func)  # fmt: skip
    func = click.option("--angular-velocity", type=(float, float), default=None, metavar="MIN MAX",
                        help="Range of the initial spin, rad/s (default 0 10).")(func)  # fmt: skip
    func = click.option("--linear-velocity", type=(float, float), default=None, metavar="MIN MAX",
                        help="Range of the initial horizontal speed, units/s (default 0 0).")(func)  # fmt: skip
    return func


def check_resume_folder(ctx: click.Context, resume: Path, out_dir: Path) -> None:
    """Refuse an ``--out`` given with ``--resume`` that is not the run folder's own: a run stays where it is."""
    source = ctx.get_parameter_source("out_dir")
    if source is not None and source.name == "COMMANDLINE" and Path(out_dir).resolve() != Path(resume).resolve().parent:
        raise click.UsageError(f"--out {out_dir} differs from the folder of --resume {resume} (a run stays where "
                               "it is)", ctx=ctx)  # fmt: skip


def run_logged(call, log, live, client, resume: str, on_failure=None):
    """``call()`` with the run `log` open and the `live` panel shown; Ctrl-C says how to resume.

    Closes the log, the panel and the Dask `client` (if any) however the run
    ends; `on_failure()` runs first when `call` raises anything but an interrupt.
    """
    import sys

    log.open()
    try:
        if live:
            live.start()
        return call()
    except KeyboardInterrupt:
        if live:
            live.stop()
        log.close()
        click.echo(f"diefab: interrupted; resume with: {resume}", err=True)
        sys.exit(130)
    except BaseException as exc:
        if on_failure is not None:
            on_failure()
        if isinstance(exc, OutputError) and log.holds_run():  # a full disk: what was logged is kept
            raise OutputError(f"{exc}; the evaluations logged so far are kept, resume with: {resume}") from exc
        raise
    finally:
        if live:
            live.stop()
        log.close()
        if client is not None:
            client.close()


#: ``--option`` -> Fill field, for the material settings every command that makes or designs a die takes.
FILL_OPTIONS = {
    "card": ("card_g_m2", float, "[paper] Card grammage, g/m² (default 160)."),
    "card_thickness": ("card_mm", float, "[paper] Card thickness, mm (default grammage / 800)."),
    "glue": ("glue_g_m2", float, "[paper] Dry glue on every tab, g/m² (default 0)."),
    "nozzle": ("nozzle_mm", float, "[print] Nozzle diameter, mm (default 0.4)."),
    "perimeters": ("perimeters", int, "[print] Perimeters (wall lines) (default 2)."),
    "layer_height": ("layer_mm", float, "[print] Layer height, mm (default 0.2)."),
    "top_layers": ("top_layers", int, "[print] Solid top layers (default 4)."),
    "bottom_layers": ("bottom_layers", int, "[print] Solid bottom layers (default 4)."),
    "infill": ("infill", float, "[print] Infill fraction in [0, 1] (default 0.15)."),
    "wall": ("wall_mm", float, "[print] Side-wall thickness, mm, instead of perimeters x line spacing."),
}


def fill_options(*groups: str, kind: bool = True):
    """A decorator adding ``--fill`` (if `kind`) and the settings of the `groups` ("paper", "print")."""

    def decorate(func):
        for option, (_, typ, text) in reversed(FILL_OPTIONS.items()):
            if text[1:].split("]")[0] in groups:
                func = click.option(f"--{option.replace('_', '-')}", option, type=typ, default=None, help=text)(func)
        if kind:
            func = click.option(
                "--fill",
                "fill_kind",
                type=click.Choice(["solid", "shell", "paper", "print"]),
                default=None,
                help="How the die is made (default: the design's [fill]); the settings below refine it.",
            )(func)
        return func

    return decorate


def check_fill_options(kind: str, settings: dict) -> None:
    """Refuse a material option given (not None) that a fill of `kind` does not read: it would be ignored."""
    for option, value in settings.items():
        group = FILL_OPTIONS[option][2][1:].split("]")[0] if option in FILL_OPTIONS else kind
        if value is not None and group != kind:
            raise click.UsageError(f"--{option.replace('_', '-')} applies only to --fill {group} (the fill is {kind})")


def apply_fill(design: Design, fill_kind: str | None = None, **settings) -> Design:
    """`design` with its fill's kind and the given settings (None: keep) replaced; DesignError if out of range."""
    from dataclasses import replace

    fill = design.fill
    changes = {FILL_OPTIONS[k][0]: v for k, v in settings.items() if k in FILL_OPTIONS and v is not None}
    if fill_kind is None and not changes:
        return design
    check_fill_options(fill_kind or fill.kind, settings)
    return replace(design, fill=replace(fill, kind=fill_kind or fill.kind, **changes))


def pop_fill(options: dict) -> dict:
    """Remove the fill options from a command's keyword arguments and return them."""
    return {k: options.pop(k) for k in ["fill_kind", *FILL_OPTIONS] if k in options}


def paper_balance(design: Design, net, spec: str, **card):
    """The balance of the paper die `net` makes (its own tabs; card settings from options or the design)."""
    from diefab.made.mass import mass_properties
    from diefab.made.unfold import net_tab_shapes
    from diefab.models.balance import made_balance

    base = design if design.fill.kind == "paper" else apply_fill(design, "paper")
    fill = apply_fill(base, None, **card).fill
    props = mass_properties(net.poly, fill, mm_per_unit=net.mm_per_unit, tabs=net_tab_shapes(net))
    if design.center_of_mass is not None or design.inertia is not None:  # stated ones override the card's
        props = design.mass_properties(fill)
    words = f"{fill.card_g_m2:g} g/m² card with {len(net.tabs)} glue tabs"
    return made_balance(design, props.center, "paper", words, spec, fill=fill, inertia=props.inertia / props.mass)


def print_balance(design: Design, solid, fill, spec: str):
    """The balance of the print of `solid` (walls, skins, infill and engraving as built)."""
    from diefab.models.balance import made_balance

    r = solid.report
    center = np.asarray(r["center_of_mass_mm"]["printed"]) / r["mm_per_unit"]
    body = design.mass_properties(fill)  # the inertia of the design's own print body (labels as stl engraves)
    if solid.markers:  # the body as cut, with its markers' pockets
        from diefab.fabricate.markers import marked_body

        body = marked_body(solid, fill)
    return made_balance(design, center, "print", fill.describe(), spec, fill=fill, inertia=body.inertia / body.mass)
