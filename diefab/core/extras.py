"""Optional dependencies, each brought by an extra named for its purpose.

Every optional import goes through :func:`require`, so that a missing one is
one line naming the extra to install (the command line prints it and exits
with status 2) rather than a traceback.

==========  ===============================================  ==================================
extra       brings                                            for
==========  ===============================================  ==================================
dask        dask[distributed]                                 runs on a Dask cluster (--scheduler)
svg         svgelements                                       SVG symbols as labels (``svg:FILE``)
camera      opencv-contrib-python-headless                    reading rolls from a camera
docs        mkdocs-material, mkdocs-click, mkdocstrings       building the documentation site
studio      nicegui, playwright                               the web studio
test        pytest, hypothesis, ruff, import-linter, ...      the test suite
==========  ===============================================  ==================================

Examples
--------
>>> require("math", "test").sqrt(4.0)
2.0
"""

from __future__ import annotations

import importlib
from types import ModuleType

from diefab.core.errors import MissingExtraError

__all__ = ["EXTRAS", "require"]

#: Extra -> what it is for, in the words of the error message.
EXTRAS = {
    "dask": "running on a Dask cluster",
    "svg": "reading SVG symbols",
    "camera": "reading rolls from a camera",
    "docs": "building the documentation",
    "studio": "the web studio",
    "tally": "the hand tally",
    "test": "running the tests",
}


def require(module: str, extra: str, purpose: str | None = None) -> ModuleType:
    """Import `module`, or raise :class:`MissingExtraError` naming `extra`.

    Parameters
    ----------
    module : str
        Dotted module name, e.g. ``"distributed"``.
    extra : str
        The diefab extra that installs it, a key of :data:`EXTRAS`.
    purpose : str, optional
        What needs it, for the message (default: the extra's purpose).

    Raises
    ------
    MissingExtraError
        ``"--scheduler needs the dask extra: pip install 'diefab[dask]' (no module named 'distributed')"``.
    """
    if extra not in EXTRAS:
        raise ValueError(f"unknown extra {extra!r}; known: {', '.join(EXTRAS)}")
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        why = purpose or EXTRAS[extra]
        missing = getattr(exc, "name", None) or module
        raise MissingExtraError(
            f"{why} needs the {extra} extra: pip install 'diefab[{extra}]' (no module named {missing!r})"
        ) from None
