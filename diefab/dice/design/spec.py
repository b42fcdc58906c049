"""Designs: a die family with parameters, face values, labels, target and size.

A design is what a template file holds (TOML, schema in the README; read and
written by :mod:`.files`).  It knows its polyhedron, how each resting face is
read, what is printed on each face, and its mass properties as made.

Examples
--------
>>> from diefab.dice.design import load_design
>>> design = load_design("fudge-gem")
>>> design.params
{'a': 1.18, 'b': 0.52, 'c': 0.72, 'd': 1.41}
>>> design.value_of["f5"], design.label_of["f4"]
(0, '+2')
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from diefab.core import tolerances as tol
from diefab.core.errors import DesignError, GeometryError
from diefab.dice.families import family
from diefab.dice.families.base import default_length
from diefab.dice.schema import check_mapping
from diefab.dice.targets import Target, parse_target
from diefab.geometry.meshes import ClosedMesh
from diefab.geometry.moments import MassProperties, stated
from diefab.geometry.polyhedron import Polyhedron, face_margins, hull_diameter, resting_faces
from diefab.made.bodies import body_properties
from diefab.made.fill import Fill
from diefab.made.mass import mesh_mass_properties
from diefab.made.placement import LabelPlan

__all__ = ["Design", "GEM_VALUES", "design_axis", "format_value", "placed_marks", "reference_length", "signed_number"]

#: Resting face -> value of the paper's gem (colors of its Fig. 3).
GEM_VALUES = {"f1": 3, "f2": 4, "f3": -3, "f4": -4, "f5": 0, "f6": 1, "f7": 2, "f8": -1, "f9": -2}


#: Default merge tolerance of a mesh design's hull faces, millimetres.
MESH_MERGE_MM = 0.01


def _number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def signed_number(x: float, digits: int) -> str:
    """A difference with its sign, as tables print it: ``+0.0538``, ``−0.0059`` (true minus sign).

    >>> signed_number(-0.00591, 4)
    '−0.0059'
    """
    text = f"{x:+.{digits}f}"
    return "−" + text[1:] if text.startswith("-") else text


def format_value(value: int, signed: bool) -> str:
    """The text printed on a face: ``+2``, ``−3`` (true minus sign), ``0``."""
    if not signed:
        return str(value)
    return "0" if value == 0 else f"+{value}" if value > 0 else f"\u2212{-value}"


@dataclass(frozen=True, eq=False)
class Design:
    """A die design.

    Parameters
    ----------
    name : str
    family : str
        A family of :mod:`diefab.dice.families` (``gem``, ``ngem``, ``prism``, ...,
        ``convex`` or ``mesh``).
    params : mapping str -> float
        Family parameters (the gem's a, b, c, d and optional e).
    values : mapping str -> int
        Value rolled when the die rests on each face (face name -> value).
        Only the faces the die can rest on carry a value; the others are
        transitional.
    target : str
        Target distribution specification (see :mod:`diefab.dice.targets`).
    labels : mapping str -> str
        Overrides of the computed label text, keyed by the face that carries it.
    size_mm : float
        Physical size as dice makers measure it (:attr:`size_note`): the
        gem's girdle short side (2 model units along its z); for the other
        families their stated reference length (``Family.reference``); for
        ``convex``, ``mesh`` and ``freeform`` dice, face to face when every
        face has a parallel opposite (a d6, d8, d20: the widest such pair),
        else the largest distance between two vertices (a d4's edge).  It
        never depends on how the vertices are rotated.
    fill : Fill
    physics : mapping
        Simulation settings stored with the design (see :mod:`diefab.physics.simulate`).
    vertices, faces, mesh
        Geometry of ``convex`` and ``mesh`` designs, in any units: the die is
        scaled so that its bounding box's longest side is 2 model units
        (``size_mm`` gives its real size).
    transitional : sequence of str
        Faces named as faces the die cannot rest on (it rolls off them).
        They carry no value.  A face with no value is transitional whether
        named or not, but it must really be one: a die that can rest on a
        face needs a value for it.
    center_of_mass : (3,) float, optional
        The real body's centre of mass (a weighted die, a print with an
        insert), used by every model and the simulation instead of the
        fill's.  In the design's own coordinates: a ``convex`` design's
        vertices', a ``mesh`` design's file's.  It must lie inside the die.
    inertia : (3, 3) float, optional
        The real body's inertia tensor about its centre of mass, per unit
        mass (same units, squared).  Without it the fill's inertia about
        the fill's own centre of mass is used.
    merge_tolerance_mm : float, optional
        Hull triangles of a ``mesh`` (or ``convex`` without ``faces``)
        design whose vertices lie within this many millimetres of one plane
        become one face (default: :data:`MESH_MERGE_MM` for meshes, exact
        coplanarity for vertex lists).  For a ``convex`` design that lists
        its ``faces``: how many millimetres a face's vertices may lie off the
        face's plane (default :data:`~diefab.tolerances.FACE_FLATNESS_MM`;
        :attr:`face_flatness_mm` reports each face's distance).
    """

    name: str
    family: str
    params: Mapping[str, float] = field(default_factory=dict)
    values: Mapping[str, int] = field(default_factory=dict)
    target: str = "4df"
    labels: Mapping[str, str] = field(default_factory=dict)
    size_mm: float = 30.0
    fill: Fill = field(default_factory=Fill)
    description: str = ""
    physics: Mapping[str, Any] = field(default_factory=dict)
    vertices: tuple[tuple[float, float, float], ...] | None = None
    faces: tuple[tuple[int, ...], ...] | None = None
    mesh: Path | None = None
    transitional: tuple[str, ...] = ()
    center_of_mass: tuple[float, float, float] | None = None
    inertia: tuple[tuple[float, float, float], ...] | None = None
    merge_tolerance_mm: float | None = None

    def __post_init__(self) -> None:
        for key in ("name", "family", "target", "description"):
            if not isinstance(getattr(self, key), str):
                raise DesignError(f"{key}={getattr(self, key)!r} must be a string")
        for key in ("params", "values", "labels", "physics"):
            check_mapping(key, getattr(self, key))
        fam = family(self.family)
        object.__setattr__(self, "params", fam.check_params(self.params))
        size = self.size_mm
        if isinstance(size, bool) or not (isinstance(size, (int, float)) and math.isfinite(size) and size > 0):
            raise DesignError(f"size_mm={self.size_mm} must be a positive number of millimetres")
        if self.family == "convex" and self.vertices is None:
            raise DesignError("a convex design needs 'vertices'")
        if self.family == "mesh" and self.mesh is None:
            raise DesignError("a mesh design needs 'mesh' (a file path)")
        self._check_body()
        values = dict(self.values) or (GEM_VALUES if self.family == "gem" else {})
        names = self.polyhedron.names
        if isinstance(self.transitional, str) or not all(isinstance(n, str) for n in self.transitional):
            raise DesignError(f"transitional={self.transitional!r} must be a list of face names")
        object.__setattr__(self, "transitional", tuple(self.transitional))
        for what, given in (("values", values), ("transitional", self.transitional)):
            extra = sorted(set(given) - set(names))
            if extra:
                raise DesignError(f"design {self.name!r}: {what}: face {extra[0]!r} does not exist")
        both = [n for n in names if n in values and n in self.transitional]
        if both:
            raise DesignError(f"design {self.name!r}: face {both[0]!r} is named transitional but has a value")
        for k, v in values.items():
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
                raise DesignError(f"value of face {k!r} is {v!r}, not an integer")
        if not values:
            raise DesignError(f"design {self.name!r}: values must give the faces the die can rest on a value")
        object.__setattr__(self, "values", {n: int(values[n]) for n in names if n in values})
        if len(values) < len(names):
            self._check_transitional(None)
        for k, v in self.labels.items():
            if k not in names:
                raise DesignError(f"labels: face {k!r} does not exist (faces: {', '.join(names)})")
            if not isinstance(v, str):
                raise DesignError(f"labels: label of face {k!r} must be a string")
            if any(c in v for c in "\n\r\t"):
                raise DesignError(f"labels: label of face {k!r} ({v!r}) holds a line break or tab: a label is one line")
        self.target_distribution  # noqa: B018 -- validate the target against the values now

    def _check_body(self) -> None:
        """Check the stated merge tolerance, centre of mass and inertia (shapes, finiteness, physics)."""
        t = self.merge_tolerance_mm
        if t is not None and not (_number(t) and 0 <= t <= 10):
            raise DesignError(f"merge_tolerance_mm={t!r} must be a number of millimetres in [0, 10]")
        if self.center_of_mass is not None:
            c = self.center_of_mass
            if not (isinstance(c, (list, tuple)) and len(c) == 3 and all(map(_number, c))):
                raise DesignError(f"center_of_mass={c!r} must be three finite numbers [x, y, z]")
            object.__setattr__(self, "center_of_mass", tuple(float(x) for x in c))
        if self.inertia is not None:
            i = self.inertia
            ok = isinstance(i, (list, tuple)) and len(i) == 3
            ok = ok and all(isinstance(r, (list, tuple)) and len(r) == 3 and all(map(_number, r)) for r in i)
            if not ok:
                raise DesignError(f"inertia={i!r} must be a 3x3 table of finite numbers")
            a = np.array(i, dtype=float)
            if not np.allclose(a, a.T, rtol=1e-6, atol=1e-12 * np.abs(a).max()):
                raise DesignError(f"inertia={a.tolist()} is not symmetric")
            m = np.linalg.eigvalsh(a)
            if m[0] <= 0 or m[2] > (m[0] + m[1]) * (1 + 1e-6):
                raise DesignError(
                    f"inertia has principal moments {m.tolist()}: need all > 0 and each at most the sum of "
                    "the other two (a real body)"
                )
            object.__setattr__(self, "inertia", tuple(tuple(float(x) for x in r) for r in a))

    @cached_property
    def _file_mesh(self) -> ClosedMesh | None:
        """A ``mesh`` design's body in the file's units, else None."""
        if self.family != "mesh":
            return None
        try:
            return ClosedMesh.load(self.mesh)
        except GeometryError as exc:
            raise DesignError(f"design {self.name!r}: {exc}") from exc

    @cached_property
    def _file_scale(self) -> float:
        """Model units per unit of the design's own coordinates.

        A ``mesh`` file and a ``convex`` design's vertices are scaled so that the longest side of their
        bounding box is 2 model units: the throw is defined in model units (the gem's girdle spans 2), so a
        die's landing cannot depend on the units its vertices are written in.  Vertices already of that
        size are used as written; a family's own parameters define its model units.
        """
        mesh = self._file_mesh
        if mesh is not None:
            return 2.0 / float(np.ptp(mesh.vertices, axis=0).max())
        if self.family != "convex":
            return 1.0
        try:
            points = np.array(self.vertices, dtype=float)
        except (TypeError, ValueError):
            return 1.0  # refused, naming what is wrong, when the polyhedron is built
        extent = float(np.ptp(points, axis=0).max()) if points.ndim == 2 and len(points) else math.nan
        if not (math.isfinite(extent) and extent > 0) or abs(extent - 2.0) <= 1e-9:
            return 1.0
        return 2.0 / extent

    @cached_property
    def body_mesh(self) -> ClosedMesh | None:
        """A ``mesh`` design's body in model units (its longest bounding-box side 2), else None."""
        mesh = self._file_mesh
        return None if mesh is None else mesh.scaled(self._file_scale)

    @cached_property
    def polyhedron(self) -> Polyhedron:
        """The die in model units: for a ``mesh`` design, the convex hull it rests on."""
        fam = family(self.family)
        if fam.build is not None:
            return fam.polyhedron(self.params)
        try:
            if self.family == "convex" and self.faces is not None:
                return self._listed_polyhedron()
            mm = MESH_MERGE_MM if self.merge_tolerance_mm is None and self.family == "mesh" else self.merge_tolerance_mm
            mesh = self.family == "mesh"
            points = self.body_mesh.vertices if mesh else np.array(self.vertices, dtype=float) * self._file_scale
            if mm is None:
                return Polyhedron.from_points(points, strict=not mesh)
            # the tolerance is in mm, and what size_mm measures depends on the merged faces: start from the
            # largest vertex distance and merge again if the faces say the die is measured face to face
            length = hull_diameter(points)  # refuses a hull too large before any distance
            poly = Polyhedron.from_points(points, strict=not mesh, merge_tolerance=mm * length / self.size_mm)
            ref = default_length(poly)[0]
            if abs(ref - length) > 1e-6 * length:
                poly = Polyhedron.from_points(points, strict=not mesh, merge_tolerance=mm * ref / self.size_mm)
            return poly
        except GeometryError as exc:
            raise DesignError(f"design {self.name!r}: {exc}") from exc

    def _listed_polyhedron(self) -> Polyhedron:
        """The listed faces, each planar within ``merge_tolerance_mm`` (refused beyond, naming face and distance)."""
        mm = tol.FACE_FLATNESS_MM if self.merge_tolerance_mm is None else float(self.merge_tolerance_mm)
        vertices = np.array(self.vertices, dtype=float) * self._file_scale
        exact = Polyhedron(vertices, self.faces, flatness=np.inf)  # topology and planes, flatness checked below
        mm_per_unit = self.size_mm / default_length(exact)[0]
        flat_mm = exact.face_flatness * mm_per_unit
        k = int(np.argmax(flat_mm))
        if flat_mm[k] > mm:
            raise GeometryError(f"face {exact.names[k]} is {flat_mm[k]:.3g} mm off its plane, beyond the "
                                f"{mm:g} mm that merge_tolerance_mm allows")  # fmt: skip
        return Polyhedron(vertices, self.faces, flatness=mm / mm_per_unit)

    @property
    def face_flatness_mm(self) -> dict[str, float]:
        """Face name -> largest distance of its vertices from its plane, mm (0 for exact geometry)."""
        poly = self.polyhedron
        return dict(zip(poly.names, (poly.face_flatness * self.mm_per_unit).tolist()))

    @cached_property
    def transitional_faces(self) -> tuple[str, ...]:
        """The faces that carry no value (the die cannot rest on them), named or detected."""
        return tuple(n for n in self.polyhedron.names if n not in self.values)

    def resting_mask(self) -> np.ndarray:
        """(m,) bool: the faces that carry a value, in face order."""
        return np.array([n in self.values for n in self.polyhedron.names])

    def _check_transitional(self, fill: Fill | None) -> None:
        """Raise :class:`DesignError` if the die can rest on a face that carries no value."""
        poly = self.polyhedron
        center = self.mass_properties(fill).center
        resting = resting_faces(poly, center)
        margins = face_margins(poly, center)
        for k, name in enumerate(poly.names):
            if name not in self.values and resting[k]:
                how = "is named transitional" if name in self.transitional else "has no value"
                with_fill = f" with a {fill.kind} fill" if fill is not None and fill != self.fill else ""
                raise DesignError(
                    f"design {self.name!r}: face {name} {how}, but the die can rest on it{with_fill} "
                    f"(margin {margins[k]:.4g}): give it a value"
                )

    @property
    def value_of(self) -> dict[str, int]:
        """Resting face name -> value."""
        return dict(self.values)

    @cached_property
    def support(self) -> list[int]:
        """The distinct values, increasing."""
        return sorted(set(self.values.values()))

    @cached_property
    def target_distribution(self) -> Target:
        return parse_target(self.target, self.support)

    @cached_property
    def mm_per_unit(self) -> float:
        """Millimetres per model unit."""
        return self.size_mm / reference_length(self)[0]

    @property
    def size_note(self) -> str:
        """What ``size_mm`` measures on this die, in words."""
        return reference_length(self)[1]

    @cached_property
    def label_face(self) -> dict[str, str | None]:
        """Resting face -> the face pointing up that shows its value (None: a vertex or edge is up).

        What points up follows :func:`diefab.dice.readings.readings`.
        """
        from diefab.dice.readings import readings

        poly = self.polyhedron
        return {
            poly.names[k]: (poly.names[r.face] if r is not None and r.kind == "face" else None)
            for k, r in enumerate(readings(poly))
        }

    @cached_property
    def markings(self) -> list:
        """Every text net and stl print, as :class:`diefab.dice.readings.Marking` (face, text, corner or edge)."""
        from diefab.dice.readings import markings

        signed = min(self.support) < 0
        return markings(self.polyhedron, self.values, {n: format_value(v, signed) for n, v in self.values.items()})

    @cached_property
    def label_of(self) -> dict[str, str]:
        """Face name -> text printed on it (faces without a label are absent).

        A face carries the value of the resting face that puts it on top;
        the template's ``labels`` table overrides or adds texts (an empty
        string removes one).
        """
        signed = min(self.support) < 0
        out: dict[str, str] = {}
        owner: dict[str, str] = {}
        for rest, up in self.label_face.items():
            if up is None or rest not in self.values:
                continue
            if up in owner and up not in self.labels:
                raise DesignError(
                    f"face {up} is on top both when resting on {owner[up]} and on {rest}: "
                    "set its text in the design's [labels] table"
                )
            owner[up] = rest
            out[up] = format_value(self.values[rest], signed)
        out.update(self.labels)
        return {k: out[k] for k in self.polyhedron.names if out.get(k)}

    def mass_properties(self, fill: Fill | None = None) -> MassProperties:
        """Mass properties in model units for the design's (or the given) fill, as made.

        A paper die includes the glue tabs of its net, a print its engraved
        labels (see :mod:`diefab.made.bodies`).  A non-convex ``mesh`` body's come
        from the mesh itself, a convex die's from its polyhedron; a stated ``center_of_mass`` and
        ``inertia`` replace the computed ones (whatever the fill).
        """
        fill = fill or self.fill
        mesh = self.body_mesh
        if mesh is not None and not self._mesh_is_convex:
            props = mesh_mass_properties(mesh, fill, mm_per_unit=self.mm_per_unit)
        else:
            labels = self.label_plan if fill.kind == "print" and fill.labels else None
            props = body_properties(self.polyhedron, fill, mm_per_unit=self.mm_per_unit, labels=labels)
        if self.center_of_mass is None and self.inertia is None:
            return props
        s = self._file_scale
        center = None if self.center_of_mass is None else np.array(self.center_of_mass) * s
        if center is not None:
            poly = self.polyhedron
            depth = poly.offsets - poly.normals @ center
            k = int(np.argmin(depth))
            if depth[k] <= 0:
                raise DesignError(
                    f"design {self.name!r}: center_of_mass {list(self.center_of_mass)} is not inside the die "
                    f"({-depth[k] * self.mm_per_unit:.3g} mm outside face {poly.names[k]})"
                )
        inertia = None if self.inertia is None else np.array(self.inertia) * s**2
        return stated(props, center, inertia)

    @cached_property
    def label_plan(self) -> LabelPlan:
        """What ``diefab net`` and ``diefab stl`` print on the faces (:class:`~diefab.made.placement.LabelPlan`)."""
        return LabelPlan(
            self.polyhedron,
            float(self.mm_per_unit),
            design_axis(self),
            dict(self.label_of),
            tuple(placed_marks(self)),
            frozenset(self.labels),
        )

    @cached_property
    def _mesh_is_convex(self) -> bool:
        return self.body_mesh is not None and self.body_mesh.is_convex()

    def margins(self, fill: Fill | None = None) -> np.ndarray:
        """(m,) float: stability margin of each face, model units."""
        return face_margins(self.polyhedron, self.mass_properties(fill).center)

    def check_stable(self, min_margin: float = 0.0, fill: Fill | None = None) -> None:
        """Raise :class:`DesignError` if the die cannot rest on a face with a value, or can on one without.

        Every face with a value needs a stability margin above `min_margin`;
        a transitional face must have none.
        """
        margins = self.margins(fill)
        resting = resting_faces(self.polyhedron, self.mass_properties(fill).center)
        mask = self.resting_mask()
        if len(self.values) < len(mask):
            self._check_transitional(fill)
        worst = np.where(mask, margins, np.inf)
        k = int(np.argmin(worst))
        if margins[k] <= min_margin or not resting[k]:
            raise DesignError(
                f"design {self.name!r} is unstable: the centre of mass projects "
                f"{'outside' if margins[k] < 0 else 'onto the edge of'} face {self.polyhedron.names[k]} "
                f"(margin {margins[k]:.4f}, need > {min_margin:g}); a face the die should roll off "
                "carries no value (list it in 'transitional')"
            )

    def with_params(self, **params: float) -> Design:
        """A copy with some parameters replaced."""
        return replace(self, params={**self.params, **params})

    def with_target(self, target: str) -> Design:
        return replace(self, target=target)


def reference_length(design: Design) -> tuple[float, str]:
    """The length ``size_mm`` measures, model units, and its name.

    >>> from diefab.dice.design import load_design
    >>> reference_length(load_design("d6"))
    (2.0, 'face to face')
    """
    if design.family == "gem":
        return 2.0, "girdle short side"
    fam = family(design.family)
    return fam.length(design.polyhedron), fam.reference_name(design.polyhedron)


def design_axis(design: Design) -> np.ndarray:
    """(3,) float: the die's up axis (+y for the gem family, +z otherwise)."""
    return np.array([0.0, 1.0, 0.0]) if design.family == "gem" else np.array([0.0, 0.0, 1.0])


def placed_marks(design: Design) -> list:
    """The values read at a corner or along an edge (:attr:`Design.markings` with a place), in order.

    Empty for a die that no convention reads (net and stl then print the
    face values alone, and :func:`reading_note` says what a point or an edge
    on top means).
    """
    try:
        return [m for m in design.markings if m.at]
    except DesignError:
        return []
