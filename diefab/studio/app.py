"""The studio's web page (NiceGUI): the die in 3D, its distribution, live sliders, jobs and downloads.

One :class:`Studio` per open page.  Everything the page computes comes from
diefab's library; long work runs in worker processes (:mod:`.jobs`), files
are written only into the output folder (:mod:`.make`).
"""

from __future__ import annotations

import asyncio
import json
import math
import time
from dataclasses import replace
from functools import lru_cache
from pathlib import Path
from typing import Any

from diefab.core.errors import DesignError, DiefabError
from diefab.dice.design import Design, list_templates, load_design, parse_design
from diefab.studio.jobs import Job, design_job, validate_job
from diefab.studio.make import net_faces, write_design, write_net, write_solid
from diefab.studio.state import FILLS, SCALE, Session, face_colors, parameters
from diefab.studio.view import face_frames, label_image, label_quad, net_svg

#: Largest design file accepted by upload, bytes (a design is a few kilobytes).
MAX_UPLOAD = 256 * 1024

#: Color of a transitional face (the die rolls off it) and of a highlighted face.
TRANSITIONAL = "#9e9e9e"
HIGHLIGHT = "#1e88e5"

#: Background of the printed value labels (a label stays the same image whatever the face's color).
LABEL = "#fbf8ef"

#: Thickness of the plates the faces are drawn as, model units.
PLATE = 0.004

#: Print and paper settings offered as sliders: Fill field -> (label, lower, upper, step).
FILL_SLIDERS = {
    "paper": {"card_g_m2": ("card, g/m²", 80.0, 400.0, 5.0), "glue_g_m2": ("glue, g/m²", 0.0, 100.0, 1.0)},
    "print": {"infill": ("infill", 0.0, 1.0, 0.05), "perimeters": ("perimeters", 1, 8, 1),
              "layer_mm": ("layer height, mm", 0.08, 0.32, 0.02), "nozzle_mm": ("nozzle, mm", 0.2, 0.8, 0.05)},
}  # fmt: skip

CSS = f"""
.studio-net .net-face:hover polygon, .studio-net .net-face.lit polygon {{ fill: {HIGHLIGHT} !important; }}
.studio-net {{ max-width: 100%; height: auto; }}
"""

NET_JS = """
(() => {
  const root = document.querySelector('.studio-net');
  if (!root || root.dataset.wired) return;
  root.dataset.wired = '1';
  root.querySelectorAll('.net-face').forEach(g => {
    g.addEventListener('mouseenter', () => emitEvent('net_hover', g.dataset.face));
    g.addEventListener('mouseleave', () => emitEvent('net_hover', ''));
    g.addEventListener('click', () => emitEvent('net_click', g.dataset.face));
  });
})();
"""


@lru_cache(maxsize=512)
def _label_url(text: str) -> str:
    return label_image(text, LABEL)


def _fmt_seconds(s: float | None) -> str:
    if s is None or not math.isfinite(s):
        return "--"
    s = int(round(s))
    return f"{s // 60}:{s % 60:02d}"


class Studio:
    """The page of one browser tab."""

    def __init__(self, design: Design, out_dir: Path, target: str | None = None) -> None:
        self.session = Session(design)
        self.out_dir = Path(out_dir)
        self.start_target = target
        self.generation = 0
        self.busy = False
        self.evaluation: dict[str, Any] | None = None
        self.selected: str | None = None
        self.hovered: str | None = None
        self.face_objects: dict[str, Any] = {}
        self.jobs: dict[str, Job] = {}
        self.profile: str | None = None
        self._net_generation = -1
        self._edit_started: float | None = None
        self._building = False

    # ----------------------------------------------------------------- layout
    def build(self) -> None:
        from nicegui import context, ui

        ui.add_css(CSS)
        with ui.header().classes("items-center gap-3 bg-slate-800"):
            ui.label("diefab studio").classes("text-lg font-bold")
            names = [t.name for t in list_templates()]
            self.template_select = ui.select(names, label="template", on_change=self.open_template,
                                             value=None).props("dense dark outlined").classes("w-48")  # fmt: skip
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
                self.scene = ui.scene(width=520, height=440, on_click=self.scene_click, grid=False,
                                      background_color="#f7f7f7").classes("studio-scene")  # fmt: skip
                self.legend = ui.html("", sanitize=False).classes("w-full")
                self.face_info = ui.label("click a face").classes("studio-face font-mono text-sm")
            with ui.column().classes("w-[440px] shrink-0"):
                self.chart = ui.echart(self._chart_options([], [], []), renderer="svg").classes(
                    "studio-chart w-full h-64"
                )
                self.status = ui.label().classes("studio-status font-bold")
                self.margins = ui.table(columns=[
                    {"name": k, "label": k, "field": k} for k in ("face", "value", "probability", "margin",
                                                                  "read from", "state")],
                    rows=[], row_key="face").props("dense flat").classes("studio-margins w-full")  # fmt: skip
        with ui.tabs().classes("w-full") as tabs:
            t_make = ui.tab("Make")
            t_validate = ui.tab("Validate")
            t_design = ui.tab("Design for target")
        with ui.tab_panels(tabs, value=t_make).classes("w-full"):
            with ui.tab_panel(t_make):
                self._build_make()
            with ui.tab_panel(t_validate):
                self._build_validate()
            with ui.tab_panel(t_design):
                self._build_design()
        ui.on("net_hover", lambda e: self.highlight(e.args or None, source="net"))
        ui.on("net_click", lambda e: self.select_face(e.args))
        client = self.client = context.client
        client.on_delete(self.stop_jobs)
        client.on_disconnect(self.stop_jobs)
        ui.timer(0.25, self.poll_jobs)
        self.rebuild_controls()
        asyncio.get_event_loop().create_task(self.refresh())
        asyncio.get_event_loop().create_task(self._place_camera())

    def _build_make(self) -> None:
        from nicegui import ui

        with ui.row().classes("w-full no-wrap items-start gap-6"):
            with ui.column().classes("w-80"):
                ui.label("Paper net").classes("font-bold")
                self.page_size = ui.select(["A5", "A4", "A3", "Letter", "Legal"], value="A4", label="page").classes(
                    "w-40"
                )
                self.copies = ui.number("copies", value=1, min=1, max=100, step=1, precision=0).classes("w-40")
                self.mark = ui.select(["bar", "period", "none"], value="bar", label="6/9 mark").classes("w-40")
                self.net_format = ui.select(["svg", "pdf"], value="svg", label="format").classes("w-40")
                ui.button("download net", on_click=self.download_net).classes("studio-download-net")
                ui.separator()
                ui.label("Printable solid").classes("font-bold")
                self.round_mm = ui.number("edge rounding, mm", value=0.0, min=0, max=5, step=0.1).classes("w-40")
                self.depth_mm = ui.number("label depth, mm", value=0.6, min=0.2, max=2, step=0.1).classes("w-40")
                self.emboss = ui.checkbox("emboss (raise) the labels")
                self.inlay = ui.checkbox("also the inlay (labels alone)")
                self.solid_format = ui.select(["stl", "3mf"], value="stl", label="format").classes("w-40")
                ui.button("download solid", on_click=self.download_solid).classes("studio-download-stl")
                self.make_note = ui.label().classes("studio-make-note text-sm")
            with ui.column().classes("grow"):
                ui.label("Net (hover a face to find it on the die; click a face on the die to find it here)")
                self.net_view = ui.html("", sanitize=False).classes("studio-net-view w-full")

    def _build_validate(self) -> None:
        from nicegui import ui

        with ui.row().classes("items-end gap-4"):
            self.sims = ui.number("drops", value=2000, min=10, max=1_000_000, step=100, precision=0)
            self.seed = ui.number("seed", value=0, min=0, step=1, precision=0)
            from diefab.physics.profiles import list_profiles

            self.profile_select = ui.select(["design's own", *list_profiles()], value="design's own",
                                            label="physics profile").classes("w-48")  # fmt: skip
            self.validate_button = ui.button("Validate", on_click=self.start_validate).classes("studio-validate")
            ui.button("cancel", on_click=lambda: self.cancel("validate")).props("flat")
        self.validate_bar = ui.linear_progress(value=0, show_value=False).classes("studio-validate-bar")
        self.validate_text = ui.label().classes("studio-validate-text")
        self.verdict = ui.label().classes("studio-verdict font-bold")
        self.validate_chart = ui.echart(self._chart_options([], [], []), renderer="svg").classes(
            "studio-validate-chart w-[640px] h-64"
        )

    def _build_design(self) -> None:
        from nicegui import ui

        with ui.row().classes("items-end gap-4"):
            self.target_input = ui.input("target", value=self.start_target or "2d6").classes("w-56")
            models = ["fast", "solid-angle", "simulation"]
            self.model_select = ui.select(models, value="fast", label="model").classes("w-40")
            self.budget = ui.number("budget, s", value=60, min=5, max=3600, step=5, precision=0)
            ui.button("Design for target", on_click=self.start_design).classes("studio-design")
            ui.button("cancel", on_click=lambda: self.cancel("design")).props("flat").classes("studio-cancel")
        self.design_bar = ui.linear_progress(value=0, show_value=False)
        self.design_text = ui.label().classes("studio-design-text")
        self.design_log = ui.log(max_lines=200).classes("w-full h-40")

    def rebuild_controls(self) -> None:
        """The sliders of the current design's family, size, fill and its settings."""
        from nicegui import ui

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
                          ).props("label")  # fmt: skip

    # ------------------------------------------------------------------ edits
    def edit(self, key: tuple, rebuild: bool = False, **changes) -> None:
        self._edit_started = time.perf_counter()
        try:
            self.session.edit(key=key, **changes)
        except DiefabError as exc:
            self.show_error(str(exc))
            return
        if rebuild:
            self.rebuild_controls()
        asyncio.get_event_loop().create_task(self.refresh())

    def undo(self) -> None:
        if self.session.undo():
            self.rebuild_controls()
            asyncio.get_event_loop().create_task(self.refresh())

    def redo(self) -> None:
        if self.session.redo():
            self.rebuild_controls()
            asyncio.get_event_loop().create_task(self.refresh())

    def open_design(self, design: Design) -> None:
        self.session.replace_design(design)
        self.rebuild_controls()
        asyncio.get_event_loop().create_task(self.refresh())

    def open_template(self, e) -> None:
        if not e.value:
            return
        try:
            self.open_design(load_design(e.value))
        except DiefabError as exc:
            self.show_error(str(exc))

    async def open_upload(self, e) -> None:
        try:
            data = await e.file.read()
            if len(data) > MAX_UPLOAD:
                raise DesignError(f"{e.file.name} is larger than {MAX_UPLOAD // 1024} KiB")
            try:
                text = data.decode("utf-8")
            except UnicodeDecodeError:
                raise DesignError(f"{e.file.name} is not UTF-8 text") from None
            design = parse_design(text, source=e.file.name, base=self.out_dir)
            self._check_reads(design, e.file.name)
            _ = design.polyhedron  # checks the geometry now
            design.check_stable(-math.inf)
            self.open_design(design)
        except DiefabError as exc:
            self.show_error(str(exc))
        except Exception as exc:  # a bug: one line, the server keeps running
            self.show_error(f"internal error: {type(exc).__name__}: {exc}")
        finally:
            e.sender.reset()

    def _check_reads(self, design: Design, source: str) -> None:
        """Refuse an uploaded design that would make the studio read a file outside its folder."""
        root = self.out_dir.resolve()
        files = [design.mesh] if design.mesh is not None else []
        files += [Path(t[4:].strip()) for t in design.labels.values() if t.startswith("svg:")]
        for f in files:
            full = Path(f).resolve()
            if root not in full.parents:
                raise DesignError(f"{source}: the studio reads files only in {self.out_dir}, not {f}")

    def upload_rejected(self) -> None:
        self.show_error(f"the file was refused: a design file is at most {MAX_UPLOAD // 1024} KiB")

    def save_design(self) -> None:
        from nicegui import ui

        try:
            path = write_design(self.session.design, self.out_dir)
        except DiefabError as exc:
            self.show_error(str(exc))
            return
        ui.download.file(path)
        ui.notify(f"wrote {path}")

    def show_error(self, message: str) -> None:
        from nicegui import ui

        self.error.set_text(message)
        with self.client:
            ui.notify(message, type="negative", multi_line=True)

    # --------------------------------------------------------------- evaluate
    async def refresh(self) -> None:
        """Evaluate the current design and redraw; while one evaluation runs, later edits wait for the newest."""
        from nicegui import run

        self.generation += 1
        if self.busy:
            return
        self.busy = True
        try:
            while True:
                gen, design = self.generation, self.session.design
                try:
                    if design.fill.kind == "solid":  # milliseconds: a thread hop would cost more than it saves
                        ev = self.session.evaluation(design)
                    else:  # a paper or print body takes seconds: keep the page responsive meanwhile
                        ev = await run.io_bound(self.session.evaluation, design)
                except DiefabError as exc:
                    if gen == self.generation:
                        self.show_error(str(exc))
                        break
                    continue
                if gen == self.generation:
                    self.draw(design, ev)
                    break
        except Exception as exc:  # a bug: one line, the server keeps running
            self.show_error(f"internal error: {type(exc).__name__}: {exc}")
        finally:
            self.busy = False
        asyncio.get_event_loop().create_task(self.refresh_net(self.generation))

    def draw(self, design: Design, ev: dict) -> None:
        self.evaluation = ev
        self.error.set_text("")
        self.title.set_text(f"{ev['name']}  ({ev['family']}, {ev['size_mm']:g} mm, {ev['fill']} fill)")
        self.chart.options.clear()
        self.chart.options.update(self._chart_options(ev["values"], ev["probabilities"], ev["target"]))
        self.chart.update()
        self.status.set_text(
            (f"stable: every valued face has a positive margin (smallest {ev['min_margin']:.4f})" if ev["stable"]
             else f"UNSTABLE: {ev['message']}") + f"   TVD to target {ev['tvd']:.4f}")  # fmt: skip
        self.status.classes(replace="studio-status font-bold " + ("text-green-700" if ev["stable"] else "text-red-700"))
        self.margins.rows = [
            {"face": f["name"], "value": f["value"] or "-", "probability": f"{f['probability']:.4f}",
             "margin": f"{f['margin']:.4f}", "read from": f["read_from"] or ("-" if f["transitional"] else "vertex"),
             "state": "transitional" if f["transitional"] else ("stable" if f["margin"] > 0 else "unstable")}
            for f in ev["faces"]
        ]  # fmt: skip
        self.margins.update()
        # the chart and numbers go out first; the 3D die follows in the next batch (skipped if already stale)
        asyncio.get_event_loop().create_task(self._draw_die_soon(design, ev, self.generation))
        self.undo_button.set_enabled(bool(self.session.undo_stack))
        self.redo_button.set_enabled(bool(self.session.redo_stack))
        started, self._edit_started = self._edit_started, None
        self.state_box.set_text(
            json.dumps(
                {
                    **ev,
                    # from the edit's arrival to the page's update being queued, ms (None: not from an edit)
                    "server_ms": None if started is None else 1000 * (time.perf_counter() - started),
                    "undo": len(self.session.undo_stack),
                    "redo": len(self.session.redo_stack),
                    "generation": self.generation,
                }
            )
        )

    @staticmethod
    def _chart_options(values, probs, target) -> dict:
        return {
            "animation": False,
            "legend": {"data": ["fast model", "target"]},
            "tooltip": {"trigger": "axis"},
            "xAxis": {"type": "category", "data": list(values), "name": "value"},
            "yAxis": {"type": "value", "name": "probability"},
            "series": [
                {"name": "fast model", "type": "bar", "data": [round(p, 6) for p in probs], "itemStyle": {
                    "color": "#fd8d3c"}},
                {"name": "target", "type": "line", "data": [round(p, 6) for p in target], "symbolSize": 8,
                 "lineStyle": {"type": "dashed"}, "itemStyle": {"color": "#333"}},
            ],
        }  # fmt: skip

    def _colors(self, ev: dict) -> dict[str, str]:
        probs = [f["probability"] for f in ev["faces"]]
        top = max(probs) if probs else 1.0
        colors = face_colors(probs, top)
        return {f["name"]: (TRANSITIONAL if f["transitional"] else c) for f, c in zip(ev["faces"], colors)}

    async def _place_camera(self) -> None:
        """Look at the die from above a girdle corner once the browser's scene exists."""
        await self.scene.initialized()
        r = float(abs(self.session.design.polyhedron.vertices).max())
        self.scene.move_camera(x=1.5 * r, y=1.2 * r, z=1.1 * r, look_at_x=0, look_at_y=0, look_at_z=0, duration=0)

    async def _draw_die_soon(self, design: Design, ev: dict, generation: int) -> None:
        await asyncio.sleep(0.02)
        if generation == self.generation:
            self.draw_die(design, ev)

    def draw_die(self, design: Design, ev: dict) -> None:
        poly = design.polyhedron
        colors = self._colors(ev)
        self.scene.clear()
        self.face_objects = {}
        with self.scene:
            for k, (name, frame) in enumerate(zip(poly.names, face_frames(poly))):
                n = poly.normals[k]
                center = [c - PLATE * x for c, x in zip(frame["center"], n)]
                color = HIGHLIGHT if name in (self.selected, self.hovered) else colors[name]
                obj = (self.scene.extrusion(frame["outline"], PLATE).with_name(name).material(color)
                       .rotate_R(frame["rotation"]).move(*center))  # fmt: skip
                self.face_objects[name] = obj
            for k, name in enumerate(poly.names):
                text = ev["labels"].get(name) or ("↻" if ev["faces"][k]["transitional"] else "")
                if text:
                    self.scene.texture(_label_url(text), label_quad(poly, k, 0.002)).with_name(name)
        top = max((f["probability"] for f in ev["faces"]), default=0.0)
        stops = ", ".join(f"rgb{c} {100 * t:.0f}%" for t, c in SCALE)
        self.legend.set_content(
            f'<div class="flex items-center gap-2 text-xs studio-legend"><span>0</span>'
            f'<div style="width:220px;height:12px;background:linear-gradient(to right, {stops});'
            f'border:1px solid #999"></div><span>{top:.3f}</span><span>probability of landing on the face</span>'
            f'<span style="display:inline-block;width:12px;height:12px;background:{TRANSITIONAL}"></span>'
            f"<span>transitional (↻ rolls off)</span></div>"
        )
        if self.selected:
            self.show_face(self.selected)

    # --------------------------------------------------------- face linking
    def scene_click(self, e) -> None:
        hit = next((h for h in e.hits if h.object_name in self.face_objects), None)
        if hit is not None:
            self.select_face(hit.object_name)

    def select_face(self, name: str | None) -> None:
        from nicegui import ui

        previous, self.selected = self.selected, name
        for n in {previous, name} - {None}:
            self._paint(n)
        if name:
            self.show_face(name)
        with self.client:
            ui.run_javascript(
                "document.querySelectorAll('.studio-net .net-face').forEach(g => g.classList.toggle('lit', "
                f"g.dataset.face === {json.dumps(name)}));"
            )

    def highlight(self, name: str | None, source: str = "") -> None:
        previous, self.hovered = self.hovered, name
        for n in {previous, name} - {None}:
            self._paint(n)

    def _paint(self, name: str) -> None:
        obj = self.face_objects.get(name)
        if obj is None or self.evaluation is None:
            return
        lit = name in (self.selected, self.hovered)
        obj.material(HIGHLIGHT if lit else self._colors(self.evaluation).get(name, TRANSITIONAL))

    def show_face(self, name: str) -> None:
        ev = self.evaluation
        f = next((f for f in ev["faces"] if f["name"] == name), None) if ev else None
        if f is None:
            return
        if f["transitional"]:
            text = f"face {name}: transitional (the die rolls off it), margin {f['margin']:.4f}"
        else:
            read = f"read from face {f['read_from']}" if f["read_from"] else "read at a vertex or edge"
            text = (f"face {name}: value {f['value']}, probability {f['probability']:.4f}, margin "
                    f"{f['margin']:.4f}, {read}")  # fmt: skip
        self.face_info.set_text(text)

    # ------------------------------------------------------------------- net
    async def refresh_net(self, generation: int) -> None:
        """Redraw the net picture once the design has stopped changing for a moment."""
        from nicegui import run, ui

        await asyncio.sleep(0.6)
        if generation != self.generation or self._building or self._net_generation == generation:
            return
        self._building = True
        try:
            design, ev = self.session.design, self.evaluation
            faces, names = await run.io_bound(net_faces, design, self.page_size.value or "A4")
            colors = self._colors(ev) if ev else {}
            svg = net_svg(faces, names, ev["labels"] if ev else {}, [colors.get(n, "#fff") for n in names])
            self.net_view.set_content(svg)
            self._net_generation = generation
            with self.client:
                ui.run_javascript(NET_JS)
        except DiefabError as exc:
            self.net_view.set_content(f"<p>no net: {exc}</p>")
        except Exception as exc:  # a bug: one line, the server keeps running
            self.show_error(f"internal error: {type(exc).__name__}: {exc}")
        finally:
            self._building = False
        if generation != self.generation:
            asyncio.get_event_loop().create_task(self.refresh_net(self.generation))

    # ------------------------------------------------------------- downloads
    async def download_net(self) -> None:
        await self._make("net", write_net, page=self.page_size.value, formats=(self.net_format.value,),
                         copies=int(self.copies.value or 1), mark=self.mark.value)  # fmt: skip

    async def download_solid(self) -> None:
        await self._make("solid", write_solid, formats=(self.solid_format.value,),
                         round_mm=float(self.round_mm.value or 0), depth_mm=float(self.depth_mm.value or 0.6),
                         emboss=bool(self.emboss.value), inlay=bool(self.inlay.value))  # fmt: skip

    async def _make(self, what: str, writer, **options) -> None:
        """Run a writer of :mod:`diefab.studio.make` in a thread and download what it wrote."""
        from nicegui import run, ui

        self.make_note.set_text(f"making the {what} ...")
        try:
            written = await run.io_bound(writer, self.session.design, self.out_dir, **options)
        except DiefabError as exc:
            message = str(exc)
        except Exception as exc:  # a bug: one line, the server keeps running
            message = f"internal error: {type(exc).__name__}: {exc}"
        else:
            paths, report = written if isinstance(written, tuple) else (written, {})
            for path in paths:
                ui.download.file(path)
            note = "wrote " + ", ".join(str(p) for p in paths)
            if report:
                note += f"; volume {report['volume_mm3']:.1f} mm³, watertight {report['watertight']}"
            self.make_note.set_text(note)
            return
        self.make_note.set_text("")
        self.show_error(message)

    # ------------------------------------------------------------------ jobs
    def start_validate(self) -> None:
        if self._running("validate"):
            return
        sims = int(self.sims.value or 0)
        if not 10 <= sims <= 1_000_000:
            self.show_error(f"drops={sims}: give between 10 and 1000000")
            return
        profile = None if self.profile_select.value == "design's own" else self.profile_select.value
        self.verdict.set_text("")
        self.jobs["validate"] = Job(validate_job, self.session.design, sims, int(self.seed.value or 0), profile)
        self.validate_text.set_text("starting a worker ...")

    def start_design(self) -> None:
        from diefab.dice.targets import parse_target

        if self._running("design"):
            return
        spec = (self.target_input.value or "").strip()
        try:
            parse_target(spec)
        except DiefabError as exc:
            self.show_error(str(exc))
            return
        budget = float(self.budget.value or 60)
        fill = self.session.design.fill
        name = "die-" + "".join(c if c.isalnum() else "-" for c in spec.lower()).strip("-")
        self.design_log.clear()
        self.jobs["design"] = Job(design_job, spec, fill, self.model_select.value, budget,
                                  int(self.seed.value or 0), name)  # fmt: skip
        self.design_text.set_text("starting a worker ...")

    def _running(self, kind: str) -> bool:
        job = self.jobs.get(kind)
        if job is not None and not job.finished:
            self.show_error(f"a {kind} job is already running (cancel it first)")
            return True
        return False

    def cancel(self, kind: str) -> None:
        job = self.jobs.get(kind)
        if job is not None and not job.finished:
            job.cancel()
            (self.validate_text if kind == "validate" else self.design_text).set_text("cancelled")

    def stop_jobs(self) -> None:
        for job in self.jobs.values():
            if not job.finished:
                job.cancel()

    def poll_jobs(self) -> None:
        """Show what the running jobs reported, and their results once they end."""
        panels = (("validate", self.validate_bar, self.validate_text, self.show_validation),
                  ("design", self.design_bar, self.design_text, self.show_designed))  # fmt: skip
        for kind, bar, text, show in panels:
            job = self.jobs.get(kind)
            if job is None or getattr(job, "shown", False):
                continue
            ended = job.poll()
            bar.set_value(job.fraction)
            if kind == "design":
                for line in job.notes[getattr(job, "logged", 0) :]:
                    self.design_log.push(line)
                job.logged = len(job.notes)
                if job.total:
                    text.set_text(f"{job.done:.0f} of {job.total:.0f} s budget, ETA at most "
                                  f"{_fmt_seconds(job.total - job.done)}")  # fmt: skip
            elif job.total:
                text.set_text(f"{int(job.done)} of {int(job.total)} drops, ETA {_fmt_seconds(job.eta_seconds)}")
            if not ended:
                continue
            job.shown = True
            if job.error is None:
                show(job)
                continue
            text.set_text(job.error)
            if job.error != "cancelled":
                self.show_error(job.error)

    def show_validation(self, job: Job) -> None:
        r = job.result
        ok = r["p_value"] >= 0.05
        self.verdict.set_text(
            (f"consistent with the target (p = {r['p_value']:.3g} >= 0.05)" if ok
             else f"differs from the target (p = {r['p_value']:.3g} < 0.05)")
            + f"; TVD {r['tvd']:.4f} (expected from noise {r['expected_tvd']:.4f}); {r['landed']} of {r['n']} "
            f"drops on a face, {r['cocked']} cocked, {r['unsettled']} unsettled, {r['seconds']:.1f} s")  # fmt: skip
        self.verdict.classes(replace="studio-verdict font-bold " + ("text-green-700" if ok else "text-red-700"))
        values = self.evaluation["values"] if self.evaluation else [str(i) for i in range(len(r["observed"]))]
        opts = self._chart_options(values, r["observed"], r["target"])
        opts["series"][0]["name"] = opts["legend"]["data"][0] = "simulated"
        opts["series"].append({"name": "95% interval", "type": "custom", "data": []})
        opts["series"][0]["markLine"] = None
        opts["tooltip"] = {"trigger": "axis"}
        opts["series"].insert(
            1,
            {
                "name": "interval low",
                "type": "scatter",
                "symbol": "triangle",
                "data": [lo for lo, _ in r["intervals"]],
                "itemStyle": {"color": "#555"},
            },
        )
        opts["series"].insert(2, {"name": "interval high", "type": "scatter", "symbol": "triangle",
                                  "symbolRotate": 180, "data": [hi for _, hi in r["intervals"]],
                                  "itemStyle": {"color": "#555"}})  # fmt: skip
        opts["series"] = [s for s in opts["series"] if s["type"] != "custom"]
        self.validate_chart.options.clear()
        self.validate_chart.options.update(opts)
        self.validate_chart.update()
        self.validate_text.set_text(f"{r['n']} drops done")
        self.last_validation = r

    def show_designed(self, job: Job) -> None:
        try:
            design = parse_design(job.result, source="designed die")
        except DiefabError as exc:
            self.show_error(str(exc))
            return
        self.design_text.set_text(f"designed {design.name}: opened (undo returns to the previous die)")
        self.open_design(design)


def make_design_fill(design: Design, kind: str) -> Design:
    """`design` made with a `kind` fill (its other fill settings kept)."""
    return replace(design, fill=replace(design.fill, kind=kind))


def serve(design: Design, out_dir: Path, *, host: str = "127.0.0.1", port: int = 8080, show: bool = True,
          target: str | None = None) -> None:  # fmt: skip
    """Serve the studio until interrupted (blocks)."""
    from nicegui import app, ui

    out_dir = Path(out_dir)

    @ui.page("/")
    def index() -> None:
        Studio(design, out_dir, target).build()

    @app.get("/healthz")
    def healthz() -> dict:
        return {"ok": True}

    ui.run(host=host, port=port, show=show, reload=False, title="diefab studio", uvicorn_logging_level="warning",
           favicon="🎲", show_welcome_message=False)  # fmt: skip
