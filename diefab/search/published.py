"""Published real rolls of objects of known geometry, read into real dice.

The package ships tables of physical roll counts from the literature
(``diefab/data/published/*.json``), each with its citation, the object, the
outcome counted and the throw and surface where stated.  They are held-out
dice: nothing in diefab was fitted to them.

``square-cuboids``: 15 homogeneous steel cuboids with two square faces
(``y x y``) and four rectangles (``x x y``), ``x / y`` from 0.47 to 2.65,
each rolled 275-1011 times by hand; the count is of a square face up
(:func:`square_cuboid_dice`).

``thick-coins``: two cylinders, thickness over diameter 0.354 and 0.577,
each flipped 1000 times by hand; the count is of the coin left on its edge
(:func:`thick_coin_dice`).

``baktash2025/``: further printed dice of the source of the shared real
rolls (Baktash et al. 2025, "Putting Rigid Bodies to Rest"), each in the
real-rolls format with its geometry, its counts and the source's own
predictions (:func:`printed_dice`).

Examples
--------
>>> dice = square_cuboid_dice()
>>> len(dice), dice[0].design.support, int(dice[0].counts[1]), dice[0].n
(15, [0, 1], 304, 332)
>>> [(d.name, int(d.counts[1]), d.n) for d in thick_coin_dice()]
[('coin-0.35', 132, 1000), ('coin-0.58', 410, 1000)]
"""

from __future__ import annotations

import json
from importlib import resources

import numpy as np

from diefab.search.realdie import RealDie

__all__ = [
    "COIN_SIDES",
    "PRINTED",
    "PUBLISHED",
    "printed_dice",
    "published_source",
    "square_cuboid",
    "square_cuboid_dice",
    "thick_coin",
    "thick_coin_dice",
]

#: The shipped tables, by name.
PUBLISHED = ("square-cuboids", "thick-coins")
#: Sides of the prism that stands in for a cylinder.
COIN_SIDES = 128
#: The shipped folder of printed dice in the real-rolls format.
PRINTED = "baktash2025"


def _table(name: str) -> dict:
    return json.loads(resources.files("diefab").joinpath("data", "published", f"{name}.json").read_text())


def published_source(name: str) -> str:
    """The citation of the shipped table `name`."""
    return _table(name)["source"]


def square_cuboid(ratio: float, name: str | None = None, size_mm: float = 20.0):
    """A homogeneous cuboid ``x x y x y`` with ``x / y = ratio`` (x along z), value 1 on the two square faces.

    Model units: its longest side is 2; `size_mm` is that side's real length
    (the published tables do not give it: the rigid model is scale-free).
    """
    from diefab.dice.design import Design

    y = 2.0 / max(1.0, ratio)
    half = np.array([y, y, ratio * y]) / 2
    vertices = [[sx * half[0], sy * half[1], sz * half[2]] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    faces = ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3))
    normals_z = [0, 0, 0, 0, -1, 1]  # which faces are square (normal along z): f5 (z-) and f6 (z+)
    values = {f"f{k + 1}": int(abs(nz) == 1) for k, nz in enumerate(normals_z)}
    return Design(name or f"cuboid-{ratio:g}", "convex", vertices=tuple(map(tuple, vertices)), faces=faces,
                  values=values, target="0:2,1:1", size_mm=size_mm,
                  description=f"square cuboid x/y = {ratio:g}, value 1 on the square faces")  # fmt: skip


def square_cuboid_dice() -> list[RealDie]:
    """The 15 steel square cuboids of the ``square-cuboids`` table, counts of (rectangle up, square up)."""
    data = _table("square-cuboids")
    dice = []
    for row in data["table"]:
        n, p = int(row["rolls"]), float(row["p_square"])
        (square,) = [c for c in range(n + 1) if round(c / n, 3) == p]  # the one count the published p allows
        design = square_cuboid(float(row["x_over_y"]), name=f"cuboid-{row['x_over_y']:.2f}")
        dice.append(RealDie(design.name, design, np.array([n - square, square])))
    return dice


def thick_coin(ratio: float, name: str | None = None, size_mm: float = 25.0, sides: int = COIN_SIDES):
    """A homogeneous coin of thickness over diameter `ratio`: a prism of `sides` sides about a circle, value 1 on them.

    The coin's axis is z; its faces are ``f1`` (top), ``f2`` (bottom) and
    the sides ``f3 ..``, each tangent to the circle of diameter 2 (model
    units), so the coin rests on a side as the cylinder rests on its edge.
    Value 0 is a face up, value 1 the edge.  `size_mm` is the diameter
    (not stated by the source; the rigid model is scale-free).
    """
    from diefab.dice.design import Design

    corner = 1.0 / np.cos(np.pi / sides)  # the polygon about the unit circle
    angle = 2 * np.pi * (np.arange(sides) + 0.5) / sides
    ring = np.column_stack([corner * np.cos(angle), corner * np.sin(angle)])
    vertices = [(x, y, z) for z in (ratio, -ratio) for x, y in ring]  # half-thickness: ratio x the radius 1 x 2 / 2
    faces = (tuple(range(sides)), tuple(range(2 * sides - 1, sides - 1, -1)),
             *((k, sides + k, sides + (k + 1) % sides, (k + 1) % sides) for k in range(sides)))  # fmt: skip
    values = {"f1": 0, "f2": 0} | {f"f{k + 3}": 1 for k in range(sides)}
    return Design(name or f"coin-{ratio:.2f}", "convex", vertices=tuple(vertices), faces=faces, values=values,
                  target="0:2,1:1", size_mm=size_mm,
                  description=f"thick coin t/d = {ratio:.3f}, value 1 on its edge")  # fmt: skip


def thick_coin_dice(sides: int = COIN_SIDES) -> list[RealDie]:
    """The two coins of the ``thick-coins`` table as prisms of `sides` sides, counts of (a face up, the edge)."""
    dice = []
    for row in _table("thick-coins")["table"]:
        n = int(row["flips"])
        edge = round(float(row["edge"]) * n)
        design = thick_coin(float(row["thickness_at_diameter_2"]) / 2, sides=sides)
        dice.append(RealDie(design.name, design, np.array([n - edge, edge])))
    return dice


def printed_dice() -> list[RealDie]:
    """The shipped printed dice of the :data:`PRINTED` folder (real-rolls format), sorted by name."""
    from pathlib import Path

    from diefab.search.realdie import realrolls_die

    folder = Path(str(resources.files("diefab").joinpath("data", "published", PRINTED)))
    return [realrolls_die(p) for p in sorted(folder.glob("*.json"))]
