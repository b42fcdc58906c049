"""``diefab stl``: a printable solid with engraved values."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from diefab.cli.common import (
    apply_fill,
    check_size,
    design_argument,
    design_inputs,
    emit_json,
    fill_options,
    get_design,
    json_option,
    out_option,
    print_balance,
    template_note,
)
from diefab.cli.net import SIZE_HELP
from diefab.core.errors import DiefabError
from diefab.core.files import check_outputs, ensure_dir, output_path, write_files

#: Largest --margin, mm, and largest --density, g/cm³.
MAX_MARGIN_MM, MAX_DENSITY = 20.0, 25.0


@click.command("stl")
@design_argument
@click.option("--size", "size_mm", type=float, default=None, help=SIZE_HELP)
@click.option("--depth", "depth_mm", type=float, default=0.6, show_default=True, help="Engraving depth, mm.")
@click.option("--font", "font_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Font file (default DejaVu Sans Bold, shipped with matplotlib).")  # fmt: skip
@click.option("--round", "round_mm", type=float, default=0.0, show_default=True, help="Edge/corner radius, mm.")
@click.option(
    "--emboss",
    is_flag=True,
    help="Raise the labels instead of engraving them (the bed face stays flat: unlabelled, or engraved).",
)
@click.option(
    "--bed",
    "bed_face",
    default=None,
    metavar="FACE",
    help="Face to print on (default: least overhang, unlabelled where possible).",
)
@click.option(
    "--mark",
    type=click.Choice(["bar", "period", "none"]),
    default="bar",
    show_default=True,
    help="Mark on a label that reads as another label of the die upside down (6 and 9).",
)
@click.option("--pips", is_flag=True, help="Values 1 to 9 as pips.")
@click.option(
    "--markers",
    "with_markers",
    is_flag=True,
    help="Inlay each face's ArUco markers beside its value, flush (3MF: second part), for diefab read.",
)
@click.option(
    "--inlay",
    is_flag=True,
    help="Also write DIR/<design>-inlay.stl: the labels alone, for paint-fill or a second material.",
)
@click.option(
    "--format",
    "formats",
    default="stl",
    show_default=True,
    metavar="stl,3mf",
    help="Output formats; the 3MF holds body and labels as two coloured parts.",
)
@click.option("--min-stroke", type=float, default=0.6, show_default=True, help="Warn below this stroke width, mm.")
@click.option("--min-text-height", type=float, default=2.0, show_default=True, help="Smallest text height, mm.")
@click.option("--margin", "margin_mm", type=float, default=1.0, show_default=True, help="Text to face edge, mm.")
@click.option("--density", type=float, default=1.24, show_default=True, help="Material density, g/cm³ (PLA).")
@fill_options("print", kind=False)
@click.option("--fit-each", is_flag=True, help="Size each value label to its face (default: one height for all).")
@click.option("--preview", is_flag=True, help="Also write DIR/<design>-preview.png.")
@out_option
@json_option
def stl(design, params, size_mm, depth_mm, font_file, round_mm, emboss, bed_face, mark, pips, with_markers, inlay,
        formats, min_stroke, min_text_height, margin_mm, density, fit_each, preview, out_dir, as_json,
        **settings) -> None:  # fmt: skip
    """Printable STL/3MF of DESIGN with its values engraved; report volume, mass and balance."""
    from diefab.core.errors import FabricationError
    from diefab.dice.design import format_value
    from diefab.dice.notes import reading_note
    from diefab.fabricate.formats import inlay_stl_bytes, stl_bytes, threemf_bytes
    from diefab.fabricate.stl import build_solid

    kinds = [f.strip().lower() for f in formats.split(",") if f.strip()]
    bad = [f for f in kinds if f not in ("stl", "3mf")]
    if bad or not kinds:
        raise click.BadParameter(f"{formats!r}: formats are stl and 3mf", param_hint="--format")
    if size_mm is not None and size_mm > 0:  # zero and negative sizes: the library's message
        check_size(size_mm)
    if not (np.isfinite(margin_mm) and 0 <= margin_mm <= MAX_MARGIN_MM):
        raise click.BadParameter(f"{margin_mm:g} mm is outside [0, {MAX_MARGIN_MM:g}] mm", param_hint="--margin")
    if not (np.isfinite(density) and 0 < density <= MAX_DENSITY):
        raise click.BadParameter(f"{density:g} g/cm³ is outside (0, {MAX_DENSITY:g}] (osmium: 22.6)",
                                 param_hint="--density")  # fmt: skip
    d = get_design(design, params, made="print")
    template, note = template_note(design, d, "print")
    try:
        fill = apply_fill(d, "print", **settings).fill
    except DiefabError as exc:
        raise FabricationError(str(exc)) from exc
    ensure_dir(out_dir)
    inputs = [*design_inputs(design, d, "print"), *([font_file] if font_file else [])]
    names = {k: output_path(out_dir, d.name, f".{k}") for k in dict.fromkeys(kinds)}
    if preview:
        names["preview"] = output_path(out_dir, d.name, "-preview.png")
    if inlay:
        names["inlay"] = output_path(out_dir, d.name, "-inlay.stl")
    check_outputs(names.values(), inputs)
    solid = build_solid(
        d, size_mm=size_mm, depth_mm=depth_mm, font=font_file, round_mm=round_mm, emboss=emboss,
        min_stroke_mm=min_stroke, min_text_height_mm=min_text_height, margin_mm=margin_mm,
        density_g_cm3=density, print_fill=fill, uniform_height=not fit_each, bed=bed_face, mark=mark, pips=pips,
        markers=with_markers,
    )  # fmt: skip
    payloads = {names[k]: (stl_bytes if k == "stl" else threemf_bytes)(solid) for k in dict.fromkeys(kinds)}
    if inlay:
        payloads[names["inlay"]] = inlay_stl_bytes(solid)
    if preview:
        from diefab.fabricate.preview import render_preview

        payloads[names["preview"]] = render_preview(solid)
    written = [str(p) for p in write_files(payloads, inputs=inputs)]
    for line in solid.warnings:
        click.echo(f"diefab: warning: {line}", err=True)
    balance = print_balance(d, solid, fill, template or design)
    if balance.warning:
        click.echo(f"diefab: warning: {balance.warning}", err=True)
    report = {
        "file": written[0],
        "files": written,
        "template": template,
        "reading": reading_note(d),
        **solid.report,
        **balance.as_json(),
    }
    if as_json:
        emit_json(report)
        return
    r = solid.report
    if note:
        click.echo(note)
    how = (
        f"{len(r['embossed'])} labels embossed, {len(r['engraved'])} engraved"
        if r["embossed"] and r["engraved"]
        else f"{len(r['labels'])} labels {'embossed' if r['embossed'] else 'engraved'}"
    )
    click.echo(
        f"{d.name}: {r['size_mm']:g} mm ({d.size_note}), {how} {depth_mm:g} mm"
        f"{f', edges rounded {round_mm:g} mm' if round_mm else ''}, printed on face {r['bed_face']}\n"
        f"to read it: {reading_note(d)}\n"
        f"volume {r['volume_mm3']:.1f} mm³ (uncut {r['uncut_volume_mm3']:.1f}, text "
        f"{r['engraved_volume_mm3']:.1f}{' with markers' if solid.markers else ''}); "
        f"watertight {r['watertight']}, bodies {r['bodies']}, genus {r['genus']}\n"
        f"mass {r['mass_g']:.2f} g printed ({fill.wall_thickness_mm:.2f} mm walls, {fill.infill:.0%} infill), "
        f"{r['mass_solid_g']:.2f} g solid, at {density:g} g/cm³\n"
        f"centre of mass shift: {'labels' if r['embossed'] else 'engraving'} {r['com_shift_norm_mm'] * 1000:.1f} µm, "
        f"infill {r['infill_com_shift_norm_mm'] * 1000:.1f} µm"
    )
    if solid.markers:
        from diefab.fabricate.markers import marker_summary

        sides, cells = [m.height_mm for m in solid.markers], [m.stroke_mm for m in solid.markers]
        click.echo(
            f"markers: {marker_summary(d, sides, cells)}; inlaid {depth_mm:g} mm deep, flush, "
            f"{r['marker_volume_mm3']:.1f} mm³ (in the 3MF's second part), centre of mass shift "
            f"{r['marker_com_shift_norm_mm'] * 1000:.1f} µm (included in the mass and balance)"
        )
    before = r["probabilities"]["rounded" if round_mm else "sharp"]
    signed = min(d.support) < 0
    click.echo("solid-angle model of the solid as cut (the balance line below is the fast model's):")
    click.echo("value       " + " ".join(f"{format_value(int(v), signed):>8s}" for v in before))
    for key in ("sharp", "rounded", "engraved", "printed"):
        if key in r["probabilities"]:
            click.echo(f"{key:<11s} " + " ".join(f"{p:8.5f}" for p in r["probabilities"][key].values()))
    click.echo(balance.summary())
    for path in written:
        click.echo(f"wrote {path}")
