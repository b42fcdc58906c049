"""``diefab net``: a paper model to print, cut, fold and glue."""

from __future__ import annotations

import click

from diefab.cli.common import (
    check_size,
    design_argument,
    design_inputs,
    emit_json,
    fill_options,
    get_design,
    json_option,
    out_option,
    paper_balance,
    template_note,
)

SIZE_HELP = (
    "Die size in mm, as dice makers measure it: face to face for dice whose faces come in parallel pairs "
    "(d6, d8, d20), else the largest vertex-to-vertex distance (a d4's edge); the gem's girdle short side. "
    "Default: the design's size_mm."
)


@click.command("net")
@design_argument
@click.option("--size", "size_mm", type=float, default=None, help=SIZE_HELP)
@click.option("--page", default="A4", show_default=True, help="A5, A4, A3, Letter, Legal or WxH in mm.")
@click.option(
    "--format", "formats", default="svg,pdf", show_default=True, metavar="svg,pdf,png", help="Output formats."
)
@click.option("--face-names", is_flag=True, help="Also print the small face names (f1, f2, ...).")
@click.option("--tab-width", type=click.FloatRange(0, 50), default=5.0, show_default=True,
              help="Glue-tab width before narrowing, mm; 0 for no tabs (edges lettered on both sides).")  # fmt: skip
@click.option("--copies", type=click.IntRange(1, 1000), default=1, show_default=True, help="Dice on the sheet(s).")
@click.option("--mark", type=click.Choice(["bar", "period", "none"]), default="bar", show_default=True,
              help="Mark on a label that reads as another label of the die upside down (6 and 9).")  # fmt: skip
@click.option("--pips", is_flag=True, help="Draw values 1 to 9 as pips.")
@click.option("--markers", "with_markers", is_flag=True,
              help="Print each face's ArUco markers beside its value, for diefab read.")  # fmt: skip
@fill_options("paper", kind=False)
@out_option
@json_option
def net(design, params, size_mm, page, formats, face_names, tab_width, copies, mark, pips, with_markers, out_dir,
        as_json, **card) -> None:  # fmt: skip
    """Unfolded, labelled, true-scale paper net of DESIGN with glue tabs (SVG/PDF/PNG).

    The SVG has Inkscape layers print, score (blue, dashed) and cut (red, one
    closed outline per piece) for cutting machines; all text is outlines.
    """
    from diefab.core.files import check_outputs, ensure_dir, output_path, write_files
    from diefab.dice.notes import reading_note, small_die_warning
    from diefab.fabricate.net import design_net, marked_net, parse_formats
    from diefab.made.pages import parse_page

    kinds = parse_formats(formats)
    sheet = parse_page(page)
    if size_mm is not None and size_mm > 0:  # zero and negative sizes: the library's message
        check_size(size_mm)
    d = get_design(design, params, made="paper")
    template, note = template_note(design, d, "paper")
    size = d.size_mm if size_mm is None else size_mm
    ensure_dir(out_dir)
    paths = {kind: output_path(out_dir, d.name, f"-net.{kind}") for kind in kinds}
    inputs = design_inputs(design, d, "paper")
    check_outputs(paths.values(), inputs)
    the_net = design_net(d, size_mm=size_mm, page=sheet, tab_width=tab_width)
    rendered, placed = marked_net(d, the_net, kinds, markers=with_markers, face_names=face_names, copies=copies,
                                  mark=mark, pips=pips)  # fmt: skip
    warning = small_die_warning(d, size)
    written = write_files({paths[k]: rendered[k] for k in kinds}, inputs=inputs)
    if warning:
        click.echo(f"diefab: warning: {warning}", err=True)
    balance = paper_balance(d, the_net, template or design, **card)
    if balance.warning:
        click.echo(f"diefab: warning: {balance.warning}", err=True)
    from diefab.made.unfold import pack_copies

    n_pages = max(n.n_pages for n in pack_copies(the_net, copies))
    if as_json:
        from diefab.fabricate.markers import marker_json

        emit_json({"files": [str(p) for p in written], "template": template, "size_mm": size,
                   "pieces": the_net.n_pieces, "pages": n_pages, "tabs": len(the_net.tabs),
                   "tab_offset_mm": the_net.search.get("tab_offset_mm", 0.0), **balance.as_json(),
                   **({"markers": marker_json(placed)} if placed else {})})  # fmt: skip
        return
    if note:
        click.echo(note)
    for path in written:
        click.echo(str(path))
    pieces = f"{the_net.n_pieces} piece{'s' * (the_net.n_pieces > 1)}{' each' * (copies > 1)}"
    tabs = f"{len(the_net.tabs)} glue tabs" if the_net.tabs else "no glue tabs"
    about = the_net.search.get("symmetric_about", "space")
    if the_net.tabs and about != "space":  # a symmetric die: how far the tabs' card sits off its symmetry
        tabs += f" (their centre {the_net.search['tab_offset_mm']:.2f} mm off the die's symmetry {about})"
    dice = f"{copies} dice, " if copies > 1 else ""
    click.echo(
        f"{d.name}: {size:g} mm die ({d.size_note}), {dice}{pieces}, {tabs}, on {n_pages} "
        f"{sheet.name} page{'s' * (n_pages > 1)}\nto read it: {reading_note(d)}"
    )
    if placed:
        from diefab.fabricate.markers import marker_summary

        sides, cells = [m.side_mm for m in placed], [m.cell_mm for m in placed]
        click.echo(f"markers: {marker_summary(d, sides, cells)}; printed ink, no mass in the balance")
    click.echo(balance.summary())
