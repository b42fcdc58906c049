"""Exception hierarchy.

Every error diefab raises on bad input derives from :class:`DiefabError` and
from the builtin exception a Python user would expect, so both
``except DiefabError`` and ``except ValueError`` work.  The command line turns
any of them into one line on stderr and exit status 2.
"""

from __future__ import annotations

__all__ = [
    "DiefabError",
    "DesignError",
    "FabricationError",
    "GeometryError",
    "OutputError",
    "PhysicsError",
    "StatsError",
    "TargetError",
]


class DiefabError(Exception):
    """Base class of all diefab errors."""


class GeometryError(DiefabError, ValueError):
    """A polyhedron is degenerate, open, non-planar or non-convex."""


class DesignError(DiefabError, ValueError):
    """A design, template or parameter is invalid."""


class TargetError(DiefabError, ValueError):
    """A target distribution is malformed or does not fit the design."""


class StatsError(DiefabError, ValueError):
    """Counts or roll logs are malformed."""


class PhysicsError(DiefabError, ValueError):
    """A physics setting is out of range or a simulation cannot run."""


class FabricationError(DiefabError, ValueError):
    """A net or solid cannot be made with the requested settings."""


class OutputError(DiefabError, OSError):
    """An output file or folder cannot be written."""
