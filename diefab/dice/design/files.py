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
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from diefab.core.errors import DesignError
from diefab.core.files import check_size
from diefab.dice.design.spec import Design
from diefab.dice.schema import check_design_data
from diefab.made.fill import Fill

__all__ = [
    "design_to_toml",
    "list_templates",
    "load_design",
    "parse_design",
    "template_for",
    "template_name",
    "template_path",
]

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


#: Fills a ready-made die may be designed for: its template is the plain one's name and ``-KIND``.
MADE_KINDS = ("paper", "print")


def _slug(name: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", str(name).lower()).strip("-")


def _template_target(path) -> str | None:
    try:
        return tomllib.loads(path.read_text(encoding="utf-8")).get("target")
    except (OSError, tomllib.TOMLDecodeError):
        return None


def template_name(name: str, made: str | None = None) -> str:
    """The shipped template that `name` stands for, made as `made` (``paper``, ``print`` or None).

    A template's own name is that template (``3df``, ``3df-paper``).  Any
    other name is a target, looked up by its spelling in lower case with
    every run of other characters than letters and digits made one ``-``
    (``3dF`` is ``3df``, ``binomial:4`` is ``binomial-4``); so is a template's
    name that is spelled as its target (``3d6``, ``2d6``).  A target made as
    `made` takes the die designed for that fill where one is shipped
    (``3dF`` made of paper is ``3df-paper``, ``3d6`` printed is
    ``3d6-print``), else the plain one.

    Parameters
    ----------
    name : str
        A template's name or a target's.
    made : {"paper", "print"} or None
        How the die will be made; None (or ``solid``) takes the plain template.

    Returns
    -------
    str
        The template's name (its file is ``NAME.toml``).

    Raises
    ------
    DesignError
        If no template stands for `name`; the message points to ``diefab design``.

    Examples
    --------
    >>> template_name("3dF", "paper"), template_name("3df", "paper"), template_name("uniform:5", "print")
    ('3df-paper', '3df', 'uniform-5')
    """
    folder = _templates_dir()
    exact = folder / f"{name}.toml"
    if exact.is_file() and (made is None or _template_target(exact) != name):
        return str(name)
    slug = _slug(name)
    if made in MADE_KINDS and (folder / f"{slug}-{made}.toml").is_file():
        return f"{slug}-{made}"
    if (folder / f"{slug}.toml").is_file():
        return slug
    known = ", ".join(sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml")))
    raise DesignError(f"unknown template {name!r} (templates: {known}; or give a path to a .toml file; "
                      f"or make a die for any target with: diefab design TARGET)")  # fmt: skip


def template_path(name: str, made: str | None = None):
    """The path of the shipped template :func:`template_name` finds for `name` made as `made`."""
    return _templates_dir() / f"{template_name(name, made)}.toml"


def template_for(spec: str | Path, made: str | None = None) -> str | None:
    """The template a net, STL or check of `spec` made as `made` is built from; None for a design file's path.

    Examples
    --------
    >>> template_for("3dF", "paper"), template_for("3dF"), template_for("mine.toml", "paper")
    ('3df-paper', '3df', None)
    """
    text = str(spec)
    if text.endswith(".toml") or Path(text).exists() or "/" in text or "\\" in text:
        return None
    return template_name(text, made)


def load_design(spec: str | Path, made: str | None = None) -> Design:
    """Load a design from a TOML file path, or the template :func:`template_name` finds for `spec` made as `made`."""
    text = str(spec)
    path = Path(text)
    name = template_for(text, made)
    if name is None:
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
    return parse_design(template_path(name).read_text(encoding="utf-8"), source=f"template {name}")


def parse_design(
    content: str, *, source: str = "<string>", base: Path | None = None, within: Path | None = None
) -> Design:
    """Parse a design from TOML text; errors name `source` and the line.

    `base` is the folder a mesh or SVG symbol file is found in; `within`, when given, a folder outside which
    no such file is read (the design is refused before any file is opened).
    """
    try:
        data = tomllib.loads(content)
    except tomllib.TOMLDecodeError as exc:
        raise DesignError(f"{source}: malformed TOML: {exc}") from exc
    except RecursionError:
        raise DesignError(f"{source}: malformed TOML: nested too deeply") from None
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
    if within is not None:
        _check_within(kwargs, source, within)
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


def files_read(mesh: str | Path | None, labels: Mapping[str, object] | None) -> list[Path]:
    """The files a design of this `mesh` and these `labels` reads: the mesh, then each SVG symbol.

    >>> [str(f) for f in files_read("die.stl", {"f1": "svg:star.svg", "f2": "4dF"})]
    ['die.stl', 'star.svg']
    """
    files = [Path(mesh)] if mesh is not None else []
    if isinstance(labels, Mapping):
        files += [Path(t[4:].strip()) for t in labels.values() if isinstance(t, str) and t.startswith("svg:")]
    return files


def _check_within(kwargs: dict, source: str, folder: Path) -> None:
    """Refuse design arguments that name a file (a mesh, an SVG symbol) outside `folder`."""
    root = Path(folder).resolve()
    for f in files_read(kwargs.get("mesh"), kwargs.get("labels")):
        if root not in Path(f).resolve().parents:
            raise DesignError(f"{source}: files are read only in {folder}, not {f}")


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
