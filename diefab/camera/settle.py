"""When a roll has ended: one roll per settle, never a double count.

:class:`Settler` takes what each frame shows (:class:`~.pose.FrameRead`) and
whether the frame moved, and says when a roll is over:

* any motion (the image changed, or the die's pose moved) starts a new
  settle window, and arms the next count;
* once the scene has been still for `settle` frames, an armed settle gives
  one :class:`Roll` (as soon as any marker is in view): its value when at least half the window's frames read
  the same face at the reader's confidence and none read another, else
  ``unread`` (value None) -- a die in motion, a hand over it, a pose that
  does not say one face clearly is never guessed;
* a settle whose pose is the last counted roll's (the same face, place and
  turn on the table, judged on the markers' image corners: a hand passed
  over a die that did not move, the light changed) counts nothing.

Examples
--------
>>> settler = Settler(settle=3)
>>> from diefab.camera.pose import FrameRead
>>> still = FrameRead(None, 2, 5, 0.9, detected=1)
>>> [settler.feed(i, still, moving=(i == 0)) for i in range(5)][3].value
5
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from diefab.camera.pose import FrameRead

__all__ = ["Roll", "Settler", "same_rest"]

#: Two rests on the same face are the same when each corner of the markers seen in both moved less than this many
#: marker sides (on average): the same place and the same turn, so a die dropped again that lands on the same face,
#: near the same place but turned, counts.
SAME_PLACE = 0.5
#: The die moved between two frames when a marker seen in both moved more than this many marker sides.
STILL_PLACE = 0.2


@dataclass(frozen=True)
class Roll:
    """One settled roll: the frame it settled at, the value and face read (None: unread), the confidence."""

    frame: int
    value: int | None
    face: int | None
    confidence: float


def marker_shift(a, b, *, corners: bool = False) -> float | None:
    """How far the markers seen in both frames moved, in marker sides (None: none in common).

    The median over the markers of how far each one's centre moved, or with `corners` of how far its
    corners moved (on average, each to its own): a turn in place moves the corners, not the centre.
    Measured on the image, not on the poses: a lone marker's pose may flip between its two planar
    solutions from frame to frame while the die lies still.
    """
    if not a.corners or not b.corners:
        return None
    common = set(a.corners) & set(b.corners)
    if not common:
        return None
    shifts = []
    for m in common:
        p, q = np.asarray(a.corners[m]), np.asarray(b.corners[m])
        side = float(np.linalg.norm(p - np.roll(p, 1, axis=0), axis=1).mean())
        moved = np.linalg.norm(p - q, axis=1).mean() if corners else np.linalg.norm(p.mean(axis=0) - q.mean(axis=0))
        shifts.append(float(moved) / max(side, 1.0))
    return float(np.median(shifts))


def same_rest(a, b) -> bool:
    """Whether reads `a` and `b` (:class:`~.pose.FrameRead`) show the die on the same face, place and turn."""
    shift = marker_shift(a, b, corners=True)
    return a.face == b.face and shift is not None and shift < SAME_PLACE


class Settler:
    """Counts rolls from a stream of frames.

    Parameters
    ----------
    settle : int
        Still frames before a roll is counted.
    size_mm : float
        The die's size (what "moved" and "the same place" are measured against).
    """

    def __init__(self, settle: int = 8, size_mm: float = 20.0) -> None:
        if settle < 1:
            raise ValueError(f"settle={settle} must be at least 1 frame")
        self.settle, self.size_mm = int(settle), float(size_mm)
        self.window: list[FrameRead] = []
        self.armed = True
        self.last_rest = None
        self._previous = None

    def moved(self, read: FrameRead) -> bool:
        """Whether the die's markers moved since the last frame that saw any of them."""
        prev, self._previous = self._previous, read if read.corners else self._previous
        shift = None if prev is None else marker_shift(read, prev)
        return shift is not None and shift > STILL_PLACE

    @property
    def needs_reading(self) -> bool:
        """Whether frames still matter: False once this settle is counted, until the next motion."""
        return self.armed

    def feed(self, frame: int, read: FrameRead, *, moving: bool) -> Roll | None:
        """Take one frame; return the :class:`Roll` it completes, if any."""
        if moving or self.moved(read):
            self.window.clear()
            self.armed = True
            return None
        self.window.append(read)
        del self.window[: -self.settle]
        if not self.armed or len(self.window) < self.settle:
            return None
        window = self.window
        if not any(r.detected for r in window):
            return None  # nothing of the die in view yet: keep looking
        self.armed = False
        reads = [r for r in window if r.face is not None]
        faces = Counter(r.face for r in reads)
        if len(faces) == 1 and 2 * len(reads) >= len(window):
            last = reads[-1]
            if self.last_rest is not None and same_rest(last, self.last_rest):
                return None
            self.last_rest = last
            confidence = float(np.median([r.confidence for r in reads]))
            return Roll(frame, last.value, last.face, confidence)
        confidence = float(max((r.confidence for r in window), default=0.0))
        return Roll(frame, None, None, confidence)
