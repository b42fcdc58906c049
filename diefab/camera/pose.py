"""From one camera frame to the die's pose and the value it shows.

:class:`MarkerDetector` finds the die's ArUco markers (OpenCV's detector);
:func:`solve_pose` solves the die's pose from the corners of every visible
marker and the die's known geometry (a perspective-n-point solve); and
:func:`read_pose` finds the face the die rests on (the face whose outward
normal points most nearly down) and its value.

The pose is trusted only when it says so itself: each marker's two planar
solutions are scored against every other visible marker, the best is refined
over all the markers that agree with it, and :func:`read_pose` gives a
confidence in [0, 1] from how far the pose is from choosing another face,
how flat the chosen face lies and how well the corners reproject.  A frame
below the reader's confidence is unread, never guessed.

Camera coordinates are OpenCV's: x right, y down, z along the optical axis.
A camera looking straight down at the table sees "down" as +z.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from diefab.core.errors import DiefabError
from diefab.dice.design import Design
from diefab.dice.markers import DICTIONARIES, MarkerLayout, marker_layout

__all__ = [
    "DEFAULT_FOV",
    "MIN_CONFIDENCE",
    "Camera",
    "FrameRead",
    "MarkerDetector",
    "MarkerError",
    "Pose",
    "read_frame",
    "read_pose",
    "solve_pose",
]

#: Horizontal field of view assumed for an uncalibrated camera, degrees (a typical webcam).
DEFAULT_FOV = 65.0
#: Straight down in camera coordinates for a camera looking straight down.
DOWN = (0.0, 0.0, 1.0)
#: Confidence below which a frame is unread.
MIN_CONFIDENCE = 0.5
#: A marker agrees with a pose when its corners reproject within this fraction of its image side.
INLIER_FRACTION = 0.12
#: The same for the pose of one marker alone, before it is refined on every marker that agrees.
COARSE_FRACTION = 0.6
#: Half the angle between the chosen face and the next, in standard errors of the pose's rotation, at which
#: the choice is fully trusted, and below which it is not at all.
SAFE_SIGMAS = (3.0, 1.5)
#: The same half angle in degrees, whatever the standard error.
SAFE_DEG = (5.0, 2.0)
#: Corner scatter assumed at least, pixels, and the rotation error an uncalibrated lens adds, degrees.
CORNER_PX, LENS_DEG = 0.2, 1.0
#: The chosen face's tilt from straight down (degrees) up to which it lies flat, and beyond which it cannot.
FLAT_DEG = (12.0, 24.0)
#: Reprojection error, as a fraction of the markers' image size, fully trusted and not at all.
REPROJECTION = (0.08, 0.16)
#: Markers a pose on several markers must leave unexplained before the frame is taken to show another die
#: (beside a one-marker pose, one is enough): one alone is taken for a pattern decoded by chance.
UNEXPLAINED = 2


#: Pixels per cell at which a candidate marker's bits are read.  A marker seen obliquely is sampled finer than
#: OpenCV's default of 4 and is then decoded: markers on the steep faces beside the top are found, so that a
#: pose rests on several markers instead of one (whose two planar solutions may rest on different faces).
PIXELS_PER_CELL = 8


class MarkerError(DiefabError, ValueError):
    """A design carries no markers, or the markers seen belong to another die or dictionary."""


@dataclass(frozen=True)
class Camera:
    """A pinhole camera: (3, 3) intrinsic matrix (pixels) and OpenCV distortion coefficients."""

    matrix: np.ndarray
    distortion: np.ndarray

    @classmethod
    def from_fov(cls, width: int, height: int, fov_deg: float = DEFAULT_FOV) -> Camera:
        """An undistorted camera of `width` x `height` pixels and horizontal field of view `fov_deg`."""
        if not (0 < fov_deg < 180):
            raise DiefabError(f"field of view {fov_deg} degrees must be in (0, 180)")
        f = (width / 2) / math.tan(math.radians(fov_deg) / 2)
        matrix = np.array([[f, 0, (width - 1) / 2], [0, f, (height - 1) / 2], [0, 0, 1.0]])
        return cls(matrix, np.zeros(5))


@dataclass(frozen=True)
class Pose:
    """The die's pose in camera coordinates.

    rotation : (3, 3) float, model coordinates -> camera; translation : (3,) float, mm (the model origin).
    markers : ids of the markers that agree with the pose; conflicts : ids of the markers of the die's
    dictionary seen that the pose does not explain (on no face of the die, or far from where the pose puts
    them), when there are enough of them (:data:`UNEXPLAINED`) to say that the frame shows another die numbered
    from the same dictionary, or two dice, else empty; error : RMS reprojection error, pixels;
    scale : mean image side of those markers, pixels; alternative : the other planar solution (rotation) of a
    one-marker pose when it fits almost as well; spread_deg : the rotation's standard error along its worst
    axis, degrees (from the solve's Jacobian and the corners' scatter); covariance : (3, 3) float, the
    covariance of the rotation's Rodrigues vector, rad^2 (None: unknown).
    """

    rotation: np.ndarray
    translation: np.ndarray
    markers: tuple[int, ...]
    error: float
    scale: float
    alternative: np.ndarray | None = None
    spread_deg: float = 0.0
    covariance: np.ndarray | None = None
    conflicts: tuple[int, ...] = ()


@dataclass(frozen=True)
class FrameRead:
    """What one frame shows: the pose (None: no marker), the resting face and its value, the confidence.

    ``face`` and ``value`` are None when the frame is unread (confidence below the reader's threshold, or
    the die rests on no face that carries a value).
    """

    pose: Pose | None
    face: int | None
    value: int | None
    confidence: float
    detected: int = 0
    box: tuple[int, int, int, int] | None = None  # x0, y0, x1, y1 of the markers seen, pixels
    corners: dict | None = None  # marker id -> (4, 2) float image corners of the die's markers seen


class MarkerDetector:
    """ArUco detection of one die's markers (OpenCV ``cv2.aruco.ArucoDetector``).

    Parameters
    ----------
    layout : MarkerLayout
        The die's markers (:func:`~diefab.dice.markers.marker_layout`).
    """

    def __init__(self, layout: MarkerLayout) -> None:
        import cv2

        self.layout = layout
        params = cv2.aruco.DetectorParameters()
        # corners from lines fitted to each side's contour: on rendered rests of small, blurred markers they
        # land 2-5x closer to the true corners (median) than sub-pixel corner search or none
        params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_CONTOUR
        params.minMarkerPerimeterRate = 0.02
        params.adaptiveThreshWinSizeMax = 33
        params.perspectiveRemovePixelPerCell = PIXELS_PER_CELL
        self._cv2 = cv2
        self._detector = cv2.aruco.ArucoDetector(
            cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, layout.dictionary)), params
        )
        self._others: list | None = None

    def detect(self, gray: np.ndarray, roi: tuple[int, int, int, int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Ids (n,) int and corners (n, 4, 2) float (pixels) of the markers in `gray` (or in its `roi`)."""
        x0 = y0 = 0
        image = gray
        if roi is not None:
            x0, y0, x1, y1 = roi
            image = gray[y0:y1, x0:x1]
        corners, ids, _ = self._detector.detectMarkers(image)
        if ids is None or len(ids) == 0:
            return np.zeros(0, dtype=int), np.zeros((0, 4, 2))
        return ids.ravel().astype(int), np.array(corners, dtype=float).reshape(-1, 4, 2) + (x0, y0)

    def foreign(self, gray: np.ndarray) -> str | None:
        """The first other dictionary (of :data:`DICTIONARIES`) with markers in `gray`, or None."""
        cv2 = self._cv2
        if self._others is None:
            self._others = [
                (name, cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name))))
                for name, _, _ in DICTIONARIES
                if name != self.layout.dictionary
            ]
        for name, detector in self._others:
            _, ids, _ = detector.detectMarkers(gray)
            if ids is not None and len(ids):
                return name
        return None


def _marker_frame(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Rotation (marker -> model), centre and side of a marker from its (4, 3) model corners (TL, TR, BR, BL)."""
    x = corners[1] - corners[0]
    side = float(np.linalg.norm(x))
    x = x / side
    y = corners[0] - corners[3]
    y = y - (y @ x) * x
    y = y / np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)]), corners.mean(axis=0), side


def _project(points: np.ndarray, rotation: np.ndarray, translation: np.ndarray, camera: Camera) -> np.ndarray:
    cam = points @ rotation.T + translation
    uv = cam @ camera.matrix.T
    return uv[..., :2] / uv[..., 2:3]


def _agreement(rotation, translation, objects, images, normals, camera, *, hidden: bool = True) -> np.ndarray:
    """(n,) float: each marker's worst corner reprojection error as a fraction of its image side.

    inf for a marker behind the camera and, with `hidden`, for one on a face turned away from it.
    """
    proj = _project(objects.reshape(-1, 3), rotation, translation, camera).reshape(objects.shape[0], 4, 2)
    side = np.linalg.norm(images - np.roll(images, 1, axis=1), axis=2).mean(axis=1)
    err = np.linalg.norm(proj - images, axis=2).max(axis=1) / np.maximum(side, 1.0)
    centres = objects.mean(axis=1) @ rotation.T + translation
    seen = centres[:, 2] > 0
    if hidden:
        seen &= np.einsum("ij,ij->i", normals @ rotation.T, centres) < 0
    return np.where(seen, err, np.inf)


def solve_pose(
    ids: np.ndarray, corners: np.ndarray, layout: MarkerLayout, camera: Camera, mm_per_unit: float
) -> Pose | None:
    """The die's pose from detected markers, or None when no detected marker belongs to the die.

    Parameters
    ----------
    ids : (n,) int
    corners : (n, 4, 2) float, pixels (ArUco's corner order)
    layout : the die's markers, model units
    camera : Camera
    mm_per_unit : millimetres per model unit (the pose's translation is in mm)
    """
    import cv2

    row_of = {int(m): j for j, m in enumerate(layout.ids)}
    known = [(i, row_of[int(m)]) for i, m in enumerate(ids) if int(m) in row_of]
    if not known:
        return None
    rows = [j for _, j in known]
    objects = layout.corners[rows] * mm_per_unit  # (n, 4, 3) mm
    images = corners[[i for i, _ in known]]
    normals = np.array([_marker_frame(o)[0][:, 2] for o in objects])
    marker_ids = np.array([int(ids[i]) for i, _ in known])
    candidates = []
    for j in range(len(rows)):
        frame, centre, side = _marker_frame(objects[j])
        h = side / 2
        square = np.array([[-h, h, 0], [h, h, 0], [h, -h, 0], [-h, -h, 0]], dtype=np.float64)
        try:
            n, rvecs, tvecs, errs = cv2.solvePnPGeneric(
                square, images[j].astype(np.float64), camera.matrix, camera.distortion, flags=cv2.SOLVEPNP_IPPE_SQUARE
            )
        except cv2.error:
            continue
        for rvec, tvec, e in zip(rvecs, tvecs, np.ravel(errs)):
            r_marker = cv2.Rodrigues(rvec)[0]
            rotation = r_marker @ frame.T  # model -> camera
            translation = tvec.ravel() - rotation @ centre
            fit = _agreement(rotation, translation, objects, images, normals, camera)
            candidates.append((j, rotation, translation, fit, float(e)))
    if not candidates:
        return None

    def score(c, tolerance):
        inliers = c[3] <= tolerance
        return (int(inliers.sum()), -float(np.where(inliers, c[3], 0).sum()))

    # a small marker's pose is coarse: gather the markers that roughly agree, refine on them, then keep those
    # that agree closely with the refined pose
    candidates.sort(key=lambda c: score(c, COARSE_FRACTION), reverse=True)
    best = candidates[0]
    rotation, translation = best[1], best[2]
    inliers = np.flatnonzero(best[3] <= COARSE_FRACTION)
    for _ in range(3):
        if len(inliers) >= 2:
            rotation, translation = _refine(objects[inliers], images[inliers], rotation, translation, camera)
        fit = _agreement(rotation, translation, objects, images, normals, camera)
        close = np.flatnonzero(fit <= INLIER_FRACTION)
        if np.array_equal(close, inliers):
            break
        inliers = close
    if len(inliers) == 0:
        return None
    alternative = None
    if len(inliers) == 1:
        same = [c for c in candidates[1:] if c[0] == inliers[0]]
        if same and same[0][4] < 4.0 * max(best[4], 0.05):
            alternative = same[0][1]  # the other planar solution of the only marker fits about as well
    proj = _project(objects[inliers].reshape(-1, 3), rotation, translation, camera)
    error = float(np.sqrt(np.mean(np.sum((proj - images[inliers].reshape(-1, 2)) ** 2, axis=1))))
    scale = float(np.linalg.norm(images[inliers] - np.roll(images[inliers], 1, axis=1), axis=2).mean())
    spread, covariance = _rotation_spread(objects[inliers].reshape(-1, 3), rotation, translation, camera, error)
    ids_in = tuple(int(m) for m in marker_ids[inliers])
    # markers the pose does not explain, of ids on no face or far from where the pose puts theirs: two of them
    # (one, beside a one-marker pose) say that the frame holds another die numbered from the same dictionary,
    # or two dice; one beside a pose on several markers is a pattern decoded by chance
    far = _agreement(rotation, translation, objects, images, normals, camera, hidden=False) > COARSE_FRACTION
    strangers = [int(m) for m in ids if int(m) not in row_of]
    unexplained = tuple(sorted({*(int(m) for m in marker_ids[far]), *strangers}))
    conflicts = unexplained if len(unexplained) >= (1 if len(inliers) == 1 else UNEXPLAINED) else ()
    return Pose(rotation, translation, ids_in, error, scale, alternative, spread, covariance, conflicts)


def _rotation_spread(objects, rotation, translation, camera, error: float) -> tuple[float, np.ndarray | None]:
    """Standard error of the pose's rotation along its worst axis (degrees) and its covariance (rad^2).

    Corner scatter through the solve's Jacobian: the corners scatter by the RMS reprojection error (at
    least :data:`CORNER_PX`); an uncalibrated lens adds :data:`LENS_DEG` to the standard error.  The
    covariance is that of the rotation's Rodrigues vector, lens not included.

    The pose's six parameters absorb part of the scatter: the RMS residual of m corner coordinates is on
    average ``sqrt((m - 6) / m)`` of it, so it is divided by that.  One marker's four corners give eight
    coordinates, and its residual is half the scatter (a small marker seen square-on tilts freely); two
    markers' sixteen keep ``sqrt(10 / 16)`` of it, and many markers nearly all.
    """
    import cv2

    rvec = cv2.Rodrigues(rotation)[0]
    _, jacobian = cv2.projectPoints(objects, rvec, translation.reshape(3, 1), camera.matrix, camera.distortion)
    j = jacobian[:, :6]
    m = 2 * len(objects)
    error *= math.sqrt(m / (m - 6))  # unbiased: the residual's degrees of freedom, not its coordinates
    sigma = max(error, CORNER_PX)
    try:
        cov = sigma**2 * np.linalg.inv(j.T @ j)
    except np.linalg.LinAlgError:
        return 90.0, None
    rot = cov[:3, :3]
    worst = float(np.sqrt(max(np.linalg.eigvalsh(rot).max(), 0.0)))
    return float(np.hypot(np.degrees(worst), LENS_DEG)), rot


def _refine(objects, images, rotation, translation, camera):
    """Rotation and translation refined (Levenberg-Marquardt) over the corners of several markers."""
    import cv2

    rvec = cv2.Rodrigues(rotation)[0]
    ok, rvec, tvec = cv2.solvePnP(
        objects.reshape(-1, 3), images.reshape(-1, 2), camera.matrix, camera.distortion,
        rvec, translation.reshape(3, 1).copy(), useExtrinsicGuess=True, flags=cv2.SOLVEPNP_ITERATIVE,
    )  # fmt: skip
    return (cv2.Rodrigues(rvec)[0], tvec.ravel()) if ok else (rotation, translation)


def _resting(rotation: np.ndarray, normals: np.ndarray, down: np.ndarray) -> tuple[int, float, float]:
    """The face whose outward normal points most nearly `down`, its angle and the next face's (degrees)."""
    cos = np.clip(normals @ rotation.T @ down, -1, 1)
    order = np.argsort(cos)[::-1]
    a1, a2 = np.degrees(np.arccos(cos[order[:2]]))
    return int(order[0]), float(a1), float(a2)


def _half_gaps(rvec: np.ndarray, normals: np.ndarray, face: int, down: np.ndarray) -> np.ndarray:
    """(n,) float: half the angle by which each face is farther from `down` than `face`, radians."""
    import cv2

    cos = np.clip(normals @ cv2.Rodrigues(rvec)[0].T @ down, -1, 1)
    angles = np.arccos(cos)
    return (angles - angles[face]) / 2


def _margin_sigmas(rotation, covariance, spread_deg: float, normals, face: int, down: np.ndarray) -> np.ndarray:
    """(n - 1,) float: for each other face, the half gap to `face` in standard errors.

    The half gap's standard error is the rotation's covariance carried along the gap's own gradient (a
    rotation about the line of sight, say, changes no gap), with :data:`LENS_DEG` added: a pose that is
    uncertain only in directions that keep the same face down is trusted.
    """
    import cv2

    rvec = cv2.Rodrigues(rotation)[0].ravel()
    gaps = _half_gaps(rvec, normals, face, down)
    near = np.flatnonzero(np.arange(len(gaps)) != face)
    if len(near) == 0:
        return np.array([np.inf])
    lens = np.radians(LENS_DEG)
    if covariance is None:  # the worst axis's standard error, which already holds the lens's
        sigma = np.full(len(near), np.radians(spread_deg))
        return gaps[near] / sigma
    step = 1e-6
    grad = np.array([(_half_gaps(rvec + step * e, normals, face, down)[near] - gaps[near]) / step for e in np.eye(3)])
    var = np.einsum("in,ij,jn->n", grad, covariance, grad)
    return gaps[near] / np.sqrt(np.maximum(var, 0.0) + lens**2)


def _ramp(x: float, full: float, zero: float) -> float:
    """1 at `full` or better, 0 at `zero` or worse, linear between."""
    return float(np.clip((zero - x) / (zero - full), 0.0, 1.0))


def read_pose(pose: Pose, design: Design, down: np.ndarray = DOWN) -> tuple[int, float]:
    """The resting face of `pose` and the confidence of that reading.

    The confidence is the product of three ramps: half the angle between
    the chosen face and each face near it (the pose error that would flip
    the choice), in standard errors of that angle (:data:`SAFE_SIGMAS`: the
    pose's rotation covariance carried along the angle's gradient) and, for
    the next face, in degrees (:data:`SAFE_DEG`),
    the chosen face's tilt from `down`
    (:data:`FLAT_DEG`: a die leaning on something is not at rest on a face)
    and the reprojection error relative to the markers' image size
    (:data:`REPROJECTION`).  A one-marker pose whose other planar solution
    fits about as well and rests on another face has confidence 0, and so
    has a pose with ``conflicts`` (enough markers seen that it leaves
    unexplained to say the frame shows another die, or two).

    Parameters
    ----------
    down : (3,) float
        Straight down in camera coordinates (+z for a camera looking straight down).
    """
    poly = design.polyhedron
    down = np.asarray(down, dtype=float) / np.linalg.norm(down)
    face, a1, a2 = _resting(pose.rotation, poly.normals, down)
    if pose.conflicts:
        return face, 0.0
    covariance = pose.covariance
    rotation = pose.rotation
    if pose.alternative is not None:
        # one marker alone has two planar solutions; a die at rest lies flat, which rules out most wrong ones
        options = [((face, a1, a2), pose.rotation), (_resting(pose.alternative, poly.normals, down), pose.alternative)]
        flat = [o for o in options if o[0][1] <= FLAT_DEG[1]]
        if len(flat) == 2 and flat[0][0][0] != flat[1][0][0]:
            return face, 0.0
        if flat:
            (face, a1, a2), chosen = min(flat, key=lambda o: o[0][1])
            if chosen is not pose.rotation:
                rotation, covariance = chosen, None  # the covariance is the other solution's
    half = (a2 - a1) / 2
    sigmas = _margin_sigmas(rotation, covariance, pose.spread_deg, poly.normals, face, down)
    safety = min(
        _ramp(-float(sigmas.min()), -SAFE_SIGMAS[0], -SAFE_SIGMAS[1]),
        _ramp(-half, -SAFE_DEG[0], -SAFE_DEG[1]),
    )
    confidence = safety * _ramp(a1, *FLAT_DEG)
    confidence *= _ramp(pose.error / max(pose.scale, 1.0), *REPROJECTION)
    return face, confidence


def read_frame(
    gray: np.ndarray,
    design: Design,
    detector: MarkerDetector,
    camera: Camera,
    *,
    roi: tuple[int, int, int, int] | None = None,
    min_confidence: float = MIN_CONFIDENCE,
    down: np.ndarray = DOWN,
) -> FrameRead:
    """Detect, solve and read one grayscale frame (uint8, (h, w))."""
    ids, corners = detector.detect(gray, roi)
    box = None
    if len(ids):
        lo, hi = corners.reshape(-1, 2).min(axis=0), corners.reshape(-1, 2).max(axis=0)
        box = (int(lo[0]), int(lo[1]), int(math.ceil(hi[0])), int(math.ceil(hi[1])))
    pose = solve_pose(ids, corners, detector.layout, camera, design.mm_per_unit) if len(ids) else None
    if pose is None:
        return FrameRead(None, None, None, 0.0, len(ids), box)
    seen = {int(m): corners[i] for i, m in enumerate(ids) if int(m) in pose.markers}
    face, confidence = read_pose(pose, design, down)
    name = design.polyhedron.names[face]
    if confidence < min_confidence or name not in design.values:
        return FrameRead(pose, None, None, confidence, len(ids), box, seen)
    return FrameRead(pose, face, design.values[name], confidence, len(ids), box, seen)


def layout_of(design: Design) -> MarkerLayout:
    """The design's markers, or :class:`MarkerError` when it carries none."""
    from diefab.core.errors import DesignError

    try:
        return marker_layout(design)
    except DesignError as exc:
        raise MarkerError(str(exc)) from exc
