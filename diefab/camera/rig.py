"""The rendering test rig: rendered rests and rendered roll videos with their true values.

:func:`rendered_rests` draws resting poses (a resting face uniformly, any yaw,
anywhere near the middle of the view) under random cameras and conditions;
:func:`roll_video` renders a session of simulated drops
(:func:`~.drops.simulated_drop`) as a camera would film it: a hand takes
the die away, the die falls, bounces and rests, and stays still a while.
Both return the truth beside the frames, so a reader can be scored.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace

import numpy as np

from diefab.camera.drops import simulated_drop
from diefab.camera.render import View, random_conditions, random_view, render, rest_pose
from diefab.dice.design import Design
from diefab.dice.markers import MarkerLayout

__all__ = ["RenderedRest", "VideoFrame", "rendered_rests", "roll_video"]


@dataclass(frozen=True)
class RenderedRest:
    """A frame of the die at rest on `face` (its value `value`), seen from `view`; `occluded`: a finger is over it."""

    image: np.ndarray
    face: int
    value: int
    view: View
    occluded: bool = False


@dataclass(frozen=True)
class VideoFrame:
    """A frame of a roll video: the drop it belongs to and whether the die rests in it."""

    image: np.ndarray
    drop: int
    resting: bool


def _spot(rng: np.random.Generator, view: View, spread: float = 0.2) -> np.ndarray:
    """A point of the table within `spread` of the frame's height from the middle of the view, mm."""
    axis = view.rotation.T @ [0.0, 0.0, 1.0]
    centre = view.position - view.position[2] / axis[2] * axis
    height = 2 * view.position[2] * (view.height / 2) / view.camera.matrix[1, 1]
    angle, radius = rng.uniform(0, 2 * np.pi), spread * height * np.sqrt(rng.random())
    return centre[:2] + radius * np.array([np.cos(angle), np.sin(angle)])


def _image_circle(design: Design, view: View, rotation, position) -> tuple[np.ndarray, float]:
    """Centre and radius of the die's image, pixels."""
    pts = design.polyhedron.vertices * design.mm_per_unit @ rotation.T + position
    cam = (pts - view.position) @ view.rotation.T
    uv = cam @ view.camera.matrix.T
    uv = uv[:, :2] / uv[:, 2:3]
    centre = uv.mean(axis=0)
    return centre, float(np.linalg.norm(uv - centre, axis=1).max())


def _finger(rng: np.random.Generator, centre: np.ndarray, radius: float, reach=(0.6, 1.0)):
    """A finger from outside reaching to within `reach` (fraction of the radius) of the die's centre."""
    angle = rng.uniform(0, 2 * np.pi)
    d = np.array([np.cos(angle), np.sin(angle)])
    tip = centre + d * radius * rng.uniform(*reach)
    return (float(tip[0]), float(tip[1]), float(angle), float(radius * rng.uniform(0.35, 0.6)))


def rendered_rests(
    design: Design, layout: MarkerLayout, n: int, seed: int, *, finger: float = 0.15, start: int = 0
) -> Iterator[RenderedRest]:
    """Rendered rests `start` to `n` - 1; rest `i` draws its own view and conditions from ``(seed, i)``.

    A share `finger` of them has a finger from outside the die reaching to 0.6-1 of its image radius
    from its centre (``occluded``); no other finger is drawn.
    """
    poly = design.polyhedron
    resting = [k for k, name in enumerate(poly.names) if name in design.values]
    textures: dict = {}
    for i in range(start, n):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(i,)))
        view = random_view(rng, design)
        face = int(rng.choice(resting))
        rotation, position = rest_pose(design, face, rng.uniform(0, 2 * np.pi), _spot(rng, view))
        conditions = random_conditions(rng, view, finger=0.0)  # the one finger a rest may have is drawn below
        occluded = bool(rng.random() < finger)
        if occluded:
            conditions = replace(conditions, finger=_finger(rng, *_image_circle(design, view, rotation, position)))
        image = render(design, layout, view, rotation, position, conditions, textures=textures)
        yield RenderedRest(image, face, design.values[poly.names[face]], view, occluded)


def roll_video(
    design: Design, layout: MarkerLayout, drops: int, seed: int, *, fps: float = 30.0, hold: int = 20
) -> tuple[View, list[int | None], Iterator[VideoFrame]]:
    """A rendered session of `drops` simulated drops filmed by one fixed camera.

    Returns the view, the true value of each drop (None: the die did not rest
    on a face) and the frames.  Each drop: a hand over the last rest (3
    frames), the empty table (2), the fall with motion blur, then `hold`
    still frames of the rest with fresh sensor noise.
    """
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(10**9,)))
    view = random_view(rng, design)
    table = random_conditions(rng, view, finger=0.0)
    plans = []
    for i in range(drops):
        drop = simulated_drop(design, seed, i, fps=fps)
        shift = np.append(_spot(rng, view) - drop.positions[-1][:2], 0.0)  # the die comes to rest in view
        plans.append(replace(drop, positions=drop.positions + shift))
    truth = [None if d.face is None else design.values.get(design.polyhedron.names[d.face]) for d in plans]

    def frames() -> Iterator[VideoFrame]:
        textures: dict = {}
        previous = None
        for i, drop in enumerate(plans):
            frng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(i, 1)))
            base = replace(random_conditions(frng, view, finger=0.0), table=table.table, table_seed=table.table_seed)
            if previous is not None:
                centre, radius = _image_circle(design, view, *previous)
                for _ in range(3):
                    hand = replace(
                        base, finger=_finger(frng, centre, radius, (-0.3, 0.3)), seed=int(frng.integers(2**31))
                    )
                    yield VideoFrame(render(design, layout, view, *previous, hand, textures=textures), i, False)
            for _ in range(2):
                away = (np.eye(3), np.array([0.0, 0.0, -1e4]))  # the die out of the picture, below the table
                yield VideoFrame(
                    render(
                        design, layout, view, *away, replace(base, seed=int(frng.integers(2**31))), textures=textures
                    ),
                    i,
                    False,
                )
            last = len(drop.rotations) - 1
            for k in range(last + 1 + hold):
                j = min(k, last)
                rest = k >= last
                if not rest:
                    step = _image_circle(design, view, drop.rotations[j + 1], drop.positions[j + 1])[0]
                    here = _image_circle(design, view, drop.rotations[j], drop.positions[j])[0]
                    c = replace(base, motion=tuple(0.5 * (step - here)), seed=int(frng.integers(2**31)))
                else:
                    c = replace(base, seed=int(frng.integers(2**31)))
                yield VideoFrame(
                    render(design, layout, view, drop.rotations[j], drop.positions[j], c, textures=textures), i, rest
                )
            previous = (drop.rotations[last], drop.positions[last])

    return view, truth, frames()
