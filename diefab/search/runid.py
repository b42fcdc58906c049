"""A run's identity: digests of everything that defines a simulation run, stored when it starts.

A run folder holds ``run.json`` (the settings, the designs as TOML, the
dice's counts, the budget) and ``identity.json``, written with it: one
SHA-256 digest per field of ``run.json`` (one level into tables such as
``physics``, one per die and field of a calibration's dice) and one per
file a design refers to (a mesh, an SVG symbol), of the file's *contents*.
A resume recomputes the digests and refuses any difference, naming the
field, so that an edited ``run.json``, a changed mesh or a mesh path that
resolves elsewhere cannot continue a run with other settings than it began
with.

The identity guards against accidents (an edit, a moved file), not
against someone who rewrites both files on purpose.
"""

from __future__ import annotations

import hashlib
import json
import os
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

from diefab.core.errors import DiefabError

__all__ = ["IDENTITY_FILE", "compare_identity", "identity_text", "pinned_toml", "run_identity"]

#: Name of the identity file in a run folder.
IDENTITY_FILE = "identity.json"
#: Version of the identity format.
IDENTITY_FORMAT = 1


def _digest(value: Any) -> str:
    text = json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _file_digest(path: Path) -> str:
    """SHA-256 of the file's contents, or a word for why there are none."""
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            while chunk := fh.read(1 << 20):
                h.update(chunk)
    except FileNotFoundError:
        return "missing"
    except OSError as exc:
        return f"unreadable ({exc.strerror or exc})"
    return h.hexdigest()


def _design_files(toml_text: Any) -> dict[str, Path]:
    """The files a design TOML refers to: ``{"mesh": path, "label FACE": path, ...}``."""
    if not isinstance(toml_text, str):
        return {}
    try:
        data = tomllib.loads(toml_text)
    except (tomllib.TOMLDecodeError, ValueError):
        return {}
    files = {}
    if isinstance(data.get("mesh"), str):
        files["mesh"] = Path(data["mesh"])
    labels = data.get("labels")
    if isinstance(labels, dict):
        for face, text in labels.items():
            if isinstance(text, str) and text.startswith("svg:"):
                files[f"label {face}"] = Path(text[4:].strip())
    return files


def run_identity(spec_text: str) -> dict[str, str]:
    """Field -> digest for the text of a ``run.json`` and the files its designs refer to.

    Raises
    ------
    DiefabError
        `spec_text` is not a JSON object.
    """
    try:
        data = json.loads(spec_text)
    except ValueError as exc:
        raise DiefabError(f"run.json is not JSON: {exc}") from None
    if not isinstance(data, dict):
        raise DiefabError("run.json is not a JSON object")
    fields: dict[str, str] = {}

    def design(prefix: str, text: Any) -> None:
        fields[prefix] = _digest(text)
        for what, path in _design_files(text).items():
            fields[f"{prefix}: {what} file"] = _file_digest(path)

    for key, value in data.items():
        if key == "design_toml":
            design(key, value)
        elif key == "dice" and isinstance(value, list):
            fields["dice"] = _digest([d.get("name") if isinstance(d, dict) else d for d in value])
            for i, die in enumerate(value):
                if not isinstance(die, dict):
                    continue
                label = f"dice[{die.get('name', i)}]"
                for sub, item in die.items():
                    if sub == "design_toml":
                        design(f"{label}.design", item)
                    else:
                        fields[f"{label}.{sub}"] = _digest(item)
        elif isinstance(value, dict):
            fields[key] = _digest(sorted(value))
            for sub, item in value.items():
                fields[f"{key}.{sub}"] = _digest(item)
        else:
            fields[key] = _digest(value)
    return fields


def identity_text(spec_text: str) -> str:
    """The content of ``identity.json`` for a run described by `spec_text`."""
    return json.dumps({"format": IDENTITY_FORMAT, "fields": run_identity(spec_text)}, indent=1, sort_keys=True) + "\n"


def compare_identity(spec_text: str, stored_text: str) -> list[str]:
    """The fields whose digest differs between `spec_text` now and the stored identity (sorted).

    Raises
    ------
    DiefabError
        `stored_text` is not an identity file.
    """
    try:
        stored = json.loads(stored_text)
        fields = stored["fields"]
        if stored.get("format") != IDENTITY_FORMAT or not isinstance(fields, dict):
            raise ValueError
    except (ValueError, KeyError, TypeError, AttributeError):
        raise DiefabError(f"{IDENTITY_FILE} is corrupt") from None
    now = run_identity(spec_text)
    return sorted(k for k in {*now, *fields} if now.get(k) != fields.get(k))


def pinned_toml(design) -> str:
    """The design's TOML with its mesh and SVG symbol paths absolute (a run is resumed from anywhere)."""
    from diefab.dice.design import design_to_toml

    changes: dict[str, Any] = {}
    if design.mesh is not None:
        changes["mesh"] = Path(os.path.abspath(design.mesh))
    labels = {
        face: f"svg:{os.path.abspath(text[4:].strip())}" if isinstance(text, str) and text.startswith("svg:") else text
        for face, text in design.labels.items()
    }
    if labels != dict(design.labels):
        changes["labels"] = labels
    return design_to_toml(replace(design, **changes) if changes else design)
