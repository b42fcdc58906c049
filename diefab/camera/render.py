"""Synthetic camera frames of a marked die: the test rig of the reader.

A die's faces are planar, so a frame is drawn exactly with planar warps:
each face that faces the camera is filled with its shaded color, far faces
first (painter's order by depth), and its marker is warped onto it with the
homography of its four projected corners (``cv2.warpPerspective`` on the
marker's bounding box).  On top come what a real camera adds
(:class:`Conditions`): a textured table and a soft shadow, uneven and
changing light, a finger over part of the die, defocus or motion blur,
sensor noise and JPEG compression.

World coordinates: z up, the table is z = 0, millimetres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from diefab.camera.pose import Camera
from diefab.dice.design import Design
from diefab.dice.markers import MarkerLayout

__all__ = ["Conditions", "View", "draw_detection", "random_conditions", "random_view", "render", "rest_pose"]


@dataclass(frozen=True)
class View:
    """A camera over the table: intrinsics, world -> camera rotation (3, 3) and position (3,), mm."""

    camera: Camera
    rotation: np.ndarray
    position: np.ndarray
    width: int
    height: int

    @property
    def down(self) -> np.ndarray:
        """(3,) float: straight down in camera coordinates."""
        return self.rotation @ np.array([0.0, 0.0, -1.0])

    def to_camera(self, rotation: np.ndarray, position: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A die pose in world coordinates (model -> world rotation, model origin mm) in camera coordinates."""
        return self.rotation @ rotation, self.rotation @ (np.asarray(position) - self.position)


@dataclass(frozen=True)
class Conditions:
    """What degrades one frame (all optional)."""

    table: float = 90.0  # table brightness, 0-255
    gain: float = 1.0  # overall light
    gradient: tuple[float, float] = (0.0, 0.0)  # light falloff across the frame, fraction per frame width, x and y
    light: tuple[float, float, float] = (0.3, -0.4, 1.0)  # direction toward the light, world
    blur: float = 0.0  # Gaussian defocus sigma, pixels
    motion: tuple[float, float] = (0.0, 0.0)  # motion blur streak, pixels (x, y)
    noise: float = 0.0  # sensor noise sigma, gray levels
    jpeg: int = 0  # JPEG quality (0: none)
    finger: tuple[float, float, float, float] | None = None  # x, y (pixels) of the tip, angle (rad), width (px)
    seed: int = 0  # sensor noise and the finger's skin
    table_seed: int = 0  # the table's texture (fixed for a fixed camera)


def rest_pose(design: Design, face: int, yaw: float, at=(0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """The die at rest on `face`: model -> world rotation and model origin (mm), turned by `yaw` (radians)."""
    from scipy.spatial.transform import Rotation

    poly = design.polyhedron
    n = poly.normals[face]
    align, _ = Rotation.align_vectors([[0.0, 0.0, -1.0]], [n])
    rotation = Rotation.from_rotvec([0.0, 0.0, yaw]).as_matrix() @ align.as_matrix()
    lowest = float((poly.vertices @ rotation.T)[:, 2].min())
    s = design.mm_per_unit
    return rotation, np.array([at[0], at[1], -lowest * s])


def random_view(rng: np.random.Generator, design: Design, *, width=1280, height=720, tilt_deg=6.0, field=(7.0, 10.0)):
    """A camera looking about straight down at the die (tilt up to `tilt_deg`), any roll, a random lens.

    The field of view's width is `field` (range) times the die's largest extent.
    """
    from scipy.spatial.transform import Rotation

    extent = float(np.ptp(design.polyhedron.vertices, axis=0).max()) * design.mm_per_unit
    fov = rng.uniform(55.0, 75.0)
    span = rng.uniform(*field) * extent
    distance = span / 2 / math.tan(math.radians(fov) / 2)
    tilt = Rotation.from_rotvec(rng.uniform(0, math.radians(tilt_deg)) * _unit(rng, 2))
    roll = Rotation.from_rotvec([0.0, 0.0, rng.uniform(0, 2 * math.pi)])
    look_down = np.diag([1.0, -1.0, -1.0])  # camera x = world x, camera y = -world y, camera z = -world z
    to_camera = look_down @ (tilt * roll).as_matrix().T
    position = to_camera.T @ np.array([0.0, 0.0, -distance])  # the optical axis passes through the origin
    return View(Camera.from_fov(width, height, fov), to_camera, position, width, height)


def _unit(rng, dim: int) -> np.ndarray:
    v = np.zeros(3)
    v[:dim] = rng.normal(size=dim)
    return v / np.linalg.norm(v)


def random_conditions(rng: np.random.Generator, view: View, *, finger: float = 0.15, moving=(0.0, 0.0)) -> Conditions:
    """Random lighting, blur, noise, compression and (with probability `finger`) a finger near the centre."""
    w, h = view.width, view.height
    tip = None
    if rng.random() < finger:
        angle = rng.uniform(0, 2 * math.pi)
        tip = (w / 2 + rng.normal(0, 0.06 * w), h / 2 + rng.normal(0, 0.06 * h), angle, rng.uniform(0.04, 0.07) * w)
    return Conditions(
        table=rng.uniform(40, 150),
        gain=rng.uniform(0.55, 1.25),
        gradient=(rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4)),
        light=tuple(_unit(rng, 3) * [1, 1, 0] + [0, 0, rng.uniform(0.8, 2.0)]),
        blur=rng.uniform(0.0, 1.2),
        motion=moving,
        noise=rng.uniform(1.0, 6.0),
        jpeg=int(rng.integers(70, 96)),
        finger=tip,
        seed=int(rng.integers(2**31)),
        table_seed=int(rng.integers(2**31)),
    )


def _marker_texture(layout: MarkerLayout, row: int, cell_px: int = 16) -> np.ndarray:
    from diefab.dice.markers import marker_cells

    cells = marker_cells(layout.dictionary, int(layout.ids[row]))
    image = np.where(cells, 0.08, 1.0).astype(np.float32)
    return np.kron(image, np.ones((cell_px, cell_px), dtype=np.float32))


def render(
    design: Design,
    layout: MarkerLayout,
    view: View,
    rotation: np.ndarray,
    position: np.ndarray,
    conditions: Conditions = Conditions(),
    *,
    textures: dict | None = None,
) -> np.ndarray:
    """A grayscale frame (h, w) uint8 of the die at `rotation`, `position` (world, mm) seen from `view`.

    `textures` caches the marker textures and the last table between frames of one camera.
    """
    import cv2

    rng = np.random.default_rng(conditions.seed)
    w, h = view.width, view.height
    textures = {} if textures is None else textures
    key = (conditions.table_seed, w, h, conditions.table)  # a fixed camera films one table: the last is kept
    if textures.get("table", (None,))[0] != key:
        textures["table"] = (key, _table(np.random.default_rng(conditions.table_seed), w, h, conditions.table))
    image = textures["table"][1].copy()
    poly = design.polyhedron
    s = design.mm_per_unit
    r_cam, t_cam = view.to_camera(rotation, position)
    k = view.camera.matrix

    def project(points_mm):
        cam = points_mm @ r_cam.T + t_cam
        uv = cam @ k.T
        return uv[:, :2] / uv[:, 2:3], cam[:, 2]

    # a soft shadow under the die
    world = poly.vertices * s @ rotation.T + position
    foot = world[:, :2].mean(axis=0)
    spread = float(np.ptp(world[:, :2], axis=0).max()) / 2
    ring = np.array(
        [[foot[0] + spread * math.cos(a), foot[1] + spread * math.sin(a), 0.0] for a in np.linspace(0, 2 * math.pi, 24)]
    )
    shadow_cam = (ring - view.position) @ view.rotation.T
    uv = shadow_cam @ k.T
    ring_px = uv[:, :2] / uv[:, 2:3]
    sigma = max(2.0, 0.15 * spread * k[0, 0] / max(float(shadow_cam[:, 2].mean()), 1.0))
    # blurred on its own box, padded past the kernel's reach: the same as blurring the whole frame
    pad = int(math.ceil(4 * sigma)) + 2
    x0, y0 = np.floor(ring_px.min(axis=0)).astype(int) - pad
    x1, y1 = np.ceil(ring_px.max(axis=0)).astype(int) + pad
    x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
    if x1 > x0 and y1 > y0:
        shadow = np.zeros((y1 - y0, x1 - x0), np.float32)
        cv2.fillPoly(shadow, [np.round((ring_px - [x0, y0]) * 16).astype(np.int32)], 1.0, cv2.LINE_AA, shift=4)
        image[y0:y1, x0:x1] *= 1.0 - 0.45 * cv2.GaussianBlur(shadow, (0, 0), sigma)

    light = np.asarray(conditions.light, dtype=float)
    light = light / np.linalg.norm(light)
    normals = poly.normals @ rotation.T
    centres_cam = (poly.face_centroids * s) @ r_cam.T + t_cam
    facing = np.einsum("ij,ij->i", normals @ view.rotation.T, centres_cam) < 0
    order = [f for f in np.argsort(-centres_cam[:, 2]) if facing[f]]
    rows: dict[int, list[int]] = {}
    for j, f in enumerate(layout.faces):
        rows.setdefault(int(f), []).append(j)
    albedo = 225.0
    for f in order:
        shade = albedo * (0.35 + 0.65 * max(0.0, float(normals[f] @ light)))
        pts, _ = project(poly.vertices[poly.faces[f]] * s)
        cv2.fillPoly(image, [np.round(pts * 16).astype(np.int32)], float(shade), cv2.LINE_AA, shift=4)
        for j in rows.get(int(f), ()):
            tex = textures.get(j)
            if tex is None:
                tex = textures[j] = _marker_texture(layout, j)
            quad, _ = project(layout.corners[j] * s)
            _paste(image, tex * shade, quad)
    image = _degrade(image, conditions, rng)
    return image


def _paste(image: np.ndarray, texture: np.ndarray, quad: np.ndarray) -> None:
    """Warp `texture` onto `quad` ((4, 2) pixels: TL, TR, BR, BL) of `image`, in place."""
    import cv2

    h, w = image.shape
    x0, y0 = np.floor(quad.min(axis=0)).astype(int) - 1
    x1, y1 = np.ceil(quad.max(axis=0)).astype(int) + 2
    x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
    if x1 <= x0 or y1 <= y0:
        return
    n = texture.shape[0]
    src = np.array([[0, 0], [n, 0], [n, n], [0, n]], dtype=np.float32) - 0.5
    dst = (quad - [x0, y0]).astype(np.float32)
    m = cv2.getPerspectiveTransform(src, dst)
    size = (x1 - x0, y1 - y0)
    warped = cv2.warpPerspective(texture, m, size, flags=cv2.INTER_AREA if n > 64 else cv2.INTER_LINEAR)
    mask = np.zeros((y1 - y0, x1 - x0), np.float32)
    cv2.fillConvexPoly(mask, np.round(dst * 16).astype(np.int32), 1.0, cv2.LINE_AA, shift=4)
    patch = image[y0:y1, x0:x1]
    patch[:] = patch * (1 - mask) + warped * mask


def _table(rng: np.random.Generator, w: int, h: int, level: float) -> np.ndarray:
    """A table top: a low-frequency mottle and fine grain around gray `level`."""
    import cv2

    coarse = rng.normal(0, 1, (h // 40 + 2, w // 40 + 2)).astype(np.float32)
    mottle = cv2.resize(coarse, (w, h), interpolation=cv2.INTER_CUBIC)
    grain = cv2.resize(rng.normal(0, 1, (h // 4, w // 4)).astype(np.float32), (w, h), interpolation=cv2.INTER_LINEAR)
    return (level * (1 + 0.08 * mottle) + 4.0 * grain).astype(np.float32)


def _degrade(image: np.ndarray, c: Conditions, rng: np.random.Generator) -> np.ndarray:
    import cv2

    h, w = image.shape
    if c.finger is not None:
        x, y, angle, width = c.finger
        far = (x + 3 * w * math.cos(angle), y + 3 * w * math.sin(angle))
        mask = np.zeros((h, w), np.float32)
        cv2.line(mask, (int(x), int(y)), (int(far[0]), int(far[1])), 1.0, int(width), cv2.LINE_AA)
        cv2.circle(mask, (int(x), int(y)), int(width / 2), 1.0, -1, cv2.LINE_AA)
        skin = 150.0 + 25.0 * cv2.GaussianBlur(rng.normal(0, 1, (h, w)).astype(np.float32), (0, 0), 6)
        image = image * (1 - mask) + skin * mask
    xx = np.arange(w, dtype=np.float32)[None, :]
    yy = np.arange(h, dtype=np.float32)[:, None]
    light = c.gain * (1 + c.gradient[0] * (xx / w - 0.5) + c.gradient[1] * (yy / h - 0.5))
    image = image * light.astype(np.float32)
    if c.motion != (0.0, 0.0):
        length = max(1, int(round(math.hypot(*c.motion))))
        kernel = np.zeros((2 * length + 1, 2 * length + 1), np.float32)
        d = np.array(c.motion) / max(math.hypot(*c.motion), 1e-9)
        cv2.line(kernel, (int(length - d[0] * length / 2), int(length - d[1] * length / 2)),
                 (int(length + d[0] * length / 2), int(length + d[1] * length / 2)), 1.0, 1)  # fmt: skip
        image = cv2.filter2D(image, -1, kernel / kernel.sum())
    if c.blur > 0.05:
        image = cv2.GaussianBlur(image, (0, 0), c.blur)
    if c.noise > 0:
        image = image + np.float32(c.noise) * rng.standard_normal(image.shape, dtype=np.float32)
    out = np.clip(image, 0, 255).astype(np.uint8)
    if c.jpeg:
        ok, data = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, int(c.jpeg)])
        out = cv2.imdecode(data, cv2.IMREAD_GRAYSCALE)
    return out


def draw_detection(gray: np.ndarray, read, design: Design, layout: MarkerLayout, camera: Camera) -> np.ndarray:
    """A color copy of `gray` with the die's pose drawn: every marker's outline, the axes, the value read."""
    import cv2

    image = cv2.cvtColor(gray, cv2.COLOR_GRAY2BGR)
    if read.pose is None:
        cv2.putText(image, "no die", (20, 40), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (0, 0, 255), 2, cv2.LINE_AA)
        return image
    s = design.mm_per_unit
    pose = read.pose
    for j, f in enumerate(layout.faces):
        quad = layout.corners[j] * s
        cam = quad @ pose.rotation.T + pose.translation
        normal = design.polyhedron.normals[f] @ pose.rotation.T
        if normal @ cam.mean(axis=0) >= 0:
            continue
        uv = cam @ camera.matrix.T
        pts = np.round(uv[:, :2] / uv[:, 2:3]).astype(np.int32)
        color = (0, 200, 0) if int(layout.ids[j]) in pose.markers else (0, 200, 255)
        cv2.polylines(image, [pts], True, color, 2, cv2.LINE_AA)
        cv2.circle(image, tuple(int(v) for v in pts[0]), 3, (255, 0, 0), -1, cv2.LINE_AA)
    centre = design.mass_properties().center * s
    axis = np.array([centre, *(centre + np.eye(3) * 0.6 * design.size_mm)])
    cam = axis @ pose.rotation.T + pose.translation
    uv = cam @ camera.matrix.T
    pts = np.round(uv[:, :2] / uv[:, 2:3]).astype(np.int32)
    for p, color in zip(pts[1:], ((0, 0, 255), (0, 255, 0), (255, 0, 0))):
        cv2.line(image, tuple(int(v) for v in pts[0]), tuple(int(v) for v in p), color, 2, cv2.LINE_AA)
    text = "unread" if read.value is None else f"{design.polyhedron.names[read.face]}: {read.value}"
    cv2.putText(
        image, f"{text}  ({read.confidence:.2f})", (20, 40), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (0, 0, 255), 2, cv2.LINE_AA
    )
    return image
