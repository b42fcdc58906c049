"""Reading a source of frames into a roll log: what ``diefab read`` and the studio's camera tab share.

:class:`LogReading` holds one roll log for one :class:`~.reader.RollReader`.
It cuts a line that a crash left torn before it appends, numbers frames after
those already logged, and appends each roll durably.  From a folder of photos
it reads only the photos the log does not already hold (by their content:
:data:`~diefab.stats.rolllog.SOURCE_PREFIX`), and checks that each of them
decodes before it reads any.  The rolls read before the die is first seen
for sure are held back until it is, so a source that shows another die (the
reader's :class:`~.pose.MarkerError`) leaves the log as it was.

The caller holds the log's lock (:func:`~diefab.core.files.hold_lock`).
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from diefab.camera.pose import FrameRead
from diefab.camera.reader import RollReader, frames, photo_files, read_photo
from diefab.stats.rolllog import Roll, append_roll, read_log, repair_log

__all__ = ["LogReading", "Reading", "photo_digest"]


@dataclass(frozen=True)
class Reading:
    """One frame read: its time, the frame, what it shows (None: not read) and the roll it ended (None: none)."""

    time: float
    gray: np.ndarray
    seen: FrameRead | None
    roll: Roll | None


def photo_digest(path: str | Path) -> str:
    """``sha256:`` and the first 16 hex digits of the SHA-256 of a file's bytes."""
    with open(path, "rb") as f:
        return "sha256:" + hashlib.file_digest(f, "sha256").hexdigest()[:16]


class LogReading:
    """The rolls `reader` reads, appended to the roll log `log`.

    Attributes
    ----------
    rows : list of Roll
        The log's rolls: those it held, then those read (held-back rolls included).
    skipped : int
        Photos of the folder read that were not read again: the log held them, or they are copies of
        another photo of the folder.
    """

    def __init__(self, reader: RollReader, log: str | Path) -> None:
        self.reader, self.log = reader, Path(log)
        if self.log.exists():
            held = read_log(self.log)  # refuses a file that is not a roll log
            if held.torn:
                repair_log(self.log)
            self.rows, self._digests = list(held.rolls), set(held.digests)
        else:
            self.rows, self._digests = [], set()
        self._offset = max((r.frame for r in self.rows if r.frame is not None), default=-1) + 1
        self._pending: list[Roll] = []
        self.skipped = 0

    def read(self, *, camera: int | None = None, video=None, images=None, ignore=()) -> Iterator[Reading]:
        """Read exactly one source, yielding every frame; each roll is in the log once the die has been seen.

        `ignore` names files of an image folder that are not photos of rolls
        (the pictures the reading itself writes there).

        Raises
        ------
        SourceError, MarkerError
            As :func:`~.reader.frames` and :class:`~.reader.RollReader`: a bad source, or another die.
        """
        if images is not None:
            stream = self._photos(images, {Path(p).resolve() for p in ignore})
        else:
            stream = ((t, gray, None) for t, gray in frames(camera=camera, video=video))
        reader = self.reader
        names = reader.design.polyhedron.names
        for t, gray, source in stream:
            seen, settled = reader.feed_rest(gray) if images is not None else reader.feed(gray)
            row = None
            if settled is not None:
                face = None if settled.face is None else names[settled.face]
                confidence = round(float(settled.confidence), 4)
                row = Roll(f"{t:.3f}", settled.value, face, confidence, self._offset + settled.frame, source)
                self.rows.append(row)
                self._pending.append(row)
                if reader.detections:
                    self._flush()
            yield Reading(t, gray, seen, row)
        self._flush()

    def skipped_line(self, folder) -> str:
        """One line on the photos of `folder` not read again ("" when none)."""
        n = self.skipped
        if not n:
            return ""
        photos = f"{n} photo{'s' * (n != 1)} of {folder} {'were' if n != 1 else 'was'}"
        return f"{photos} read before (in the log, or a copy of another): not read again"

    def _photos(self, folder, ignore: set[Path]) -> Iterator[tuple[float, np.ndarray, str]]:
        todo = []
        for i, path in enumerate(p for p in photo_files(folder) if p.resolve() not in ignore):
            digest = photo_digest(path)
            if digest in self._digests:
                self.skipped += 1
                continue
            read_photo(path)  # every photo decodes before any is read
            self._digests.add(digest)
            name = path.name if path.name.isprintable() else repr(path.name)
            todo.append((float(i), path, f"{digest} {name}"))
        for t, path, source in todo:
            yield t, read_photo(path), source

    def _flush(self) -> None:
        while self._pending:
            append_roll(self.log, self._pending[0])
            self._pending.pop(0)
