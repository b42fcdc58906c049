"""What a die is made of: solid, shell, card or a fused-filament print, and what is glued or cut into it.

:class:`Fill` is the material and how it is laid down; :class:`TabShape` a
paper die's glue tab on one of its edges; :class:`LabelMass` a print's
engraved or embossed label on one of its faces.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Literal

import numpy as np

from diefab.core.errors import DesignError

__all__ = [
    "CARD_DENSITY",
    "KINDS",
    "LABEL_DEPTH_MM",
    "LINE_WIDTH_FACTOR",
    "MIN_LAYER_MM",
    "TAB_MAX_FRACTION",
    "TAB_TOP_FRACTION",
    "Fill",
    "LabelMass",
    "TabShape",
]

#: Density of card, g/cm³: the thickness of a card is its grammage over this (160 g/m² -> 0.2 mm).
CARD_DENSITY = 0.8
#: Extrusion width of a line as a multiple of the nozzle diameter (PrusaSlicer's automatic width).
LINE_WIDTH_FACTOR = 1.125
#: Thinnest print layer (and nozzle), mm: the modelled layers are counted, so memory grows as 1 / layer.
MIN_LAYER_MM = 0.01
#: Engraving depth of the labels in the print model of a design, mm (``diefab stl``'s default).
LABEL_DEPTH_MM = 0.6
#: A tab is never wider than this fraction of its edge ("about half the edge").
TAB_MAX_FRACTION = 0.45
#: The tab's outer side keeps at least this fraction of the edge length.
TAB_TOP_FRACTION = 0.1

KINDS = ("solid", "shell", "paper", "print")


def _number(name: str, value, lo: float, hi: float, unit: str, *, lo_open: bool = True, integer: bool = False):
    """Check one Fill field: a real number (not a bool or a string) in its range."""
    kind = "an integer" if integer else "a number"
    unit = f" {unit}" if unit else ""
    ok_type = isinstance(value, (int, np.integer)) if integer else isinstance(value, (int, float, np.number))
    if isinstance(value, (bool, np.bool_)) or not ok_type:
        raise DesignError(f"fill {name}={value!r} must be {kind} in {'(' if lo_open else '['}{lo:g}, {hi:g}]{unit}")
    if not (math.isfinite(value) and (value > lo if lo_open else value >= lo) and value <= hi):
        raise DesignError(f"fill {name}={value!r} is outside {'(' if lo_open else '['}{lo:g}, {hi:g}]{unit}")


@dataclass(frozen=True)
class Fill:
    """How the die is made.

    Parameters
    ----------
    kind : {"solid", "shell", "paper", "print"}
    card_g_m2 : float
        Paper: grammage of the card, g/m² (0, 1000].
    card_mm : float, optional
        Paper: card thickness, mm (0, 2]; default ``card_g_m2 / 800``
        (card of density 0.8 g/cm³).
    tabs : bool
        Paper: include the glue tabs of the die's net.
    tab_mm : float
        Paper: glue-tab width before narrowing, mm (the net's ``--tab-width``).
    glue_g_m2 : float
        Paper: dry glue on every tab, g/m² [0, 500].
    nozzle_mm : float
        Print: nozzle diameter, mm (0, 2]; lines are 1.125 of it wide.
    perimeters : int
        Print: perimeters (wall lines) along the sides, [1, 20].
    layer_mm : float
        Print: layer height, mm, (0, nozzle_mm].
    top_layers, bottom_layers : int
        Print: solid layers under every upward face and above every downward
        one (the bed face included), [0, 50].
    infill : float
        Print: fraction of the inside that is material, [0, 1].
    wall_mm : float, optional
        Print: side-wall thickness, mm, overriding ``perimeters`` lines
        (default: perimeters x line spacing).
    solid_below_mm2 : float
        Print: a layer whose infill region is smaller than this (mm²) is
        filled solid, [0, 10000] (PrusaSlicer's ``solid_infill_below_area``).
    skin_margin_mm : float
        Print: how far the solid layers next to an engraving reach into the
        infill beyond the text, mm, [0, 50] (PrusaSlicer widens top and
        bottom surfaces by 3 mm).
    labels : bool
        Print: include the engraved labels in a design's body.
    """

    kind: Literal["solid", "shell", "paper", "print"] = "solid"
    card_g_m2: float = 160.0
    card_mm: float | None = None
    tabs: bool = True
    tab_mm: float = 5.0
    glue_g_m2: float = 0.0
    nozzle_mm: float = 0.4
    perimeters: int = 2
    layer_mm: float = 0.2
    top_layers: int = 4
    bottom_layers: int = 4
    infill: float = 0.15
    wall_mm: float | None = None
    solid_below_mm2: float = 70.0
    skin_margin_mm: float = 3.0
    labels: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.kind, str) or self.kind not in KINDS:
            raise DesignError(f"fill kind={self.kind!r} is not one of {', '.join(KINDS)}")
        _number("card_g_m2", self.card_g_m2, 0, 1000, "g/m²")
        if self.card_mm is not None:
            _number("card_mm", self.card_mm, 0, 2, "mm")
        for name in ("tabs", "labels"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise DesignError(f"fill {name}={getattr(self, name)!r} must be true or false")
        _number("tab_mm", self.tab_mm, 0, 50, "mm", lo_open=False)
        _number("glue_g_m2", self.glue_g_m2, 0, 500, "g/m²", lo_open=False)
        _number("nozzle_mm", self.nozzle_mm, MIN_LAYER_MM, 2, "mm", lo_open=False)
        _number("perimeters", self.perimeters, 1, 20, "", lo_open=False, integer=True)
        _number("layer_mm", self.layer_mm, MIN_LAYER_MM, self.nozzle_mm, "mm (at most the nozzle)", lo_open=False)
        _number("top_layers", self.top_layers, 0, 50, "", lo_open=False, integer=True)
        _number("bottom_layers", self.bottom_layers, 0, 50, "", lo_open=False, integer=True)
        _number("infill", self.infill, 0, 1, "", lo_open=False)
        if self.wall_mm is not None:
            _number("wall_mm", self.wall_mm, 0, 50, "mm")
        _number("solid_below_mm2", self.solid_below_mm2, 0, 10000, "mm²", lo_open=False)
        _number("skin_margin_mm", self.skin_margin_mm, 0, 50, "mm", lo_open=False)

    @classmethod
    def from_mapping(cls, data, source: str = "[fill]") -> Fill:
        """A fill from a design's ``[fill]`` table; unknown keys are errors."""
        if not isinstance(data, dict):
            raise DesignError(f"{source} must be a table, got {data!r}")
        known = [f.name for f in fields(cls)]
        unknown = sorted(set(data) - set(known))
        if unknown:
            raise DesignError(f"{source}: unknown key {unknown[0]!r} (keys: {', '.join(known)})")
        return cls(**data)

    def to_mapping(self) -> dict:
        """The fields that matter for this kind, TOML-ready (unset optional fields left out)."""
        keys = {
            "solid": (),
            "shell": (),
            "paper": ("card_g_m2", "card_mm", "tabs", "tab_mm", "glue_g_m2"),
            "print": ("nozzle_mm", "perimeters", "layer_mm", "top_layers", "bottom_layers", "infill", "wall_mm",
                      "solid_below_mm2", "skin_margin_mm", "labels"),
        }[self.kind]  # fmt: skip
        return {"kind": self.kind, **{k: getattr(self, k) for k in keys if getattr(self, k) is not None}}

    @property
    def card_thickness_mm(self) -> float:
        """Thickness of the card, mm."""
        return self.card_mm if self.card_mm is not None else self.card_g_m2 / (1000 * CARD_DENSITY)

    @property
    def line_spacing_mm(self) -> float:
        """Distance between neighbouring perimeter lines, mm: width - layer x (1 - pi/4) (rounded-edge lines)."""
        return LINE_WIDTH_FACTOR * self.nozzle_mm - self.layer_mm * (1 - math.pi / 4)

    @property
    def wall_thickness_mm(self) -> float:
        """Side-wall thickness of a print, mm (the material of `perimeters` lines)."""
        return self.wall_mm if self.wall_mm is not None else self.perimeters * self.line_spacing_mm

    def describe(self) -> str:
        """One line: the settings of this kind."""
        if self.kind == "paper":
            tabs = f"glue tabs {self.tab_mm:g} mm" if self.tabs else "no tabs"
            glue = f", glue {self.glue_g_m2:g} g/m²" if self.glue_g_m2 else ""
            return f"paper {self.card_g_m2:g} g/m² card {self.card_thickness_mm:.2f} mm, {tabs}{glue}"
        if self.kind == "print":
            walls = f"{self.wall_mm:g} mm walls" if self.wall_mm is not None else f"{self.perimeters} perimeters"
            return (
                f"print {self.nozzle_mm:g} mm nozzle, {walls}, {self.layer_mm:g} mm layers, "
                f"{self.top_layers}/{self.bottom_layers} top/bottom layers, {self.infill:.0%} infill"
            )
        return self.kind


@dataclass(frozen=True)
class TabShape:
    """One glue tab of a paper net, in terms of the die's edge it glues.

    The tab hangs off the edge from vertex `a` to vertex `b` (in that order
    around the face it is printed on) and, folded in, lies flat on the inside
    of face `glued`: a trapezoid `width_mm` deep whose far side starts
    ``lean_a * width_mm`` from `a` and ends ``lean_b * width_mm`` before `b`.
    Taken from a laid-out net (:func:`diefab.made.unfold.net_tab_shapes`), it can
    be put on any die of the same combinatorics; a shorter edge narrows it by
    the net's own rule.
    """

    a: int
    b: int
    glued: int
    width_mm: float
    lean_a: float
    lean_b: float


@dataclass(frozen=True)
class LabelMass:
    """The material a label takes away (engraved) or adds (embossed), as a thin prism.

    area_mm2 : text area; centroid_mm : (3,) its centroid on the face;
    normal : (3,) the face's outward normal; face : index of the face;
    depth_mm : engraving depth or embossing height.  Optionally the text's
    outline (shapely, face coordinates x along `baseline`, y along `up`,
    from `origin_mm`), which gives the footprint of the walls that follow
    the engraving; without it they follow the text's own area.
    """

    face: int
    area_mm2: float
    centroid_mm: np.ndarray
    normal: np.ndarray
    depth_mm: float
    emboss: bool = False
    outline: object = None
    origin_mm: np.ndarray | None = None
    baseline: np.ndarray | None = None
    up: np.ndarray | None = None

    def footprint(self, grow_mm: float) -> tuple[float, np.ndarray]:
        """Area (mm²) and centroid (mm, on the face) of the text grown by `grow_mm`."""
        if self.outline is None or grow_mm <= 0:
            return self.area_mm2, np.asarray(self.centroid_mm, dtype=float)
        grown = self.outline.buffer(grow_mm)
        c = grown.centroid
        return float(grown.area), self.origin_mm + c.x * self.baseline + c.y * self.up
