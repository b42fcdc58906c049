"""``diefab templates`` and ``diefab predict``: what a design is and how it lands."""

from __future__ import annotations

import click

from diefab.cli.common import (
    apply_fill,
    console,
    design_argument,
    emit_json,
    fill_options,
    get_design,
    heading,
    json_option,
    note_fast_fill,
    pop_fill,
    values_dict,
)
from diefab.dice.design import format_value, signed_number


@click.command()
@json_option
def templates(as_json: bool) -> None:
    """List the shipped design templates."""
    from diefab.dice.design import list_templates

    designs = list_templates()
    if as_json:
        emit_json({d.name: d.description for d in designs})
        return
    width = max(len(d.name) for d in designs)
    for d in designs:
        click.echo(f"{d.name:<{width}}  {d.description}")


@click.command()
@design_argument
@click.option("--model", default="auto", show_default=True,
              help="Landing model: fast, basins (quasi-static) or solid-angle (the paper's); auto: the one to trust "
              "for this die (fast, or basins where the design's physics is quasi-static).")  # fmt: skip
@fill_options("paper", "print")
@click.option("--target", default=None, help="Override the design's target distribution.")
@json_option
def predict(design: str, params, model: str, target: str | None, as_json: bool, **fill) -> None:
    """Landing probabilities, centre of mass and stability margins of DESIGN."""

    from diefab.models.choice import best_model
    from diefab.models.probabilities import face_probabilities, to_values
    from diefab.stats.goodness import jsd, pearson_divergence, tvd

    fill = pop_fill(fill)
    d = apply_fill(get_design(design, params, target, fill.get("fill_kind")), **fill)
    choice = best_model(d) if model == "auto" else None
    model = choice.name if choice is not None else model
    fill_model = d.fill
    d.check_stable(0.0, fill_model)
    note_fast_fill(d, model, fill_model.kind)
    poly = d.polyhedron
    bound = None
    if model == "basins":
        from diefab.models.probabilities import basin_shares

        faces, bound = basin_shares(poly, d.mass_properties(fill_model).center)
    else:
        faces = face_probabilities(d, model, fill_model)
    values = to_values(d, faces)
    goal = d.target_distribution.aligned(d.support)
    com = d.mass_properties(fill_model).center
    margins = d.margins(fill_model)
    transitional = d.transitional_faces
    rolls_to = {}
    if transitional:
        from diefab.models.basins import RestBasins

        targets = RestBasins.of(poly, com).targets
        rolls_to = {n: poly.names[targets[k]] for k, n in enumerate(poly.names) if n in transitional}
    result = {
        "design": d.name,
        "model": model,
        **({"model_reason": choice.reason} if choice is not None else {}),
        "fill": fill_model.kind,
        "params": dict(d.params),
        "target": d.target,
        "faces": [
            {
                "name": n,
                "value": d.values.get(n),
                "resting": n in d.values,
                "label_face": d.label_face[n] if n in d.values else None,
                "probability": float(p),
                "margin": float(m),
                **({"rolls_to": rolls_to[n]} if n in rolls_to else {}),
            }
            for n, p, m in zip(poly.names, faces, margins)
        ],
        "transitional": list(transitional),
        "transitional_named": list(d.transitional),
        "values": values_dict(d, values),
        "target_values": values_dict(d, goal),
        "center_of_mass": com.tolist(),
        "margins": {n: float(m) for n, m in zip(poly.names, margins)},
        "min_margin": float(margins[d.resting_mask()].min()),
        **({} if bound is None else {"error_bound": bound}),
        "objective": pearson_divergence(values, goal),
        "tvd": tvd(values, goal),
        "jsd": jsd(goal, values),
    }
    if as_json:
        emit_json(result)
        return
    from rich.table import Table

    con = console()
    con.print(heading(d, model=model, fill=fill_model.kind))
    if choice is not None:
        con.print(f"model: {model} ({choice.reason}; --model chooses another)")
    con.print(f"centre of mass: ({com[0]:.4f}, {com[1]:.4f}, {com[2]:.4f})  model units")
    table = Table("rests on", "value", "label on", "probability", "margin",
                  title=f"Resting faces, {model} model", title_justify="left")  # fmt: skip
    for f in result["faces"]:
        if not f["resting"]:
            continue
        table.add_row(
            f["name"],
            format_value(f["value"], min(d.support) < 0),
            f["label_face"] or "(vertex)",
            f"{f['probability']:.4f}",
            f"{f['margin']:.4f}",
        )
    con.print(table)
    if transitional:
        named = f", {len(d.transitional)} named in the design" if d.transitional else ""
        con.print(f"{len(transitional)} transitional faces (the die rolls off them; probability 0{named}):")
        shown = "  ".join(f"{n}\u2192{rolls_to[n]}" for n in transitional[:40])
        more = f"  ... ({len(transitional) - 40} more; --json lists all)" if len(transitional) > 40 else ""
        con.print("  " + shown + more)
    table = Table("value", "predicted", "target", "difference", title=f"Values, {model} model",
                  title_justify="left")  # fmt: skip
    for v, p, q in zip(d.support, values, goal):
        table.add_row(format_value(v, min(d.support) < 0), f"{p:.4f}", f"{q:.4f}", signed_number(p - q, 4))
    con.print(table)
    con.print(f"Eq. (2) objective {result['objective']:.5f}   TVD {result['tvd']:.4f}   JSD {result['jsd']:.5f}")
    if bound is not None:
        con.print(f"basins measured to within {bound:.1e} (share of orientations on basin rims not yet resolved)")
