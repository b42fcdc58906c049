"""The page's Validate and Design tabs: long jobs in worker processes, their progress, results and cancelling."""

from __future__ import annotations

import math

from nicegui import ui

from diefab.core.errors import DiefabError
from diefab.dice.design import parse_design
from diefab.studio.chart import distribution_options, validation_line, validation_options
from diefab.studio.host import Host
from diefab.studio.jobs import Job, design_job, validate_job


def fmt_seconds(s: float | None) -> str:
    """``m:ss``, or ``--`` when unknown."""
    if s is None or not math.isfinite(s):
        return "--"
    s = int(round(s))
    return f"{s // 60}:{s % 60:02d}"


class JobPanel:
    """One tab running one kind of job at a time: a start button, a cancel button, a progress bar and a text."""

    kind = ""

    def __init__(self, studio: Host) -> None:
        self.studio = studio
        self.job: Job | None = None
        self._logged = 0

    def _progress_row(self) -> None:
        self.bar = ui.linear_progress(value=0, show_value=False).classes(f"studio-{self.kind}-bar")
        self.text = ui.label().classes(f"studio-{self.kind}-text")

    def busy(self) -> bool:
        """True (and say so) when a job of this kind is running."""
        if self.job is not None and not self.job.finished:
            self.studio.show_error(f"a {self.kind} job is already running (cancel it first)")
            return True
        return False

    def start(self, func, *args) -> None:
        self.job, self._logged = Job(func, *args), 0
        self.text.set_text("starting a worker ...")

    def cancel(self) -> None:
        if self.job is not None and not self.job.finished:
            self.job.cancel()
            self.text.set_text("cancelled")

    def stop(self) -> None:
        """End a running job without a word (the page is closing)."""
        if self.job is not None and not self.job.finished:
            self.job.cancel()

    def poll(self) -> None:
        """Show what the job reported, and its result once it ends."""
        job = self.job
        if job is None or getattr(job, "shown", False):
            return
        ended = job.poll()
        self.bar.set_value(job.fraction)
        self.progress(job)
        if not ended:
            return
        job.shown = True
        if job.error is None:
            self.show(job.result)
        else:
            self.text.set_text(job.error)
            if job.error != "cancelled":
                self.studio.show_error(job.error)

    def progress(self, job: Job) -> None:
        raise NotImplementedError

    def show(self, result) -> None:
        raise NotImplementedError


class ValidatePanel(JobPanel):
    """Drops of the die in the physics simulation, then the verdict and the shares against the target."""

    kind = "validate"

    def build(self) -> None:
        from diefab.physics.profiles import list_profiles

        with ui.row().classes("items-end gap-4"):
            self.sims = ui.number("drops", value=2000, min=10, max=1_000_000, step=100, precision=0)
            self.seed = ui.number("seed", value=0, min=0, step=1, precision=0)
            self.profile = ui.select(["design's own", *list_profiles()], value="design's own",
                                     label="physics profile").classes("w-48")  # fmt: skip
            ui.button("Validate", on_click=self.start_validate).classes("studio-validate")
            ui.button("cancel", on_click=self.cancel).props("flat")
        self._progress_row()
        self.verdict = ui.label().classes("studio-verdict font-bold")
        self.chart = ui.echart(distribution_options([], [], []), renderer="svg").classes(
            "studio-validate-chart w-[640px] h-64"
        )

    def start_validate(self) -> None:
        if self.busy():
            return
        sims = int(self.sims.value or 0)
        if not 10 <= sims <= 1_000_000:
            self.studio.show_error(f"drops={sims}: give between 10 and 1000000")
            return
        profile = None if self.profile.value == "design's own" else self.profile.value
        self.verdict.set_text("")
        self.start(validate_job, self.studio.session.design, sims, int(self.seed.value or 0), profile)

    def progress(self, job: Job) -> None:
        if job.total and not job.finished:
            self.text.set_text(f"{int(job.done)} of {int(job.total)} drops, ETA {fmt_seconds(job.eta_seconds)}")

    def show(self, r: dict) -> None:
        ok = r["p_value"] >= 0.05
        self.verdict.set_text(validation_line(r))
        self.verdict.classes(replace="studio-verdict font-bold " + ("text-green-700" if ok else "text-red-700"))
        ev = self.studio.evaluation
        values = ev["values"] if ev else [str(i) for i in range(len(r["observed"]))]
        self.chart.options.clear()
        self.chart.options.update(validation_options(values, r))
        self.chart.update()
        self.text.set_text(f"{r['n']} drops done" + (f"; note: {r['note']}" if r.get("note") else ""))


class DesignPanel(JobPanel):
    """A design search for a target, with its progress and log; the designed die opens in the page."""

    kind = "design"

    def build(self, target: str | None) -> None:
        with ui.row().classes("items-end gap-4"):
            self.target = ui.input("target", value=target or "2d6").classes("w-56")
            self.model = ui.select(["fast", "solid-angle", "simulation"], value="fast",
                                   label="model").classes("w-40 studio-design-model")  # fmt: skip
            self.budget = ui.number("budget, s", value=60, min=5, max=3600, step=5, precision=0)
            self.seed = ui.number("seed", value=0, min=0, step=1, precision=0)
            ui.button("Design for target", on_click=self.start_design).classes("studio-design")
            ui.button("cancel", on_click=self.cancel).props("flat").classes("studio-cancel")
        self._progress_row()
        self.log = ui.log(max_lines=200).classes("w-full h-40")

    def start_design(self) -> None:
        from diefab.dice.targets import parse_target

        if self.busy():
            return
        spec = (self.target.value or "").strip()
        try:
            parse_target(spec)
        except DiefabError as exc:
            self.studio.show_error(str(exc))
            return
        budget = float(self.budget.value or 60)
        fill = self.studio.session.design.fill
        name = "die-" + "".join(c if c.isalnum() else "-" for c in spec.lower()).strip("-")
        self.log.clear()
        self.start(design_job, spec, fill, self.model.value, budget, int(self.seed.value or 0), name)

    def progress(self, job: Job) -> None:
        for line in job.notes[self._logged :]:
            self.log.push(line)
        self._logged = len(job.notes)
        if job.total and not job.finished:
            self.text.set_text(f"{job.done:.0f} of {job.total:.0f} s budget, ETA at most "
                               f"{fmt_seconds(job.total - job.done)}")  # fmt: skip

    def show(self, toml: str) -> None:
        try:
            design = parse_design(toml, source="designed die")
        except DiefabError as exc:
            self.studio.show_error(str(exc))
            return
        self.text.set_text(f"designed {design.name}: opened (undo returns to the previous die)")
        self.studio.open_design(design)
