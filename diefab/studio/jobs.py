"""Long work of the studio (drops, design searches) in a worker process the page can watch and stop.

A job runs one function in a fresh ("spawn") process, so that the web
server's threads and event loop are not copied into it; the function reports
through a queue: ``("progress", done, total)``, ``("note", text)``, then
``("done", result)`` or ``("error", message)``; any other kind is kept in
:attr:`Job.events` for the page to read.  :meth:`Job.cancel` ends the
process, which is what the page does when it closes.
"""

from __future__ import annotations

import multiprocessing as mp
import queue as queue_module
import threading
import time
from collections.abc import Callable
from typing import Any

from diefab.core.errors import DiefabError


class Job:
    """`func(*args, report=...)` running in a worker process.

    Parameters
    ----------
    func : callable
        A module-level function (it is pickled into the worker) taking
        ``report`` as a keyword: ``report(kind, *data)``.
    """

    def __init__(self, func: Callable[..., Any], *args: Any) -> None:
        ctx = mp.get_context("spawn")
        self._queue = ctx.Queue()
        self.process = ctx.Process(target=_run, args=(func, args, self._queue), daemon=True)
        self.started = time.monotonic()
        self.done: int | float = 0
        self.total: int | float = 0
        self.notes: list[str] = []
        self.events: list[tuple] = []
        self.result: Any = None
        self.error: str | None = None
        self.finished = False
        self.process.start()

    @property
    def fraction(self) -> float:
        """Share of the work done, in [0, 1]."""
        return min(1.0, self.done / self.total) if self.total else 0.0

    @property
    def eta_seconds(self) -> float | None:
        """Seconds left at the rate so far (None before the first progress)."""
        if not self.done or not self.total:
            return None
        spent = time.monotonic() - self.started
        return spent * (self.total - self.done) / self.done

    def poll(self) -> bool:
        """Read what the worker reported; True once the job has ended (result or error set)."""
        while True:
            try:
                msg = self._queue.get_nowait()
            except (queue_module.Empty, OSError, ValueError):
                break
            kind = msg[0]
            if kind == "progress":
                self.done, self.total = msg[1], msg[2]
            elif kind == "note":
                self.notes.append(msg[1])
            elif kind == "done":
                self.result, self.finished = msg[1], True
            elif kind == "error":
                self.error, self.finished = msg[1], True
            else:
                self.events.append(msg)
        if not self.finished and not self.process.is_alive():
            self.poll_once_more()
        return self.finished

    def poll_once_more(self) -> None:
        """The worker has exited: take its last message, or record that it died without one."""
        try:
            msg = self._queue.get(timeout=0.5)
        except (queue_module.Empty, OSError, ValueError):
            self.error = f"the worker process stopped unexpectedly (exit code {self.process.exitcode})"
            self.finished = True
            return
        self._queue.put(msg)  # let poll() handle it the usual way
        self.poll()

    def cancel(self) -> None:
        """Stop the worker (SIGTERM, then SIGKILL after 2 s), without waiting for it to end."""
        end_process(self.process)
        if not self.finished:
            self.error, self.finished = "cancelled", True
        self._queue.close()


def end_process(process) -> None:
    """End a worker `process` without waiting for it: SIGTERM now, SIGKILL from a thread if it lives 2 s on.

    The page's event loop must not block: the browser's heartbeat goes
    unanswered while it waits, and the page is dropped and loaded afresh.
    """
    if process.is_alive():
        process.terminate()
        threading.Thread(target=_kill_if_alive, args=(process,), name="diefab-end-worker", daemon=True).start()


def _kill_if_alive(process, grace: float = 2.0) -> None:
    process.join(grace)
    if process.is_alive():
        process.kill()
        process.join(1.0)


def _quiet_stops() -> None:
    """In a worker: a stop signal (the page cancelling it, the server stopping) ends it quietly.

    The parent, the ``diefab`` command, says "interrupted" once for all.
    """
    from diefab.core.stopping import install

    install()  # raises KeyboardInterrupt, which the worker catches, instead of printing a line and exiting


def _run(func, args, q) -> None:
    _quiet_stops()

    def report(kind: str, *data: Any) -> None:
        q.put((kind, *data))

    try:
        q.put(("done", func(*args, report=report)))
    except DiefabError as exc:
        q.put(("error", str(exc)))
    except KeyboardInterrupt:
        q.put(("error", "cancelled"))
    except Exception as exc:  # a bug in the worker: one line in the page, never a traceback
        q.put(("error", f"internal error: {type(exc).__name__}: {exc}"))
    finally:
        try:
            q.close()
            q.join_thread()
        except KeyboardInterrupt:  # stopped again while the last message goes: nobody waits for it
            pass


class Evaluator:
    """A worker process that evaluates designs (:func:`diefab.studio.state.evaluate`) one at a time.

    For a made body whose mass model takes seconds: the page keeps serving
    while the worker computes.  :meth:`evaluate` blocks its (thread's) caller
    until the result arrives; :meth:`stop` ends the worker, and a caller
    waiting on it gets :class:`~diefab.core.errors.DiefabError`.
    """

    def __init__(self) -> None:
        ctx = mp.get_context("spawn")
        self._inbox, self._outbox = ctx.Queue(), ctx.Queue()
        self.process = ctx.Process(target=_evaluate_forever, args=(self._inbox, self._outbox), daemon=True)
        self.process.start()
        self._asked = 0

    def evaluate(self, design) -> dict:
        """The evaluation of `design` (blocks; one caller at a time)."""
        self._asked += 1
        self._inbox.put((self._asked, design))
        while True:
            try:
                number, kind, payload = self._outbox.get(timeout=0.5)
            except queue_module.Empty:
                if not self.process.is_alive():
                    raise DiefabError("the evaluation worker stopped") from None
                continue
            except (OSError, ValueError):
                raise DiefabError("the evaluation worker stopped") from None
            if number != self._asked:
                continue  # the answer to a question whose caller gave up
            if kind == "error":
                raise DiefabError(payload)
            return payload

    def stop(self) -> None:
        """End the worker (SIGTERM, then SIGKILL after 2 s), without waiting for it to end."""
        end_process(self.process)


def _evaluate_forever(inbox, outbox) -> None:
    _quiet_stops()
    from diefab.studio.state import evaluate

    try:
        while True:
            number, design = inbox.get()
            try:
                outbox.put((number, "done", evaluate(design)))
            except DiefabError as exc:
                outbox.put((number, "error", str(exc)))
            except Exception as exc:  # a bug: one line in the page, never a traceback
                outbox.put((number, "error", f"internal error: {type(exc).__name__}: {exc}"))
    except KeyboardInterrupt:  # the server was stopped, or the page closed
        pass


def validate_job(design, sims: int, seed: int, profile: str | None, *, report) -> dict:
    """Drop `design` `sims` times and test the counts against its target (as ``diefab validate``)."""
    import numpy as np

    from diefab.core.errors import PhysicsError
    from diefab.physics.profiles import domain_note, load_profile
    from diefab.physics.simulate import PhysicsSettings, simulate
    from diefab.stats.goodness import goodness_of_fit

    settings = (load_profile(profile, base=design.physics) if profile
                else PhysicsSettings.from_mapping(design.physics))  # fmt: skip
    report("progress", 0, sims)
    result = simulate(design, sims, seed=seed, workers=1, settings=settings,
                      progress=lambda done, total: report("progress", done, total))  # fmt: skip
    if result.landed == 0:
        raise PhysicsError(f"no drop came to rest on a face ({result.cocked} cocked, {result.unsettled} unsettled)")
    counts = result.value_counts(design)
    goal = design.target_distribution.aligned(design.support)
    fit = goodness_of_fit(counts, goal, seed=seed)
    return {
        "n": int(result.n),
        "landed": int(result.landed),
        "cocked": int(result.cocked),
        "unsettled": int(result.unsettled),
        "counts": [int(c) for c in counts],
        "observed": [float(p) for p in fit.observed],
        "intervals": [[float(lo), float(hi)] for lo, hi in fit.intervals],
        "target": [float(g) for g in goal],
        "p_value": float(fit.p_value),
        "tvd": float(fit.tvd),
        "expected_tvd": float(fit.expected_tvd),
        "chi2": float(fit.chi2) if np.isfinite(fit.chi2) else None,
        "seconds": float(result.seconds),
        "note": domain_note(profile, design.fill.kind) if profile else None,
    }


def design_job(target: str, fill, model: str, budget_seconds: float, seed: int, name: str, *, report) -> str:
    """Design a die for `target` (as ``diefab design``, without its closing check); the design as TOML."""
    from diefab.dice.design import design_to_toml
    from diefab.dice.targets import parse_target
    from diefab.search.synthesis import synthesize

    start = time.monotonic()
    report("progress", 0.0, budget_seconds)

    def say(text: str) -> None:
        report("note", text)
        report("progress", min(time.monotonic() - start, budget_seconds), budget_seconds)

    found = synthesize(parse_target(target), fill=fill, model=model, budget_seconds=budget_seconds, seed=seed,
                       name=name, workers=1, progress=say)  # fmt: skip
    report("progress", budget_seconds, budget_seconds)
    return design_to_toml(found.design, comment=f"designed by diefab studio for target {target}")


def solid_job(design, *, report) -> dict:
    """The printable solid of `design` as ``diefab stl`` makes it by default, for the 3D view (:func:`.made_mesh`)."""
    from diefab.fabricate.stl import build_solid
    from diefab.studio.view import made_mesh

    fill = design.fill if design.fill.kind == "print" else None
    solid = build_solid(design, **({"print_fill": fill} if fill is not None else {}))
    return made_mesh(design.polyhedron, solid.vertices / design.mm_per_unit, solid.triangles, solid.label_triangles)


#: Width of the camera frames the page shows, pixels, and the least time between two of them, seconds.
PREVIEW_WIDTH = 480
PREVIEW_EVERY = 0.25


def read_job(design, source: dict, settle: int, min_confidence: float, fov: float, log_path, *, report) -> int:
    """Read rolls of `design`'s marked die from `source` (as ``diefab read``) and append them to `log_path`.

    `source` is one of ``{"camera": index}``, ``{"video": path}``, ``{"images": folder}``.
    Reports ``("frame", jpeg data URL)`` now and then (the frame with the
    detection drawn), ``("roll", time, value or None, face or None,
    confidence)`` for every roll, and ``("progress", frames read, 0)``.
    Returns the number of rolls read.
    """
    import base64

    import cv2

    from diefab.camera.reader import RollReader
    from diefab.camera.render import draw_detection
    from diefab.camera.session import LogReading
    from diefab.core.files import hold_lock

    reader = RollReader(design, settle=settle, min_confidence=min_confidence, fov=fov)
    hold_lock(log_path, f"roll log {log_path}")  # one writer per log, until the worker ends
    session = LogReading(reader, log_path)
    photos = "images" in source
    shown, count = 0.0, 0
    for step in session.read(**source):
        seen, roll = step.seen, step.roll
        now = time.monotonic()
        if seen is not None and (photos or roll is not None or now - shown >= PREVIEW_EVERY):
            image = draw_detection(step.gray, seen, design, reader.layout, reader.camera)
            scale = PREVIEW_WIDTH / image.shape[1]
            small = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
            ok, data = cv2.imencode(".jpg", small, [cv2.IMWRITE_JPEG_QUALITY, 80])
            if ok:
                report("frame", "data:image/jpeg;base64," + base64.b64encode(data.tobytes()).decode("ascii"))
                shown = now
        report("progress", reader.frame + 1, 0)
        if roll is None:
            continue
        report("roll", step.time, roll.value, roll.face, float(roll.confidence))
        count += 1
    if session.skipped:
        report("note", session.skipped_line(source["images"]))
    return count
