"""The studio's web page (NiceGUI): its layout, the live sliders and how an edit reaches the page.

One :class:`Studio` per open page.  An edit is evaluated at once and drawn
in three messages, most wanted first: the chart (straight to ECharts), then
the numbers (status, margins table), then the 3D die, once the edits pause
for :data:`DIE_PAUSE` (redrawing it on every step of a dragged slider would
hold up the next step's chart).  A die whose made body takes long to
evaluate (paper, print) is drawn first as its solid body, marked
provisional, while a worker process (:class:`~diefab.studio.jobs.Evaluator`)
computes the made body; its result replaces the stand-in if the die has not
changed meanwhile, otherwise the worker goes on with the newest die.
"""

from __future__ import annotations

import asyncio
import json
import math
import time
from pathlib import Path
from typing import Any

from nicegui import context, run, ui

from diefab.core.errors import DiefabError
from diefab.dice.design import Design, list_templates, load_design
from diefab.studio.camera_panel import CameraPanel
from diefab.studio.chart import distribution_options, margin_rows, status_line
from diefab.studio.files import MAX_UPLOAD, parse_upload
from diefab.studio.job_panels import DesignPanel, ValidatePanel
from diefab.studio.jobs import Evaluator
from diefab.studio.make import write_design
from diefab.studio.make_panel import MakePanel
from diefab.studio.scene import DieView
from diefab.studio.state import FILLS, Session, made_body_is_slow, parameters

#: Print and paper settings offered as sliders: Fill field -> (label, lower, upper, step).
FILL_SLIDERS = {
    "paper": {"card_g_m2": ("card, g/m²", 80.0, 400.0, 5.0), "glue_g_m2": ("glue, g/m²", 0.0, 100.0, 1.0)},
    "print": {"infill": ("infill", 0.0, 1.0, 0.05), "perimeters": ("perimeters", 1, 8, 1),
              "layer_mm": ("layer height, mm", 0.08, 0.32, 0.02), "nozzle_mm": ("nozzle, mm", 0.2, 0.8, 0.05)},
}  # fmt: skip

#: Seconds a page may go unheard before the server drops it (and the browser loads it afresh).  NiceGUI's 3 s
#: is shorter than a design search on a busy machine can keep the server from answering.
RECONNECT_SECONDS = 15.0

#: The 3D die is redrawn once edits pause this long, seconds: while a slider is dragged the chart goes first.
DIE_PAUSE = 0.3


class Studio:
    """The page of one browser tab."""

    def __init__(self, design: Design, out_dir: Path, target: str | None = None, inputs: tuple[Path, ...] = ()) -> None:
        self.session = Session(design)
        self.out_dir = Path(out_dir)
        self.inputs = tuple(inputs)  # the files the studio was opened on: never replaced
        self.start_target = target
        self.generation = 0
        self.evaluation: dict[str, Any] | None = None
        self.selected: str | None = None
        self.hovered: str | None = None
        self.evaluator: Evaluator | None = None
        self._made_running = False
        self._stopped = False
        self._chart_shown = False
        self._last_edit = -math.inf
        self._edit_started: float | None = None
        self.die_view = DieView(self.select_face, self.session.is_current)
        self.make = MakePanel(self)
        self.validate = ValidatePanel(self)
        self.designer = DesignPanel(self)
        self.camera = CameraPanel(self)

    # ----------------------------------------------------------------- layout
    def build(self) -> None:
        with ui.header().classes("items-center gap-3 bg-slate-800"):
            ui.label("diefab studio").classes("text-lg font-bold")
            names = [t.name for t in list_templates()]
            ui.select(names, label="template", on_change=self.open_template, value=None).props(
                "dense dark outlined").classes("w-48")  # fmt: skip
            ui.button("save TOML", on_click=self.save_design).props("flat color=white")
            self.undo_button = ui.button("undo", on_click=self.undo).props("flat color=white")
            self.redo_button = ui.button("redo", on_click=self.redo).props("flat color=white")
            ui.space()
            self.title = ui.label().classes("font-mono")
        self.error = ui.label().classes("studio-error text-red-700 font-bold")
        self.state_box = ui.label().classes("studio-state hidden")
        with ui.row().classes("w-full no-wrap items-start gap-4"):
            with ui.column().classes("w-72 shrink-0"):
                self.controls = ui.column().classes("w-full gap-1")
                ui.upload(label="open a design file (.toml)", auto_upload=True, max_file_size=MAX_UPLOAD,
                          on_upload=self.open_upload, on_rejected=self.upload_rejected
                          ).props("accept=.toml").classes("studio-upload w-full")  # fmt: skip
            with ui.column().classes("grow items-center"):
                self.die_view.build()
            with ui.column().classes("w-[440px] shrink-0"):
                self.chart = ui.echart(distribution_options([], [], []), renderer="svg").classes(
                    "studio-chart w-full h-64"
                )
                self.status = ui.label().classes("studio-status font-bold")
                self.margins = ui.table(columns=[
                    {"name": k, "label": k, "field": k} for k in ("face", "value", "probability", "margin",
                                                                  "read from", "state")],
                    rows=[], row_key="face").props("dense flat").classes("studio-margins w-full")  # fmt: skip
        with ui.tabs().classes("w-full") as tabs:
            tab_make = ui.tab("Make")
            tab_validate = ui.tab("Validate")
            tab_design = ui.tab("Design for target")
            tab_camera = ui.tab("Test with the camera")
        with ui.tab_panels(tabs, value=tab_make).classes("w-full"):
            with ui.tab_panel(tab_make):
                self.make.build()
            with ui.tab_panel(tab_validate):
                self.validate.build()
            with ui.tab_panel(tab_design):
                self.designer.build(self.start_target)
            with ui.tab_panel(tab_camera):
                self.camera.build()
        ui.on("net_hover", lambda e: self.highlight(e.args or None))
        ui.on("net_click", lambda e: self.select_face(e.args))
        self.client = context.client
        # a page that lost its connection for a moment (a busy machine, a sleeping laptop) keeps its jobs;
        # they stop once the page is gone for good
        self.client.on_delete(self.stop)
        ui.timer(0.25, self.poll)
        self.rebuild_controls()
        self.refresh()
        asyncio.get_event_loop().create_task(self.die_view.place_camera(self.session.design))

    def rebuild_controls(self) -> None:
        """The sliders of the current design's family, size, fill and its settings."""
        d = self.session.design
        self.controls.clear()
        with self.controls:
            ui.label(f"{d.family} parameters").classes("font-bold")
            for p in parameters(d):
                step = (p["upper"] - p["lower"]) / 500
                ui.label(f"{p['name']}: {p['description']}").classes("text-xs text-gray-600")
                ui.slider(min=p["lower"], max=p["upper"], step=step, value=p["value"],
                          on_change=lambda e, n=p["name"]: self.edit(("param", n), params={n: e.value})
                          ).props("label").classes(f"studio-param-{p['name']}")  # fmt: skip
            ui.label("size, mm").classes("font-bold")
            ui.slider(min=8, max=80, step=0.5, value=d.size_mm,
                      on_change=lambda e: self.edit(("size",), size_mm=e.value)).props("label")  # fmt: skip
            ui.select(list(FILLS), value=d.fill.kind if d.fill.kind in FILLS else "solid", label="fill",
                      on_change=lambda e: self.edit(("fill",), fill=e.value, rebuild=True)
                      ).classes("studio-fill w-full")  # fmt: skip
            for name, (label, lo, hi, step) in FILL_SLIDERS.get(d.fill.kind, {}).items():
                ui.label(label).classes("text-xs")
                ui.slider(min=lo, max=hi, step=step, value=getattr(d.fill, name),
                          on_change=lambda e, n=name: self.edit(("fill", n), fill_settings={
                              n: int(e.value) if isinstance(getattr(d.fill, n), int) else e.value})
                          ).props("label").classes(f"studio-fill-{name}")  # fmt: skip

    # ------------------------------------------------------------------ edits
    def edit(self, key: tuple, rebuild: bool = False, **changes) -> None:
        self._edit_started = time.perf_counter()
        self._last_edit = time.monotonic()
        try:
            self.session.edit(key=key, **changes)
        except DiefabError as exc:
            self.show_error(str(exc))
            return
        if rebuild:
            self.rebuild_controls()
        self.refresh()

    def undo(self) -> None:
        if self.session.undo():
            self.rebuild_controls()
            self.refresh()

    def redo(self) -> None:
        if self.session.redo():
            self.rebuild_controls()
            self.refresh()

    def open_design(self, design: Design) -> None:
        self.session.replace_design(design)
        self.rebuild_controls()
        self.refresh()

    def open_template(self, e) -> None:
        if not e.value:
            return
        try:
            self.open_design(load_design(e.value))
        except DiefabError as exc:
            self.show_error(str(exc))

    async def open_upload(self, e) -> None:
        try:
            self.open_design(parse_upload(await e.file.read(), e.file.name, self.out_dir))
        except DiefabError as exc:
            self.show_error(str(exc))
        except Exception as exc:  # a bug: one line, the server keeps running
            self.show_error(f"internal error: {type(exc).__name__}: {exc}")
        finally:
            e.sender.reset()

    def upload_rejected(self) -> None:
        self.show_error(f"the file was refused: a design file is at most {MAX_UPLOAD // 1024} KiB")

    def save_design(self) -> None:
        try:
            path = write_design(self.session.design, self.out_dir, inputs=self.inputs)
        except DiefabError as exc:
            self.show_error(str(exc))
            return
        ui.download.file(path)
        ui.notify(f"wrote {path}")

    def show_error(self, message: str) -> None:
        self.error.set_text(message)
        with self.client:
            ui.notify(message, type="negative", multi_line=True)

    # --------------------------------------------------------------- evaluate
    def refresh(self) -> None:
        """Evaluate the current design now (a slow made body: its solid stand-in) and draw it."""
        self.generation += 1
        design = self.session.design
        try:
            ev = self.session.cached(design)
            if ev is None and made_body_is_slow(design):
                ev = self.session.provisional(design)
                asyncio.get_event_loop().create_task(self._evaluate_made())
            elif ev is None:
                ev = self.session.evaluation(design)
        except DiefabError as exc:
            self.show_error(str(exc))
            return
        except Exception as exc:  # a bug: one line, the server keeps running
            self.show_error(f"internal error: {type(exc).__name__}: {exc}")
            return
        asyncio.get_event_loop().create_task(self.draw(design, ev, self.generation))

    async def _evaluate_made(self) -> None:
        """Evaluate the made body of the newest design in the worker, until the newest has its evaluation."""
        if self._made_running:
            return  # the running loop takes the newest design when its evaluation ends
        self._made_running = True
        try:
            while True:
                design = self.session.design
                if not made_body_is_slow(design) or self.session.cached(design) is not None:
                    return
                if self.evaluator is None:
                    self.evaluator = Evaluator()
                try:
                    ev = await run.io_bound(self.evaluator.evaluate, design)
                except DiefabError as exc:
                    if self._stopped:
                        return
                    if self.session.is_current(design):
                        self.show_error(str(exc))
                        return
                    continue
                if ev is None:  # the server is shutting down
                    return
                self.session.remember(design, ev)
                if self.session.is_current(design):
                    self.generation += 1
                    await self.draw(design, ev, self.generation)
                    return
        finally:
            self._made_running = False

    async def _flush(self) -> None:
        """Let what was updated so far go out to the browser before more is updated."""
        outbox = self.client.outbox
        for _ in range(50):
            if not outbox.updates and not outbox.messages:
                return
            await asyncio.sleep(0.002)

    async def draw(self, design: Design, ev: dict, generation: int) -> None:
        """Show evaluation `ev` of `design`: the chart first, then the numbers, then the 3D die (skipped if stale)."""
        if generation != self.generation:
            return
        self.evaluation = ev
        name = "solid body (the made body is being computed)" if ev["provisional"] else "fast model"
        options = distribution_options(ev["values"], ev["probabilities"], ev["target"], name=name,
                                       provisional=ev["provisional"])  # fmt: skip
        self.chart.options.clear()
        self.chart.options.update(options)  # what the page is built from if the browser reconnects
        if self._chart_shown:  # straight to ECharts: no re-render of the page's other elements
            self.chart.run_chart_method("setOption", options, {"notMerge": True})
        else:
            self.chart.update()
            self._chart_shown = True
        started, self._edit_started = self._edit_started, None
        server_ms = None if started is None else 1000 * (time.perf_counter() - started)
        await self._flush()
        if generation != self.generation:
            return
        self.error.set_text("")
        self.title.set_text(f"{ev['name']}  ({ev['family']}, {ev['size_mm']:g} mm, {ev['fill']} fill)")
        self.status.set_text(("PROVISIONAL (solid body): " if ev["provisional"] else "") + status_line(ev))
        self.status.classes(replace="studio-status font-bold " + ("text-green-700" if ev["stable"] else "text-red-700"))
        self.margins.rows = margin_rows(ev)
        self.margins.update()
        self.undo_button.set_enabled(bool(self.session.undo_stack))
        self.redo_button.set_enabled(bool(self.session.redo_stack))
        self.state_box.set_text(json.dumps({
            **ev,
            "server_ms": server_ms,  # from the edit's arrival to the chart's update being queued, ms
            "undo": len(self.session.undo_stack),
            "redo": len(self.session.redo_stack),
            "generation": generation,
        }))  # fmt: skip
        await self._flush()
        if generation != self.generation:
            return
        while (wait := self._last_edit + DIE_PAUSE - time.monotonic()) > 0:  # a slider is being dragged
            await asyncio.sleep(wait)
            if generation != self.generation:
                return
        self.die_view.draw(design, ev)
        if self.selected:
            self.die_view.show_face(self.selected)
        asyncio.get_event_loop().create_task(self.make.refresh_net())

    # --------------------------------------------------------- face linking
    def select_face(self, name: str | None) -> None:
        self.selected = name or None
        self.die_view.light({self.selected, self.hovered})
        if name:
            self.die_view.show_face(name)
        self.make.light(self.selected)

    def highlight(self, name: str | None) -> None:
        self.hovered = name or None
        self.die_view.light({self.selected, self.hovered})

    # ------------------------------------------------------------------ jobs
    def poll(self) -> None:
        for panel in (self.validate, self.designer, self.camera, self.die_view):
            panel.poll()

    def stop(self) -> None:
        """Stop every worker of the page (it closed)."""
        self._stopped = True
        for panel in (self.validate, self.designer, self.camera, self.die_view):
            panel.stop()
        if self.evaluator is not None:
            self.evaluator.stop()


def serve(design: Design, out_dir: Path, *, host: str = "127.0.0.1", port: int = 8080, show: bool = True,
          target: str | None = None, inputs: tuple[Path, ...] = ()) -> None:  # fmt: skip
    """Serve the studio until interrupted (blocks); `inputs`: the files it was opened on, never replaced."""
    import signal

    from nicegui import app

    out_dir = Path(out_dir)
    if hasattr(signal, "SIGHUP") and signal.getsignal(signal.SIGHUP) is not signal.SIG_IGN:
        # the server stops gracefully on SIGTERM and SIGINT, which it handles itself; a hang-up does the same
        signal.signal(signal.SIGHUP, lambda signum, frame: signal.raise_signal(signal.SIGTERM))

    @ui.page("/")
    def index() -> None:
        Studio(design, out_dir, target, inputs).build()

    @app.get("/healthz")
    def healthz() -> dict:
        return {"ok": True}

    ui.run(host=host, port=port, show=show, reload=False, title="diefab studio", uvicorn_logging_level="warning",
           favicon="🎲", show_welcome_message=False, reconnect_timeout=RECONNECT_SECONDS)  # fmt: skip
