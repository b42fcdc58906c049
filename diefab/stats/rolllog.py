"""Roll logs: one CSV line per roll, appended durably, read back strictly.

The format, shared by the camera reader and the hand tally::

    time,value,face,confidence,frame
    2026-05-01T18:03:11.250Z,-1,f3,0.998,1412
    2026-05-01T18:03:14.020Z,2,,,

``time``
    UTC, ISO 8601 with milliseconds and a ``Z`` (a hand tally), or seconds
    into the video (a camera reader).
``value``
    The value rolled (``-1``, ``+2`` and ``−3`` with a true minus are read);
    empty for a roll a machine reader saw but could not read (an unread
    roll: kept in the log, never counted).
``face``
    The resting face (``f3``), empty for a hand tally.
``confidence``
    The reader's confidence in [0, 1], empty for a hand tally.
``frame``
    The video frame the roll was read on, empty for a hand tally.

A line that starts with ``#`` is a comment.  A roll read from a file of its
own (a photo) is followed by ``# source sha256:DIGEST NAME``: the first 16
hex digits of the file's SHA-256 and its name, so that a folder read again
is not counted twice.

Each roll is one ``write`` of its whole lines with ``O_APPEND`` followed by
``fsync``: a crash loses at most the roll being written, and a line cut short
by a crash (no newline at its end) is never read as a roll.  Reopening a log
for writing removes such a line.

Examples
--------
>>> import tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "rolls.csv"
>>> append_roll(path, Roll.now(3))
>>> append_roll(path, Roll.now(-1))
>>> read_log(path).values.tolist()
[3, -1]
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from diefab.core.errors import StatsError
from diefab.core.files import atomic_write, output_path

__all__ = [
    "HEADER",
    "LOG_SUFFIX",
    "MAX_LOG_BYTES",
    "Roll",
    "RollLog",
    "SOURCE_PREFIX",
    "append_roll",
    "is_roll_log",
    "log_path",
    "parse_value",
    "read_log",
    "remove_last_roll",
    "repair_log",
]

#: The roll log's header line.
HEADER = ("time", "value", "face", "confidence", "frame")
#: Largest roll log read (about 2 million rolls).
MAX_LOG_BYTES = 100 << 20
#: A roll log's file name after its name: ``OUT/NAME-rolls.csv``, whether ``read`` or ``roll`` writes it.
LOG_SUFFIX = "-rolls.csv"
#: A comment line naming the file the roll above it was read from.
SOURCE_PREFIX = "# source "
#: The suffix hand tallies were once saved with; such a log, alone in its folder, is still read and resumed.
_OLD_SUFFIX = ".rolls.csv"


def log_path(folder: str | Path, name: str) -> Path:
    """The roll log of `name` in `folder`: ``NAME-rolls.csv``, or an existing ``NAME.rolls.csv`` when only it exists.

    Examples
    --------
    >>> log_path("rolls", "d6").as_posix()
    'rolls/d6-rolls.csv'
    """
    path = output_path(folder, name, LOG_SUFFIX)
    old = output_path(folder, name, _OLD_SUFFIX)
    return old if old.is_file() and not path.exists() else path


@dataclass(frozen=True)
class Roll:
    """One roll of a die.

    Attributes
    ----------
    time : str
        UTC time, ISO 8601 (``2026-05-01T18:03:11.250Z``), or seconds into a video.
    value : int or None
        The value rolled; None: seen but not read.
    face : str or None
        Resting face name (``f3``), if known.
    confidence : float or None
        Reader's confidence in [0, 1], if read by a machine.
    frame : int or None
        Video frame index, if read from video.
    source : str or None
        The file the roll was read from, if any: ``sha256:DIGEST NAME`` (one line).
    """

    time: str
    value: int | None
    face: str | None = None
    confidence: float | None = None
    frame: int | None = None
    source: str | None = None

    @classmethod
    def now(cls, value: int, face: str | None = None, confidence: float | None = None, frame: int | None = None):
        """A roll stamped with the current UTC time."""
        stamp = datetime.now(UTC).isoformat(timespec="milliseconds").replace("+00:00", "Z")
        return cls(stamp, None if value is None else int(value), face, confidence, frame)

    def line(self) -> str:
        """The roll as one CSV line, newline included."""
        if self.face is not None and not re.fullmatch(r"[A-Za-z0-9_.\-]+", self.face):
            raise StatsError(f"face name {self.face!r} must be letters, digits, '_', '.' or '-'")
        if self.confidence is not None and not (0 <= self.confidence <= 1):
            raise StatsError(f"confidence={self.confidence!r} is outside [0, 1]")
        cells = [
            self.time,
            "" if self.value is None else str(int(self.value)),
            self.face or "",
            "" if self.confidence is None else f"{self.confidence:.4f}",
            "" if self.frame is None else str(int(self.frame)),
        ]
        line = ",".join(cells) + "\n"
        if self.source is not None:
            if not self.source.isprintable():
                raise StatsError(f"source {self.source!r} must be one line of printable text")
            line += SOURCE_PREFIX + self.source + "\n"
        return line


@dataclass(frozen=True, eq=False)
class RollLog:
    """The rolls of one log, in order.

    Attributes
    ----------
    path : Path
    rolls : tuple of Roll
    torn : bool
        The file ended in a line cut short by a crash (ignored).
    """

    path: Path
    rolls: tuple[Roll, ...]
    torn: bool = False

    @property
    def values(self) -> np.ndarray:
        """(n,) int64 values read, in the order rolled (unread rolls left out)."""
        return np.array([r.value for r in self.rolls if r.value is not None], dtype=np.int64)

    @property
    def unread(self) -> int:
        """Rolls seen but not read."""
        return sum(r.value is None for r in self.rolls)

    @property
    def digests(self) -> frozenset[str]:
        """``sha256:DIGEST`` of every file a roll of the log was read from."""
        return frozenset(r.source.split()[0] for r in self.rolls if r.source)

    def __len__(self) -> int:
        return len(self.rolls)


def is_roll_log(first_line: str) -> bool:
    """Whether a header line is the roll-log header."""
    return tuple(h.strip().lower() for h in first_line.strip().split(",")) == HEADER


def _cell(token: str, where: str, name: str, kind):
    t = token.strip()
    if t == "":
        return None
    try:
        value = kind(t)
    except ValueError:
        expected = "a number" if kind is float else "a whole number"
        raise StatsError(f"{where}: {name} {_short(t)!r} is not {expected}") from None
    if kind is float and not (math.isfinite(value) and 0 <= value <= 1):
        raise StatsError(f"{where}: confidence {_short(t)!r} is outside [0, 1]")
    return value


def _short(text: str, width: int = 40) -> str:
    return text if len(text) <= width else text[: width - 3] + "..."


def parse_value(token: str, where: str) -> int:
    """A die value from a token (``+2``, ``-3`` and ``−3`` accepted); StatsError naming `where` otherwise."""
    t = token.strip().replace("\u2212", "-").replace("\u2013", "-")
    if not re.fullmatch(r"[+-]?\d+", t):
        raise StatsError(f"{where}: {_short(token.strip())!r} is not a whole-number roll")
    if len(t.lstrip("+-").lstrip("0")) > 9:
        raise StatsError(f"{where}: {_short(token.strip())!r} is not a die value (magnitude at most 10^9)")
    return int(t)


def _read_text(path: Path) -> str:
    if path.exists() and not path.is_file():
        raise StatsError(f"roll log {path} is not a regular file")
    try:
        if path.stat().st_size > MAX_LOG_BYTES:
            raise StatsError(f"roll log {path} is larger than {MAX_LOG_BYTES >> 20} MiB")
        return path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise StatsError(f"cannot read roll log {path}: {exc}") from exc


def read_log(path: str | Path) -> RollLog:
    """Read a roll log strictly: a bad cell is an error naming its line and token.

    Raises
    ------
    StatsError
        The file is missing, unreadable, not a roll log, or has a bad line.
    """
    path = Path(path)
    text = _read_text(path)
    lines = text.split("\n")
    torn = lines[-1] != ""  # the last line has no newline: cut short by a crash
    lines = lines[:-1] if len(lines) > 1 or not is_roll_log(lines[0]) else lines  # a header alone is a header
    if not lines or not is_roll_log(lines[0]):
        raise StatsError(f"{path}:1: not a roll log (its first line must be {','.join(HEADER)})")
    rolls = []
    for i, line in enumerate(lines[1:], start=2):
        if line.startswith(SOURCE_PREFIX) and rolls and rolls[-1].source is None and line[len(SOURCE_PREFIX) :].strip():
            rolls[-1] = replace(rolls[-1], source=line[len(SOURCE_PREFIX) :].strip())
            continue
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        where = f"{path}:{i}"
        row = next(csv.reader(io.StringIO(line)))
        if len(row) != len(HEADER):
            raise StatsError(f"{where}: {len(row)} cells in {_short(line.strip())!r}, expected {len(HEADER)}")
        stamp, value, face, confidence, frame = row
        rolls.append(
            Roll(
                stamp.strip(),
                None if not value.strip() else parse_value(value, where),
                face.strip() or None,
                _cell(confidence, where, "confidence", float),
                _cell(frame, where, "frame", int),
            )
        )
    return RollLog(path, tuple(rolls), torn)


def repair_log(path: str | Path) -> int:
    """Create the log with its header if missing; cut a torn last line, or end a header alone.  Returns the bytes cut.

    Call it once, holding the log's lock, before appending.
    """
    path = Path(path)
    if not path.exists():
        atomic_write(path, ",".join(HEADER) + "\n")
        return 0
    read_log(path)  # refuse to append to a file that is not a roll log
    try:
        with open(path, "rb+") as f:
            data = f.read()
            keep = data.rfind(b"\n") + 1
            if keep == 0:  # the header alone, without its line end: end it
                f.write(b"\n")
            elif keep < len(data):
                f.truncate(keep)
            else:
                return 0
            f.flush()
            os.fsync(f.fileno())
            return len(data) - keep if keep else 0
    except OSError as exc:
        raise StatsError(f"cannot open roll log {path} for writing: {exc.strerror or exc}") from exc


def append_roll(path: str | Path, roll: Roll) -> None:
    """Append one roll durably: its lines in one write, then fsync.

    The log is created with its header if it does not exist.  A write that
    fails or is cut short (a full disk) is cut back off, so that the log
    holds the roll whole, with its source, or not at all.
    """
    path = Path(path)
    if not path.exists():
        repair_log(path)
    payload = roll.line().encode("utf-8")
    try:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND)
    except OSError as exc:
        raise StatsError(f"cannot append to roll log {path}: {exc.strerror or exc}") from exc
    try:
        size = os.fstat(fd).st_size
        try:
            written = os.write(fd, payload)
            if written != len(payload):
                raise StatsError(f"could not append a whole roll to {path} (disk full?)")
            os.fsync(fd)
        except (OSError, StatsError):
            _cut_back(fd, size)
            raise
    except OSError as exc:
        raise StatsError(f"cannot append to roll log {path}: {exc.strerror or exc}") from exc
    finally:
        os.close(fd)


def _cut_back(fd: int, size: int) -> None:
    """Truncate the file open as `fd` to `size` bytes, as far as the system lets."""
    try:
        os.ftruncate(fd, size)
        os.fsync(fd)
    except OSError:
        pass


def remove_last_roll(path: str | Path) -> Roll:
    """Remove the last roll read (an undo of the last value counted) from the log; returns it.

    Its source line goes with it, and so does a torn last line; rolls seen
    but not read after it stay.  When it is the log's last roll the cut is
    one ``ftruncate`` followed by ``fsync``, else the log is rewritten
    atomically: the log holds the roll or not, never part of it.
    """
    path = Path(path)
    log = read_log(path)
    read = [r for r in log.rolls if r.value is not None]
    if not read:
        raise StatsError(f"roll log {path} has no roll read to remove")
    try:
        with open(path, "rb+") as f:
            data = f.read()
            lines = data[: data.rfind(b"\n") + 1].split(b"\n")[:-1]
            j = max(i for i in range(1, len(lines)) if _read_roll_line(lines[i]))
            k = j + 1  # the comment lines that follow a roll are its own (its source)
            while k < len(lines) and (not lines[k].strip() or lines[k].lstrip().startswith(b"#")):
                k += 1
            if any(line.strip() for line in lines[k:]):  # unread rolls after it stay
                atomic_write(path, b"".join(line + b"\n" for line in lines[:j] + lines[k:]))
                return read[-1]
            f.truncate(sum(len(line) + 1 for line in lines[:j]))
            f.flush()
            os.fsync(f.fileno())
    except OSError as exc:
        raise StatsError(f"cannot remove the last roll of {path}: {exc.strerror or exc}") from exc
    return read[-1]


def _read_roll_line(line: bytes) -> bool:
    """Whether a line of a log (read strictly before) is a roll with a value."""
    text = line.decode("utf-8", errors="replace").strip()
    if not text or text.startswith("#"):
        return False
    row = next(csv.reader(io.StringIO(text)))
    return len(row) == len(HEADER) and bool(row[1].strip())
