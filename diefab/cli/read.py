"""``diefab read``: count real rolls of a marked die with a camera, a video or a folder of images."""

from __future__ import annotations

import itertools
from pathlib import Path

import click

from diefab.cli.common import design_argument, get_design, out_option
from diefab.cli.live import tally_view


@click.command("read")
@design_argument
@click.option(
    "--camera", "camera_index", type=click.IntRange(0, 99), default=None, help="Camera number (0: the first)."
)
@click.option("--video", type=click.Path(path_type=Path), default=None, help="Video file to read.")
@click.option("--images", type=click.Path(path_type=Path), default=None, help="Folder of images, read in name order.")
@click.option("--name", default=None, help="Roll log name (default: the design's): OUT/NAME-rolls.csv.")
@click.option("--target", default=None, help="Override the design's target distribution.")
@click.option("--delta", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.03, show_default=True,
              help="Tolerance in TVD of the verdict: within it of the target, or off by at least it.")  # fmt: skip
@click.option("--settle", type=click.IntRange(1, 1000), default=8, show_default=True,
              help="Still frames before a roll counts (a folder of images: each image is one rest).")  # fmt: skip
@click.option("--min-confidence", type=click.FloatRange(0, 1), default=0.5, show_default=True,
              help="Frames read with less confidence are unread.")  # fmt: skip
@click.option("--fov", type=click.FloatRange(10, 170), default=65.0, show_default=True,
              help="The camera's horizontal field of view, degrees.")  # fmt: skip
@click.option("--show", is_flag=True, help="Show the frame with the detection drawn (a window, or OUT/NAME-live.png).")
@out_option
def read(
    design, params, camera_index, video, images, name, target, delta, settle, min_confidence, fov, show, out_dir
) -> None:
    """Read rolls of DESIGN's marked die and append them to a roll log.

    Put the camera above the table, looking straight down.  A roll counts
    once the die has been still for --settle frames; a die in motion, a hand
    over it or a pose that does not clearly show one face is logged unread
    (an empty value), never guessed.  The log (time,value,face,confidence,frame)
    gets one line per roll, written durably; run again to resume it.  The
    live table shows the counts beside the target and the anytime-valid
    verdict, as `diefab roll` does.
    """
    from diefab.camera.reader import RollReader
    from diefab.camera.session import LogReading
    from diefab.core.files import ensure_dir, hold_lock
    from diefab.stats.rolllog import log_path
    from diefab.stats.tally import Tally

    if sum(x is not None for x in (camera_index, video, images)) != 1:
        raise click.UsageError("give exactly one of --camera, --video and --images")
    d = get_design(design, params, target)
    reader = RollReader(d, settle=settle, min_confidence=min_confidence, fov=fov)
    ensure_dir(out_dir)
    log = log_path(out_dir, name or d.name)
    hold_lock(log, f"roll log {log}")  # one writer per log, until the command ends
    session = LogReading(reader, log)
    done = [r.value for r in session.rows if r.value is not None]
    tally = Tally(d.support, d.target_distribution.aligned(d.support), delta, done)
    live = live_picture(out_dir, name or d.name)  # what --show writes is never read as a photo
    source = session.read(camera=camera_index, video=video, images=images, ignore=[live])
    first = next(source, None)  # opens the source: a bad one fails here, before the live table is drawn
    source = itertools.chain([] if first is None else [first], source)
    new = _run(d, session, source, tally, show, out_dir, name)
    if session.skipped:
        click.echo(session.skipped_line(images), err=True)
    if not session.rows:
        click.echo(f"no roll read; log {log} not written", err=True)
        return
    from diefab.stats.verdict import sequential_line, target_label

    click.echo(sequential_line(tally.result(), target_label(d.target)))
    click.echo(f"wrote {log}" if new else f"{log} unchanged")


def _run(d, session, source, tally, show, out_dir, name) -> int:
    """Show the live table while `source` is read; returns the number of rolls read."""
    from rich.live import Live

    from diefab.cli.common import console
    from diefab.stats.verdict import target_label

    label = target_label(d.target)
    reader = session.reader

    def view(verdict: bool = True):
        unread = sum(r.value is None for r in session.rows)
        title = f"{d.name} against {label}: {tally.n} rolls read, {unread} unread (frame {reader.frame + 1})"
        return tally_view(tally, label, title, verdict=verdict)

    out = console()
    if not out.is_terminal:  # a file or a pipe gets the table once, when reading is done; the verdict follows it
        new = sum(_take(d, reader, step, tally, show, out_dir, name) for step in source)
        out.print(view(verdict=False))
        return new
    new = 0
    with Live(view(), console=out, refresh_per_second=4, transient=False) as live:
        for step in source:
            new += _take(d, reader, step, tally, show, out_dir, name)
            live.update(view())
        live.update(view())
    return new


def _take(d, reader, step, tally, show, out_dir, name) -> int:
    """One step of the reading: shown when asked, its roll counted; 1 if it read a roll, else 0."""
    if show and step.seen is not None:
        _show(d, reader, step.gray, step.seen, out_dir, name)
    if step.roll is None:
        return 0
    if step.roll.value is not None:
        tally.add(step.roll.value)
    return 1


def _show(d, reader, gray, seen, out_dir, name) -> None:
    import cv2

    from diefab.camera.render import draw_detection
    from diefab.core.files import atomic_write

    image = draw_detection(gray, seen, d, reader.layout, reader.camera)
    try:
        cv2.imshow("diefab read", image)
        cv2.waitKey(1)
    except cv2.error:  # a headless OpenCV has no window: keep the latest frame in a file
        ok, data = cv2.imencode(".png", image)
        if ok:
            atomic_write(live_picture(out_dir, name or d.name), data.tobytes())


def live_picture(out_dir, name: str):
    """The file ``--show`` keeps the latest frame in, where no window can open."""
    from diefab.core.files import output_path

    return output_path(out_dir, name, "-live.png")
