"""A search's run folder: its description (``run.json``), its identity, and the log of its evaluations.

Each evaluation is one JSON line, appended, flushed and fsynced as it
finishes (``evaluations.jsonl``).  A resumed run reads the log back strictly,
every field typed and bounded, and replays it; a run whose description or
inputs changed since it started is refused by name.
"""

from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path
from typing import Any

from diefab.core.errors import DiefabError, OutputError
from diefab.core.files import hold_lock, write_files
from diefab.physics.simulate import MAX_DROPS
from diefab.search.runspec import RunError, RunSpec, is_finite_number

__all__ = ["RunLog"]


class RunLog:
    """A run folder: ``run.json`` (the :class:`RunSpec`) and ``evaluations.jsonl``.

    Each evaluation is one JSON line, appended, flushed and fsynced as it
    finishes.  A line torn by a kill can only be the last one: :meth:`read`
    skips it (and reports it), and :meth:`open` cuts it off before anything
    is appended.
    """

    #: Keys every simulated (feasible) record holds.
    FEASIBLE: tuple[str, ...] = ("min_margin",)

    def __init__(self, folder: str | Path) -> None:
        from diefab.search.runid import IDENTITY_FILE

        self.folder = Path(folder)
        self.spec_path = self.folder / "run.json"
        self.path = self.folder / "evaluations.jsonl"
        self.identity_path = self.folder / IDENTITY_FILE
        self._fh = None
        self._created = False  # create() made the folder itself

    def lock(self, _creating: bool = False) -> None:
        """Take the run's lock (until :func:`diefab.core.files.release_locks`): a second process is refused.

        Raises
        ------
        diefab.core.files.LockError
            Another process runs or resumes this run; the message names its id.
        """
        from diefab.core.files import ensure_dir

        folder = Path(os.path.abspath(self.folder))
        if not folder.is_dir():  # a resume of nothing: spec_text() says so; a new run: its parent is made now
            if not _creating:
                return
            ensure_dir(folder.parent)
        hold_lock(folder.resolve() if folder.exists() else folder, f"run {self.folder}")

    def holds_run(self) -> bool:
        """True when the folder holds a run with at least one evaluation (an empty start can be replaced)."""
        try:
            return self.path.stat().st_size > 0
        except FileNotFoundError:
            return False

    def create(self, spec: RunSpec) -> None:
        """Start the run: take its lock (:meth:`lock`), then write ``run.json``, its identity and an empty log."""
        self.lock(_creating=True)
        if self.holds_run():
            raise RunError(f"{self.folder} already holds a run: resume it with --resume {self.folder} or pick --name")
        self._created = not self.folder.exists()
        try:
            self._write_spec(spec, {self.path: b""})
        except BaseException:
            if self._created:  # a full disk: no empty run folder left to block the rerun
                with contextlib.suppress(OSError):
                    self.folder.rmdir()
            raise

    def update(self, spec: RunSpec) -> None:
        """Rewrite ``run.json`` and its identity (a resumed run's new budget, given on the command line)."""
        self._write_spec(spec)

    def _write_spec(self, spec, others=None) -> None:
        from diefab.search.runid import identity_text

        text = spec.to_json()
        write_files({self.spec_path: text, self.identity_path: identity_text(text), **(others or {})})

    def discard(self, *others: Path) -> None:
        """Remove a run that never logged an evaluation: its files, `others`, and the folder if this made it."""
        if self.holds_run():
            return
        self.close()
        for path in (self.spec_path, self.path, self.identity_path, *others):
            Path(path).unlink(missing_ok=True)
        if self._created:
            with contextlib.suppress(OSError):
                self.folder.rmdir()

    def spec(self) -> RunSpec:
        text = self.spec_text()
        spec = RunSpec.from_json(text, str(self.spec_path))
        self.check_identity(text)
        from diefab.physics.simulate import PhysicsSettings

        try:  # the design and every physics table must load before anything runs
            spec.design  # noqa: B018
            for table in (spec.physics, *spec.robust):
                PhysicsSettings.from_mapping(table)
        except (DiefabError, ValueError, KeyError, TypeError, AttributeError) as exc:
            raise RunError(f"{self.spec_path} is not a diefab run description: {exc}") from None
        return spec

    def spec_text(self) -> str:
        """The text of ``run.json``, once the folder is known to hold a run."""
        if not self.folder.is_dir():
            state = "is not a folder" if self.folder.exists() else "does not exist"
            raise RunError(f"resume folder {self.folder} {state}")
        if not self.spec_path.is_file() or not self.path.is_file():
            raise RunError(f"{self.folder} is not a diefab run folder (no run.json or evaluations.jsonl)")
        raw = _read_capped(self.spec_path, SPEC_MAX)
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise RunError(
                f"{self.spec_path} is not UTF-8 text (byte {exc.start}); the run cannot be resumed"
            ) from None

    def check_identity(self, text: str) -> None:
        """Refuse a run whose ``run.json`` or design files changed since it started, naming the fields.

        Raises
        ------
        RunError
            The identity file is missing or corrupt, or a field differs.
        """
        from diefab.search.runid import compare_identity

        if not self.identity_path.is_file():
            raise RunError(f"{self.folder} has no {self.identity_path.name} (the record of what the run was "
                           "started with): it cannot be resumed safely; start a new run")  # fmt: skip
        try:
            changed = compare_identity(text, _read_capped(self.identity_path, SPEC_MAX).decode("utf-8"))
        except (DiefabError, UnicodeDecodeError) as exc:
            raise RunError(f"{self.identity_path}: {exc}; the run cannot be resumed") from None
        if changed:
            shown = ", ".join(changed[:4]) + (f" and {len(changed) - 4} more" if len(changed) > 4 else "")
            raise RunError(f"run {self.folder} changed since it started: {shown} differ(s) from what it was started "
                           f"with (recorded in {self.identity_path}); it cannot be resumed")  # fmt: skip

    def read(self) -> tuple[list[dict[str, Any]], str | None]:
        """The logged records, and a warning if a torn last line was skipped.

        Raises
        ------
        RunError
            A corrupt line before the last, naming it.
        """
        raw = _read_capped(self.path, LOG_MAX)
        lines = raw.split(b"\n")
        complete, tail = lines[:-1], lines[-1]  # text after the last newline was cut mid-write
        records, warning = [], None
        for number, line in enumerate(complete, start=1):
            record = _parse_record(line, len(records))
            if record is None:
                if number == len(complete) and not tail.strip():
                    warning = f"{self.path} line {number} is incomplete (killed mid-write?); skipped"
                    break
                raise RunError(f"{self.path} line {number} is corrupt; the run cannot be resumed")
            records.append(record)
        if tail.strip():
            if warning is None and _parse_record(tail, len(records)) is not None:
                records.append(_parse_record(tail, len(records)))
            else:
                warning = f"{self.path} line {len(complete) + 1} is incomplete (killed mid-write?); skipped"
        self._good = sum(len(line) + 1 for line in complete[: len(records)])
        if len(records) > len(complete):
            self._good = len(raw)
        names = set(self.spec().names)
        for number, record in enumerate(records, start=1):
            if not names <= set(record["params"]) or (record["feasible"] and not all(
                    k in record for k in self.FEASIBLE)):  # fmt: skip
                raise RunError(f"{self.path} line {number} is corrupt (not an evaluation of this run); the run "
                               "cannot be resumed")  # fmt: skip
        return records, warning

    def open(self) -> None:
        """Open for appending, cutting off a torn last line first (call :meth:`read` before)."""
        good = getattr(self, "_good", None)
        fh = open(self.path, "r+b", buffering=0)  # noqa: SIM115 -- kept open for the run, closed by close()
        if good is not None:
            fh.truncate(good)
            fh.seek(good)
            if good and not self.path.read_bytes()[:good].endswith(b"\n"):
                fh.write(b"\n")
        else:
            fh.seek(0, os.SEEK_END)
        self._fh = fh

    def append(self, record: dict[str, Any]) -> None:
        """Log `record` as one line, on disk when this returns.

        Raises
        ------
        OutputError
            The line could not be written (a full disk); the log is cut back
            to the lines before it, so the run can be resumed.
        """
        line = memoryview(json.dumps(record, separators=(",", ":"), allow_nan=False).encode() + b"\n")
        start = self._fh.tell()
        try:
            while line:  # an unbuffered write may take part of the line
                line = line[self._fh.write(line) :]
            os.fsync(self._fh.fileno())
        except OSError as exc:
            with contextlib.suppress(OSError):
                self._fh.truncate(start)
                self._fh.seek(start)
            raise OutputError(f"cannot write {self.path}: {exc.strerror or exc}") from exc

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None


#: Largest ``run.json`` read, bytes (a calibration of many dice is a few hundred kilobytes).
SPEC_MAX = 64 << 20
#: Largest ``evaluations.jsonl`` read, bytes (a month-long run logs a few tens of megabytes).
LOG_MAX = 1 << 30


def _read_capped(path: Path, limit: int) -> bytes:
    """The bytes of `path`, refusing a file larger than `limit` (RunError)."""
    try:
        with open(path, "rb") as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise RunError(f"cannot read {path}: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise RunError(f"{path} is larger than {limit >> 20} MiB, more than any run writes; it cannot be resumed")
    return data


#: Optional keys of a record that must be numbers when present.
_NUMBERS = ("elapsed", "seconds", "min_margin", "deviance", "prior", "cocked", "unsettled")
_REQUIRED = {"i": int, "kind": str, "x": list, "params": dict, "drops": int, "objective": float, "feasible": bool}


def _parse_record(line: bytes, index: int) -> dict[str, Any] | None:
    try:
        record = json.loads(line)
    except (ValueError, UnicodeDecodeError):
        return None
    if not isinstance(record, dict):
        return None
    for key, kind in _REQUIRED.items():
        value = record.get(key)
        if kind is float:
            ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        else:
            ok = isinstance(value, kind) and not (kind is int and isinstance(value, bool))
        if not ok:
            return None
    if not 0 <= record["drops"] <= MAX_DROPS or not is_finite_number(record["objective"]):
        return None
    if not all(is_finite_number(v) for v in record["x"]) or not all(
        is_finite_number(v) for v in record["params"].values()
    ):
        return None
    if not all(is_finite_number(record[k]) for k in _NUMBERS if k in record):
        return None
    counts = record.get("face_counts", [])
    if not (isinstance(counts, list) and all(isinstance(c, int) and not isinstance(c, bool) and c >= 0 for c in counts)
            and sum(counts) <= record["drops"]):  # fmt: skip
        return None
    return record if record["i"] == index else None
