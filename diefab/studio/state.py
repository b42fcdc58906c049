"""What the studio shows: one die being edited, its evaluation, and its undo history.

Nothing here knows about the web page; the page calls :class:`Session` and
draws what :func:`evaluate` returns.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from diefab.core.errors import DesignError, DiefabError
from diefab.dice.design import Design, format_value
from diefab.dice.families import family

#: Fill kinds the studio offers (``shell`` is the CLI's thin-skin solid; the studio keeps to what makers build).
FILLS = ("solid", "paper", "print")

#: Most undo steps kept.
HISTORY = 200

#: Evaluations kept in the cache (a slider dragged back and forth costs nothing the second time).
CACHE = 256


def parameters(design: Design) -> list[dict[str, Any]]:
    """The family's real parameters the design uses, with their bounds: ``[{name, lower, upper, value, ...}]``."""
    fam = family(design.family)
    out = []
    for p in fam.parameters:
        if p.integer or p.name not in design.params:
            continue
        out.append({"name": p.name, "lower": float(p.lower), "upper": float(p.upper),
                    "value": float(design.params[p.name]), "description": p.description})  # fmt: skip
    return out


def evaluate(design: Design, model: str = "fast") -> dict[str, Any]:
    """The fast model's landing probabilities, margins and readings of `design`, as plain JSON data.

    Returns
    -------
    dict
        ``faces``: one entry per face (name, value or None, probability,
        stability margin in model units, the face its value is read from,
        transitional); ``values``/``probabilities``/``target`` aligned on
        ``design.support``; ``stable`` and ``message`` (why not);
        ``min_margin`` over the resting faces.
    """
    from diefab.models.probabilities import face_probabilities, to_values
    from diefab.stats.goodness import tvd

    poly = design.polyhedron
    fill = design.fill
    margins = design.margins(fill)
    message = ""
    try:
        design.check_stable(0.0, fill)
        stable = True
    except DesignError as exc:
        stable, message = False, str(exc)
    faces = face_probabilities(design, model, fill)
    values = to_values(design, faces)
    goal = design.target_distribution.aligned(design.support)
    signed = min(design.support) < 0
    label_face = design.label_face
    resting = design.resting_mask()
    return {
        "name": design.name,
        "family": design.family,
        "params": {k: float(v) for k, v in design.params.items()},
        "size_mm": float(design.size_mm),
        "fill": fill.kind,
        "model": model,
        "faces": [
            {
                "name": n,
                "value": format_value(design.values[n], signed) if n in design.values else None,
                "probability": float(p),
                "margin": float(m),
                "read_from": label_face.get(n) if n in design.values else None,
                "transitional": n not in design.values,
            }
            for n, p, m in zip(poly.names, faces, margins)
        ],
        "labels": dict(design.label_of) if _labels_ok(design) else {},
        "values": [format_value(v, signed) for v in design.support],
        "probabilities": [float(p) for p in values],
        "target": [float(g) for g in goal],
        "tvd": float(tvd(values, goal)),
        "min_margin": float(margins[resting].min()) if resting.any() else float("nan"),
        "stable": stable,
        "message": message,
        "provisional": False,
    }


def made_body_is_slow(design: Design) -> bool:
    """True when the made body's mass model takes long (a paper net's tabs, a print's shells and labels).

    The page then shows :func:`provisional_evaluation` at once and the full
    evaluation when a worker has it.
    """
    return design.fill.kind != "solid"


def provisional_evaluation(design: Design) -> dict[str, Any]:
    """:func:`evaluate` of `design` as a solid body (milliseconds), marked ``provisional``.

    A stand-in while the made body's evaluation runs: the shape's effect on
    the distribution, without the fill's.
    """
    from diefab.made.fill import Fill

    ev = evaluate(replace(design, fill=Fill()))
    return {**ev, "fill": design.fill.kind, "provisional": True}


def _labels_ok(design: Design) -> bool:
    try:
        _ = design.label_of
    except DiefabError:
        return False
    return True


@dataclass
class Session:
    """The die being edited, with undo and redo and a cache of evaluations.

    Each edit (:meth:`edit`) checks the new design and pushes the old one on
    the undo stack; a bad edit raises :class:`DesignError` and changes
    nothing.
    """

    design: Design
    profile: str = ""
    undo_stack: list[Design] = field(default_factory=list)
    redo_stack: list[Design] = field(default_factory=list)
    _cache: OrderedDict = field(default_factory=OrderedDict)
    _last_key: tuple = ()

    def edit(self, *, key: tuple = (), params: dict[str, float] | None = None, size_mm: float | None = None,
             fill: str | None = None, fill_settings: dict[str, float] | None = None) -> Design:  # fmt: skip
        """Apply an edit and return the new design (DesignError if it is not a valid die).

        Consecutive edits with the same non-empty `key` (one slider dragged)
        make one undo step.
        """
        d = self.design
        new = d
        if params:
            new = new.with_params(**params)
        if size_mm is not None:
            new = replace(new, size_mm=float(size_mm))
        if fill is not None or fill_settings:
            new = replace(new, fill=replace(new.fill, kind=fill or new.fill.kind, **(fill_settings or {})))
        _ = new.polyhedron  # builds and checks the geometry now, not in the page
        if _key(new) != _key(d):
            if not (key and key == self._last_key and self.undo_stack and not self.redo_stack):
                self.undo_stack.append(d)
                del self.undo_stack[:-HISTORY]
            self.redo_stack.clear()
            self.design = new
            self._last_key = key
        return new

    def replace_design(self, design: Design) -> None:
        """Open another design (undoable; opening the same design again changes nothing)."""
        if _key(design) == _key(self.design):
            return
        self.undo_stack.append(self.design)
        del self.undo_stack[:-HISTORY]
        self.redo_stack.clear()
        self.design = design
        self._last_key = ()

    def undo(self) -> bool:
        """Go back one edit; False when there is none."""
        return self._step(self.undo_stack, self.redo_stack)

    def redo(self) -> bool:
        """Redo the edit last undone; False when there is none."""
        return self._step(self.redo_stack, self.undo_stack)

    def _step(self, source: list[Design], sink: list[Design]) -> bool:
        if not source:
            return False
        sink.append(self.design)
        self.design = source.pop()
        self._last_key = ()
        return True

    def evaluation(self, design: Design | None = None) -> dict[str, Any]:
        """:func:`evaluate` of `design` (default: the current one), cached."""
        d = design or self.design
        hit = self.cached(d)
        if hit is None:
            hit = evaluate(d)
            self.remember(d, hit)
        return hit

    def provisional(self, design: Design | None = None) -> dict[str, Any]:
        """:func:`provisional_evaluation` of `design` (default: the current one), cached."""
        d = design or self.design
        key = ("provisional", _key(d))
        hit = self._cache.get(key)
        if hit is None:
            hit = provisional_evaluation(d)
            self._store(key, hit)
        return hit

    def cached(self, design: Design) -> dict[str, Any] | None:
        """The evaluation of `design` if it was made already, else None."""
        key = _key(design)
        hit = self._cache.get(key)
        if hit is not None:
            self._cache.move_to_end(key)
        return hit

    def remember(self, design: Design, ev: dict[str, Any]) -> None:
        """Keep `ev` as the evaluation of `design` (one made elsewhere, e.g. in a worker process)."""
        self._store(_key(design), ev)

    def is_current(self, design: Design) -> bool:
        """True when `design` is the die being edited (equal in every field, not necessarily the same object)."""
        return _key(design) == _key(self.design)

    def _store(self, key: tuple, ev: dict[str, Any]) -> None:
        self._cache[key] = ev
        self._cache.move_to_end(key)
        while len(self._cache) > CACHE:
            self._cache.popitem(last=False)


def _key(design: Design) -> tuple:
    from dataclasses import astuple

    return (design.name, design.family, tuple(sorted(design.params.items())), tuple(sorted(design.values.items())),
            design.target, design.size_mm, astuple(design.fill), design.vertices, design.faces)  # fmt: skip


def face_colors(probabilities: np.ndarray, top: float | None = None) -> list[str]:
    """``#rrggbb`` of each probability on the studio's scale (0 pale yellow ... `top` dark red).

    Parameters
    ----------
    probabilities : (m,) float
    top : float, optional
        Probability drawn darkest (default: the largest given).
    """
    p = np.asarray(probabilities, dtype=float)
    top = float(p.max()) if top is None else float(top)
    t = np.clip(p / top, 0.0, 1.0) if top > 0 else np.zeros_like(p)
    return [_ramp(x) for x in t]


#: The scale's stops (position, RGB): the sequential "YlOrRd" ramp's ends and middle.
SCALE = ((0.0, (255, 255, 204)), (0.5, (253, 141, 60)), (1.0, (128, 0, 38)))


def _ramp(t: float) -> str:
    for (t0, c0), (t1, c1) in zip(SCALE, SCALE[1:]):
        if t <= t1:
            w = (t - t0) / (t1 - t0)
            rgb = [round(a + (b - a) * w) for a, b in zip(c0, c1)]
            return "#{:02x}{:02x}{:02x}".format(*rgb)
    return "#{:02x}{:02x}{:02x}".format(*SCALE[-1][1])
