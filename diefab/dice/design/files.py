"""Design files: the shipped templates, reading a design from TOML and writing one back.

Examples
--------
>>> design = parse_design(design_to_toml(load_design("d6")))
>>> design.name, design.family, len(list_templates()) > 5
('d6', 'convex', True)
"""

from __future__ import annotations

import re
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

from diefab.core.errors import DesignError
from diefab.core.files import check_size
from diefab.dice.design.spec import Design
from diefab.dice.schema import check_design_data
from diefab.made.fill import Fill

__all__ = ["design_to_toml", "list_templates", "load_design", "parse_design", "template_path"]

#: Largest design file read, bytes (a convex die of a thousand faces is under a megabyte).
DESIGN_MAX_BYTES = 16 << 20

#: Largest design file read.
MAX_DESIGN_BYTES = 64 << 20

_KEYS = {
    "name", "description", "family", "params", "target", "values", "labels", "size_mm",
    "fill", "physics", "vertices", "faces", "mesh", "transitional", "center_of_mass", "inertia",
    "merge_tolerance_mm",
}  # fmt: skip


def _templates_dir():
    """The shipped templates: package data when installed, ``templates/`` beside ``diefab/`` in a checkout."""
    try:
        return resources.files("diefab.templates")
    except ModuleNotFoundError:  # imported from a source tree (e.g. pytest run in the repository)
        return Path(__file__).resolve().parents[3] / "templates"


def list_templates() -> list[Design]:
    """Every shipped template, sorted by name."""
    files = sorted(p for p in _templates_dir().iterdir() if p.name.endswith(".toml"))
    return [parse_design(p.read_text(encoding="utf-8"), source=str(p)) for p in files]


def template_path(name: str):
    """The path of the shipped template called `name`, or of the ready-made die for the target `name`.

    A target is looked up by its spelling in lower case with every run of
    other characters than letters and digits made one ``-``: ``3dF`` is
    the template ``3df``, ``binomial:4`` is ``binomial-4``.
    """
    folder = _templates_dir()
    path = folder / f"{name}.toml"
    if not path.is_file():
        slug = re.sub(r"[^a-z0-9]+", "-", str(name).lower()).strip("-")
        path = folder / f"{slug}.toml"
    if not path.is_file():
        known = ", ".join(sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml")))
        raise DesignError(f"unknown template {name!r} (templates: {known}; or give a path to a .toml file; "
                          f"or make a die for any target with: diefab design TARGET)")  # fmt: skip
    return path


def load_design(spec: str | Path) -> Design:
    """Load a design by template name or from a TOML file path."""
    text = str(spec)
    path = Path(text)
    if text.endswith(".toml") or path.exists() or "/" in text or "\\" in text:
        if not path.is_file():
            raise DesignError(f"design file {text} {'is not a regular file' if path.exists() else 'does not exist'}")
        if path.stat().st_size > MAX_DESIGN_BYTES:
            raise DesignError(f"design file {text} is larger than {MAX_DESIGN_BYTES >> 20} MiB")
        try:
            check_size(path, DESIGN_MAX_BYTES, "design file", DesignError)
            content = path.read_text(encoding="utf-8-sig")  # a byte-order mark is not TOML
        except (OSError, UnicodeDecodeError) as exc:
            raise DesignError(f"cannot read design file {text}: {exc}") from exc
        return parse_design(content, source=text, base=path.parent)
    return parse_design(template_path(text).read_text(encoding="utf-8"), source=f"template {text}")


def parse_design(content: str, *, source: str = "<string>", base: Path | None = None) -> Design:
    """Parse a design from TOML text; errors name `source` and the line."""
    try:
        data = tomllib.loads(content)
    except tomllib.TOMLDecodeError as exc:
        raise DesignError(f"{source}: malformed TOML: {exc}") from exc
    try:
        check_design_data(data)
    except DesignError as exc:
        raise DesignError(f"{source}: {exc}") from None
    unknown = sorted(set(data) - _KEYS)
    if unknown:
        raise DesignError(f"{source}: unknown key {unknown[0]!r} (keys: {', '.join(sorted(_KEYS))})")
    for key in ("name", "family"):
        if key not in data:
            raise DesignError(f"{source}: missing key {key!r}")
    try:
        fill = Fill.from_mapping(data.get("fill", {}), "[fill]")
    except DesignError as exc:
        raise DesignError(f"{source}: [fill]: {exc}") from exc
    kwargs = {
        k: data[k] for k in ("name", "family", "params", "values", "target", "labels", "description") if k in data
    }
    if "size_mm" in data:
        kwargs["size_mm"] = data["size_mm"]
    if "vertices" in data:
        kwargs["vertices"] = tuple(tuple(v) for v in data["vertices"])
    if "faces" in data:
        kwargs["faces"] = tuple(tuple(f) for f in data["faces"])
    if "mesh" in data:
        kwargs["mesh"] = (base or Path.cwd()) / data["mesh"]
    for key in ("center_of_mass", "inertia", "merge_tolerance_mm"):
        if key in data:
            kwargs[key] = data[key]
    if isinstance(data.get("labels"), dict) and base is not None:
        # an SVG symbol's file is found beside the design file, as a mesh is
        kwargs["labels"] = {
            face: f"svg:{base / text[4:].strip()}" if isinstance(text, str) and text.startswith("svg:") else text
            for face, text in data["labels"].items()
        }
    if "transitional" in data:
        if not isinstance(data["transitional"], list):
            raise DesignError(f"{source}: transitional must be a list of face names")
        kwargs["transitional"] = tuple(data["transitional"])
    try:
        return Design(**kwargs, fill=fill, physics=data.get("physics", {}))
    except DesignError as exc:
        raise DesignError(f"{source}: {exc}") from exc
    except (TypeError, ValueError) as exc:
        raise DesignError(f"{source}: {exc}") from exc


def design_to_toml(design: Design, *, comment: str = "") -> str:
    """The design as a TOML template (round-trips through :func:`parse_design`)."""
    import tomli_w

    data: dict[str, Any] = {"name": design.name}
    if design.description:
        data["description"] = design.description
    data["family"] = design.family
    data["target"] = design.target
    data["size_mm"] = _toml_number(design.size_mm)
    if design.params:
        data["params"] = {k: _toml_number(v) for k, v in design.params.items()}
    if design.vertices is not None:
        data["vertices"] = [list(map(_toml_number, v)) for v in design.vertices]
    if design.faces is not None:
        data["faces"] = [list(map(int, f)) for f in design.faces]
    if design.mesh is not None:
        data["mesh"] = str(design.mesh)
    data["values"] = dict(design.values)
    if design.transitional:
        data["transitional"] = list(design.transitional)
    if design.merge_tolerance_mm is not None:
        data["merge_tolerance_mm"] = _toml_number(design.merge_tolerance_mm)
    if design.center_of_mass is not None:
        data["center_of_mass"] = [_toml_number(x) for x in design.center_of_mass]
    if design.inertia is not None:
        data["inertia"] = [[_toml_number(x) for x in r] for r in design.inertia]
    if design.labels:
        data["labels"] = dict(design.labels)
    data["fill"] = _whole(design.fill.to_mapping())
    if design.physics:
        data["physics"] = _whole(dict(design.physics))
    header = "".join(f"# {line}\n" for line in comment.splitlines())
    return header + tomli_w.dumps(data)


def _toml_number(x: float) -> int | float:
    """A whole number as an int (``n = 12``, not ``12.0``), any other as a float.

    >>> _toml_number(12.0), _toml_number(0.5)
    (12, 0.5)
    """
    x = float(x)
    return int(x) if x.is_integer() and abs(x) < 2**53 else x


def _whole(table: dict) -> dict:
    """`table` with its whole float values written as ints (booleans and strings untouched)."""
    return {k: _toml_number(v) if isinstance(v, float) else v for k, v in table.items()}
