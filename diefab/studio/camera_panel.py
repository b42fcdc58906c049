"""The page's camera tab: read real rolls of the marked die (a webcam, a video or a folder of photos) with live counts.

The reading runs in a worker process (:func:`diefab.studio.jobs.read_job`)
that appends every roll to the die's roll log in the output folder, as
``diefab read`` does; the page shows the latest frame with the detection
drawn, the shares of the values read against the target, and the verdict:
the anytime-valid test of :mod:`diefab.stats.sequential` (valid however
often it is looked at) and the plain-language verdict of
:mod:`diefab.stats.verdict`.
"""

from __future__ import annotations

from pathlib import Path

from nicegui import ui

from diefab.core.errors import DiefabError
from diefab.dice.design import Design, format_value
from diefab.studio.chart import counts_options, distribution_options, live_verdict
from diefab.studio.host import Host
from diefab.studio.job_panels import JobPanel
from diefab.studio.jobs import read_job

SOURCES = {"camera": "camera number", "video": "video file in the output folder",
           "images": "folder of photos in the output folder"}  # fmt: skip


class CameraPanel(JobPanel):
    """Start and stop reading rolls; the frame, the counts and the verdict, live."""

    kind = "camera"

    def __init__(self, studio: Host) -> None:
        super().__init__(studio)
        self.values: list[int] = []
        self.unread = 0
        self.design: Design | None = None
        self.log: Path | None = None
        self._seen = 0

    def build(self) -> None:
        with ui.row().classes("items-end gap-4"):
            self.source = ui.select(SOURCES, value="camera", label="source").classes("studio-camera-source w-72")
            self.where = ui.input("camera number, or path in the output folder", value="0").classes(
                "studio-camera-where w-72"
            )
            self.settle = ui.number("still frames", value=8, min=1, max=1000, step=1, precision=0).classes("w-28")
            self.confidence = ui.number("least confidence", value=0.5, min=0, max=1, step=0.05).classes("w-32")
            self.fov = ui.number("field of view, °", value=65, min=10, max=170, step=1).classes("w-32")
            self.delta = ui.number("tolerance (TVD)", value=0.03, min=0.001, max=0.5, step=0.005).classes("w-32")
            ui.button("Start reading", on_click=self.start_reading).classes("studio-camera-start")
            ui.button("stop", on_click=self.cancel).props("flat").classes("studio-camera-stop")
        self._progress_row()
        with ui.row().classes("w-full no-wrap items-start gap-6"):
            self.frame = ui.image().classes("studio-camera-frame w-[480px] h-[270px] bg-gray-200")
            with ui.column().classes("grow"):
                self.rolls = ui.label("no rolls read yet").classes("studio-camera-rolls font-bold")
                self.chart = ui.echart(distribution_options([], [], []), renderer="svg").classes(
                    "studio-camera-chart w-[560px] h-56"
                )
                self.sequential = ui.label().classes("studio-camera-sequential text-sm")
                self.verdict = ui.label().classes("studio-camera-verdict font-bold")

    def _source(self) -> dict:
        """The reader's source from the form: a camera number, or a path that must be inside the output folder."""
        kind, where = self.source.value, (self.where.value or "").strip()
        if kind == "camera":
            if not (where.isascii() and where.isdigit()) or int(where) > 99:
                raise DiefabError(f"camera number {where!r}: give 0 (the first camera) to 99")
            return {"camera": int(where)}
        root = self.studio.out_dir.resolve()
        path = (root / where).resolve()
        if not where or (path != root and root not in path.parents):
            raise DiefabError(f"{kind} {where!r}: the studio reads files only in {self.studio.out_dir}")
        return {kind: path}

    def start_reading(self) -> None:
        from diefab.core.files import ensure_dir, output_path
        from diefab.stats.rolllog import read_log

        if self.busy():
            return
        try:
            source = self._source()
            design = self.studio.session.design
            ensure_dir(self.studio.out_dir)
            log = output_path(self.studio.out_dir, design.name, "-rolls.csv")
            rows = read_log(log).rolls if log.exists() else []
        except DiefabError as exc:
            self.studio.show_error(str(exc))
            return
        self.design, self.log = design, log
        self.values = [r.value for r in rows if r.value is not None]
        self.unread = sum(r.value is None for r in rows)
        self._seen = 0
        self.start(read_job, design, source, int(self.settle.value or 8), float(self.confidence.value or 0),
                   float(self.fov.value or 65), Path(log))  # fmt: skip
        self.show_counts()

    def progress(self, job) -> None:
        new = job.events[self._seen :]
        self._seen = len(job.events)
        frame = next((e[1] for e in reversed(new) if e[0] == "frame"), None)
        if frame is not None:
            self.frame.set_source(frame)
        rolls = [e for e in new if e[0] == "roll"]
        for _, _, value, _, _ in rolls:
            if value is None:
                self.unread += 1
            else:
                self.values.append(int(value))
        if rolls:
            self.show_counts()
        if not job.finished:
            self.text.set_text(f"reading: frame {int(job.done)}")

    def show(self, count: int) -> None:
        self.text.set_text(f"the source ended: {count} rolls read in this session; the log is {self.log}")

    def show_counts(self) -> None:
        d = self.design
        if d is None:
            return
        counts, sequential, plain = live_verdict(d, self.values, float(self.delta.value or 0.03))
        signed = min(d.support) < 0
        values = [format_value(v, signed) for v in d.support]
        goal = d.target_distribution.aligned(d.support)
        self.chart.options.clear()
        self.chart.options.update(counts_options(values, counts, goal))
        self.chart.update()
        self.rolls.set_text(f"{sum(counts)} rolls read, {self.unread} unread (log {self.log.name})")
        self.sequential.set_text(sequential)
        self.verdict.set_text(plain)
