"""Draw docs/img/marker-stickers.png and docs/img/read-detection.png.

    python docs/images/camera_figures.py

The gem's sticker sheet (the top of its first page), and a rendered frame of
the gem at rest (a fixed camera straight above it, seed 3) with what the
reader found drawn on it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from diefab.camera.pose import Camera, MarkerDetector, read_frame
from diefab.camera.render import Conditions, View, draw_detection, render, rest_pose
from diefab.dice.design import load_design
from diefab.dice.markers import marker_layout
from diefab.fabricate.pdf import render_png
from diefab.fabricate.stickers import sticker_sheets

IMG = Path(__file__).resolve().parent.parent / "img"


def stickers(design) -> None:
    import cv2

    sheet = sticker_sheets(design)[:1]
    image = cv2.imdecode(np.frombuffer(render_png(sheet, dpi=150), np.uint8), cv2.IMREAD_COLOR)
    inner = image[8:-8, 8:-8]  # inside the page's outline
    ys, _ = np.nonzero(inner.min(axis=2) < 200)
    top = image[: min(int(ys.max()) + 8 + 40, image.shape[0])]
    scale = 744 / top.shape[1]
    cv2.imwrite(
        str(IMG / "marker-stickers.png"), cv2.resize(top, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    )


def detection(design) -> None:
    import cv2

    layout = marker_layout(design)
    camera = Camera.from_fov(1280, 720, 65.0)
    view = View(camera, np.diag([1.0, -1.0, -1.0]), np.array([0.0, 0.0, 160.0]), 1280, 720)
    rotation, position = rest_pose(design, 3, 0.6, (4.0, -2.0))
    image = render(design, layout, view, rotation, position, Conditions(noise=2.0, blur=0.6, seed=3, table_seed=3))
    read = read_frame(image, design, MarkerDetector(layout), camera, down=view.down)
    drawn = draw_detection(image, read, design, layout, camera)
    cv2.imwrite(str(IMG / "read-detection.png"), cv2.resize(drawn, (960, 540), interpolation=cv2.INTER_AREA))


if __name__ == "__main__":
    gem = load_design("fudge-gem")
    stickers(gem)
    detection(gem)
    print(f"wrote {IMG / 'marker-stickers.png'} and {IMG / 'read-detection.png'}")
