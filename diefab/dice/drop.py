"""The drop a die is designed for: how it is thrown, onto what, and how a simulation steps it.

A design file's ``[physics]`` table holds these settings (see
:class:`PhysicsSettings`); :mod:`diefab.physics` drops the die with them.

Examples
--------
>>> s = PhysicsSettings.from_mapping({"restitution": 0.5, "angular_velocity": [0, 20]})
>>> s.restitution, s.friction, s.angular_velocity
(0.5, 0.8, (0.0, 20.0))
>>> PhysicsSettings(friction=-1)
Traceback (most recent call last):
...
diefab.core.errors.PhysicsError: physics friction=-1.0 must be a finite number >= 0
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from typing import Any

import numpy as np

from diefab.core.errors import PhysicsError

__all__ = ["MIN_TIME_STEP", "OPT_IN", "PhysicsSettings"]

#: Finest simulation step, seconds (10 kHz; pybullet's default is 240 Hz).
MIN_TIME_STEP = 1e-4
#: Settings added after the others, with the value that turns them off (the rigid simulation).
OPT_IN = {"capture_energy": 0.0, "table_softness": 0.0, "table_damping": 0.0, "edge_radius": 0.0, "flat_faces": False}


def _check(name: str, value, ok: bool, expected: str) -> None:
    if not ok:
        raise PhysicsError(f"physics {name}={value!r} must be {expected}")


def _finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


@dataclass(frozen=True)
class PhysicsSettings:
    """Settings of a simulated drop (model units, seconds, radians; tolerance in degrees).

    Parameters
    ----------
    restitution : float
        Bullet's restitution, given to the die and to the ground alike, in
        [0, 1] (paper: 0.3).  The engine multiplies the two, so it is not
        the coefficient of restitution of an impact: a die dropped flat
        leaves the table at about 0.7 times the setting's square of its
        impact speed (0.07 at 0.3, 0.24 at 0.6, 0.56 at 0.9, after a fall
        of two units at the default step).
    friction : float
        Bullet's Coulomb (lateral) friction, given to the die and to the
        ground alike, >= 0 (paper: 0.8).  The engine multiplies the two: the
        sliding die's friction coefficient is its square (0.64 at 0.8).
    rolling_friction, spinning_friction : float
        Bullet's rolling and spinning friction, >= 0.
    time_step : float
        Simulation step, seconds, in (0, 0.05].
    solver_iterations : int
        Constraint-solver iterations per step, a fixed number (pybullet's
        default is up to 50 with an early exit on a residual, which would
        couple the dice stepped in one world; Bullet's own default is 10).
        For one die on a plane 5 already give the same distribution as
        pybullet's defaults (``benchmarks/bench_validate.py``).
    collision_margin : float
        Bullet's collision margin of the die, model units, in [0, 0.1].
    gravity : float
        Units/s² (the die is simulated in model units).
    drop_height : float
        Initial height of the centre of mass above the ground (paper: about 5).
    height_jitter : float
        The height is uniform in ``drop_height ± height_jitter``.
    angular_velocity : (float, float)
        Range of the initial spin, rad/s; uniform magnitude, uniform direction.
    linear_velocity : (float, float)
        Range of the initial horizontal speed, units/s; uniform heading.
    still_speed, still_spin : float
        A die is still when its speed (units/s) and spin (rad/s) are below these.
    settle_time : float
        Without the energy rule (``energy_fraction`` 0), a die still this
        long (s) on a face it can rest on, within ``face_tolerance`` of
        straight down, has landed on that face.  With it, a die has landed
        when it can no longer leave its face (see ``energy_fraction``) or
        has been still on it for ``cocked_time``: a short still window
        counts a die toppling slowly off a face as resting on it.
    cocked_time : float
        A die still this long (s) with no face down is cocked (a die
        momentarily balanced on an edge can be still for a short while).
    energy_fraction : float
        The landing rule: a die whose orientation lies in face f's basin
        (:class:`diefab.models.basins.RestBasins`) has landed on f once its kinetic
        energy plus potential energy above rest on f is below this fraction
        of the basin's barrier (its lowest saddle): it can no longer leave
        f.  0 turns the rule off (``settle_time`` then decides).  The rest
        is a margin for the engine's energy errors.  In [0, 1).
    capture_energy : float
        Quasi-static capture, in units of ``m g L`` (mass, gravity, the die's
        radius L: the largest distance from its centre of mass to a
        vertex).  A die in face f's basin whose kinetic energy plus
        potential energy above rest on f is below this has landed on f,
        even where that is above f's barrier: a real die loses its energy
        faster than a rigid hull on a rigid plane (plastic impacts, a table
        that gives), so a slow die stays in the basin it is in.  One
        threshold for all faces acts most in wide, shallow basins, which a
        rigid hull rolls out of.  0 (the default)
        turns it off: the rigid simulation.  Very large, every die lands in
        the basin of its orientation at the first check after it nears the
        ground, the quasi-static model.  In [0, 100].
    table_softness : float
        A table that gives: how far the die sinks into it under its own
        weight, in units of the die's radius L (the contact stiffness is
        ``m g / (table_softness L)``).  0 (the default) is a rigid table.
        In [0, 0.1].
    table_damping : float
        Damping ratio of the soft table's contact (critical at 1), used
        only with ``table_softness``.  In [0, 10].
    edge_radius : float
        Rounded edges and corners, as printed dice have: the die collides as
        its hull shrunk by this radius and swept by a ball of it (its faces
        stay where they are), in units of the die's radius L.  A face
        narrower than the rounding vanishes, and the die cannot rest on it.
        0 (the default) is the sharp hull.  In [0, 0.2].
    flat_faces : bool
        Hold every face the die can rest on flat in the engine.  Bullet
        rounds a hull's corners to a grid of 1/10216 of its size, which
        folds a face of four or more corners that does not lie across an
        axis (a trapezohedron's kites, the icosahedral die's pentagons); on
        a die of shallow faces the folds make faces its symmetry makes alike
        land unevenly.  True gives the engine such a die as flat-faced parts
        (:mod:`diefab.physics.shapes`), two to four times slower per drop;
        a die whose hull folds none of its resting faces, or whose margin is
        not the engine's 0.001, is simulated as one hull either way.  False
        (the default) is the one hull.
    time_limit : float
        A die still moving after this many seconds is unsettled.
    face_tolerance : float
        Degrees: a settled die lies on a face when that face's outward normal
        is within this angle of straight down, otherwise it is cocked.
    """

    restitution: float = 0.3
    friction: float = 0.8
    rolling_friction: float = 0.0
    spinning_friction: float = 0.0
    time_step: float = 1.0 / 240.0
    solver_iterations: int = 5
    collision_margin: float = 0.001
    gravity: float = 9.81
    drop_height: float = 5.0
    height_jitter: float = 0.5
    angular_velocity: tuple[float, float] = (0.0, 10.0)
    linear_velocity: tuple[float, float] = (0.0, 0.0)
    still_speed: float = 0.02
    still_spin: float = 0.05
    settle_time: float = 0.1
    cocked_time: float = 1.0
    energy_fraction: float = 0.95
    capture_energy: float = 0.0
    table_softness: float = 0.0
    table_damping: float = 0.0
    edge_radius: float = 0.0
    flat_faces: bool = False
    time_limit: float = 20.0
    face_tolerance: float = 3.0

    def __post_init__(self) -> None:
        for name in ("angular_velocity", "linear_velocity"):
            value = getattr(self, name)
            if not isinstance(value, tuple):
                try:
                    value = tuple(value)
                except TypeError:
                    raise PhysicsError(f"physics {name}={value!r} must be a [min, max] pair") from None
                object.__setattr__(self, name, value)
            _check(name, list(value), len(value) == 2 and all(map(_finite, value)), "a [min, max] pair of numbers")
            object.__setattr__(self, name, (float(value[0]), float(value[1])))
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "solver_iterations":
                ok = isinstance(value, (int, np.integer)) and not isinstance(value, bool) and 1 <= value <= 1000
                _check(f.name, value, ok, "an integer in [1, 1000]")
                object.__setattr__(self, f.name, int(value))
            elif f.name == "flat_faces":
                _check(f.name, value, isinstance(value, (bool, np.bool_)), "true or false")
                object.__setattr__(self, f.name, bool(value))
            elif not isinstance(value, tuple):
                _check(f.name, value, _finite(value), "a finite number")
                object.__setattr__(self, f.name, float(value))
        c = _check
        c("restitution", self.restitution, 0 <= self.restitution <= 1, "in [0, 1]")
        for name in ("friction", "rolling_friction", "spinning_friction"):
            c(name, getattr(self, name), getattr(self, name) >= 0, "a finite number >= 0")
        c("time_step", self.time_step, MIN_TIME_STEP <= self.time_step <= 0.05,
          f"in [{MIN_TIME_STEP:g}, 0.05] seconds (finer steps give nothing but hours per drop)")  # fmt: skip
        c("collision_margin", self.collision_margin, 0 <= self.collision_margin <= 0.1, "in [0, 0.1] model units")
        c("gravity", self.gravity, 0 < self.gravity <= 1000, "in (0, 1000] units/s²")
        c("drop_height", self.drop_height, 0 < self.drop_height <= 1000, "in (0, 1000] model units")
        c("height_jitter", self.height_jitter, 0 <= self.height_jitter < self.drop_height,
          f"in [0, drop_height={self.drop_height:g})")  # fmt: skip
        for name, top in (("angular_velocity", 1000.0), ("linear_velocity", 100.0)):
            lo, hi = getattr(self, name)
            c(name, [lo, hi], 0 <= lo <= hi <= top, f"a range [min, max] with 0 <= min <= max <= {top:g}")
        c("still_speed", self.still_speed, self.still_speed > 0, "> 0 units/s")
        c("still_spin", self.still_spin, self.still_spin > 0, "> 0 rad/s")
        c("settle_time", self.settle_time, 0 <= self.settle_time <= 10, "in [0, 10] seconds")
        c("cocked_time", self.cocked_time, self.settle_time <= self.cocked_time <= 60,
          f"in [settle_time={self.settle_time:g}, 60] seconds")  # fmt: skip
        c("energy_fraction", self.energy_fraction, 0 <= self.energy_fraction < 1, "in [0, 1)")
        c("capture_energy", self.capture_energy, 0 <= self.capture_energy <= 100, "in [0, 100] (units of m g L)")
        c("table_softness", self.table_softness, 0 <= self.table_softness <= 0.1, "in [0, 0.1] (units of L)")
        c("table_damping", self.table_damping, 0 <= self.table_damping <= 10, "in [0, 10]")
        c("edge_radius", self.edge_radius, 0 <= self.edge_radius <= 0.2, "in [0, 0.2] (units of L)")
        c("time_limit", self.time_limit, self.cocked_time < self.time_limit <= 600,
          f"in (cocked_time={self.cocked_time:g}, 600] seconds")  # fmt: skip
        c("face_tolerance", self.face_tolerance, 0 < self.face_tolerance < 45, "in (0, 45) degrees")

    @classmethod
    def from_mapping(cls, mapping: Mapping[str, Any] | None, **overrides: Any) -> PhysicsSettings:
        """Settings from a design's ``[physics]`` table, then `overrides` (None values are ignored)."""
        if mapping is not None and not isinstance(mapping, Mapping):
            raise PhysicsError(f"physics settings {mapping!r} are not a table of name = value")
        data = dict(mapping or {})
        data.update({k: v for k, v in overrides.items() if v is not None})
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise PhysicsError(f"unknown physics setting {unknown[0]!r} (settings: {', '.join(sorted(known))})")
        return cls(**data)

    def as_dict(self) -> dict[str, Any]:
        """The settings as a plain mapping (ranges as lists), e.g. for JSON.

        An opt-in setting (:data:`OPT_IN`) at its off value is left out, so
        the mapping of settings that do not use it is the same as before it
        existed (stored runs and caches compare these mappings).
        """
        return {
            k: list(v) if isinstance(v, tuple) else v
            for k, v in asdict(self).items()
            if not (k in OPT_IN and v == OPT_IN[k])
        }
