"""The page's 3D die: faces colored by landing probability, its values as made, a legend, face picking.

The die is one scene object (``die.js``) redrawn by a single message per
change: the whole shape when the geometry or the labels changed, only the
colors otherwise (a hover, a selection, a new fill).  While the die changes
its faces are flat with the values printed on them; once it has stayed the
same a moment, a solid or print die is shown as :func:`diefab.fabricate.stl.build_solid`
makes it, values engraved, built in a worker process (a paper die keeps its
printed values).
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from nicegui import ui
from nicegui.elements.scene.scene_object3d import Object3D

from diefab.dice.design import Design
from diefab.studio.jobs import Job, solid_job
from diefab.studio.state import SCALE, face_colors
from diefab.studio.view import die_data, face_at

#: Seconds a die must stay unchanged before its solid is built for the view (a build takes seconds).
MADE_QUIET = 1.5

#: Color of a transitional face (the die rolls off it) and of a highlighted face.
TRANSITIONAL = "#9e9e9e"
HIGHLIGHT = "#1e88e5"


class Die(Object3D, component="die.js"):
    """The die as one scene object; :meth:`show` redraws it, :meth:`paint` recolors its faces."""

    def __init__(self, data: dict) -> None:
        super().__init__(data)

    def show(self, data: dict) -> None:
        self.args = [data]  # what the scene sends again if the browser rebuilds it
        self.run_method("show", data)

    def paint(self, colors: list[str]) -> None:
        self.args[0]["colors"] = colors
        self.run_method("paint", colors)


def probability_colors(ev: dict) -> dict[str, str]:
    """Each face's color: its landing probability on the studio's scale, gray for a transitional face."""
    probs = [f["probability"] for f in ev["faces"]]
    colors = face_colors(probs, max(probs) if probs else 1.0)
    return {f["name"]: (TRANSITIONAL if f["transitional"] else c) for f, c in zip(ev["faces"], colors)}


class DieView:
    """The 3D view of the die, its legend and the clicked face's numbers.

    Parameters
    ----------
    on_select : callable
        Called with a face name when a face is clicked on the die.
    is_current : callable
        True for a design that is still the one being edited.
    """

    def __init__(self, on_select: Callable[[str], Any], is_current: Callable[[Design], bool]) -> None:
        self.on_select = on_select
        self.is_current = is_current
        self.job: Job | None = None
        self.made: tuple[Design, dict] | None = None  # a design and its solid's mesh
        self.die: Die | None = None
        self.design: Design | None = None
        self.evaluation: dict | None = None
        self.lit: set[str] = set()
        self._shape: tuple | None = None
        self._colors: list[str] = []

    def build(self) -> None:
        self.scene = ui.scene(width=520, height=440, on_click=self._click, grid=False,
                              background_color="#f7f7f7").classes("studio-scene")  # fmt: skip
        self.legend = ui.html("", sanitize=False).classes("w-full")
        with ui.row().classes("items-center gap-2"):
            self.as_made = ui.checkbox("engraved values, as printed", value=True,
                                       on_change=self._as_made_changed).classes("studio-as-made")  # fmt: skip
            self.made_note = ui.label().classes("studio-made-note text-xs text-gray-600")
        self.face_info = ui.label("click a face").classes("studio-face font-mono text-sm")

    async def place_camera(self, design: Design) -> None:
        """Look at the die from above a girdle corner once the browser's scene exists."""
        await self.scene.initialized()
        r = float(abs(design.polyhedron.vertices).max())
        self.scene.move_camera(x=1.5 * r, y=1.2 * r, z=1.1 * r, look_at_x=0, look_at_y=0, look_at_z=0, duration=0)

    def draw(self, design: Design, ev: dict) -> None:
        """Show `design` colored by its evaluation `ev` (:func:`diefab.studio.state.evaluate`)."""
        self.design, self.evaluation = design, ev
        poly = design.polyhedron
        colors = self.colors()
        labels = [ev["labels"].get(n) or ("↻" if f["transitional"] else "") for n, f in zip(poly.names, ev["faces"])]
        mesh = (
            self.made[1] if self.made is not None and self._wanted(design) and self.is_current(self.made[0]) else None
        )
        shape = (poly.vertices.tobytes(), tuple(map(tuple, poly.faces)), tuple(labels), id(mesh))
        if shape != self._shape:
            data = {**die_data(poly, colors, labels), "mesh": mesh}
            if self.die is None:
                with self.scene:
                    self.die = Die(data).with_name("die")
            else:
                self.die.show(data)
        elif colors != self._colors:
            self.die.paint(colors)
        self._shape, self._colors = shape, colors
        self.as_made.set_visibility(design.fill.kind != "paper")  # a paper die's values are printed
        waiting = mesh is None and self._wanted(design)
        self.made_note.set_text("(flat faces until the solid is built)" if waiting else "")
        if waiting:
            asyncio.get_event_loop().create_task(self._build_made(design))
        top = max((f["probability"] for f in ev["faces"]), default=0.0)
        stops = ", ".join(f"rgb{c} {100 * t:.0f}%" for t, c in SCALE)
        self.legend.set_content(
            f'<div class="flex items-center gap-2 text-xs studio-legend"><span>0</span>'
            f'<div style="width:220px;height:12px;background:linear-gradient(to right, {stops});'
            f'border:1px solid #999"></div><span>{top:.3f}</span><span>probability of landing on the face</span>'
            f'<span style="display:inline-block;width:12px;height:12px;background:{TRANSITIONAL}"></span>'
            f"<span>transitional (↻ rolls off)</span></div>"
        )

    def colors(self) -> list[str]:
        """Each face's color now: its probability's, or the highlight for a hovered or selected face."""
        if self.design is None or self.evaluation is None:
            return []
        by_name = probability_colors(self.evaluation)
        return [HIGHLIGHT if n in self.lit else by_name[n] for n in self.design.polyhedron.names]

    def light(self, names: set[str]) -> None:
        """Highlight the faces `names` (hovered on the net, or selected) and no other."""
        self.lit = set(names) - {None, ""}
        if self.die is not None:
            colors = self.colors()
            if colors != self._colors:
                self.die.paint(colors)
                self._colors = colors

    def show_face(self, name: str | None) -> None:
        """Write face `name`'s value, probability, margin and the face it is read from under the die."""
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

    def _wanted(self, design: Design) -> bool:
        return bool(self.as_made.value) and design.fill.kind != "paper"

    def _as_made_changed(self) -> None:
        if self.design is not None and self.evaluation is not None:
            self.draw(self.design, self.evaluation)

    async def _build_made(self, design: Design) -> None:
        """Build `design`'s solid in a worker once it has stayed the die being edited for :data:`MADE_QUIET` s."""
        if self.job is not None and not self.job.finished and not self.is_current(self.job.design):
            self.job.cancel()  # a die no longer shown
        await asyncio.sleep(MADE_QUIET)
        if not self.is_current(design) or (self.job is not None and not self.job.finished):
            return
        self.job = Job(solid_job, design)
        self.job.design = design
        self.made_note.set_text("(building the solid ...)")

    def poll(self) -> None:
        """Show the built solid once its worker has it (if the die is still the same)."""
        job = self.job
        if job is None or not job.poll() or getattr(job, "shown", False):
            return
        job.shown = True
        if job.error is not None:
            self.made_note.set_text("" if job.error == "cancelled" else f"(no solid: {job.error})")
        elif self.is_current(job.design):
            self.made = (job.design, job.result)
            if self.design is not None and self.evaluation is not None:
                self.draw(self.design, self.evaluation)

    def stop(self) -> None:
        """Stop building (the page closed)."""
        if self.job is not None and not self.job.finished:
            self.job.cancel()

    def _click(self, e) -> None:
        hit = next((h for h in e.hits if h.object_name == "die"), None)
        if hit is not None and self.design is not None:
            poly = self.design.polyhedron
            self.on_select(poly.names[face_at(poly, (hit.x, hit.y, hit.z))])
