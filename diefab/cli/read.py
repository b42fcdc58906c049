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
    from diefab.camera.reader import RollReader, frames
    from diefab.core.files import ensure_dir, hold_lock
    from diefab.stats.rolllog import log_path, read_log
    from diefab.stats.tally import Tally

    if sum(x is not None for x in (camera_index, video, images)) != 1:
        raise click.UsageError("give exactly one of --camera, --video and --images")
    d = get_design(design, params, target)
    reader = RollReader(d, settle=settle, min_confidence=min_confidence, fov=fov)
    ensure_dir(out_dir)
    log = log_path(out_dir, name or d.name)
    hold_lock(log, f"roll log {log}")  # one writer per log, until the command ends
    rows = list(read_log(log).rolls) if log.exists() else []
    done = [r.value for r in rows if r.value is not None]
    tally = Tally(d.support, d.target_distribution.aligned(d.support), delta, done)
    source = frames(camera=camera_index, video=video, images=images)
    first = next(source, None)  # opens the source: a bad one fails here, before the live table is drawn
    source = itertools.chain([] if first is None else [first], source)
    _run(d, reader, source, log, rows, tally, show, out_dir, name, photos=images is not None)


def _run(d, reader, source, log, rows, tally, show, out_dir, name, photos: bool) -> None:
    from rich.live import Live

    from diefab.cli.common import console
    from diefab.stats.rolllog import Roll, append_roll
    from diefab.stats.verdict import sequential_line, target_label

    label = target_label(d.target)

    def view():
        unread = sum(r.value is None for r in rows)
        title = f"{d.name} against {label}: {tally.n} rolls read, {unread} unread (frame {reader.frame + 1})"
        return tally_view(tally, label, title)

    offset = max((r.frame for r in rows if r.frame is not None), default=-1) + 1
    with Live(view(), console=console(), refresh_per_second=4, transient=False) as live:
        for t, gray in source:
            seen, roll = reader.feed_rest(gray) if photos else reader.feed(gray)
            if show and seen is not None:
                _show(d, reader, gray, seen, out_dir, name)
            if roll is None:
                continue
            face = None if roll.face is None else d.polyhedron.names[roll.face]
            row = Roll(f"{t:.3f}", roll.value, face, round(float(roll.confidence), 4), offset + roll.frame)
            append_roll(log, row)
            rows.append(row)
            if roll.value is not None:
                tally.add(roll.value)
            live.update(view())
        live.update(view())
    if not rows:
        click.echo(f"no roll read; log {log} not written", err=True)
    else:
        click.echo(sequential_line(tally.result(), label))
        click.echo(f"wrote {log}")


def _show(d, reader, gray, seen, out_dir, name) -> None:
    import cv2

    from diefab.camera.render import draw_detection
    from diefab.core.files import atomic_write, output_path

    image = draw_detection(gray, seen, d, reader.layout, reader.camera)
    try:
        cv2.imshow("diefab read", image)
        cv2.waitKey(1)
    except cv2.error:  # a headless OpenCV has no window: keep the latest frame in a file
        ok, data = cv2.imencode(".png", image)
        if ok:
            atomic_write(output_path(out_dir, name or d.name, "-live.png"), data.tobytes())
