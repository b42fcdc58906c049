"""Design files in and out of the page: an uploaded design checked as the CLI checks one, and saving as TOML."""

from __future__ import annotations

import math
from pathlib import Path

from diefab.core.errors import DesignError
from diefab.dice.design import Design, parse_design

#: Largest design file accepted by upload, bytes (a design is a few kilobytes).
MAX_UPLOAD = 256 * 1024


def parse_upload(data: bytes, name: str, folder: Path) -> Design:
    """The design in an uploaded file, checked: size, text, the design-file checks, geometry and stability.

    Raises
    ------
    DesignError
        The file is too large, not UTF-8, not a valid design, or would make
        the studio read a file outside `folder`.
    """
    if len(data) > MAX_UPLOAD:
        raise DesignError(f"{name} is larger than {MAX_UPLOAD // 1024} KiB")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise DesignError(f"{name} is not UTF-8 text") from None
    design = parse_design(text, source=name, base=folder, within=folder)
    _ = design.polyhedron  # checks the geometry now
    design.check_stable(-math.inf)
    return design
