"""The types of a design file's fields, checked before a :class:`~diefab.dice.design.Design` is built.

TOML has booleans, strings, dates, integers, floats, arrays and tables; a
design file must put the right one in each field.  :data:`FIELDS` maps each
top-level key to its check, so that a new key is one row.  Booleans and
strings never pass as numbers, a face index must be a whole integer, and
every number is finite and of a sane magnitude (which keeps the geometry
clear of overflow).  Ranges that depend on the die (a parameter's bounds, a
face that exists) are checked by the design itself.

Examples
--------
>>> check_design_data({"name": "x", "size_mm": True})
Traceback (most recent call last):
...
diefab.core.errors.DesignError: size_mm = true is a boolean, not a number
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

from diefab.core.errors import DesignError, DiefabError
from diefab.dice.drop import PhysicsSettings

__all__ = ["FIELDS", "MAGNITUDE", "check_design_data", "check_mapping"]

#: Largest magnitude of any number in a design file (model units, millimetres or values).
MAGNITUDE = 1e6

Check = Callable[[str, Any], None]


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, (list, tuple)):
        return "an array"
    if isinstance(value, Mapping):
        return "a table"
    if isinstance(value, int):
        return "an integer"
    if isinstance(value, float):
        return "a float"
    return f"a {type(value).__name__}"


def _fail(where: str, value: Any, expected: str) -> None:
    raise DesignError(f"{where} = {_text(value)} is {_kind(value)}, not {expected}")


def _text(value: Any) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, (list, tuple)):
        return "[...]"
    if isinstance(value, Mapping):
        return "{...}"
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def number(where: str, value: Any) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        _fail(where, value, "a number")
    if not math.isfinite(value) or abs(value) > MAGNITUDE:
        raise DesignError(f"{where} = {_text(value)} is not a finite number of magnitude at most {MAGNITUDE:g}")


def positive(where: str, value: Any) -> None:
    number(where, value)
    if value <= 0:
        raise DesignError(f"{where} = {_text(value)} is not a positive number")


def integer(where: str, value: Any) -> None:
    if isinstance(value, bool) or not isinstance(value, int):
        _fail(where, value, "an integer")
    if abs(value) > MAGNITUDE:
        raise DesignError(f"{where} = {value} is not an integer of magnitude at most {MAGNITUDE:g}")


def index(where: str, value: Any) -> None:
    integer(where, value)
    if value < 0:
        raise DesignError(f"{where} = {value} is not a vertex index (>= 0)")


def text(where: str, value: Any) -> None:
    if not isinstance(value, str):
        _fail(where, value, "a string")
    if any(ord(ch) < 32 or ord(ch) == 127 for ch in value.replace("\n", "").replace("\t", "")):
        raise DesignError(f"{where} = {_text(value)} contains a control character")


def line(where: str, value: Any) -> None:
    """A one-line string, perhaps empty (a label: printed on one line)."""
    if isinstance(value, str) and ("\n" in value or "\t" in value or "\r" in value):
        raise DesignError(f"{where} = {_text(value)} contains a line break or tab: a label is one line")
    text(where, value)


def word(where: str, value: Any) -> None:
    """A non-empty one-line string (names, families, targets, paths)."""
    if isinstance(value, str) and ("\n" in value or "\t" in value or "\x00" in value):
        raise DesignError(f"{where} = {_text(value)} contains a control character")
    text(where, value)
    if not value.strip():
        raise DesignError(f"{where} is empty")


def flag(where: str, value: Any) -> None:
    if not isinstance(value, bool):
        _fail(where, value, "true or false")


def table(item: Check | None = None) -> Check:
    """A TOML table, each value checked by `item` (None: left to the design)."""

    def check(where: str, value: Any) -> None:
        if not isinstance(value, Mapping):
            _fail(where, value, "a table")
        if item is not None:
            for key, v in value.items():
                item(f"{where}.{key}", v)

    return check


def record(**items: Check) -> Check:
    """A TOML table whose named keys are checked by their own checks (other keys are left to the design)."""

    def check(where: str, value: Any) -> None:
        table()(where, value)
        for key, v in value.items():
            if key in items:
                items[key](f"{where}.{key}", v)

    return check


def array(item: Check, *, length: int | None = None, least: int = 0) -> Check:
    """An array of `length` (or at least `least`) items, each checked by `item`."""

    def check(where: str, value: Any) -> None:
        if not isinstance(value, (list, tuple)):
            _fail(where, value, "an array")
        if length is not None and len(value) != length:
            raise DesignError(f"{where} has {len(value)} items, not {length}")
        if len(value) < least:
            raise DesignError(f"{where} has {len(value)} items, fewer than {least}")
        for i, v in enumerate(value):
            item(f"{where}[{i}]", v)

    return check


def _physics(where: str, value: Any) -> None:
    table()(where, value)
    try:
        PhysicsSettings.from_mapping(value)
    except DiefabError as exc:
        raise DesignError(f"[{where}]: {exc}") from None


point = array(number, length=3)

#: Top-level key -> check of its value.
FIELDS: dict[str, Check] = {
    "name": word,
    "description": text,
    "family": word,
    "target": word,
    "size_mm": positive,
    "params": table(number),
    "values": table(integer),
    "labels": table(line),
    # ranges (and unknown keys): diefab.made.fill.Fill
    "fill": record(
        kind=word,
        card_g_m2=number,
        card_mm=number,
        tabs=flag,
        tab_mm=number,
        glue_g_m2=number,
        nozzle_mm=number,
        perimeters=integer,
        layer_mm=number,
        top_layers=integer,
        bottom_layers=integer,
        infill=number,
        wall_mm=number,
        solid_below_mm2=number,
        skin_margin_mm=number,
        labels=flag,
    ),
    "physics": _physics,
    "vertices": array(point, least=4),
    "faces": array(array(index, least=3), least=4),
    "mesh": word,
    "center_of_mass": point,
    "inertia": array(point, length=3),
    "transitional": array(word),
    "merge_tolerance_mm": positive,
}


def check_design_data(data: Mapping[str, Any]) -> None:
    """Check the type of every known field of a parsed design file (unknown keys are the caller's)."""
    for key, value in data.items():
        if key in FIELDS:
            FIELDS[key](key, value)


def check_mapping(where: str, value: Any) -> None:
    """Raise :class:`DesignError` unless `value` is a mapping (for the constructors' arguments)."""
    table()(where, value)
