"""The ``diefab`` command line: parse, call the library, write files, print.

One module per command or group of commands; shared options live in
:mod:`diefab.cli.common`.  Every error a user can cause ends in one line,
``diefab: error: ...``, on stderr and exit status 2; a bug ends in one line and
status 1.  Ctrl-C, SIGTERM and SIGHUP end a command cleanly with status 130.
Outputs are written atomically, as one transaction per command, never over an
input (:mod:`diefab.core.files`).
"""

from __future__ import annotations

import os
import sys

import click

from diefab.cli.calibrate import calibrate
from diefab.cli.design import design
from diefab.cli.markers import markers
from diefab.cli.net import net
from diefab.cli.optimize import optimize
from diefab.cli.predict import predict, templates
from diefab.cli.read import read
from diefab.cli.roll import roll
from diefab.cli.stats import stats
from diefab.cli.stl import stl
from diefab.cli.studio import studio
from diefab.cli.validate import validate
from diefab.core.errors import DiefabError

__all__ = ["cli", "main"]


@click.group(context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(package_name="diefab")
def cli() -> None:
    """Design, simulate and fabricate dice with unequal face probabilities."""


for _command in (
    templates,
    predict,
    stats,
    design,
    optimize,
    validate,
    calibrate,
    net,
    stl,
    markers,
    read,
    roll,
    studio,
):
    cli.add_command(_command)


#: Longest error line printed (a 5-million-digit token stays out of the terminal).
MESSAGE_MAX = 1000


def main(argv: list[str] | None = None) -> None:
    """Console entry point: one-line errors, exit status 2 on bad input."""
    import signal
    import warnings

    from diefab.core import stopping
    from diefab.core.files import release_locks

    stopping.reset()
    caught = stopping.install()  # a kill (SIGTERM) or hang-up (SIGHUP) stops a run as cleanly as Ctrl-C
    try:
        with warnings.catch_warnings():
            shown: set[str] = set()

            def show(message, category, filename, lineno, file=None, line=None) -> None:
                """A Python warning as one ``diefab: warning:`` line, each text once."""
                text = _one_line(str(message))
                if text not in shown:
                    shown.add(text)
                    click.echo(f"diefab: warning: {text}", err=True)

            warnings.showwarning = show
            _main(argv)
    finally:
        late = []
        try:
            release_locks()  # with the stops deferred: one received meanwhile is raised as it ends
        except KeyboardInterrupt:
            late.append(stopping.stop_requested() or signal.SIGINT)
        stopping.restore(caught, late)  # and goes to the handlers put back: one line, exit status 130


def _one_line(text: str) -> str:
    text = " ".join(text.split())
    return text if len(text) <= MESSAGE_MAX else text[: MESSAGE_MAX - 3] + "..."


def error(message: str, status: int = 2):
    """Print ``diefab: error: MESSAGE`` (one line) on stderr and exit with `status`."""
    _say(f"diefab: error: {_one_line(message)}")
    sys.exit(status)


def _say(line: str) -> None:
    """Print `line` on stderr; if stderr is gone (its terminal closed), the exit status alone tells."""
    try:
        click.echo(line, err=True)
    except (OSError, ValueError):
        _silence(sys.stderr)


def _silence(stream) -> None:
    """Point `stream` at /dev/null so that the interpreter's last flush cannot fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, stream.fileno())
    except (OSError, ValueError, AttributeError):
        pass


def _interrupted() -> None:
    _say("diefab: interrupted")
    sys.exit(130)


def _main(argv: list[str] | None) -> None:
    from diefab.core.stopping import check_stop, stop_requested

    try:
        # the command is invoked as click's ``main`` would, but a stop is not turned into click's ``Abort`` after a
        # blank line on stderr: it ends in the one line of :func:`_interrupted`
        with cli.make_context("diefab", list(sys.argv[1:] if argv is None else argv)) as ctx:
            rv = cli.invoke(ctx)
        if not rv:  # a command that succeeded after a stop whose exception something swallowed: still a stop
            check_stop()
        sys.stdout.flush()
    except SystemExit:  # the command's own exit (an interrupted run that said how to resume)
        raise
    except BaseException as exc:
        if stop_requested() and not isinstance(exc, (KeyboardInterrupt, click.exceptions.Exit)):  # a swallowed stop
            _interrupted()
        _fail(exc)
    sys.exit(rv if isinstance(rv, int) else 0)


def _usage(exc: click.ClickException) -> None:
    ctx = getattr(exc, "ctx", None)
    command = ctx.command_path.removeprefix("diefab").strip() if ctx is not None else ""
    where = f"{command}: " if command else ""
    error(f"{where}{exc.format_message()}")


def _fail(exc: BaseException) -> None:
    try:
        raise exc
    except BrokenPipeError:  # the reader went away (``diefab templates | head -1``): stop quietly, as click does
        _silence(sys.stdout)
        sys.exit(1)
    except (click.exceptions.Abort, KeyboardInterrupt):
        _interrupted()
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.UsageError as exc:
        if type(exc).__name__ == "NoArgsIsHelpError" and exc.ctx is not None:  # a bare ``diefab``: its help
            click.echo(exc.ctx.get_help())
            sys.exit(0)
        _usage(exc)
    except click.ClickException as exc:
        _usage(exc)
    except DiefabError as exc:
        error(str(exc))
    except OSError as exc:  # the system refused (a full disk under stdout, an I/O error), not a bug
        try:
            sys.stdout.flush()
        except OSError:  # stdout itself failed: its last flush at exit must not fail again
            _silence(sys.stdout)
        where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
        error(f"{exc.strerror or exc}{where}")
    except RecursionError as exc:  # a pathological input nested too deep for the parser
        error(f"input nested too deeply to read ({exc})")
    except Exception as exc:  # a bug, not bad input: one line unless asked for the traceback
        if os.environ.get("DIEFAB_DEBUG"):
            raise
        error(f"internal error: {type(exc).__name__}: {exc} (set DIEFAB_DEBUG=1 for a traceback)", status=1)
