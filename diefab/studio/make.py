"""Files the studio makes (net, solid, design file), written atomically into its output folder only."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from diefab.core.errors import FabricationError, OutputError
from diefab.dice.design import Design, design_to_toml, files_read


def _inside(out_dir: Path, path: Path) -> Path:
    """`path`, refusing one that is not inside `out_dir` (a design name cannot climb out of it)."""
    root = Path(out_dir).resolve()
    full = Path(path).resolve()
    if root != full.parent and root not in full.parents:
        raise OutputError(f"{path} is outside the studio's folder {out_dir}")
    return Path(path)


def _kept(design: Design, inputs: Iterable[Path]) -> list[Path]:
    """The files no writer may replace: the design's own (its mesh, its SVG symbols) and `inputs`."""
    return [*files_read(design.mesh, design.labels), *inputs]


def write_net(design: Design, out_dir: Path, *, page: str = "A4", formats: tuple[str, ...] = ("svg", "pdf"),
              copies: int = 1, mark: str = "bar", pips: bool = False, face_names: bool = False,
              tab_width: float = 5.0, markers: bool = False, inputs: Iterable[Path] = ()) -> list[Path]:  # fmt: skip
    """Write the paper net of `design` (as ``diefab net``, with ``--markers`` if `markers`); the files written.

    Every writer here refuses to replace `inputs` (the files the studio was opened on) or the design's own files.
    """
    from diefab.core.files import ensure_dir, output_path, write_files
    from diefab.fabricate.net import design_net, marked_net
    from diefab.made.pages import parse_page

    ensure_dir(out_dir)
    net = design_net(design, page=parse_page(page), tab_width=tab_width)
    rendered, _ = marked_net(design, net, formats, markers=markers, face_names=face_names, copies=copies, mark=mark,
                             pips=pips)  # fmt: skip
    paths = {k: _inside(out_dir, output_path(out_dir, design.name, f"-net.{k}")) for k in formats}
    return write_files({paths[k]: rendered[k] for k in formats}, inputs=_kept(design, inputs))


def write_solid(
    design: Design,
    out_dir: Path,
    *,
    formats: tuple[str, ...] = ("stl",),
    round_mm: float = 0.0,
    depth_mm: float = 0.6,
    emboss: bool = False,
    inlay: bool = False,
    markers: bool = False,
    inputs: Iterable[Path] = (),
) -> tuple[list[Path], dict]:
    """Write the printable solid of `design` (as ``diefab stl``); the files written and the solid's report.

    `markers` inlays each face's ArUco marker, as ``diefab stl --markers``.
    """
    from diefab.core.files import ensure_dir, output_path, write_files
    from diefab.fabricate.formats import inlay_stl_bytes, stl_bytes, threemf_bytes
    from diefab.fabricate.stl import build_solid

    bad = [f for f in formats if f not in ("stl", "3mf")]
    if bad or not formats:
        raise FabricationError(f"formats {','.join(formats)!r}: the solid's formats are stl and 3mf")
    ensure_dir(out_dir)
    fill = design.fill if design.fill.kind == "print" else None
    solid = build_solid(design, round_mm=round_mm, depth_mm=depth_mm, emboss=emboss, markers=markers,
                        **({"print_fill": fill} if fill is not None else {}))  # fmt: skip
    payloads = {}
    for k in formats:
        path = _inside(out_dir, output_path(out_dir, design.name, f".{k}"))
        payloads[path] = stl_bytes(solid) if k == "stl" else threemf_bytes(solid)
    if inlay:
        payloads[_inside(out_dir, output_path(out_dir, design.name, "-inlay.stl"))] = inlay_stl_bytes(solid)
    return write_files(payloads, inputs=_kept(design, inputs)), dict(solid.report)


def write_design(design: Design, out_dir: Path, *, inputs: Iterable[Path] = ()) -> Path:
    """Write `design` as a TOML design file into `out_dir`."""
    from diefab.core.files import ensure_dir, output_path, write_files

    ensure_dir(out_dir)
    path = _inside(out_dir, output_path(out_dir, design.name, ".toml"))
    text = design_to_toml(design, comment="saved by diefab studio")
    return write_files({path: text}, inputs=_kept(design, inputs))[0]


def net_faces(design: Design, page: str = "A4"):
    """The laid-out net of `design` for the page's picture: (faces side by side, mm), face names."""
    from diefab.fabricate.net import design_net
    from diefab.made.pages import parse_page
    from diefab.studio.view import side_by_side

    net = design_net(design, page=parse_page(page))
    return side_by_side(net.faces, net.face_page, net.page.width), list(net.poly.names)
