"""``diefab design``: from a target distribution to a die that predict, validate, net and stl take."""

from __future__ import annotations

import re
import time
from pathlib import Path

import click
import numpy as np

from diefab.cli.common import (
    FILL_OPTIONS,
    check_fill_options,
    console,
    emit_json,
    fill_options,
    json_option,
    out_option,
    physics_file_option,
    seed_option,
)

_METHOD = {
    "fair": "a fair die, its faces counted out to the target",
    "two-class": "two classes of faces counted out to the target, one share tuned",
    "shaped": "shape optimized",
}


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-") or "target"


@click.command()
@click.argument("target", metavar="TARGET")
@click.option("--faces", type=click.IntRange(2, 120), default=None, help="Resting faces of the die (default: chosen).")
@click.option("--family", "family_name", default="auto", show_default=True,
              help="Die family (ngem, prism, bipyramid, trapezohedron, cuboid, freeform, gem) or auto.")  # fmt: skip
@fill_options("paper", "print")
@click.option("--model", type=click.Choice(["fast", "solid-angle", "basins", "simulation"]), default="simulation",
              show_default=True,
              help="Model optimized; simulation refines the fast model's die against pybullet drops.")  # fmt: skip
@click.option("--budget", type=float, default=6.0, show_default=True,
              help="Wall-time budget of the search, minutes (the closing check comes on top).")  # fmt: skip
@click.option("--name", default=None, help="Design name (default FAMILY-TARGET).")
@seed_option("Seed of starts and drops.")
@click.option("--size", "size_mm", type=float, default=30.0, show_default=True,
              help="Size in mm of the family's reference length (see the design file's description).")  # fmt: skip
@click.option("--min-margin", type=float, default=0.05, show_default=True,
              help="Smallest stability margin of every resting face, model units.")  # fmt: skip
@click.option("--validate-sims", type=click.IntRange(0, 10_000_000), default=10_000, show_default=True,
              help="Drops of the closing check (on a seed the search never used); 0 skips it.")  # fmt: skip
@click.option("--workers", type=click.IntRange(1, 256), default=None, help="Worker processes (default all cores).")
@physics_file_option
@click.option("--robust", is_flag=True,
              help="Refine and check against every standard throw and table (the shipped profiles soft-tray, "
              "wooden-table, hard-tray, low-spin, high-spin; each over --physics), judged by the worst.")  # fmt: skip
@out_option
@json_option
def design(target, faces, family_name, model, budget, name, seed, size_mm, min_margin, validate_sims, workers,
           physics_profile, robust, out_dir, as_json, fill_kind, **fill_settings) -> None:  # fmt: skip
    """Design a die that rolls like TARGET (2d6, 3dF, binomial:4, uniform:3, 1:3,2:3,...).

    Picks a family and face count that can carry the target's values,
    assigns values to faces, optimizes the shape, checks it by simulation on
    a fresh seed, and writes OUT/NAME.toml.  With --fill paper or print (and
    their settings) the die is designed as it will be made.  With --physics
    the die is refined and checked under that profile, which the design file
    keeps as its [physics] table; with --robust, under each standard throw
    and table at once.
    """
    from dataclasses import replace

    from diefab.core.files import atomic_write, ensure_dir, output_path
    from diefab.dice.design import design_to_toml
    from diefab.dice.targets import parse_target
    from diefab.made.mass import Fill
    from diefab.physics.profiles import STANDARD, load_profile
    from diefab.physics.simulate import PhysicsSettings, simulate
    from diefab.search.synthesis import synthesize
    from diefab.stats.goodness import goodness_of_fit, pearson_divergence, tvd

    t0 = time.monotonic()
    goal = parse_target(target)
    check_fill_options(fill_kind or "solid", fill_settings)
    changes = {FILL_OPTIONS[k][0]: v for k, v in fill_settings.items() if v is not None}
    made = Fill(kind=fill_kind or "solid", **changes)  # a setting out of range: DesignError, one line
    if not (np.isfinite(budget) and budget > 0):
        raise click.BadParameter(f"{budget} must be a positive number of minutes", param_hint="--budget")
    if not (np.isfinite(size_mm) and size_mm > 0):
        raise click.BadParameter(f"{size_mm} must be a positive number of millimetres", param_hint="--size")
    if not (np.isfinite(min_margin) and min_margin >= 0):
        raise click.BadParameter(f"{min_margin} must be a non-negative number", param_hint="--min-margin")
    if name is not None and not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._-]{0,99}", name):
        raise click.BadParameter(f"{name!r}: use letters, digits, '.', '_' and '-'", param_hint="--name")
    if robust and model != "simulation":
        raise click.BadParameter("--robust needs --model simulation (the other models do not simulate)",
                                 param_hint="--robust")  # fmt: skip
    physics = {} if physics_profile is None else load_profile(physics_profile).as_dict()
    throws = [load_profile(p, base=physics).as_dict() for p in STANDARD] if robust else []
    family = None if family_name == "auto" else family_name
    ensure_dir(out_dir)
    err = console(stderr=True)
    say = (lambda text: err.print(text)) if not as_json else None
    found = synthesize(
        goal, faces=faces, family=family, fill=made, model=model, budget_seconds=budget * 60, seed=seed,
        name=name or "die", size_mm=size_mm, min_margin=min_margin, workers=workers, progress=say,
        settings=PhysicsSettings.from_mapping(physics), throws=throws,
    )  # fmt: skip
    d = replace(
        found.design,
        physics=physics,
        name=name or f"{found.design.family}-{_slug(target)}",
        description=f"designed for {target} by diefab design: {_METHOD[found.method]} "
        f"({found.model} model, seed {seed})",
    )
    how = (f" --physics {physics_profile}" if physics_profile else "") + (" --robust" if robust else "")
    path = atomic_write(
        output_path(out_dir, d.name, ".toml"),
        design_to_toml(
            d,
            comment=f"Written by: diefab design {target} --model {model} --seed {seed}"
            + (f" --fill {made.kind}" if made.kind != "solid" else "")
            + how,
        ),  # fmt: skip
    )
    aligned = goal.aligned(d.support)
    validated = None
    if validate_sims:
        check_seed = seed + 1_000_003  # never used by the search (its drops use seed .. seed + steps)
        checks = []
        for throw in throws or [d.physics]:
            result = simulate(d, validate_sims, seed=check_seed, workers=workers,
                              settings=PhysicsSettings.from_mapping(throw))  # fmt: skip
            fit = goodness_of_fit(result.value_counts(d), aligned, seed=check_seed)
            checks.append({"n": result.n, "landed": result.landed, "seed": check_seed, "tvd": fit.tvd,
                           "p_value": fit.p_value})  # fmt: skip
        validated = max(checks, key=lambda c: c["tvd"])
        if throws:
            validated = {**validated, "profiles": dict(zip(STANDARD, checks)),
                         "worst_profile": STANDARD[checks.index(validated)]}  # fmt: skip
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
        "validated": validated,
        "physics": physics_profile,
        "robust": robust,
        "tried": found.tried,
        "refinement": found.steps,
        "seconds": time.monotonic() - t0,
    }
    if as_json:
        emit_json(report)
        return
    _print_report(d, report, path)


def _print_report(d, report: dict, path: Path) -> None:
    from rich.table import Table

    con = console()
    con.print(f"[bold]{d.name}[/bold]  family {d.family}  " + " ".join(f"{k}={v:.4g}" for k, v in d.params.items()))
    con.print(_METHOD[report["method"]])
    table = Table("value", "faces", "predicted", "target")
    faces_of: dict[int, list[str]] = {}
    for face, value in d.values.items():
        faces_of.setdefault(value, []).append(face)
    for v in d.support:
        table.add_row(
            str(v), " ".join(faces_of[v]), f"{report['predicted'][str(v)]:.4f}", f"{report['target'][str(v)]:.4f}"
        )
    con.print(table)
    con.print(f"Eq. (2) {report['objective']:.5f}, TVD {report['tvd']:.4f} under the {report['model']} model")
    v = report["validated"]
    if v and "profiles" in v:
        for profile, c in v["profiles"].items():
            con.print(f"validated under {profile}: {c['n']} drops (seed {c['seed']}), TVD {c['tvd']:.4f}, "
                      f"p = {c['p_value']:.3g}")  # fmt: skip
        con.print(f"worst: {v['worst_profile']}, TVD {v['tvd']:.4f}")
    elif v:
        under = f" under {report['physics']}" if report["physics"] else ""
        con.print(f"validated{under}: {v['n']} drops (seed {v['seed']}), TVD {v['tvd']:.4f}, p = {v['p_value']:.3g}")
    con.print(f"wrote {path} ({report['seconds']:.0f} s)")
