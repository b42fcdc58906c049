"""The worker side of the physics validator: pybullet worlds that drop dice.

Everything here runs inside a worker process (or a Dask worker): one
:class:`World` per process, reused from batch to batch, holds a ground plane
and a few die bodies ("slots") that fall side by side.  The dice never collide
with each other (collision filter groups), so each drop's trajectory depends
only on its own initial conditions, which come from ``(seed, drop index)``
through :class:`numpy.random.SeedSequence`: drop *i* is the same whatever the
batching, the number of slots or the number of workers.

Units and scale
---------------
The die is simulated in the paper's model units (the gem's girdle spans
z in [-1, 1]) with gravity 9.81 units/s² and unit density, so the mass is the
die's volume (its area for a shell).  Rigid-body dynamics with Coulomb
friction and restitution is scale-free: a die of size L simulated with
gravity g behaves like one of size L' with velocities scaled by sqrt(L'/L) and
times by sqrt(L'/L); the outcome distribution is the same.  Only Bullet's
collision margin is a length, and it is set explicitly (model units).

The body frame is the die's principal frame: origin at the centre of mass,
axes along the principal axes of inertia (a proper rotation), so pybullet
gets the inertia as a diagonal and no inertial-frame offset is needed.

Outcome codes: a face index ``>= 0``, :data:`COCKED` or :data:`UNSETTLED`.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import threading
from dataclasses import dataclass

import numpy as np

from diefab.models.basins import RestBasins
from diefab.physics.shapes import engine_shape, folded_resting_faces

__all__ = [
    "COCKED",
    "UNSETTLED",
    "DieBody",
    "World",
    "die_body",
    "import_pybullet",
    "initial_conditions",
    "resting_face",
    "run_batch",
]

COCKED = -1
UNSETTLED = -2

#: Raised whenever a change to this module can change a drop's outcome at given settings and seed
#: (the fast model's benchmark keys its cached counts by it).
OUTCOME_VERSION = 2
#: Steps between two settle checks of the fast path (it never changes a trajectory).
CHECK_EVERY = 32
#: Die bodies stepped together in one world.
SLOTS = 24
#: Drops start in this many lanes, on a grid LANE_COLUMNS wide and LANE_SPACING model units apart.
LANES, LANE_COLUMNS, LANE_SPACING = 24, 6, 20.0
#: The collision margin pybullet gives the parts of a compound shape (model units); the die is given as the
#: compound of its faces' pyramids (:mod:`diefab.physics.shapes`) when its margin is this one.
FACE_MARGIN = 0.001
#: Where an idle slot waits, far from the others (it never touches anything).
_PARK = (0.0, 0.0, 1.0e4)


def import_pybullet():
    """Import pybullet without its build banner (it writes one to stderr, which must stay one line per error)."""
    import sys

    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
            try:
                import pybullet
            finally:
                os.dup2(saved, 2)
    finally:
        os.close(saved)
    return pybullet


# ----------------------------------------------------------------------
# the die in its principal frame


@dataclass(frozen=True, eq=False)
class DieBody:
    """A die ready for the physics engine, in its principal frame (model units).

    Attributes
    ----------
    vertices : (n, 3) float
        Hull vertices, body frame (origin at the centre of mass).
    normals : (m, 3) float
        Outward unit face normals, body frame, polyhedron face order.
    heights : (m,) float
        Distance from the centre of mass to each face plane.
    basins : RestBasins
        Which face's basin each orientation lies in, the height the centre
        of mass must rise to leave it and which faces the die can rest on,
        body frame.
    mass : float
    inertia : (3,) float
        Principal moments of inertia.
    rotation : (3, 3) float
        Columns are the principal axes in model coordinates (det +1).
    center : (3,) float
        Centre of mass in model coordinates.
    faces : tuple of (k,) int arrays
        Each face's corners, indices into `vertices`, in face order.
    """

    vertices: np.ndarray
    normals: np.ndarray
    heights: np.ndarray
    basins: RestBasins
    mass: float
    inertia: np.ndarray
    rotation: np.ndarray
    center: np.ndarray
    faces: tuple[np.ndarray, ...] = ()

    @property
    def radius(self) -> float:
        """Largest distance from the centre of mass to a vertex."""
        return float(np.linalg.norm(self.vertices, axis=1).max())

    def key(self) -> bytes:
        """Bytes that identify the body (a world is rebuilt when they change)."""
        return b"".join(np.ascontiguousarray(a, dtype=float).tobytes() for a in (self.vertices, self.inertia)) + (
            np.float64(self.mass).tobytes()
        )


def die_body(poly, mass_props) -> DieBody:
    """The :class:`DieBody` of polyhedron `poly` with mass properties `mass_props` (model units)."""
    moments, axes = np.linalg.eigh(mass_props.inertia)
    if np.linalg.det(axes) < 0:  # eigh may return a reflection; the body frame must be a rotation
        axes[:, 2] *= -1
    center = np.asarray(mass_props.center, dtype=float)
    vertices = (poly.vertices - center) @ axes
    normals = poly.normals @ axes
    heights = poly.offsets - poly.normals @ center
    basins = RestBasins.of(poly.with_vertices(vertices), np.zeros(3))
    return DieBody(vertices, normals, heights, basins, float(mass_props.mass), moments, axes, center,
                   tuple(np.asarray(f) for f in poly.faces))  # fmt: skip


# ----------------------------------------------------------------------
# initial conditions and classification


def _quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """(..., 4) pybullet quaternions (x, y, z, w) -> (..., 3, 3) rotation matrices (body -> world)."""
    q = np.asarray(q, dtype=float)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    r = np.empty(q.shape[:-1] + (3, 3))
    r[..., 0, 0] = 1 - 2 * (y * y + z * z)
    r[..., 0, 1] = 2 * (x * y - z * w)
    r[..., 0, 2] = 2 * (x * z + y * w)
    r[..., 1, 0] = 2 * (x * y + z * w)
    r[..., 1, 1] = 1 - 2 * (x * x + z * z)
    r[..., 1, 2] = 2 * (y * z - x * w)
    r[..., 2, 0] = 2 * (x * z - y * w)
    r[..., 2, 1] = 2 * (y * z + x * w)
    r[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return r


def _quat_rates(q: np.ndarray, w: np.ndarray, inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Time derivatives of orientation `q` (k, 4; x, y, z, w) and body angular velocity `w` (k, 3), torque-free."""
    x, y, z, s = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    a, b, c = w[:, 0], w[:, 1], w[:, 2]
    dq = 0.5 * np.stack(
        [s * a + y * c - z * b, s * b + z * a - x * c, s * c + x * b - y * a, -x * a - y * b - z * c], 1
    )
    dw = np.cross(w * inertia, w) / inertia  # Euler's equations in the principal frame
    return dq, dw


def fly(states: np.ndarray, body: DieBody, settings, clearance: float = 0.25) -> tuple[np.ndarray, np.ndarray]:
    """Carry drops through their first free fall, until the die could be `clearance` above the ground.

    Gravity is the only force until the die first comes near the ground, so
    that stretch needs no collision engine: the centre of mass follows
    Bullet's own discrete free fall exactly (semi-implicit Euler at
    ``time_step``), and the orientation and spin follow the torque-free
    Euler equations (RK4 at four time steps, far more accurate than
    the engine's one-step integrator).  The hand-over happens after a whole
    number of steps, a multiple of four, while the lowest point of the die cannot be lower than
    `clearance` (centre height minus the die's radius).

    Returns
    -------
    states : (k, 13) float
        The drops at the hand-over.
    steps : (k,) int
        Engine steps skipped by each drop.
    """
    s = settings
    dt, g = s.time_step, s.gravity
    z0, vz0 = states[:, 2], states[:, 9]
    # z after k steps: z0 + dt * (k vz0 - g dt k (k + 1) / 2); largest even k with z - radius >= clearance
    a, b, c = -g * dt * dt / 2, dt * vz0 - g * dt * dt / 2, z0 - body.radius - clearance
    disc = np.maximum(b * b - 4 * a * c, 0.0)
    k = np.floor((-b - np.sqrt(disc)) / (2 * a)).astype(np.int64)
    k = np.where(c > 0, np.maximum(k, 0), 0)
    k -= k % 4
    out = states.copy()
    kf = k.astype(float)
    out[:, 0:2] += states[:, 7:9] * (kf * dt)[:, None]
    out[:, 2] = z0 + dt * (kf * vz0 - g * dt * kf * (kf + 1) / 2)
    out[:, 9] = vz0 - g * dt * kf
    # orientation: RK4 in the principal frame, each drop frozen after its own k / 2 steps
    q = states[:, 3:7].copy()
    rot = _quat_to_matrix(q)
    w = np.einsum("kji,kj->ki", rot, states[:, 10:13])
    h = 4 * dt
    inertia = body.inertia
    for i in range(int(k.max(initial=0)) // 4):
        live = k // 4 > i
        if not live.any():
            break
        ql, wl = q[live], w[live]
        k1q, k1w = _quat_rates(ql, wl, inertia)
        k2q, k2w = _quat_rates(ql + h / 2 * k1q, wl + h / 2 * k1w, inertia)
        k3q, k3w = _quat_rates(ql + h / 2 * k2q, wl + h / 2 * k2w, inertia)
        k4q, k4w = _quat_rates(ql + h * k3q, wl + h * k3w, inertia)
        ql = ql + h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q)
        q[live] = ql / np.linalg.norm(ql, axis=1)[:, None]
        w[live] = wl + h / 6 * (k1w + 2 * k2w + 2 * k3w + k4w)
    out[:, 3:7] = q
    out[:, 10:13] = np.einsum("kij,kj->ki", _quat_to_matrix(q), w)
    return out, k


def initial_conditions(seed: int, start: int, stop: int, settings) -> np.ndarray:
    """(stop - start, 13) float: position, quaternion (x, y, z, w), linear and angular velocity of drops.

    Drop *i* draws from ``SeedSequence(seed, spawn_key=(i,))`` (the *i*-th child
    of ``SeedSequence(seed)``), so it does not depend on how drops are batched.
    It falls in lane ``i % LANES``, a point of a grid :data:`LANE_SPACING`
    apart, so that the dice stepped together in one world seldom overlap in
    the engine's broadphase (a horizontal shift does not change the physics).
    """
    out = np.empty((stop - start, 13))
    s = settings
    lane = np.arange(start, stop) % LANES
    out[:, 0] = LANE_SPACING * (lane % LANE_COLUMNS)
    out[:, 1] = LANE_SPACING * (lane // LANE_COLUMNS)
    for row, i in enumerate(range(start, stop)):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(i,)))
        u = rng.random(7)
        q = rng.normal(size=4)  # uniform on SO(3)
        q /= np.linalg.norm(q)
        spin_axis = rng.normal(size=3)
        spin_axis /= np.linalg.norm(spin_axis)
        height = s.drop_height + s.height_jitter * (2 * u[0] - 1)
        spin = s.angular_velocity[0] + (s.angular_velocity[1] - s.angular_velocity[0]) * u[1]
        speed = s.linear_velocity[0] + (s.linear_velocity[1] - s.linear_velocity[0]) * u[2]
        heading = 2 * np.pi * u[3]
        out[row, 2:] = [height, *q, speed * np.cos(heading), speed * np.sin(heading), 0.0, *(spin * spin_axis)]
    return out


def resting_face(normals: np.ndarray, quaternion, tolerance_deg: float) -> int:
    """Face whose outward normal is within `tolerance_deg` of straight down, or :data:`COCKED`.

    Parameters
    ----------
    normals : (m, 3) float
        Body-frame outward face normals.
    quaternion : (4,) float
        Body orientation, pybullet order (x, y, z, w).
    """
    down = -_quat_to_matrix(quaternion)[2]  # world -z in body coordinates: row 2 of R is R^T e_z
    cos = normals @ down
    k = int(np.argmax(cos))
    return k if cos[k] >= np.cos(np.radians(tolerance_deg)) else COCKED


# ----------------------------------------------------------------------
# the world


class World:
    """A pybullet DIRECT world with a ground plane and `slots` copies of one die.

    Parameters
    ----------
    body : DieBody
    settings : PhysicsSettings
    slots : int
        Dice that fall side by side (they never touch each other).
    engine_defaults : bool
        Keep pybullet's own engine parameters (50 solver iterations with its
        residual early exit) instead of ``settings.solver_iterations`` fixed
        iterations: the straightforward loop a paper script would run
        (:meth:`run_plain`, one slot).
    """

    def __init__(self, body: DieBody, settings, slots: int = SLOTS, *, engine_defaults: bool = False) -> None:
        p = import_pybullet()
        self.p, self.body, self.settings = p, body, settings
        s = settings
        self.cid = cid = p.connect(p.DIRECT)
        p.setGravity(0, 0, -s.gravity, physicsClientId=cid)
        p.setTimeStep(s.time_step, physicsClientId=cid)
        # a fixed number of solver iterations (no residual early exit, which would couple the dice
        # solved in one batch) and sorted overlapping pairs: drop i is the same in any slot
        if not engine_defaults:
            p.setPhysicsEngineParameter(
                numSolverIterations=s.solver_iterations,
                solverResidualThreshold=0.0,
                deterministicOverlappingPairs=1,
                physicsClientId=cid,
            )
        # rounded edges: the shrunk hull, swept by the engine's margin (the faces' indices in the sharp die)
        self.faces = np.arange(len(body.normals))
        margin = s.collision_margin
        if s.edge_radius > 0:
            from diefab.physics.edges import shrunk_body

            radius = s.edge_radius * body.radius
            self.body, self.faces = shrunk_body(body, radius)
            margin += radius
        self.margin = margin
        plane = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid)
        self.ground = p.createMultiBody(0, plane, physicsClientId=cid)
        p.changeDynamics(
            self.ground,
            -1,
            restitution=s.restitution,
            lateralFriction=s.friction,
            rollingFriction=s.rolling_friction,
            spinningFriction=s.spinning_friction,
            physicsClientId=cid,
        )
        self.sink = 0.0  # how far the die sinks into a soft table at rest, model units
        if s.table_softness > 0:
            self.sink = s.table_softness * body.radius
            stiffness = body.mass * s.gravity / self.sink
            damping = 2.0 * s.table_damping * np.sqrt(stiffness * body.mass)
            p.changeDynamics(self.ground, -1, contactStiffness=stiffness, contactDamping=damping,
                             physicsClientId=cid)  # fmt: skip
        p.setCollisionFilterGroupMask(self.ground, -1, 1, 2, physicsClientId=cid)
        # a compound's parts keep the engine's margin: a die with another one (rounded) stays one hull
        flat = folded_resting_faces(p, self.body) if s.flat_faces and margin == FACE_MARGIN else np.zeros(1, bool)
        # the parts' files are read again as each body is made
        with tempfile.TemporaryDirectory(prefix="diefab-die-") if flat.any() else contextlib.nullcontext() as files:
            if flat.any():
                p.setPhysicsEngineParameter(enableFileCaching=0, physicsClientId=cid)  # the files are temporary
                shape = engine_shape(p, self.body, flat, cid, files)
            else:
                shape = p.createCollisionShape(p.GEOM_MESH, vertices=self.body.vertices.tolist(), physicsClientId=cid)
            self.dice = [self._add_die(shape, k, margin) for k in range(slots)]
        self._park_all()

    def _add_die(self, shape: int, slot: int, margin: float) -> int:
        p, cid, s, body = self.p, self.cid, self.settings, self.body
        die = p.createMultiBody(body.mass, shape, basePosition=[0, 0, _PARK[2] + 10 * slot], useMaximalCoordinates=True,
                                physicsClientId=cid)  # fmt: skip
        # pybullet bug: localInertiaDiagonal without mass= on a maximal-coordinate body gives NaN
        p.changeDynamics(
            die,
            -1,
            mass=body.mass,
            localInertiaDiagonal=body.inertia.tolist(),
            restitution=s.restitution,
            lateralFriction=s.friction,
            rollingFriction=s.rolling_friction,
            spinningFriction=s.spinning_friction,
            collisionMargin=margin,
            linearDamping=0.0,
            angularDamping=0.0,
            # a body that falls asleep at rest and is then reset into the air would hang there
            activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING,
            physicsClientId=cid,
        )
        p.setCollisionFilterGroupMask(die, -1, 2, 1, physicsClientId=cid)
        return die

    def close(self) -> None:
        if self.cid is not None:
            self.p.disconnect(physicsClientId=self.cid)
            self.cid = None

    # -- body state --------------------------------------------------
    def place(self, slot: int, state) -> None:
        """Put the die of `slot` at `state` (13 numbers, see :func:`initial_conditions`) and wake it."""
        p, die = self.p, self.dice[slot]
        p.resetBasePositionAndOrientation(die, state[0:3], state[3:7], physicsClientId=self.cid)
        p.resetBaseVelocity(die, state[7:10], state[10:13], physicsClientId=self.cid)
        p.changeDynamics(die, -1, activationState=p.ACTIVATION_STATE_WAKE_UP, physicsClientId=self.cid)

    def _park(self, slot: int) -> None:
        x, y, z = _PARK
        self.place(slot, [x + 10.0 * slot, y, z, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0])

    def _park_all(self) -> None:
        for slot in range(len(self.dice)):
            self._park(slot)

    def state(self, slot: int) -> tuple:
        """(position, quaternion, linear velocity, angular velocity) of the die in `slot`."""
        p, die = self.p, self.dice[slot]
        pos, quat = p.getBasePositionAndOrientation(die, physicsClientId=self.cid)
        lin, ang = p.getBaseVelocity(die, physicsClientId=self.cid)
        return pos, quat, lin, ang

    def step(self, steps: int = 1) -> None:
        step, cid = self.p.stepSimulation, self.cid
        for _ in range(steps):
            step(physicsClientId=cid)

    # -- the fast path -----------------------------------------------
    def run(self, states: np.ndarray, *, early: bool = True, with_steps: bool = False):
        """Drop the dice of `states` ((k, 13)) and return their (k,) outcome codes.

        Each drop first falls freely (:func:`fly`, no engine needed) until it
        nears the ground; then the engine steps all slots together, and every
        :data:`CHECK_EVERY` steps each die is checked: it has landed on face f
        once its orientation lies in f's basin (:class:`RestBasins`) and its
        kinetic energy plus its potential energy above rest on f is below
        ``settings.energy_fraction`` of f's basin barrier (it can never leave
        the basin, whose only resting place is f), or once it has been still
        for ``settings.cocked_time`` on a face it can rest on, within
        ``face_tolerance`` of straight down; still that long on no such
        face, it is cocked; it is unsettled at ``settings.time_limit``.
        Without the energy rule (`early` False or ``energy_fraction`` 0) a
        die still for ``settings.settle_time`` on a face it can rest on has
        landed.  The quasi-static capture (``settings.capture_energy``)
        raises the energy below which a die in a basin has landed there.
        `early` False turns off the free-fall shortcut, the energy rule and
        the capture (the die then runs until still).
        `with_steps` True also returns the (k,) int engine steps after which
        each drop ended (counting the free fall).
        """
        s, body = self.settings, self.body
        n = len(states)
        if early:
            # (a rounded die reaches its shrunk hull's radius plus the rounding)
            states, skipped = fly(states, body, s, clearance=0.25 + self.margin - s.collision_margin)
        else:
            skipped = np.zeros(n, dtype=np.int64)
        outcomes = np.full(n, UNSETTLED, dtype=np.int32)
        ended = np.zeros(n, dtype=np.int64)
        slots = len(self.dice)
        current = np.full(slots, -1)  # drop index in each slot
        steps = np.zeros(slots, dtype=np.int64)
        still = np.zeros(slots, dtype=np.int64)
        max_steps = int(np.ceil(s.time_limit / s.time_step - 1e-9))
        settle_steps = int(np.ceil(s.settle_time / s.time_step - 1e-9))
        cocked_steps = int(np.ceil(s.cocked_time / s.time_step - 1e-9))
        mg = body.mass * s.gravity
        # (on a soft table the die rests up to its sink lower: counting it makes the energy rule only stricter)
        rest = body.heights + s.collision_margin - self.sink
        # None: the energy rule is off
        basins = body.basins if early and (s.energy_fraction > 0 or s.capture_energy > 0) else None
        if basins is not None:
            # (0 times an infinite barrier would be NaN)
            limit = s.energy_fraction * mg * basins.barriers if s.energy_fraction > 0 else np.zeros(len(rest))
            if s.capture_energy > 0:  # quasi-static capture: below this energy a die stays in its basin
                limit = np.maximum(limit, s.capture_energy * mg * body.radius)
            ceiling = (mg * rest + limit).max()  # total energy above which no die is trapped
        else:
            ceiling = -np.inf
        # with the energy rule a die must be still for cocked_time on a face (settle_time without it)
        still_window = cocked_steps if early and s.energy_fraction > 0 else settle_steps
        cos_tol = np.cos(np.radians(s.face_tolerance))
        resting = body.basins.resting
        half_m, half_i, normals = 0.5 * body.mass, 0.5 * body.inertia, body.normals
        half_i_min = half_i.min()
        still_speed2, still_spin2 = s.still_speed**2, s.still_spin**2
        p, cid, dice = self.p, self.cid, self.dice
        nxt = 0

        def load(slot: int) -> None:
            nonlocal nxt
            if nxt < n:
                self.place(slot, states[nxt])
                current[slot], steps[slot], still[slot] = nxt, skipped[nxt], 0
                nxt += 1
            else:
                self._park(slot)
                current[slot] = -1

        for slot in range(slots):
            load(slot)
        while True:
            live = np.flatnonzero(current >= 0)
            if len(live) == 0:
                break
            self.step(CHECK_EVERY)
            steps[live] += CHECK_EVERY
            state = np.array(
                [
                    sum(p.getBasePositionAndOrientation(dice[k], physicsClientId=cid), ())
                    + sum(p.getBaseVelocity(dice[k], physicsClientId=cid), ())
                    for k in live
                ]
            )
            lin, ang = state[:, 7:10], state[:, 10:13]
            speed2, spin2 = (lin * lin).sum(1), (ang * ang).sum(1)
            is_still = (speed2 < still_speed2) & (spin2 < still_spin2)
            still[live] = np.where(is_still, still[live] + CHECK_EVERY, 0)
            # a lower bound of the total energy spares the dice that cannot be trapped a closer look
            bound = half_m * speed2 + half_i_min * spin2 + mg * state[:, 2]
            near = np.flatnonzero((bound < ceiling) | (still[live] >= settle_steps) | (steps[live] >= max_steps))
            live, state, still_near = live[near], state[near], still[live[near]]
            rot = _quat_to_matrix(state[:, 3:7])
            cos = -rot[:, 2, :] @ normals.T  # world -z in body coordinates, against each normal
            face = np.argmax(cos, axis=1)
            if basins is None:
                basin, trapped = face, np.zeros(len(live), dtype=bool)
            else:
                omega = np.einsum("kji,kj->ki", rot, state[:, 10:13])  # body-frame angular velocity
                energy = half_m * speed2[near] + (half_i * omega * omega).sum(1) + mg * state[:, 2]
                basin = basins.lookup(-rot[:, 2, :])
                trapped = energy - mg * rest[basin] < limit[basin]
            # still on a face it cannot rest on, a die is toppling (or, if it stays, cocked)
            down = (cos[np.arange(len(live)), face] >= cos_tol) & resting[face]
            # the landing rule: a die has landed once it can no longer leave its face (in the face's basin,
            # below its barrier); a short still window is not enough (a die toppling slowly off a face is
            # still for a while), so without the energy rule a die must be still for settle_time and with it
            # (engine errors can hide a tiny barrier) for cocked_time
            landed = trapped | (down & (still_near >= still_window))
            cocked = ~down & (still_near >= cocked_steps)
            timeout = steps[live] >= max_steps
            for j in np.flatnonzero(landed | cocked | timeout):
                k = live[j]
                ended[current[k]] = steps[k]
                if landed[j]:
                    outcomes[current[k]] = basin[j] if trapped[j] else face[j]
                else:
                    outcomes[current[k]] = COCKED if cocked[j] else UNSETTLED
                load(k)
            if nxt >= n:
                for k in np.flatnonzero(current < 0):
                    self._park(k)  # idle dice would otherwise fall for the rest of the run
        outcomes = self._sharp(outcomes)
        return (outcomes, ended) if with_steps else outcomes

    def _sharp(self, outcomes: np.ndarray) -> np.ndarray:
        """Outcome codes with the faces of a rounded die's shrunk hull numbered as the sharp die's."""
        return np.where(outcomes >= 0, self.faces[np.maximum(outcomes, 0)], outcomes).astype(np.int32)

    # -- the straightforward loop ------------------------------------
    def run_plain(self, states: np.ndarray) -> np.ndarray:
        """The paper-style reference loop: one die, one step at a time, velocities polled every step.

        A die still (speeds below ``still_speed`` / ``still_spin``) for
        ``settle_time`` with a face within ``face_tolerance`` of straight down
        has landed on it; still for ``cocked_time`` with no face down, it is
        cocked; unsettled at ``time_limit``.  The benchmark and the tests use
        it as the baseline the fast path must agree with.
        """
        p, cid, die = self.p, self.cid, self.dice[0]
        s = self.settings
        outcomes = np.full(len(states), UNSETTLED, dtype=np.int32)
        for i, state in enumerate(states):
            self.place(0, state)
            t = still = 0.0
            while t < s.time_limit - 1e-12:
                p.stepSimulation(physicsClientId=cid)
                t += s.time_step
                lin, ang = p.getBaseVelocity(die, physicsClientId=cid)
                if np.linalg.norm(lin) < s.still_speed and np.linalg.norm(ang) < s.still_spin:
                    still += s.time_step
                    if still >= s.settle_time - 1e-12:
                        quat = p.getBasePositionAndOrientation(die, physicsClientId=cid)[1]
                        face = resting_face(self.body.normals, quat, s.face_tolerance)
                        if face != COCKED and not self.body.basins.resting[face]:
                            face = COCKED  # still on a transitional face: toppling, or cocked if it stays
                        if face != COCKED or still >= s.cocked_time - 1e-12:
                            outcomes[i] = face
                            break
                else:
                    still = 0.0
        self._park(0)
        return self._sharp(outcomes)


# ----------------------------------------------------------------------
# one world per process (per thread under Dask's threaded workers)

_LOCAL = threading.local()


def _world(body: DieBody, settings, plain: bool) -> World:
    key = (body.key(), settings, plain)
    world = getattr(_LOCAL, "world", None)
    if world is None or _LOCAL.key != key:
        if world is not None:
            world.close()
        _LOCAL.world = World(body, settings, 1, engine_defaults=True) if plain else World(body, settings)
        _LOCAL.key = key
    return _LOCAL.world


def run_batch(body: DieBody, settings, seed: int, start: int, stop: int, plain: bool = False) -> np.ndarray:
    """Outcome codes of drops ``start .. stop - 1`` at `seed` (the unit of work sent to a worker)."""
    world = _world(body, settings, plain)
    states = initial_conditions(seed, start, stop, settings)
    return world.run_plain(states) if plain else world.run(states)


def worker_rss_mb() -> float:
    """Resident memory of this process, MB (Linux /proc)."""
    with open("/proc/self/status", encoding="ascii") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def worker_signals() -> None:
    """Worker initializer: Ctrl-C and hang-ups are left to the parent, and the parent's SIGTERM ends the worker.

    The parent cancels a run cleanly on Ctrl-C.  A forked worker would
    otherwise inherit the command line's SIGTERM handler, which turns SIGTERM
    into an interrupt of the current batch, and the worker would live on.
    """
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if hasattr(signal, "SIGHUP"):  # a closed terminal hangs up the whole group: the parent stops the run
        signal.signal(signal.SIGHUP, signal.SIG_IGN)
