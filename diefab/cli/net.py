"""``diefab net``: a paper model to print, cut, fold and glue."""

from __future__ import annotations

from pathlib import Path

import click

from ..design import Design
from ..errors import DiefabError
from .common import design_argument, emit_json, fill_options, get_design, json_option, out_option, paper_balance


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
@fill_options("paper", kind=False)
@out_option
@json_option
def net(design, params, size_mm, page, formats, face_names, tab_width, out_dir, as_json, **card) -> None:  # fmt: skip
    """Unfolded, labelled, true-scale paper net of DESIGN with glue tabs (SVG/PDF/PNG)."""
    from ..fabricate.net import design_net, parse_formats, render_net
    from ..fabricate.unfold import parse_page
    from ..files import atomic_write, ensure_dir

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
    balance = paper_balance(d, the_net, design, **card)
    size = d.size_mm if size_mm is None else size_mm
    if as_json:
        emit_json({"files": [str(p) for p in written], "size_mm": size, "pieces": the_net.n_pieces,
                   "pages": the_net.n_pages, "tabs": len(the_net.tabs), **balance.as_json()})  # fmt: skip
    else:
        for path in written:
            click.echo(str(path))
        pieces = f"{the_net.n_pieces} piece{'s' * (the_net.n_pieces > 1)}"
        pages = f"{the_net.n_pages} {sheet.name} page{'s' * (the_net.n_pages > 1)}"
        click.echo(f"{d.name}: {size:g} mm die ({_size_note(d)}), {pieces} on {pages}, {len(the_net.tabs)} glue tabs")
        click.echo(balance.summary())
    if balance.warning:
        click.echo(f"diefab: warning: {balance.warning}", err=True)


def _size_note(design: Design) -> str:
    from ..fabricate.net import size_note

    return size_note(design)
