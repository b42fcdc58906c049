"""Simulated drops as camera sees them: the die's pose frame by frame until it rests.

The physics (:mod:`diefab.physics.world`) runs in model units under gravity 9.81
units/s²; a die of ``mm_per_unit`` millimetres per unit moves like the model
with time stretched by ``sqrt(mm_per_unit / 1000)`` (rigid-body dynamics with
friction and restitution is scale-free), so the frames of a camera at `fps`
frames per second are the simulation sampled every ``1 / (fps * stretch)``
model seconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from diefab.dice.design import Design
from diefab.dice.drop import PhysicsSettings
from diefab.physics.simulate import _body
from diefab.physics.world import (
    COCKED,
    LANE_COLUMNS,
    LANE_SPACING,
    LANES,
    World,
    _quat_to_matrix,
    initial_conditions,
    resting_face,
)

__all__ = ["Drop", "simulated_drop"]

#: A die whose speed stays below this (model units/s, and rad/s) for REST_TIME model seconds has stopped.
REST_SPEED, REST_TIME = 0.02, 0.5


@dataclass(frozen=True)
class Drop:
    """One drop, frame by frame: rotations (n, 3, 3) model -> world, model origins (n, 3) mm, the rest face.

    ``face`` is the face the die came to rest on, or None when it stopped cocked or never stopped.
    """

    rotations: np.ndarray
    positions: np.ndarray
    face: int | None


def simulated_drop(design: Design, seed: int, index: int, *, fps: float = 30.0, at=(0.0, 0.0)) -> Drop:
    """Drop `index` of the design's physics with `seed`, sampled at `fps`, landing around `at` (mm, x y)."""
    settings = PhysicsSettings.from_mapping(design.physics)
    body = _body(design)
    state = initial_conditions(seed, index, index + 1, settings)[0]
    lane = index % LANES
    state[0] -= LANE_SPACING * (lane % LANE_COLUMNS)
    state[1] -= LANE_SPACING * (lane // LANE_COLUMNS)
    stretch = math.sqrt(design.mm_per_unit / 1000.0)
    steps = max(1, round(1.0 / (fps * stretch) / settings.time_step))
    world = World(body, settings, slots=1)
    rotations, positions = [], []
    still = 0.0
    s = design.mm_per_unit
    try:
        world.place(0, state)
        limit = settings.time_limit
        t = 0.0
        while t < limit:
            pos, quat, lin, ang = world.state(0)
            r_body = _quat_to_matrix(np.asarray(quat))
            rotation = r_body @ body.rotation.T  # model -> world
            origin = np.asarray(pos) - rotation @ body.center
            rotations.append(rotation)
            positions.append(origin * s + [at[0], at[1], 0.0])
            speed = max(float(np.linalg.norm(lin)), float(np.linalg.norm(ang)) * body.radius)
            still = still + steps * settings.time_step if speed < REST_SPEED else 0.0
            if still >= REST_TIME:
                break
            world.step(steps)
            t += steps * settings.time_step
        code = resting_face(body.normals, quat, settings.face_tolerance) if still >= REST_TIME else COCKED
    finally:
        world.close()
    return Drop(np.array(rotations), np.array(positions), None if code < 0 else int(code))
