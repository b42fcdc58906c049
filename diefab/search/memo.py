"""Model optimizations kept in a folder: a search run again takes each one it made instead of repeating it.

:func:`~diefab.search.optimize.optimize_design` is a function of its start
design, its options and the landing models' code.  :class:`OptimizationMemo`
keeps each result it computes in a JSON file named by a digest of the first
two and the package's version, its numbers exact (``float.hex``), and takes
a kept result only where the models, evaluated again at its parameters, give
exactly the objective, values and margins it kept: one evaluation instead of
thousands, and a result the models no longer give is computed again, not
taken.  A failed optimization is kept as its message.  An optimization with
a wall-time deadline is not a function of its inputs, and is neither kept
nor taken.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.design import Design
from diefab.dice.readings import KINDS
from diefab.search.optimize import OptimizationResult, Problem, optimize_design

__all__ = ["OptimizationMemo"]

#: Largest file read as a kept optimization (one holds a few kilobytes).
MAX_BYTES = 1 << 20


class OptimizationMemo:
    """The optimizations of one search, kept in the folder ``optimized`` of `folder`.

    :meth:`optimize` takes the arguments of
    :func:`~diefab.search.optimize.optimize_design`; :attr:`found` and
    :attr:`made` count the results taken from the folder and those computed.
    """

    FOLDER = "optimized"

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder) / self.FOLDER
        self.found = self.made = 0

    def optimize(self, design: Design, **options: Any) -> OptimizationResult:
        """:func:`~diefab.search.optimize.optimize_design` of `design`, from the folder where it holds."""
        deadline = options.get("deadline")
        if deadline is not None and np.isfinite(deadline):
            return optimize_design(design, **options)
        key = _digest(design, options)
        path = self.folder / f"{key[:32]}.json"
        kept = _read(path, key)
        if kept is not None and "error" in kept:
            self.found += 1
            raise DesignError(kept["error"])
        if kept is not None:
            result = _result(design, kept, options)
            if result is not None:
                self.found += 1
                return result
        try:
            result = optimize_design(design, **options)
        except DesignError as exc:
            self._write(path, {"key": key, "error": str(exc)})
            raise
        self._write(path, {"key": key, **_numbers(result)})
        return result

    def _write(self, path: Path, data: dict[str, Any]) -> None:
        from diefab.core.files import atomic_write, ensure_dir

        ensure_dir(self.folder)
        atomic_write(path, json.dumps(data, sort_keys=True) + "\n")
        self.made += 1


def _digest(design: Design, options: dict[str, Any]) -> str:
    """Hex digest of what decides an optimization: the start design, the options and the package's version."""
    from importlib.metadata import PackageNotFoundError, version

    from diefab.dice.design import design_to_toml

    try:
        package = version("diefab")
    except PackageNotFoundError:  # pragma: no cover - run from a checkout that was never installed
        package = "unknown"

    correction = options.get("correction")
    plain = {k: (list(v) if isinstance(v, tuple) else v) for k, v in options.items()
             if k not in ("deadline", "correction")}  # fmt: skip
    if correction is not None:
        array = np.ascontiguousarray(correction, dtype=np.float64)
        plain["correction"] = [list(array.shape), hashlib.sha256(array.tobytes()).hexdigest()]
    digest = hashlib.sha256()
    for part in (design_to_toml(design), json.dumps(plain, sort_keys=True, default=str), package):
        digest.update(part.encode("utf-8") + b"\0")
    return digest.hexdigest()


def _numbers(result: OptimizationResult) -> dict[str, Any]:
    """The result's numbers, exactly (``float.hex``), and the name and description of its design."""
    return {"params": [[k, float(v).hex()] for k, v in result.design.params.items()],  # in the design's order
            "objective": float(result.objective).hex(), "values": [float(v).hex() for v in result.values],
            "margins": [float(m).hex() for m in result.margins], "evaluations": int(result.evaluations),
            "starts": int(result.starts), "feasible_starts": int(result.feasible_starts),
            "name": result.design.name, "description": result.design.description}  # fmt: skip


def _read(path: Path, key: str) -> dict[str, Any] | None:
    """The kept result of `key` at `path`, or None (no file, another key, a file that is not one or is too large)."""
    from diefab.core.files import check_size

    try:
        check_size(path, MAX_BYTES, "kept optimization", ValueError)
        kept = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return kept if isinstance(kept, dict) and kept.get("key") == key else None


def _result(design: Design, kept: dict[str, Any], options: dict[str, Any]) -> OptimizationResult | None:
    """The kept result as an :class:`OptimizationResult`, if the models give it again at its parameters."""
    try:
        params = {str(k): float.fromhex(v) for k, v in kept["params"]}
        objective = float.fromhex(kept["objective"])
        values = np.array([float.fromhex(v) for v in kept["values"]])
        margins = np.array([float.fromhex(m) for m in kept["margins"]])
        counts = int(kept["evaluations"]), int(kept["starts"]), int(kept["feasible_starts"])
        found = replace(design, params=params, name=str(kept["name"]), description=str(kept["description"]))
    except (KeyError, TypeError, ValueError, AttributeError, DesignError):
        return None
    from diefab.dice.families import family

    names = options.get("names") or family(design.family).free_names(design.params)
    problem = Problem(design, tuple(names), options.get("model", "solid-angle"), options.get("objective", "eq2"),
                      options.get("min_margin", 0.05), options.get("correction"),
                      tuple(options.get("read_by", KINDS)))  # fmt: skip
    f, v, m = problem.evaluate(params)
    if f != objective or not np.array_equal(v, values, equal_nan=True) or not np.array_equal(m, margins):
        return None
    return OptimizationResult(found, objective, values, margins, *counts)
