"""What every die family is: bounded parameters, a builder, a reference length, a readability rule."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from diefab.core.errors import DesignError, GeometryError

if TYPE_CHECKING:
    from diefab.geometry.polyhedron import Polyhedron

__all__ = ["Family", "Parameter"]


@dataclass(frozen=True)
class Parameter:
    """A bounded real parameter of a family.

    An ``integer`` parameter is structural (a face count): it must be a
    whole number and is never optimized.
    """

    name: str
    lower: float
    upper: float
    description: str
    optional: bool = False
    #: Value of an optional parameter computed from the others when absent
    #: (None from it: the parameter does not apply to this die).
    default: Callable[[Mapping[str, float]], float | None] | None = None
    integer: bool = False

    def check(self, value: float) -> float:
        if isinstance(value, (bool, str)):
            raise DesignError(f"{self.name}={value!r} is not a number")
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise DesignError(f"{self.name}={value!r} is not a number") from None
        if not np.isfinite(value):
            raise DesignError(f"{self.name}={value} is not a finite number")
        if not self.lower <= value <= self.upper:
            raise DesignError(f"{self.name}={value:g} is outside [{self.lower:g}, {self.upper:g}]")
        if self.integer and value != int(value):
            raise DesignError(f"{self.name}={value:g} must be a whole number")
        return value


def _all_parameters(family: Family, params: Mapping[str, float]) -> list[str]:
    return [p.name for p in family.parameters if not p.integer]


@dataclass(frozen=True)
class Family:
    """A named family of convex dice.

    Parameters
    ----------
    name : str
    parameters : tuple of Parameter
    description : str
    build : callable, optional
        Complete, checked parameters -> :class:`~diefab.geometry.polyhedron.Polyhedron`
        (model units).  Families without one (``convex``, ``mesh``) take
        their geometry from the design file.
    reference : str
        What ``size_mm`` measures on the die.
    reference_length : callable, optional
        Polyhedron -> that length in model units (default:
        :func:`default_length`, the rule for ``convex`` and ``mesh`` dice).
    readability : str
        How each resting face is read on the finished die.
    free : callable, optional
        Complete parameters -> the names an optimizer varies (default: every
        non-structural parameter).
    """

    name: str
    parameters: tuple[Parameter, ...]
    description: str
    build: Callable[[Mapping[str, float]], Polyhedron] | None = None
    reference: str = "face to face when every face has a parallel opposite, else the largest vertex distance"
    reference_length: Callable[[Polyhedron], float] | None = None
    readability: str = "the value on the face that points up; the value at the vertex that points up when one does"
    free: Callable[[Family, Mapping[str, float]], list[str]] = _all_parameters

    def check_params(self, params: Mapping[str, float]) -> dict[str, float]:
        """Validated parameters: known names, all required present, within bounds."""
        known = {p.name: p for p in self.parameters}
        unknown = sorted(set(params) - set(known))
        if unknown:
            raise DesignError(
                f"family {self.name!r} has no parameter {unknown[0]!r} (parameters: {', '.join(known) or 'none'})"
            )
        missing = [p.name for p in self.parameters if not p.optional and p.name not in params]
        if missing:
            raise DesignError(f"family {self.name!r} needs parameter {missing[0]!r}")
        return {name: known[name].check(value) for name, value in params.items()}

    def complete(self, params: Mapping[str, float]) -> dict[str, float]:
        """`params` with every absent optional parameter set to its default."""
        out = dict(params)
        for p in self.parameters:
            if p.name not in out and p.default is not None:
                value = p.default(out)
                if value is not None:  # None: the parameter does not apply to this die
                    out[p.name] = value
        return out

    def bounds(self, names: list[str]) -> np.ndarray:
        """(k, 2) float: lower and upper bounds of the named parameters."""
        known = {p.name: p for p in self.parameters}
        return np.array([(known[n].lower, known[n].upper) for n in names])

    def free_names(self, params: Mapping[str, float]) -> list[str]:
        """The parameters an optimizer varies for a die with these (structural) parameters."""
        return self.free(self, self.complete(params))

    def polyhedron(self, params: Mapping[str, float]) -> Polyhedron:
        """The die for `params` (checked here), model units.

        Raises
        ------
        DesignError
            If the family has no builder or the parameters give no convex die.
        """
        if self.build is None:
            raise DesignError(f"family {self.name!r} takes its geometry from the design file")
        params = self.complete(self.check_params(params))
        try:
            return self.build(params)
        except GeometryError as exc:
            shown = ", ".join(f"{k}={v:g}" for k, v in params.items())
            raise DesignError(f"{self.name} parameters {shown} do not give a convex die: {exc}") from exc

    def length(self, poly: Polyhedron) -> float:
        """The reference length of `poly`, model units (``size_mm`` measures it)."""
        if self.reference_length is None:
            return default_length(poly)[0]
        return float(self.reference_length(poly))

    def reference_name(self, poly: Polyhedron) -> str:
        """What :meth:`length` measures on `poly`, in words."""
        return default_length(poly)[1] if self.reference_length is None else self.reference


def default_length(poly: Polyhedron) -> tuple[float, str]:
    """Face to face when every face has a parallel opposite (the widest pair), else the largest vertex distance."""
    from diefab.core import tolerances as tol
    from diefab.geometry.polyhedron import hull_diameter

    cos = poly.normals @ poly.normals.T
    opposite = np.argmin(cos, axis=1)
    if np.all(cos[np.arange(len(cos)), opposite] < -1 + tol.COPLANAR):
        return float((poly.offsets + poly.offsets[opposite]).max()), "face to face"
    return hull_diameter(poly.vertices), "largest vertex-to-vertex distance"


def width_along(poly: Polyhedron, face: int = 0) -> float:
    """Width of `poly` along the normal of `face`: face-to-face when the opposite side is a parallel face."""
    heights = poly.vertices @ poly.normals[face]
    return float(heights.max() - heights.min())


def offset_parameters(
    prefix: str, count: int, lower: float, upper: float, what: str, sides: str = "n"
) -> tuple[Parameter, ...]:
    """Optional parameters ``prefix1 .. prefixN``: support-plane offsets, 1 by default for the first `sides`."""
    return tuple(
        Parameter(
            f"{prefix}{k}",
            lower,
            upper,
            f"{what} {k} (default 1)",
            optional=True,
            default=lambda p, k=k: 1.0 if k <= p[sides] else None,
        )
        for k in range(1, count + 1)
    )


def offsets(params: Mapping[str, float], prefix: str, count: int) -> np.ndarray:
    """(count,) float: ``prefix1 .. prefix<count>`` of complete parameters."""
    return np.array([params[f"{prefix}{k}"] for k in range(1, count + 1)])


def unused_offsets(params: Mapping[str, float], prefix: str, used: int, family: str) -> None:
    """Raise if `params` sets an offset beyond the first `used` (a face the die does not have)."""
    extra = sorted(
        (k for k in params if k.startswith(prefix) and k[len(prefix) :].isdigit() and int(k[len(prefix) :]) > used),
        key=lambda k: int(k[len(prefix) :]),
    )
    if extra:
        raise DesignError(f"{extra[0]} is set but a {family} with {used} of them has no {extra[0]}")


def integer(params: Mapping[str, float], name: str) -> int:
    """A structural parameter as an int."""
    return int(params[name])
