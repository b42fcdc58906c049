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
* a settle whose pose is the last counted roll's (the same place and
  orientation: a hand passed over a die that did not move, the light
  changed) counts nothing.

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

from .pose import FrameRead

__all__ = ["Roll", "Settler", "same_rest"]

#: Two rests are the same when the die moved less than this fraction of its size and turned less than this.
SAME_PLACE, SAME_TURN_DEG = 0.25, 15.0
#: The die moved between two frames when its origin moved more than this fraction of its size.
STILL_PLACE = 0.06


@dataclass(frozen=True)
class Roll:
    """One settled roll: the frame it settled at, the value and face read (None: unread), the confidence."""

    frame: int
    value: int | None
    face: int | None
    confidence: float


def same_rest(a, b, size_mm: float, place: float = SAME_PLACE, turn_deg: float = SAME_TURN_DEG) -> bool:
    """Whether poses `a` and `b` (:class:`~.pose.Pose`) put the die in the same place and orientation."""
    moved = float(np.linalg.norm(a.translation - b.translation))
    cos = (np.trace(a.rotation @ b.rotation.T) - 1) / 2
    return moved < place * size_mm and np.degrees(np.arccos(np.clip(cos, -1, 1))) < turn_deg


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
        """Whether `read`'s pose moved from the previous frame's (both must have a pose)."""
        prev, self._previous = self._previous, read.pose if read.pose is not None else self._previous
        if read.pose is None or prev is None:
            return False
        return float(np.linalg.norm(read.pose.translation - prev.translation)) > STILL_PLACE * self.size_mm

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
            if (
                self.last_rest is not None
                and last.pose is not None
                and same_rest(last.pose, self.last_rest, self.size_mm)
            ):
                return None
            self.last_rest = last.pose
            confidence = float(np.median([r.confidence for r in reads]))
            return Roll(frame, last.value, last.face, confidence)
        confidence = float(max((r.confidence for r in window), default=0.0))
        return Roll(frame, None, None, confidence)
