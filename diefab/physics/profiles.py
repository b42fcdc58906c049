"""Physics profiles: TOML files of simulation settings, the shipped set, and the sensitivity of a die to them.

A profile is a TOML file with a ``[physics]`` table (the keys of
:class:`diefab.physics.simulate.PhysicsSettings`), optionally ``name``,
``description``, a ``[calibration]`` table (what ``diefab calibrate``
found) and a ``[domain]`` table: the fills of the dice it was fitted on
(``fills``) and how and where they were rolled (``rolled``), against
which :func:`domain_note` checks a die.  ``validate``, ``optimize``,
``design`` and ``calibrate`` take one with ``--physics``: a path, or the
name of a shipped profile (:func:`list_profiles`).

The shipped set describes a standard set of throws and tables
(:data:`STANDARD`): a soft tray, a wooden table, a hard tray, and a low and a
high spin.  They are plausible settings chosen to span what a die meets,
not measurements: a die whose distribution holds across them is robust to
the throw and the table.

Examples
--------
>>> s = load_profile("hard-tray")
>>> s.restitution > load_profile("soft-tray").restitution
True
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from diefab.core.errors import PhysicsError
from diefab.core.files import check_size
from diefab.physics.simulate import PhysicsSettings

#: Largest physics profile read, bytes (one is a few hundred).
PROFILE_MAX_BYTES = 1 << 20

__all__ = [
    "PROFILE_KEYS",
    "STANDARD",
    "domain_note",
    "fitted_profiles",
    "list_profiles",
    "load_profile",
    "profile_to_toml",
    "read_profile",
    "sensitivity",
]

#: Top-level keys of a physics profile.
PROFILE_KEYS = ("name", "description", "physics", "calibration", "domain")
#: The standard throws and tables of ``validate --sensitivity`` and ``optimize --robust`` (shipped profiles).
STANDARD = ("soft-tray", "wooden-table", "hard-tray", "low-spin", "high-spin")


def _profiles_dir():
    from importlib import resources

    return resources.files("diefab").joinpath("data", "profiles")


def list_profiles() -> list[str]:
    """Names of the shipped physics profiles, sorted."""
    folder = _profiles_dir()
    if not folder.is_dir():
        return []
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def fitted_profiles() -> list[str]:
    """Names of the shipped profiles fitted on real dice (those with a ``[calibration]`` table), sorted."""
    return [name for name in list_profiles() if "calibration" in read_profile(name)[0]]


def read_profile(spec) -> tuple[dict[str, Any], str]:
    """The parsed TOML of profile `spec` (a shipped profile's name or a file path) and its source.

    Raises
    ------
    PhysicsError
        The file is missing, unreadable, not TOML or not a profile (unknown
        top-level key, no ``[physics]`` table).
    """
    import tomllib
    from pathlib import Path

    text = str(spec)
    if text.endswith(".toml") or "/" in text or "\\" in text or Path(text).exists():
        path, source = Path(text), f"physics profile {text}"
        if not path.is_file():
            raise PhysicsError(f"physics profile {text} {'is not a file' if path.exists() else 'does not exist'}")
    else:
        path, source = _profiles_dir() / f"{text}.toml", f"physics profile {text!r}"
        if not path.is_file():
            known = ", ".join(list_profiles()) or "none"
            raise PhysicsError(f"unknown physics profile {text!r} (shipped: {known}; or give a path to a .toml file)")
    try:
        check_size(path, PROFILE_MAX_BYTES, "physics profile", PhysicsError)
        data = tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError) as exc:
        raise PhysicsError(f"cannot read {source}: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise PhysicsError(f"{source}: malformed TOML: {exc}") from None
    unknown = sorted(set(data) - set(PROFILE_KEYS))
    if unknown:
        raise PhysicsError(f"{source}: unknown key {unknown[0]!r} (keys: {', '.join(PROFILE_KEYS)})")
    if not isinstance(data.get("physics"), dict):
        raise PhysicsError(f"{source}: needs a [physics] table of settings")
    for key, kind, what in (("name", str, "a string"), ("description", str, "a string"),
                            ("calibration", dict, "a table"), ("domain", dict, "a table")):  # fmt: skip
        if key in data and not isinstance(data[key], kind):
            raise PhysicsError(f"{source}: {key} = {data[key]!r} is not {what}")
    if "domain" in data:
        _check_domain(data["domain"], source)
    return data, source


def _check_domain(domain: Mapping[str, Any], source: str) -> None:
    from diefab.made.fill import KINDS

    unknown = sorted(set(domain) - {"fills", "rolled"})
    if unknown:
        raise PhysicsError(f"{source}: unknown key {unknown[0]!r} in [domain] (keys: fills, rolled)")
    fills = domain.get("fills", [])
    if not isinstance(fills, list) or not fills or any(f not in KINDS for f in fills):
        raise PhysicsError(f"{source}: domain.fills = {fills!r} is not a list of fills ({', '.join(KINDS)})")
    if not isinstance(domain.get("rolled", ""), str):
        raise PhysicsError(f"{source}: domain.rolled = {domain['rolled']!r} is not a string")


def domain_note(spec, fill: str) -> str | None:
    """Why a die of fill `fill` lies outside the dice profile `spec` was fitted on, or None if it does not.

    Only a profile with a ``[domain]`` table has dice to lie outside of.

    Examples
    --------
    >>> domain_note("printed-table", "solid") is None
    True
    >>> print(domain_note("printed-table", "paper"))  # doctest: +ELLIPSIS
    physics profile 'printed-table' was fitted on solid dice rolled on ...; this die is paper, outside them
    """
    data, source = read_profile(spec)
    domain = data.get("domain")
    if domain is None or fill in domain["fills"]:
        return None
    rolled = f" rolled {domain['rolled']}" if domain.get("rolled") else ""
    return f"{source} was fitted on {' and '.join(domain['fills'])} dice{rolled}; this die is {fill}, outside them"


def load_profile(spec, base: Mapping[str, Any] | None = None, **overrides: Any) -> PhysicsSettings:
    """Settings of physics profile `spec` over `base` (e.g. a design's ``[physics]``), then `overrides`.

    `spec` is a shipped profile's name (:func:`list_profiles`) or a TOML file
    with a ``[physics]`` table (the keys of :class:`PhysicsSettings`); None
    values in `overrides` are ignored, as in :meth:`PhysicsSettings.from_mapping`.
    """
    data, source = read_profile(spec)
    try:
        return PhysicsSettings.from_mapping({**dict(base or {}), **data["physics"]}, **overrides)
    except PhysicsError as exc:
        raise PhysicsError(f"{source}: {exc}") from None
    except TypeError as exc:
        raise PhysicsError(f"{source}: {exc}") from None


def profile_to_toml(settings: PhysicsSettings, *, name: str = "", description: str = "",
                    calibration: Mapping[str, Any] | None = None, domain: Mapping[str, Any] | None = None,
                    comment: str = "") -> str:  # fmt: skip
    """A physics profile as TOML (round-trips through :func:`load_profile`)."""
    import tomli_w

    data: dict[str, Any] = {}
    if name:
        data["name"] = name
    if description:
        data["description"] = description
    data["physics"] = settings.as_dict()
    if calibration:
        data["calibration"] = dict(calibration)
    if domain:
        data["domain"] = dict(domain)
    header = "".join(f"# {line}\n" for line in comment.splitlines())
    return header + tomli_w.dumps(data)


def sensitivity(design, profiles: Sequence[str] = STANDARD, n: int = 10_000, *, seed: int = 0,
                workers: int | None = None, scheduler=None, **overrides: Any) -> list[dict[str, Any]]:  # fmt: skip
    """Simulate `design` under each physics profile; per profile its value counts and fit to the target.

    Each profile is applied over the design's ``[physics]`` table, then
    `overrides`; every profile drops the die `n` times with the same `seed`.

    Returns
    -------
    list of dict
        ``profile``, ``settings``, ``counts`` (per value of ``design.support``),
        ``cocked``, ``unsettled`` and the :func:`diefab.stats.goodness.goodness_of_fit`
        numbers ``tvd``, ``expected_tvd``, ``chi2``, ``p_value``.
    """
    from diefab.physics.simulate import simulate
    from diefab.stats.goodness import goodness_of_fit

    if not profiles:
        raise PhysicsError("sensitivity needs at least one physics profile")
    settings = [load_profile(p, base=design.physics, **overrides) for p in profiles]
    goal = design.target_distribution.aligned(design.support)
    out = []
    for name, s in zip(profiles, settings):
        result = simulate(design, n, seed=seed, workers=workers, settings=s, scheduler=scheduler)
        if result.landed == 0:
            raise PhysicsError(f"profile {name}: no drop came to rest on a face")
        counts = result.value_counts(design)
        fit = goodness_of_fit(counts, goal, seed=seed)
        out.append({"profile": str(name), "settings": s.as_dict(), "counts": counts.tolist(),
                    "cocked": result.cocked, "unsettled": result.unsettled, "tvd": fit.tvd,
                    "expected_tvd": fit.expected_tvd, "chi2": fit.chi2, "p_value": fit.p_value,
                    "seconds": result.seconds})  # fmt: skip
    return out
