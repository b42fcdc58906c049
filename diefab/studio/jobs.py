"""Long work of the studio (drops, design searches) in a worker process the page can watch and stop.

A job runs one function in a fresh ("spawn") process, so that the web
server's threads and event loop are not copied into it; the function reports
through a queue: ``("progress", done, total)``, ``("note", text)``, then
``("done", result)`` or ``("error", message)``.  :meth:`Job.cancel` ends the
process, which is what the page does when it closes.
"""

from __future__ import annotations

import multiprocessing as mp
import queue as queue_module
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
        """Stop the worker (SIGTERM, then SIGKILL after 2 s)."""
        if self.process.is_alive():
            self.process.terminate()
            self.process.join(2.0)
            if self.process.is_alive():
                self.process.kill()
                self.process.join(1.0)
        if not self.finished:
            self.error, self.finished = "cancelled", True
        self._queue.close()


def _run(func, args, q) -> None:
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
        q.close()
        q.join_thread()


def validate_job(design, sims: int, seed: int, profile: str | None, *, report) -> dict:
    """Drop `design` `sims` times and test the counts against its target (as ``diefab validate``)."""
    import numpy as np

    from diefab.core.errors import PhysicsError
    from diefab.physics.profiles import load_profile
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
