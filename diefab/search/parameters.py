"""The physics settings calibration can fit: their ranges, units and scale, and settings at given values."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

__all__ = ["DEFAULT_FREE", "MAX_GRID", "PARAMETERS", "Parameter", "parameter_value", "settings_at"]


@dataclass(frozen=True)
class Parameter:
    """A physics setting that calibration can fit.

    ``setting`` is the :class:`diefab.physics.simulate.PhysicsSettings` field it
    changes; for a range (``angular_velocity``, ``linear_velocity``) the
    parameter is the range's upper end.  Over the unit cube u of the search
    the parameter is ``low + (high - low) u ** power``: a power above 1
    spreads the search where small values already matter.
    """

    name: str
    setting: str
    low: float
    high: float
    unit: str
    text: str
    power: float = 1.0


PARAMETERS: dict[str, Parameter] = {
    p.name: p
    for p in (
        Parameter("restitution", "restitution", 0.0, 0.9, "", "Bullet's restitution of die and ground, each"),
        Parameter("friction", "friction", 0.1, 1.5, "", "Bullet's Coulomb friction of die and ground, each"),
        Parameter("rolling_friction", "rolling_friction", 0.0, 0.06, "units", "Bullet's rolling friction"),
        Parameter("spinning_friction", "spinning_friction", 0.0, 0.02, "", "Bullet's spinning friction"),
        Parameter("spin", "angular_velocity", 0.0, 40.0, "rad/s", "upper end of the initial spin range"),
        Parameter("speed", "linear_velocity", 0.0, 30.0, "units/s", "upper end of the initial horizontal speed"),
        Parameter("drop_height", "drop_height", 2.0, 10.0, "units", "drop height of the centre of mass"),
        Parameter("capture", "capture_energy", 0.0, 1.0, "m g L", "quasi-static capture energy", power=2.0),
        Parameter("softness", "table_softness", 0.0, 0.05, "L", "sink of the die into a soft table under its weight"),
        Parameter("table_damping", "table_damping", 0.0, 2.0, "", "damping ratio of the soft table's contact"),
        Parameter("edge_radius", "edge_radius", 0.0, 0.1, "L", "radius of the die's rounded edges and corners"),
    )
}
#: The most points a calibration's grid (``method="grid"``) may have in all.
MAX_GRID = 1024
#: Fitted unless ``free`` says otherwise.
DEFAULT_FREE = ("restitution", "friction", "rolling_friction", "spin", "drop_height")


def settings_at(base, names: Sequence[str], values: Sequence[float]):
    """`base` (:class:`~diefab.physics.simulate.PhysicsSettings`) with parameters `names` set to `values`."""
    changes: dict[str, Any] = {}
    for name, value in zip(names, values):
        p = PARAMETERS[name]
        value = float(value)
        if p.setting in ("angular_velocity", "linear_velocity"):
            lo = getattr(base, p.setting)[0]
            changes[p.setting] = (min(lo, value), value)
        else:
            changes[p.setting] = value
    return replace(base, **changes)


def parameter_value(settings, name: str) -> float:
    """The value of calibration parameter `name` in `settings`."""
    value = getattr(settings, PARAMETERS[name].setting)
    return float(value[1] if isinstance(value, tuple) else value)
