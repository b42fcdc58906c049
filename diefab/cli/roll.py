"""``diefab roll``: tally the rolls of a made die by hand, in the terminal."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from diefab.cli.common import design_argument, get_design, named_folder
from diefab.cli.live import bars
from diefab.core.stopping import STOPPED


@click.command()
@design_argument
@click.option("--target", default=None, help="Override the design's target distribution.")
@click.option("--out", "out", type=click.Path(file_okay=False), default=".", show_default=True, callback=named_folder,
              help="Folder of the roll log.")  # fmt: skip
@click.option("--name", default=None, help="Name of the roll log, OUT/NAME-rolls.csv (default: the design's name).")
@click.option("--delta", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.03, show_default=True,
              help="Tolerance in TVD of the verdict: within it of the target, or off by at least it.")  # fmt: skip
def roll(design, params, target, out, name, delta) -> None:
    """Tally rolls of DESIGN by hand: one key per value, live counts and verdict.

    Every roll is appended to the roll log at once, so a tally can be stopped
    and resumed; `diefab stats --rolls` and `diefab calibrate` read the log.
    One process at a time may write a log.
    """
    from diefab.core.errors import StatsError
    from diefab.core.extras import require
    from diefab.core.files import ensure_dir, hold_lock
    from diefab.stats.rolllog import log_path, read_log, repair_log
    from diefab.stats.tally import Tally
    from diefab.stats.verdict import sequential_line, target_label

    require("textual", "tally", "diefab roll")
    d = get_design(design, params, target)
    path = log_path(ensure_dir(out), name or d.name)
    hold_lock(path, f"roll log {path}")  # one writer per log, until the command ends
    if not all(stream is not None and stream.isatty() for stream in (sys.stdin, sys.stdout)):
        raise StatsError("diefab roll needs a terminal (it reads one key per roll)")
    repair_log(path)
    tally = Tally(d.support, d.target_distribution.aligned(d.support), delta, read_log(path).values)
    label = target_label(d.target)
    app = roll_app(tally, path, f"{d.name} against {label}", label)
    app.run()
    if app.return_code == STOPPED:
        raise KeyboardInterrupt  # Ctrl-C, which the app reads as a key: every roll is already in the log
    click.echo(sequential_line(tally.result(), label))
    click.echo(f"roll log: {path} ({tally.n} rolls)")


def roll_app(tally, path: Path, title: str, label: str):
    """The textual app of a tally recorded in the roll log at `path`."""
    from textual.app import App, ComposeResult
    from textual.binding import Binding
    from textual.widgets import Footer, Static

    from diefab.core.errors import DiefabError
    from diefab.dice.design import format_value
    from diefab.stats.rolllog import Roll, append_roll, remove_last_roll
    from diefab.stats.tally import QUIT_KEYS, UNDO_KEYS
    from diefab.stats.verdict import sequential_line

    class RollApp(App):
        """Hand tally: one key per value, undo, live counts and the verdict."""

        CSS = "Static { padding: 0 1; } #verdict { text-style: bold; }"
        TITLE = "diefab roll"
        BINDINGS = [Binding("ctrl+c", "interrupt", "stop", show=False, priority=True)]

        def __init__(self) -> None:
            super().__init__()
            self.tally, self.path, self.status = tally, path, "roll the die and press its value's key"

        def compose(self) -> ComposeResult:
            yield Static(f"{title}   log: {path}", id="title", markup=False)  # names and paths are plain text
            yield Static(id="table")
            yield Static(id="verdict", markup=False)
            yield Static(id="status", markup=False)
            signed = min(tally.values) < 0
            keys = "  ".join(f"{k}={format_value(v, signed)}" for k, v in zip(tally.keys, tally.values))
            yield Static(f"keys: {keys}   undo: {'/'.join(UNDO_KEYS)}   quit: {'/'.join(QUIT_KEYS)}", id="keys",
                         markup=False)  # fmt: skip
            yield Footer()

        def action_interrupt(self) -> None:
            self.exit(return_code=STOPPED)

        def on_mount(self) -> None:
            self.refresh_view()

        def refresh_view(self) -> None:
            self.query_one("#table", Static).update(bars(self.tally))
            self.query_one("#verdict", Static).update(sequential_line(self.tally.result(), label))
            self.query_one("#status", Static).update(self.status)

        def on_key(self, event) -> None:
            done = self.tally.press(event.key)
            try:
                if done.kind == "roll":
                    append_roll(self.path, Roll.now(done.value))
                    self.status = f"rolled {done.value} ({self.tally.n} rolls)"
                elif done.kind == "undo":
                    remove_last_roll(self.path)
                    self.status = f"undid {done.value} ({self.tally.n} rolls)"
                elif done.kind == "quit":
                    self.exit()
                    return
                else:
                    return
            except DiefabError as exc:
                self.tally.revert(done)
                self.status = f"not recorded: {exc}"
            event.stop()
            self.refresh_view()

    return RollApp()
