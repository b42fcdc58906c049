"""``diefab studio``: serve the local web studio."""

from __future__ import annotations

from pathlib import Path

import click

from diefab.cli.common import out_option


@click.command()
@click.argument("spec", metavar="[DESIGN|TARGET]", required=False, default=None)
@click.option("--port", type=click.IntRange(1, 65535), default=8080, show_default=True, help="Port to serve on.")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Address to bind; another lets other machines use the studio and its --out.")  # fmt: skip
@click.option("--no-browser", is_flag=True, help="Only serve; do not open a browser.")
@out_option
def studio(spec, port, host, no_browser, out_dir) -> None:
    """Design, see and make a die in a local web page.

    DESIGN (a template name or a design file) opens that die; a TARGET
    (2d6, 3dF, 1:3,2:3 ...) opens the default die with the target filled in
    for "Design for target".  Files are read and written only in --out and
    the shipped templates.
    """
    from diefab.core.errors import DiefabError
    from diefab.core.files import ensure_dir
    from diefab.dice.design import load_design

    target = None
    if spec is None:
        design = load_design("fudge-gem")
    else:
        try:
            design = load_design(spec)
        except DiefabError as design_error:
            from diefab.dice.targets import parse_target

            try:
                parse_target(spec)
            except DiefabError:
                raise design_error from None
            target, design = spec, load_design("fudge-gem")
    _ = design.polyhedron  # a bad design fails here, before serving
    ensure_dir(out_dir)
    if host not in ("127.0.0.1", "localhost", "::1"):
        click.echo(f"diefab: warning: serving on {host}: other machines can open the studio and write into "
                   f"{Path(out_dir).resolve()}", err=True)  # fmt: skip
    _check_port(host, port)
    try:
        import nicegui  # noqa: F401
    except ImportError:
        raise click.ClickException("the studio needs NiceGUI: pip install 'diefab[studio]'") from None
    from diefab.studio.app import serve

    where = f"[{host}]" if ":" in host else host  # an IPv6 address is bracketed in a URL
    click.echo(f"diefab studio: http://{where}:{port}/  (files in {out_dir}; Ctrl-C stops)", err=True)
    inputs = (Path(spec),) if spec is not None and Path(spec).is_file() else ()
    serve(design, out_dir, host=host, port=port, show=not no_browser, target=target, inputs=inputs)


def _check_port(host: str, port: int) -> None:
    """Refuse a port another program holds, with one line instead of the server's log."""
    import socket

    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except OSError as exc:
        raise click.BadParameter(f"{host}: {exc.strerror or exc}", param_hint="--host") from None
    family, _, _, _, address = infos[0]
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(address)
        except OSError as exc:
            raise click.BadParameter(f"cannot serve on {host}:{port}: {exc.strerror or exc}",
                                     param_hint="--port") from None  # fmt: skip
