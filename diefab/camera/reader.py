"""Reading rolls from a stream of frames: motion, markers, pose, settle.

:class:`RollReader` takes grayscale frames one by one.  Each frame is first
compared with the last one at 1/8 scale (cheap, and blind to a uniform change
of light); a frame that moved resets the settle window and is not searched
for markers at all, since a die in motion is never read.  A still frame is
searched near where the die was last seen or last moved (then, failing that,
everywhere), its pose solved and read (:func:`~.pose.read_frame`), and the
:class:`~.settle.Settler` says when a roll is over.  Once a settle is
counted, frames are not read again until something moves.

:func:`frames` yields the frames of a camera, a video file or a folder of
images; bad input raises :class:`~.pose.MarkerError` or
:class:`~diefab.core.errors.DiefabError` subclasses with one-line messages.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from diefab.camera.pose import (
    DEFAULT_FOV,
    MIN_CONFIDENCE,
    Camera,
    FrameRead,
    MarkerDetector,
    MarkerError,
    layout_of,
    read_frame,
)
from diefab.camera.settle import Roll, Settler
from diefab.core.errors import DiefabError
from diefab.dice.design import Design

__all__ = [
    "IMAGE_SUFFIXES",
    "MIN_FRAME",
    "RollReader",
    "SourceError",
    "check_frame",
    "frames",
    "photo_files",
    "read_photo",
]

#: Image files read from a folder, in name order.
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")
#: Motion is measured on the frame shrunk by this factor.
MOTION_SCALE = 8
#: A shrunk pixel changed when it differs by more than this fraction of the frame's mean brightness ...
MOTION_LEVEL = 0.12
#: ... and the frame moved when at least this many shrunk pixels changed.
MOTION_PIXELS = 6
#: Least width and height of a frame, pixels.
MIN_FRAME = 64
#: The largest image file read, bytes.
MAX_PHOTO_BYTES = 512 << 20
#: Frames with markers of other dictionaries only, and none of the die's, before the reader gives up.
FOREIGN_FRAMES = 10


class SourceError(DiefabError, OSError):
    """A camera, video or image folder cannot be read."""


@dataclass
class _Motion:
    previous: np.ndarray | None = None
    box: tuple[int, int, int, int] | None = None  # where the last motion was, full-frame pixels

    def update(self, gray: np.ndarray) -> bool:
        import cv2

        h, w = gray.shape
        small = cv2.resize(gray, (w // MOTION_SCALE, h // MOTION_SCALE), interpolation=cv2.INTER_AREA).astype(
            np.float32
        )
        small /= max(float(small.mean()), 1.0)
        prev, self.previous = self.previous, small
        if prev is None or prev.shape != small.shape:
            return True
        changed = np.abs(small - prev) > MOTION_LEVEL
        if int(changed.sum()) < MOTION_PIXELS:
            return False
        ys, xs = np.nonzero(changed)
        s = MOTION_SCALE
        self.box = (int(xs.min()) * s, int(ys.min()) * s, (int(xs.max()) + 1) * s, (int(ys.max()) + 1) * s)
        return True


class RollReader:
    """Turns frames into rolls for one design.

    Parameters
    ----------
    design : Design
    camera : Camera or None
        None: an uncalibrated camera of the first frame's size and :data:`~.pose.DEFAULT_FOV`.
    settle : int
        Still frames before a roll counts.
    min_confidence : float
        Frames read below this are unread.
    down : (3,) float
        Straight down in camera coordinates (+z: the camera looks straight down).
    """

    def __init__(
        self,
        design: Design,
        camera: Camera | None = None,
        *,
        settle: int = 8,
        min_confidence: float = MIN_CONFIDENCE,
        fov: float = DEFAULT_FOV,
        down=(0.0, 0.0, 1.0),
    ) -> None:
        if not 0 <= min_confidence <= 1:
            raise DiefabError(f"min confidence {min_confidence} must be in [0, 1]")
        if settle < 1:
            raise DiefabError(f"settle {settle} must be at least 1 frame")
        self.design = design
        self.layout = layout_of(design)
        self.detector = MarkerDetector(self.layout)
        self.camera, self.fov = camera, fov
        self.min_confidence = min_confidence
        self.down = np.asarray(down, dtype=float)
        self.size_mm = float(np.ptp(design.polyhedron.vertices, axis=0).max()) * design.mm_per_unit
        self.settler = Settler(settle, self.size_mm)
        self.motion = _Motion()
        self.box: tuple[int, int, int, int] | None = None
        self.frame = -1
        self.last: FrameRead | None = None
        self.detections = 0
        self._foreign = 0

    def _roi(self, shape) -> tuple[int, int, int, int] | None:
        box = self.box or self.motion.box
        if box is None:
            return None
        h, w = shape
        x0, y0, x1, y1 = box
        pad = max(x1 - x0, y1 - y0, 48)
        return max(0, x0 - pad), max(0, y0 - pad), min(w, x1 + pad), min(h, y1 + pad)

    def read(self, gray: np.ndarray, photo: bool = False) -> FrameRead:
        """Read one frame without the settle logic (near the die's last place first, then everywhere).

        `photo`: the frame is a photo of a scene of its own, not the next frame of a stream.
        """
        if self.camera is None:
            h, w = gray.shape
            self.camera = Camera.from_fov(w, h, self.fov)
        kwargs = dict(min_confidence=self.min_confidence, down=self.down)
        roi = self._roi(gray.shape)
        read = read_frame(gray, self.design, self.detector, self.camera, roi=roi, **kwargs) if roi else None
        if read is None or read.pose is None:
            read = read_frame(gray, self.design, self.detector, self.camera, **kwargs)
        if read.box is not None:
            self.box = read.box
        clean = read.pose is not None and not read.pose.conflicts
        self.detections += clean
        if not clean and not self.detections:
            self._check_foreign(gray, read, photo)
        return read

    def _check_foreign(self, gray: np.ndarray, read: FrameRead, photo: bool) -> None:
        """Give up, with :class:`MarkerError`, on a source that keeps showing markers that are not this die's.

        A frame counts 1 (a dictionary other than the die's: 5, looked for every 15th frame) and a photo,
        which is a scene of its own, half of :data:`FOREIGN_FRAMES` (another dictionary: all of it).
        """
        if read.detected:  # markers of the die's dictionary that are not on the die, or not where the pose puts them
            self._foreign += FOREIGN_FRAMES // 2 if photo else 1
            where = "markers that are not on this die (another die, or two dice in view)"
        else:
            other = self.detector.foreign(gray) if photo or self.frame % 15 == 0 else None
            if other is None:
                return
            self._foreign += FOREIGN_FRAMES if photo else 5
            where = f"markers of {other}; design {self.design.name!r} uses {self.layout.dictionary}"
        if self._foreign >= FOREIGN_FRAMES:
            raise MarkerError(f"the camera sees {where}: is this the die of design {self.design.name!r}?")

    def feed(self, gray: np.ndarray) -> tuple[FrameRead | None, Roll | None]:
        """Take the next frame ((h, w) uint8); return what it shows (None: not read) and the roll it ends."""
        if gray.ndim != 2:
            raise DiefabError(f"frames must be grayscale (h, w), got shape {gray.shape}")
        self.frame += 1
        moving = self.motion.update(gray)
        if moving:
            self.settler.feed(self.frame, FrameRead(None, None, None, 0.0), moving=True)
            return None, None
        if not self.settler.needs_reading:
            return None, None
        read = self.read(gray)
        self.last = read
        return read, self.settler.feed(self.frame, read, moving=False)

    def feed_rest(self, gray: np.ndarray) -> tuple[FrameRead, Roll]:
        """Read a photo of the die at rest (no motion or settle): one roll per photo, unread when unsure."""
        self.frame += 1
        self.box = None  # each photo is its own scene
        read = self.read(gray, photo=True)
        self.last = read
        return read, Roll(self.frame, read.value, read.face, read.confidence)


def photo_files(folder: str | Path) -> list[Path]:
    """The images of `folder` (:data:`IMAGE_SUFFIXES`), in name order; SourceError when there are none."""
    folder = Path(folder)
    if not folder.is_dir():
        raise SourceError(f"image folder {folder} {'is not a folder' if folder.exists() else 'does not exist'}")
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file())
    if not files:
        raise SourceError(f"image folder {folder} holds no image ({', '.join(IMAGE_SUFFIXES)})")
    return files


def read_photo(path: str | Path) -> np.ndarray:
    """One image file as a grayscale frame (uint8, (h, w)).

    Raises
    ------
    SourceError
        The file cannot be decoded, is too large to decode, or is too small to read markers on.
    """
    import cv2

    path = Path(path)
    try:  # read here, not by OpenCV: any file name Python can open, and a size checked before decoding
        if path.stat().st_size > MAX_PHOTO_BYTES:
            raise SourceError(f"image {path} is larger than {MAX_PHOTO_BYTES >> 20} MiB")
        data = np.frombuffer(path.read_bytes(), dtype=np.uint8)
    except OSError as exc:
        raise SourceError(f"cannot read image {path}: {exc.strerror or exc}") from None
    _opencv_log("SILENT")  # a photo that cannot be decoded is one line, the caller's
    try:
        with _native_stderr_silenced():  # libpng and libjpeg write their own complaints to the process's stderr
            image = cv2.imdecode(data, cv2.IMREAD_GRAYSCALE) if data.size else None
    except cv2.error as exc:
        why = "more pixels than OpenCV decodes" if "CV_IO_MAX_IMAGE_PIXELS" in str(exc) else _last_line(exc)
        raise SourceError(f"cannot read image {path}: {why}") from None
    if image is None:
        raise SourceError(f"cannot read image {path}")
    check_frame(image, f"image {path}")
    return image


def _opencv_log(level: str) -> None:
    """OpenCV's own log at `level` (``ERROR``, ``SILENT``, ...), where this OpenCV has the setting."""
    import cv2

    try:
        cv2.utils.logging.setLogLevel(getattr(cv2.utils.logging, f"LOG_LEVEL_{level}"))
    except AttributeError:
        pass


@contextmanager
def _native_stderr_silenced() -> Iterator[None]:
    """File descriptor 2 pointed at the null device for the duration, where C libraries write directly."""
    try:
        sys.stderr.flush()  # what Python holds for stderr goes out first
        saved = os.dup(2)
    except (OSError, ValueError, AttributeError):  # no stderr to silence
        yield
        return
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(null, 2)
        finally:
            os.close(null)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def _last_line(exc: Exception) -> str:
    """The last line of an OpenCV error, which names what failed."""
    lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
    return lines[-1] if lines else type(exc).__name__


def check_frame(gray: np.ndarray, what: str = "frame") -> None:
    """SourceError when a frame is too small to read a die on (under :data:`MIN_FRAME` pixels a side)."""
    h, w = gray.shape[:2]
    if min(h, w) < MIN_FRAME:
        raise SourceError(f"{what} is {w} x {h} pixels: at least {MIN_FRAME} a side are needed to read markers")


def frames(
    *, camera: int | None = None, video: str | Path | None = None, images: str | Path | None = None
) -> Iterator[tuple[float, np.ndarray]]:
    """(time in seconds, grayscale frame) from exactly one source.

    A camera's time is the wall clock since the first frame, a video's its
    timestamps, a folder's the image's index.

    Raises
    ------
    SourceError
        No such camera, a video that cannot be read, a folder without images.
    """
    import cv2

    _opencv_log("ERROR")  # a camera that cannot be opened is reported in one line, not in OpenCV's warnings too
    # nor a file FFmpeg cannot decode in FFmpeg's own lines (OpenCV reads this when it first opens a video)
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
    if sum(x is not None for x in (camera, video, images)) != 1:
        raise SourceError("give exactly one source: a camera, a video file or a folder of images")
    if images is not None:
        for i, path in enumerate(photo_files(images)):
            yield float(i), read_photo(path)
        return
    if video is not None:
        path = Path(video)
        if not path.is_file():
            raise SourceError(f"video {path} {'is not a regular file' if path.exists() else 'does not exist'}")
        try:  # OpenCV takes the name as UTF-8, and fails hard on a name that is not
            str(path).encode("utf-8")
        except UnicodeEncodeError:
            raise SourceError(f"video {path}: its name is not valid UTF-8; rename the file") from None
        capture, name = cv2.VideoCapture(str(path)), f"video {video}"
    else:
        capture, name = cv2.VideoCapture(int(camera)), f"camera {camera}"
    try:
        if not capture.isOpened():
            raise SourceError(f"cannot open {name}")
        import time

        start = time.monotonic()
        first = True
        while True:
            try:
                ok, image = capture.read()
            except cv2.error as exc:
                raise SourceError(f"cannot read {name}: {_last_line(exc)}") from None
            if not ok:
                if first:
                    raise SourceError(f"{name} gives no frame")
                return
            check_frame(image, f"{name}'s frame")
            first = False
            t = capture.get(cv2.CAP_PROP_POS_MSEC) / 1000 if video is not None else time.monotonic() - start
            yield t, cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    finally:
        capture.release()
