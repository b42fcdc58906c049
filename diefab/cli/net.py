"""``diefab net``: a paper model to print, cut, fold and glue."""

from __future__ import annotations

import click

from ..design import Design
from .common import design_argument, design_inputs, get_design, out_option


@click.command("net")
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
    from ..fabricate.net import design_net, parse_formats, render_net
    from ..fabricate.unfold import parse_page
    from ..files import check_outputs, ensure_dir, output_path, write_files

    kinds = parse_formats(formats)
    sheet = parse_page(page)
    d = get_design(design, params)
    ensure_dir(out_dir)
    paths = {kind: output_path(out_dir, d.name, f"-net.{kind}") for kind in kinds}
    inputs = design_inputs(design, d)
    check_outputs(paths.values(), inputs)
    the_net = design_net(d, size_mm=size_mm, page=sheet, tab_width=tab_width)
    rendered = render_net(d, the_net, kinds, face_names=face_names)
    written = write_files({paths[k]: rendered[k] for k in kinds}, inputs=inputs)
    for path in written:
        click.echo(str(path))
    size = d.size_mm if size_mm is None else size_mm
    pieces = f"{the_net.n_pieces} piece{'s' * (the_net.n_pieces > 1)}"
    pages = f"{the_net.n_pages} {sheet.name} page{'s' * (the_net.n_pages > 1)}"
    click.echo(f"{d.name}: {size:g} mm die ({_size_note(d)}), {pieces} on {pages}, {len(the_net.tabs)} glue tabs")


def _size_note(design: Design) -> str:
    from ..fabricate.net import size_note

    return size_note(design)
