"""The page's Make tab: download the net and the printable solid, and the net drawn beside the die, linked to it."""

from __future__ import annotations

import asyncio
import json
from html import escape

from nicegui import run, ui

from diefab.core.errors import DiefabError
from diefab.studio.host import Host
from diefab.studio.make import net_faces, write_net, write_solid
from diefab.studio.scene import HIGHLIGHT, probability_colors
from diefab.studio.view import net_svg

CSS = f"""
.studio-net .net-face:hover polygon, .studio-net .net-face.lit polygon {{ fill: {HIGHLIGHT} !important; }}
.studio-net {{ max-width: 100%; height: auto; }}
"""

#: Wires the net's faces to the page's events once the net is drawn.
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

#: Seconds the design must stay unchanged before the net is drawn again (unfolding takes a while).
NET_QUIET = 0.6


class MakePanel:
    """Downloads of the net and the solid, and the net linked to the 3D die."""

    def __init__(self, studio: Host) -> None:
        self.studio = studio
        self._drawn = None  # the design whose net is shown
        self._building = False

    def build(self) -> None:
        ui.add_css(CSS)
        with ui.row().classes("w-full no-wrap items-start gap-6"):
            with ui.column().classes("w-80"):
                ui.label("Paper net").classes("font-bold")
                self.page_size = ui.select(["A5", "A4", "A3", "Letter", "Legal"], value="A4", label="page").classes(
                    "w-40"
                )
                self.copies = ui.number("copies", value=1, min=1, max=100, step=1, precision=0).classes("w-40")
                self.mark = ui.select(["bar", "period", "none"], value="bar", label="6/9 mark").classes("w-40")
                self.net_format = ui.select(["svg", "pdf"], value="svg", label="format").classes("w-40")
                self.net_markers = ui.checkbox("ArUco markers (for diefab read)")
                ui.button("download net", on_click=self.download_net).classes("studio-download-net")
                ui.separator()
                ui.label("Printable solid").classes("font-bold")
                self.round_mm = ui.number("edge rounding, mm", value=0.0, min=0, max=5, step=0.1).classes("w-40")
                self.depth_mm = ui.number("label depth, mm", value=0.6, min=0.2, max=2, step=0.1).classes("w-40")
                self.emboss = ui.checkbox("emboss (raise) the labels")
                self.inlay = ui.checkbox("also the inlay (labels alone)")
                self.solid_markers = ui.checkbox("ArUco markers, inlaid (for diefab read)")
                self.solid_format = ui.select(["stl", "3mf"], value="stl", label="format").classes("w-40")
                ui.button("download solid", on_click=self.download_solid).classes("studio-download-stl")
                self.note = ui.label().classes("studio-make-note text-sm")
            with ui.column().classes("grow"):
                ui.label("Net (hover a face to find it on the die; click a face on the die to find it here)")
                self.net_view = ui.html("", sanitize=False).classes("studio-net-view w-full")

    def light(self, name: str | None) -> None:
        """Highlight face `name` on the net (None: none)."""
        with self.studio.client:
            ui.run_javascript(
                "document.querySelectorAll('.studio-net .net-face').forEach(g => g.classList.toggle('lit', "
                f"g.dataset.face === {json.dumps(name)}));"
            )

    async def refresh_net(self) -> None:
        """Redraw the net picture once the design has stopped changing for a moment."""
        design = self.studio.session.design
        await asyncio.sleep(NET_QUIET)
        if not self.studio.session.is_current(design) or self._building or design is self._drawn:
            return
        self._building = True
        try:
            faces, names = await run.io_bound(net_faces, design, self.page_size.value or "A4")
            ev = self.studio.evaluation
            colors = probability_colors(ev) if ev else {}
            svg = net_svg(faces, names, ev["labels"] if ev else {}, [colors.get(n, "#fff") for n in names])
            self.net_view.set_content(svg)
            self._drawn = design
            with self.studio.client:
                ui.run_javascript(NET_JS)
        except DiefabError as exc:
            self.net_view.set_content(f"<p>no net: {escape(str(exc))}</p>")
        except Exception as exc:  # a bug: one line, the server keeps running
            self.studio.show_error(f"internal error: {type(exc).__name__}: {exc}")
        finally:
            self._building = False
        if not self.studio.session.is_current(design):
            asyncio.get_event_loop().create_task(self.refresh_net())

    async def download_net(self) -> None:
        await self._make("net", write_net, page=self.page_size.value, formats=(self.net_format.value,),
                         copies=int(self.copies.value or 1), mark=self.mark.value,
                         markers=bool(self.net_markers.value))  # fmt: skip

    async def download_solid(self) -> None:
        await self._make("solid", write_solid, formats=(self.solid_format.value,),
                         round_mm=float(self.round_mm.value or 0), depth_mm=float(self.depth_mm.value or 0.6),
                         emboss=bool(self.emboss.value), inlay=bool(self.inlay.value),
                         markers=bool(self.solid_markers.value))  # fmt: skip

    async def _make(self, what: str, writer, **options) -> None:
        """Run a writer of :mod:`diefab.studio.make` in a thread and download what it wrote."""
        self.note.set_text(f"making the {what} ...")
        try:
            written = await run.io_bound(
                writer, self.studio.session.design, self.studio.out_dir, inputs=self.studio.inputs, **options
            )
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
            self.note.set_text(note)
            return
        self.note.set_text("")
        self.studio.show_error(message)
