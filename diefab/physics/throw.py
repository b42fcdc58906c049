"""A one-parameter throw: from a die released at rest just above the table, through the paper's drop, to a hard throw.

Two set-ups predict real printed dice differently.  The source of the
real-rolls data (Baktash et al. 2025) simulates a die released at rest,
in random orientation, on the ground, with ground friction 0.1 and no
bounce (restitution 0.9 against a ground of 0); diefab's default is the
paper's throw: a drop from about 5 units with up to 10 rad/s of spin, on a
table of restitution 0.3 and friction 0.8.  Bullet multiplies the die's and
the table's values (see :class:`~diefab.dice.drop.PhysicsSettings`), and
diefab gives both the same: the source's die keeps Bullet's default
friction 0.5, a product of 0.05 with its ground, where vigor 0 gives die
and table 0.1 each, a product of 0.01.  Neither set-up is "right": real
throws lie somewhere between, and how a die is thrown matters as much as
the table.  :func:`throw_settings` spans the two with one number, the
throw's *vigor* ``v`` in [0, 3], every setting moving linearly between its
two ends (:data:`GENTLE` at 0, :data:`VIGOROUS`, the defaults, at 1), and
past 1 on along the line through the defaults and :data:`HARD` (vigor 2):
at 3, a drop from 15 units with up to 30 rad/s of spin on a table of
restitution 0.9.

The gentle end is released :data:`GENTLE_HEIGHT` units up (centre of
mass), clear of the table for every die whose radius (largest distance
from the centre of mass to a vertex) is smaller: a fall of at most about
one radius, where the source's die starts touching the ground.

Examples
--------
>>> throw_settings(1.0) == throw_settings(1.0, base=None)
True
>>> s = throw_settings(0.0)
>>> s.restitution, s.friction, s.angular_velocity
(0.0, 0.1, (0.0, 0.0))
>>> s = throw_settings(1.5)
>>> s.restitution, s.drop_height, s.angular_velocity
(0.45, 7.5, (0.0, 15.0))
"""

from __future__ import annotations

from dataclasses import replace

from diefab.core.errors import PhysicsError
from diefab.physics.simulate import PhysicsSettings

__all__ = ["GENTLE", "GENTLE_HEIGHT", "HARD", "MAX_VIGOR", "VIGOROUS", "throw_settings"]

#: Centre-of-mass height (model units) of the gentle release: above the radius of every real die here (at most 1.55).
GENTLE_HEIGHT = 1.6

#: The settings at vigor 0: released at rest, low friction, no bounce (the source's Bullet set-up).
GENTLE = {"restitution": 0.0, "friction": 0.1, "drop_height": GENTLE_HEIGHT, "height_jitter": 0.0,
          "spin": 0.0}  # fmt: skip

#: The settings at vigor 1: the paper's throw (diefab's defaults).
VIGOROUS = {"restitution": 0.3, "friction": 0.8, "drop_height": 5.0, "height_jitter": 0.5, "spin": 10.0}

#: The settings at vigor 2: a hard throw, from twice the height with twice the spin, on a bouncier table.
HARD = {"restitution": 0.6, "friction": 0.8, "drop_height": 10.0, "height_jitter": 1.0, "spin": 20.0}

#: The largest vigor: the line through :data:`VIGOROUS` and :data:`HARD` extended as far again (restitution 0.9).
MAX_VIGOR = 3.0


def throw_settings(vigor: float, base: PhysicsSettings | None = None) -> PhysicsSettings:
    """Physics settings of a throw of `vigor` in [0, 3] (see the module docstring) over `base` (default settings).

    ``spin`` is the upper end of the initial spin range (``angular_velocity``,
    rad/s, from 0); every other setting of `base` is kept.

    Raises
    ------
    PhysicsError
        `vigor` is not a number in [0, 3].
    """
    if isinstance(vigor, bool) or not isinstance(vigor, (int, float)) or not 0.0 <= vigor <= MAX_VIGOR:
        raise PhysicsError(f"vigor={vigor!r} must be a number in [0, {MAX_VIGOR:g}]")
    v = float(vigor)
    low, high, t = (GENTLE, VIGOROUS, v) if v <= 1.0 else (VIGOROUS, HARD, v - 1.0)
    mixed = {k: (1 - t) * low[k] + t * high[k] for k in GENTLE}
    spin = mixed.pop("spin")
    return replace(base or PhysicsSettings(), **{k: round(x, 9) for k, x in mixed.items()},
                   angular_velocity=(0.0, round(spin, 9)))  # fmt: skip
