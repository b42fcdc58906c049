"""What every die family is: bounded parameters, a builder, a reference length."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import DesignError

__all__ = ["Family", "Parameter"]


@dataclass(frozen=True)
class Parameter:
    """A bounded real parameter of a family."""

    name: str
    lower: float
    upper: float
    description: str
    optional: bool = False
    #: Value of an optional parameter computed from the others when absent.
    default: Callable[[Mapping[str, float]], float] | None = None

    def check(self, value: float) -> float:
        if isinstance(value, (bool, str)) or not isinstance(value, (int, float, np.number)):
            raise DesignError(f"{self.name}={value!r} is not a number")
        value = float(value)
        if not np.isfinite(value):
            raise DesignError(f"{self.name}={value} is not a finite number")
        if not self.lower <= value <= self.upper:
            raise DesignError(f"{self.name}={value:g} is outside [{self.lower:g}, {self.upper:g}]")
        return value


@dataclass(frozen=True)
class Family:
    """A named family of convex dice."""

    name: str
    parameters: tuple[Parameter, ...]
    description: str

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
                out[p.name] = p.default(out)
        return out

    def bounds(self, names: list[str]) -> np.ndarray:
        """(k, 2) float: lower and upper bounds of the named parameters."""
        known = {p.name: p for p in self.parameters}
        return np.array([(known[n].lower, known[n].upper) for n in names])
