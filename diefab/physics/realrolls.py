"""Physical roll counts of real dice, turned into diefab designs.

The files (one JSON object per die, Baktash et al. 2025; see the data's
README) hold the die's convex hull in ``geometry.units`` (millimetres,
centimetres, metres, inches, or ``model`` units with ``geometry.size_mm``
the real length of the bounding box's longest side; read as millimetres
when absent), the centre of mass and
inertia of the printed body (for a figurine die, off the hull's centroid),
the outcome each hull face counts for, the counts of real rolls and the
source's own predictions.  :func:`load_real_rolls` reads one;
:meth:`RealRolls.design_files` turns it into a design TOML that every
diefab command accepts: the hull, with the body's ``center_of_mass`` and
``inertia`` stated.

Outcomes are read off the hull triangles: each face of the design's hull
(triangles merged within ``merge_tolerance_mm``) that the die can rest on
takes the outcome of the data's resting triangles in it, or of its other
triangles, or else the outcome whose resting triangle's normal is nearest
(what the source's own notes do for the few faces they assign by hand).
Faces the die cannot rest on are transitional.

Examples
--------
>>> rolls = RealRolls(name="coin", outcomes=(0, 1), counts=np.array([48, 52]))
>>> rolls.n, rolls.frequencies.tolist()
(100, [0.48, 0.52])
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from itertools import permutations, product
from pathlib import Path

import numpy as np

from diefab.core.errors import DesignError
from diefab.core.files import check_size

#: Largest real-rolls file read, bytes (the largest shipped one is 0.4 MB).
REALROLLS_MAX_BYTES = 16 << 20

__all__ = ["RealRolls", "grouped_tvd", "load_real_rolls"]

#: Hull triangles within this distance of one plane become one face (mm).
MERGE_TOLERANCE_MM = 0.05

#: Millimetres per unit of ``geometry.units`` (``model`` units take ``geometry.size_mm`` instead).
UNITS_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4}
#: Smallest and largest span of a real die's hull, mm (a grain of sand to a beach ball).
HULL_SPAN_MM = (0.1, 10_000.0)


@dataclass(frozen=True, eq=False)
class RealRolls:
    """One real die and its rolls.

    Attributes
    ----------
    name : str
    outcomes : tuple of int
        The values read on the die, in the order of `counts`.
    counts : (k,) int
        Real rolls per outcome.
    groups : tuple of tuple of int
        Outcomes whose face assignment the source does not pin down
        (mirror images): compare up to relabelling within each group.
    reference : dict str -> (k,) float
        The source's own predictions per outcome (``ours``, ``bullet``,
        ``ipc``), normalized.
    hull_vertices : (n, 3) float, mm
    hull_faces : (t, 3) int
        Triangles of the hull, indices into `hull_vertices`.
    outcome_faces, outcome_stable_faces : dict int -> list of int
        Hull triangles that count for each outcome / that it rests on.
    center_of_mass : (3,) float, mm
        Of the printed body (for a non-convex die, off the hull's centroid).
    inertia : (3, 3) float, mm²
        The printed body's inertia about its centre of mass, per unit mass.
    description : str
    """

    name: str
    outcomes: tuple[int, ...]
    counts: np.ndarray
    groups: tuple[tuple[int, ...], ...] = ()
    reference: dict = field(default_factory=dict)
    hull_vertices: np.ndarray | None = None
    hull_faces: np.ndarray | None = None
    outcome_faces: dict = field(default_factory=dict)
    outcome_stable_faces: dict = field(default_factory=dict)
    center_of_mass: np.ndarray | None = None
    inertia: np.ndarray | None = None
    description: str = ""

    @property
    def n(self) -> int:
        """Number of real rolls."""
        return int(np.sum(self.counts))

    @property
    def frequencies(self) -> np.ndarray:
        return np.asarray(self.counts) / self.n

    def noise_tvd(self, samples: int = 20_000, seed: int = 0) -> float:
        """Expected TVD between `n` rolls and the distribution they are drawn from (Monte-Carlo at the
        observed frequencies, compared up to relabelling like every model): what a perfect model scores."""
        rng = np.random.default_rng(seed)
        draws = rng.multinomial(self.n, self.frequencies, size=samples) / self.n
        return float(np.mean([grouped_tvd(d, self.frequencies, self.outcomes, self.groups) for d in draws]))

    def tvd(self, predicted) -> float:
        """TVD of a predicted distribution over `outcomes` (plus any extra mass) to the real frequencies.

        `predicted` maps outcome -> probability; probability on values that
        are not outcomes counts as mass on faces the real die never showed.
        """
        p = np.array([float(predicted.get(o, 0.0)) for o in self.outcomes])
        extra = max(0.0, 1.0 - float(sum(predicted.values())))
        extra += sum(float(v) for k, v in predicted.items() if k not in self.outcomes)
        return grouped_tvd(p, self.frequencies, self.outcomes, self.groups) + 0.5 * extra

    # ------------------------------------------------------------------
    def design_files(self, merge_tolerance_mm: float = MERGE_TOLERANCE_MM) -> dict[str, str]:
        """File name -> content: the die's design TOML.

        The design is in model units (the longest side of the bounding box
        is 2 units, ``size_mm`` the real length it stands for), its values are the
        outcomes, its target the die's designed distribution (Binomial or
        uniform, from the name).
        """
        from dataclasses import replace

        from diefab.dice.design import Design, design_to_toml
        from diefab.dice.families.base import default_length
        from diefab.geometry.polyhedron import Polyhedron, resting_faces

        if self.hull_vertices is None:
            raise DesignError(f"real die {self.name!r} has no geometry")
        scale = 2.0 / float(np.ptp(self.hull_vertices, axis=0).max())  # model units per mm
        vertices = self.hull_vertices * scale
        poly = Polyhedron.from_points(vertices, strict=False, merge_tolerance=merge_tolerance_mm * scale)
        size_mm = default_length(poly)[0] / scale  # the real length of what size_mm measures
        body = {}
        if self.center_of_mass is not None:
            body["center_of_mass"] = tuple((self.center_of_mass * scale).tolist())
        if self.inertia is not None:
            body["inertia"] = tuple(map(tuple, (self.inertia * scale**2).tolist()))
        design = Design(
            self.name, "convex", vertices=tuple(map(tuple, vertices.tolist())), size_mm=size_mm,
            merge_tolerance_mm=float(merge_tolerance_mm), description=self.description,
            values={n: 0 for n in poly.names}, target="1", **body,
        )  # fmt: skip
        poly = design.polyhedron
        resting = resting_faces(poly, design.mass_properties().center)
        values = {poly.names[f]: self._outcome_of(poly, f, scale) for f in np.flatnonzero(resting)}
        weights = _designed_target(self.name, self.outcomes)
        target = ",".join(f"{o}:{w:.12g}" for o, w in zip(self.outcomes, weights))
        text = design_to_toml(replace(design, values=values, target=target), comment=f"real die {self.name}: "
                              f"{self.description}; hull, centre of mass and inertia of the printed body")  # fmt: skip
        return {f"{self.name}.toml": text}

    def _outcome_of(self, poly, face: int, scale: float) -> int:
        """The outcome of design face `face` (see the module docstring)."""
        tri = np.asarray(self.hull_faces)
        v = self.hull_vertices[tri] * scale
        normals = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
        normals /= np.linalg.norm(normals, axis=1)[:, None]
        centers = v.mean(axis=1)
        n, off = poly.normals[face], poly.offsets[face]
        inside = (normals @ n > np.cos(np.radians(5))) & (np.abs(centers @ n - off) < 0.01)
        for table in (self.outcome_stable_faces, self.outcome_faces):
            hits = [o for o, faces in table.items() for t in faces if inside[t]]
            if hits:
                return max(set(hits), key=hits.count)
        stable = [(o, t) for o, faces in self.outcome_stable_faces.items() for t in faces]
        return max(stable, key=lambda ot: float(normals[ot[1]] @ n))[0]


def _designed_target(name: str, outcomes: tuple[int, ...]) -> np.ndarray:
    """The distribution the die was designed for: Binomial(N, 1/2) for ``binomN``, else uniform."""
    import re

    if m := re.match(r"binom(\d+)", name):
        from scipy.stats import binom

        return binom.pmf(np.asarray(outcomes, dtype=float), int(m[1]), 0.5)  # any N, without overflow
    return np.full(len(outcomes), 1.0 / len(outcomes))


def grouped_tvd(p, q, outcomes, groups) -> float:
    """TVD between `p` and `q` (over `outcomes`), the least over relabellings of `p` within each group."""
    p, q = np.asarray(p, float), np.asarray(q, float)
    index = {o: i for i, o in enumerate(outcomes)}
    groups = [[index[o] for o in g if o in index] for g in groups]
    best = np.inf
    for perms in product(*(permutations(g) for g in groups)):
        order = np.arange(len(p))
        for g, perm in zip(groups, perms):
            order[g] = perm
        best = min(best, 0.5 * float(np.abs(p[order] - q).sum()))
    return best


def _finite(where: str, value) -> None:
    """A finite number of any magnitude (volumes in mm³ and inertias in mm⁵ exceed a design file's 1e6)."""
    from diefab.dice.schema import _fail

    if isinstance(value, bool) or not isinstance(value, (int, float)):
        _fail(where, value, "a number")
    if not math.isfinite(value):
        raise DesignError(f"{where} = {value!r} is not a finite number")


def _count(where: str, value) -> None:
    from diefab.dice.schema import _fail
    from diefab.stats.goodness import MAX_COUNT

    if isinstance(value, bool) or not isinstance(value, int):
        _fail(where, value, "an integer")
    if not 0 <= value <= MAX_COUNT:
        raise DesignError(f"{where} = {value} is not a number of rolls in [0, {MAX_COUNT:.0e}]")


def _fields() -> dict:
    """Top-level key of a real-rolls file -> the check of its value (:mod:`diefab.dice.schema`'s checks)."""
    from diefab.dice.schema import array, index, integer, point, positive, record, table, text, word

    prediction = array(_finite, least=1)
    return {
        "shape": word,
        "description": text,
        "physical": record(outcomes=array(integer, least=1), counts=array(_count, least=1)),
        "their_model_and_sims": record(ours=prediction, bullet=prediction, ipc=prediction),
        "geometry": record(hull_vertices=array(point, least=4), hull_faces=array(array(index, length=3), least=4),
                           units=word, size_mm=positive),
        "fabricated_body": record(volume=_finite, com=point,
                                  inertia_about_com_unit_density=array(array(_finite, length=3), length=3)),
        "outcome_faces": table(array(index)),
        "outcome_stable_faces": table(array(index)),
        "ambiguous_groups": array(array(integer, least=2)),
    }  # fmt: skip


#: Keys a real-rolls file must have (dotted: a key of a table).
REQUIRED = ("physical.outcomes", "physical.counts", "geometry.hull_vertices", "geometry.hull_faces",
            "fabricated_body.com", "fabricated_body.inertia_about_com_unit_density", "fabricated_body.volume",
            "outcome_faces", "outcome_stable_faces")  # fmt: skip


def _check_data(data) -> None:
    """Raise :class:`DesignError` naming the field unless `data` is a real-rolls die diefab can use."""
    from diefab.dice.schema import _kind
    from diefab.stats.goodness import MAX_COUNT

    if not isinstance(data, dict):
        raise DesignError(f"holds {'null' if data is None else _kind(data)}, not a JSON object")
    fields = _fields()
    for key, value in data.items():
        if key in fields:
            fields[key](key, value)
    for key in REQUIRED:
        node = data
        for part in key.split("."):
            if not isinstance(node, dict) or part not in node:
                raise DesignError(f"no {key}")
            node = node[part]
    phys = data["physical"]
    outcomes, counts = phys["outcomes"], phys["counts"]
    if len(counts) != len(outcomes):
        raise DesignError(f"physical.counts has {len(counts)} items for the {len(outcomes)} physical.outcomes")
    if len(set(outcomes)) != len(outcomes):
        raise DesignError(f"physical.outcomes = {outcomes} names an outcome twice")
    if sum(counts) > MAX_COUNT:
        raise DesignError(f"physical.counts add up to {sum(counts):.3g}, more than the {MAX_COUNT:.0e} rolls diefab "
                          "can count")  # fmt: skip
    geo = data["geometry"]
    n_vertices, n_faces = len(geo["hull_vertices"]), len(geo["hull_faces"])
    for i, tri in enumerate(geo["hull_faces"]):
        if max(tri) >= n_vertices:
            raise DesignError(f"geometry.hull_faces[{i}] = {tri} names a vertex beyond the {n_vertices} hull_vertices")
    units = geo.get("units", "mm")
    if units not in (*UNITS_MM, "model"):
        raise DesignError(f"geometry.units = {units!r} is not one of {', '.join((*UNITS_MM, 'model'))}")
    if units == "model" and "size_mm" not in geo:
        raise DesignError("geometry.units = 'model' needs geometry.size_mm, the real length (mm) of the longest "
                          "side of the hull's bounding box")  # fmt: skip
    if units != "model" and "size_mm" in geo:
        raise DesignError(f"geometry.size_mm is for model units; geometry.units = {units!r} already gives the size")
    if data["fabricated_body"]["volume"] <= 0:
        raise DesignError(f"fabricated_body.volume = {data['fabricated_body']['volume']!r} is not a positive number")
    for key in ("outcome_faces", "outcome_stable_faces"):
        for outcome, faces in data[key].items():
            if not outcome.lstrip("-").isdigit() or int(outcome) not in outcomes:
                raise DesignError(f"{key} has key {outcome!r}, which is not one of physical.outcomes {outcomes}")
            if faces and max(faces) >= n_faces:
                raise DesignError(f"{key}.{outcome} names triangle {max(faces)} beyond the {n_faces} hull_faces")
    if not any(data["outcome_stable_faces"].values()):
        raise DesignError("outcome_stable_faces names no triangle the die rests on")
    for i, group in enumerate(data.get("ambiguous_groups", [])):
        if not set(group) <= set(outcomes):
            raise DesignError(f"ambiguous_groups[{i}] = {group} names a value that is not one of physical.outcomes")
    for key, p in data.get("their_model_and_sims", {}).items():
        if key in ("ours", "bullet", "ipc") and (len(p) != len(outcomes) or min(p) < 0 or sum(p) <= 0):
            raise DesignError(f"their_model_and_sims.{key} is not a distribution over the {len(outcomes)} outcomes")


def load_real_rolls(path: str | Path) -> RealRolls:
    """Read one die of the real-rolls data (a JSON file).

    The geometry and the body (``fabricated_body``, in the hull's
    coordinates and units) are converted from ``geometry.units`` to
    millimetres.

    Raises
    ------
    DesignError
        The file is not a regular file, not UTF-8 JSON, or a field has the
        wrong type, is missing or disagrees with another (counts for every
        outcome, triangles of the hull, outcomes that exist, a unit diefab
        knows); the message names the file and the field.
    """
    path = Path(path)
    if not path.is_file():
        raise DesignError(f"real rolls {path} {'is not a regular file' if path.exists() else 'does not exist'}")
    check_size(path, REALROLLS_MAX_BYTES, "real rolls", DesignError)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DesignError(f"cannot read real rolls {path}: {exc}") from None
    try:
        _check_data(data)
    except DesignError as exc:
        raise DesignError(f"real rolls {path}: {exc}") from None
    phys, geo, body = data["physical"], data["geometry"], data["fabricated_body"]
    vertices = np.array(geo["hull_vertices"], dtype=float)
    units = geo.get("units", "mm")
    mm = UNITS_MM[units] if units != "model" else float(geo["size_mm"]) / float(np.ptp(vertices, axis=0).max())
    span = float(np.ptp(vertices, axis=0).max()) * mm
    if not (HULL_SPAN_MM[0] <= span <= HULL_SPAN_MM[1]):
        raise DesignError(f"real rolls {path}: geometry.hull_vertices span {span:.3g} mm; a die spans "
                          f"{HULL_SPAN_MM[0]:g} mm to {HULL_SPAN_MM[1]:g} mm (are geometry.units right?)")  # fmt: skip
    reference = {}
    for key in ("ours", "bullet", "ipc"):
        if key in data.get("their_model_and_sims", {}):
            r = np.array(data["their_model_and_sims"][key], dtype=float)
            reference[key] = r / r.sum()
    return RealRolls(
        name=str(data.get("shape", path.stem)),
        outcomes=tuple(phys["outcomes"]),
        counts=np.array(phys["counts"], dtype=np.int64),
        groups=tuple(tuple(g) for g in data.get("ambiguous_groups", [])),
        reference=reference,
        hull_vertices=vertices * mm,
        hull_faces=np.array(geo["hull_faces"], dtype=np.intp),
        outcome_faces={int(k): list(v) for k, v in data["outcome_faces"].items()},
        outcome_stable_faces={int(k): list(v) for k, v in data["outcome_stable_faces"].items()},
        center_of_mass=np.array(body["com"], dtype=float) * mm,
        inertia=np.array(body["inertia_about_com_unit_density"], dtype=float) / float(body["volume"]) * mm**2,
        description=str(data.get("description", "")),
    )
