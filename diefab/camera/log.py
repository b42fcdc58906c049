"""The roll log: one CSV row per settled roll, written so that a stop never loses or corrupts it.

Columns: ``time,value,face,confidence,frame`` -- the source's time in seconds,
the value read (empty: unread), the resting face's name (empty: unread), the
confidence and the frame the roll settled at.  :func:`append_roll` rewrites
the whole file through a temporary file and a rename, so the log on disk is
always a complete log; :func:`read_log` reads it back, so a stopped session
resumes with its counts.

Examples
--------
>>> import tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "rolls.csv"
>>> append_roll(path, [LogRow(1.5, 3, "f2", 0.97, 45)])
>>> [r.value for r in read_log(path)]
[3]
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from diefab.core.errors import StatsError
from diefab.core.files import atomic_write

__all__ = ["HEADER", "LogRow", "append_roll", "read_log"]

HEADER = ("time", "value", "face", "confidence", "frame")


@dataclass(frozen=True)
class LogRow:
    """One roll of the log (value and face None: unread)."""

    time: float
    value: int | None
    face: str | None
    confidence: float
    frame: int


def _format(rows: Sequence[LogRow]) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(HEADER)
    for r in rows:
        value = "" if r.value is None else str(r.value)
        writer.writerow([f"{r.time:.3f}", value, r.face or "", f"{r.confidence:.3f}", str(r.frame)])
    return out.getvalue()


def read_log(path: str | Path) -> list[LogRow]:
    """The rows of a roll log ([] when the file does not exist)."""
    path = Path(path)
    if not path.exists():
        return []
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise StatsError(f"cannot read roll log {path}: {exc}") from exc
    rows = list(csv.reader(io.StringIO(text)))
    if not rows or tuple(h.strip() for h in rows[0]) != HEADER:
        raise StatsError(f"roll log {path} does not start with the header {','.join(HEADER)}")
    out = []
    for i, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        try:
            t, value, face, confidence, frame = row
            out.append(LogRow(float(t), int(value) if value else None, face or None, float(confidence), int(frame)))
        except ValueError as exc:
            raise StatsError(f"{path}:{i}: malformed roll {','.join(row)!r} ({exc})") from None
    return out


def append_roll(path: str | Path, rows: Sequence[LogRow], *, existing: Sequence[LogRow] | None = None) -> None:
    """Append `rows` to the log at `path`: the whole log is rewritten atomically.

    `existing` is the log's current content when the caller holds it (it is read from disk otherwise).
    """
    before = read_log(path) if existing is None else list(existing)
    atomic_write(path, _format([*before, *rows]))
