"""The ``diefab`` command line: parse, call the library, write files, print.

One module per command or group of commands; shared options live in
:mod:`diefab.cli.common`.  Every error a user can cause ends in one line on
stderr and exit status 2; Ctrl-C ends with status 130.  Outputs are written
atomically.
"""

from __future__ import annotations

import os
import sys

import click

from ..errors import DiefabError
from .calibrate import calibrate
from .design import design
from .net import net
from .optimize import optimize
from .predict import predict, templates
from .stats import stats
from .stl import stl
from .validate import validate

__all__ = ["cli", "main"]


@click.group(context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(package_name="diefab")
def cli() -> None:
    """Design, simulate and fabricate dice with unequal face probabilities."""


for _command in (templates, predict, stats, design, optimize, validate, calibrate, net, stl):
    cli.add_command(_command)


def _terminate(signum, frame) -> None:
    raise KeyboardInterrupt  # a kill (SIGTERM) stops a run as cleanly as Ctrl-C


def main(argv: list[str] | None = None) -> None:
    """Console entry point: one-line errors, exit status 2 on bad input."""
    import signal
    import threading

    previous = signal.getsignal(signal.SIGTERM)
    catch = previous is signal.SIG_DFL and threading.current_thread() is threading.main_thread()
    if catch:
        signal.signal(signal.SIGTERM, _terminate)
    try:
        _main(argv)
    finally:
        if catch:
            signal.signal(signal.SIGTERM, previous)


def _main(argv: list[str] | None) -> None:
    try:
        rv = cli.main(args=argv, prog_name="diefab", standalone_mode=False)
    except click.exceptions.Abort:
        click.echo("diefab: interrupted", err=True)
        sys.exit(130)
    except KeyboardInterrupt:
        click.echo("diefab: interrupted", err=True)
        sys.exit(130)
    except click.ClickException as exc:
        ctx = getattr(exc, "ctx", None)
        where = f"{ctx.command_path}: " if ctx is not None else "diefab: "
        click.echo(f"{where}error: {exc.format_message()}".replace("\n", " "), err=True)
        sys.exit(2)
    except DiefabError as exc:
        click.echo(f"diefab: error: {exc}".replace("\n", " "), err=True)
        sys.exit(2)
    except Exception as exc:  # a bug, not bad input: one line unless asked for the traceback
        if os.environ.get("DIEFAB_DEBUG"):
            raise
        click.echo(
            f"diefab: internal error: {type(exc).__name__}: {exc} (set DIEFAB_DEBUG=1 for a traceback)".replace(
                "\n", " "
            ),
            err=True,
        )
        sys.exit(1)
    sys.exit(rv if isinstance(rv, int) else 0)
