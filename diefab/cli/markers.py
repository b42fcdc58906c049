"""``diefab markers``: a true-scale sheet of marker stickers, one per face, for ``diefab read``."""

from __future__ import annotations

import click

from diefab.cli.common import check_size, design_argument, design_inputs, get_design, out_option


@click.command("markers")
@design_argument
@click.option("--size", "size_mm", type=float, default=None, help="Die size in mm (default: the design's size_mm).")
@click.option("--page", default="A4", show_default=True, help="A5, A4, A3, Letter, Legal or WxH in mm.")
@out_option
def markers(design, params, size_mm, page, out_dir) -> None:
    """Sticker sheet (SVG and PDF, true scale): each sticker cut to its face, with its marker and value."""
    from diefab.core.files import ensure_dir, output_path, write_files
    from diefab.fabricate.pdf import render_pdf
    from diefab.fabricate.stickers import sticker_sheets
    from diefab.fabricate.svg import render_svg

    if size_mm is not None:
        check_size(size_mm)
    d = get_design(design, params)
    sheets = sticker_sheets(d, size_mm=size_mm, page=page)
    ensure_dir(out_dir)
    files = {
        output_path(out_dir, d.name, "-markers.svg"): render_svg(sheets),
        output_path(out_dir, d.name, "-markers.pdf"): render_pdf(sheets),
    }
    for path in write_files(files, inputs=design_inputs(design, d)):
        click.echo(f"wrote {path}")
