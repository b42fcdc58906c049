"""Random dice of every family, for training and measuring landing models.

A random die of a named family fixes its structural parameters (face counts,
which optional shape parameters are present) by a small rule per family and
draws the others uniformly in the family's box, rejection-sampled until every
face holds the die with a margin of at least ``min_margin``.  A random
``convex`` die is cut by planes along jittered normals and stretched.  Every
face gets its own value, so a die rolls ``1 .. m``.

Examples
--------
>>> import numpy as np
>>> d = random_design("cuboid", np.random.default_rng(0))
>>> d.family, len(d.values)
('cuboid', 6)
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from diefab.core.errors import DesignError, DiefabError

__all__ = ["RANDOM_FAMILIES", "design_record", "random_design", "record_design", "structure"]

#: Families :func:`random_design` draws from, with the range of their face-count parameter ``n``.
RANDOM_FAMILIES: dict[str, tuple[int, int] | None] = {
    "gem": None,
    "ngem": (3, 8),
    "prism": (3, 8),
    "bipyramid": (3, 8),
    "trapezohedron": (3, 8),
    "cuboid": None,
    "freeform": (6, 16),
    "convex": (8, 12),
}


def structure(name: str, rng: np.random.Generator) -> dict[str, float]:
    """Random structural parameters of family `name`: ``n`` and which optional shape parameters are present.

    Optional parameters are marked present by a placeholder (their value is
    drawn with the others): the ngem's apex shift, the prism's caps, the
    cuboid's taper, each with probability 1/2.
    """
    span = RANDOM_FAMILIES[name]
    out: dict[str, float] = {} if span is None else {"n": int(rng.integers(span[0], span[1] + 1))}
    if name == "ngem" and rng.random() < 0.5:
        out |= {"sx": np.nan, "sz": np.nan}
    elif name == "prism" and rng.random() < 0.5:
        out["k"] = np.nan
    elif name == "cuboid" and rng.random() < 0.5:
        out["t"] = np.nan
    return out


def random_design(
    name: str,
    rng: np.random.Generator,
    fixed: Mapping[str, float] | None = None,
    *,
    min_margin: float = 0.02,
    max_radius: float = 4.0,
    label: str | None = None,
    tries: int = 10_000,
):
    """A random die of family `name` that rests on every face with at least `min_margin` (model units).

    Parameters
    ----------
    name : str
        A key of :data:`RANDOM_FAMILIES`.
    rng : numpy.random.Generator
    fixed : mapping, optional
        Structural parameters (default: :func:`structure`); a value of NaN
        marks an optional parameter to draw.
    min_margin : float
        Smallest stability margin of every face.
    max_radius : float
        Largest distance from the centre of mass to a vertex (model units):
        the simulator drops a die from a fixed height, which it must clear.
    label : str, optional
        The design's name (default: the family's).
    tries : int
        Draws before giving up.

    Raises
    ------
    DesignError
        If `name` is not a family drawn from, or no draw is stable enough.
    """
    from diefab.dice.design import Design
    from diefab.dice.families import family
    from diefab.geometry.polyhedron import Polyhedron

    if name not in RANDOM_FAMILIES:
        raise DesignError(f"no random dice of family {name!r} (known: {', '.join(RANDOM_FAMILIES)})")
    fixed = structure(name, rng) if fixed is None else dict(fixed)
    fam = family(name)
    if name != "convex":
        drawn = [k for k, v in fixed.items() if v != v]  # NaN: present, value drawn
        base = {k: v for k, v in fixed.items() if v == v}
        mid = {p.name: (p.lower + p.upper) / 2 for p in fam.parameters if not p.optional and p.name not in base}
        free = sorted(set(fam.free_names({**base, **mid})) | set(drawn), key=[p.name for p in fam.parameters].index)
        lo, hi = fam.bounds(free).T
    for _ in range(tries):
        try:
            if name == "convex":
                vertices = _random_hull(int(fixed["n"]), rng)
                names, kw = Polyhedron.from_points(vertices).names, {"vertices": vertices}
            else:
                params = {**base, **dict(zip(free, np.round(lo + rng.random(len(free)) * (hi - lo), 4).tolist()))}
                names, kw = fam.polyhedron(params).names, {"params": params}
            values = {f: i + 1 for i, f in enumerate(names)}
            design = Design(label or name, name, values=values, target=f"uniform:{len(names)}", **kw)
            reach = np.linalg.norm(design.polyhedron.vertices - design.mass_properties().center, axis=1).max()
            if design.margins().min() >= min_margin and reach <= max_radius:
                return design
        except DiefabError:  # not a convex die, or not one of this family
            continue
    raise DesignError(f"no random {name} die with every margin >= {min_margin:g} and radius <= {max_radius:g} "
                      f"in {tries} draws")  # fmt: skip


def _random_hull(k: int, rng: np.random.Generator) -> tuple[tuple[float, float, float], ...]:
    """Vertices of a die cut by `k` planes along jittered, randomly turned Fibonacci normals, then stretched.

    The normals are those of the free-form family turned by a random
    rotation and each tilted by about 0.25 rad; the offsets are uniform in
    [0.8, 1.2]; the die is then stretched along the axes by factors in
    [0.7, 1.4] (still convex, no longer isotropic).
    """
    from scipy.spatial.transform import Rotation

    from diefab.dice.families.freeform import fibonacci_normals
    from diefab.dice.families.planes import polyhedron_from_planes

    normals = Rotation.random(random_state=rng).apply(fibonacci_normals(k)) + 0.25 * rng.normal(size=(k, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    poly = polyhedron_from_planes(normals, 0.8 + 0.4 * rng.random(k))
    return tuple(map(tuple, (poly.vertices * (0.7 + 0.7 * rng.random(3))).tolist()))


def design_record(design) -> dict:
    """What rebuilds a random die (:func:`record_design`): family, and parameters or vertices."""
    out: dict = {"family": design.family}
    if design.vertices is not None:
        out["vertices"] = [list(v) for v in design.vertices]
    else:
        out["params"] = dict(design.params)
    return out


def record_design(record: Mapping, name: str | None = None):
    """The die a :func:`design_record` describes, every face with its own value."""
    from diefab.dice.design import Design
    from diefab.dice.families import family
    from diefab.geometry.polyhedron import Polyhedron

    fam = record["family"]
    if "vertices" in record:
        vertices = tuple(map(tuple, record["vertices"]))
        kw: dict = {"vertices": vertices}
        names = Polyhedron.from_points(np.array(vertices)).names
    else:
        kw = {"params": dict(record["params"])}
        names = family(fam).polyhedron(kw["params"]).names
    values = {f: i + 1 for i, f in enumerate(names)}
    return Design(name or fam, fam, values=values, target=f"uniform:{len(names)}", **kw)
