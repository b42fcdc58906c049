"""Label text as polygons: font outlines through matplotlib, geometry in shapely.

A label is turned into a shapely (Multi)Polygon whose *digit height* (the
height of the font's ``0``) is 1 and whose bounding box is centred on the
origin; the caller scales it to millimetres.  Glyph contours are flattened
with a fixed number of points per Bézier segment and nested by depth, so
counters (the holes of ``0``, ``4``, ``d``) are holes and islands inside
holes are filled again, whatever the font's contour orientation.

Two readability rules are applied to the text itself:

* a true minus sign (U+2212) is used when the font has one; otherwise the
  ASCII hyphen-minus, which is shorter and could read as a scratch, is drawn
  as a bar as wide as the font's ``+``;
* a label that reads as another label of the same die upside down (``6``
  and ``9`` on a d20, not ``16``, whose turned reading ``91`` is on no face)
  may get a mark: a bar under it (``mark="bar"``) or a period after it
  (``mark="period"``); the caller decides with :func:`ambiguous`.

Examples
--------
>>> font = load_font()
>>> zero = text_polygons("0", font)
>>> len(zero.interiors), round(zero.bounds[3] - zero.bounds[1], 3)
(1, 1.0)
>>> needs_underline("6"), needs_underline("+6"), needs_underline("8"), needs_underline("−3")
(True, True, False, False)
>>> ambiguous("6", ["6", "9"]), ambiguous("16", ["16", "19"]), ambiguous("6", ["1", "6"])
(True, False, False)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from diefab.core.errors import FabricationError

__all__ = [
    "MARKS",
    "Font",
    "ambiguous",
    "load_font",
    "needs_underline",
    "nest_rings",
    "stroke_width",
    "text_advance",
    "text_outline",
    "text_polygons",
    "thin_fraction",
]

MINUS = "\u2212"
#: Digits that rotate by 180 degrees into a digit.
_ROTATED = {"0": "0", "1": "1", "6": "9", "8": "8", "9": "6"}
#: Points per Bézier segment when flattening glyph outlines.
CURVE_STEPS = 8
#: How a label that reads as another one upside down is marked.
MARKS = ("bar", "period", "none")


@dataclass(frozen=True)
class Font:
    """A TrueType/OpenType font file that matplotlib can read."""

    path: Path

    @property
    def name(self) -> str:
        return self.path.name


def default_font_path(bold: bool = True) -> Path:
    """DejaVu Sans Bold (or Book), which ships with matplotlib (bold strokes print better)."""
    from matplotlib import font_manager

    prop = font_manager.FontProperties(family="DejaVu Sans", weight="bold" if bold else "normal")
    return Path(font_manager.findfont(prop, fallback_to_default=True))


def load_font(path: str | Path | None = None, *, bold: bool = True) -> Font:
    """Check that `path` (default: DejaVu Sans Bold, or Book if not `bold`) is a readable font.

    Raises
    ------
    FabricationError
        If the file does not exist or FreeType cannot read it.
    """
    font_path = default_font_path(bold) if path is None else Path(path)
    if not font_path.is_file():
        state = "is not a regular file" if font_path.exists() else "does not exist"
        raise FabricationError(f"font file {font_path} {state}")
    try:
        _ft2font(str(font_path))
    except Exception as exc:  # FreeType reports unreadable files as RuntimeError/OSError/ValueError
        raise FabricationError(f"font file {font_path} cannot be read as a font: {exc}") from exc
    return Font(font_path)


@lru_cache(maxsize=8)
def _ft2font(path: str):
    from matplotlib.ft2font import FT2Font

    return FT2Font(path)


def _has_glyph(font: Font, char: str) -> bool:
    return _ft2font(str(font.path)).get_char_index(ord(char)) != 0


def needs_underline(text: str) -> bool:
    """True if `text` rotated by 180 degrees reads as a different number."""
    digits = "".join(ch for ch in text if ch.isdigit())
    if not digits or any(ch not in _ROTATED for ch in digits):
        return False
    if any(not (ch.isdigit() or ch in "+-" + MINUS) for ch in text):
        return False
    return "".join(_ROTATED[ch] for ch in reversed(digits)) != digits


def turned(text: str) -> str | None:
    """`text` as it reads turned by 180 degrees, or None if it does not read as a label then."""
    if not text or not all(ch in _ROTATED for ch in text):
        return None
    return "".join(_ROTATED[ch] for ch in reversed(text))


def ambiguous(text: str, others) -> bool:
    """True if `text` turned by 180 degrees reads as a different label among `others`.

    A "6" needs a mark on a die that also carries a "9", not on a d6; a "16"
    needs none on a d20, since no face reads "91".
    """
    other = turned(text)
    return other is not None and other != text and other in set(others)


def _flatten(path) -> list[np.ndarray]:
    """Closed rings of a matplotlib path, Bézier segments sampled at CURVE_STEPS points."""
    from matplotlib.path import Path as MplPath

    rings: list[np.ndarray] = []
    current: list[np.ndarray] = []
    t = np.linspace(0, 1, CURVE_STEPS + 1)[1:]
    for bezier, code in path.iter_bezier():
        if code == MplPath.MOVETO:
            if len(current) >= 3:
                rings.append(np.array(current))
            current = [bezier.control_points[0]]
        elif code == MplPath.LINETO:
            current.append(bezier.control_points[-1])
        elif code == MplPath.CLOSEPOLY:
            current.append(bezier.control_points[-1])
            if len(current) >= 3:
                rings.append(np.array(current))
            current = []
        else:  # CURVE3 / CURVE4
            current.extend(bezier(t))
    if len(current) >= 3:
        rings.append(np.array(current))
    return rings


def nest_rings(rings: list[np.ndarray]):
    """Closed rings (each (k, 2)) nested even-odd into one shapely geometry, whatever their orientation."""
    return _nest(rings)


def _nest(rings: list[np.ndarray]):
    """Even-odd nesting of closed rings into a shapely geometry."""
    from shapely import make_valid
    from shapely.geometry import Polygon
    from shapely.ops import unary_union

    polys = []
    for ring in rings:
        poly = Polygon(ring)
        if not poly.is_valid:
            poly = make_valid(poly)
        if poly.area > 0:
            polys.append(poly)
    probes = [p.representative_point() for p in polys]
    bounds = [p.bounds for p in polys]

    def inside(j: int, i: int) -> bool:  # ring j within ring i (bounding boxes first: text has many rings)
        x, y = probes[j].x, probes[j].y
        b = bounds[i]
        return b[0] <= x <= b[2] and b[1] <= y <= b[3] and polys[i].contains(probes[j])

    depth = [
        sum(1 for j, q in enumerate(polys) if j != i and q.area > p.area and inside(i, j)) for i, p in enumerate(polys)
    ]
    filled = []
    for i, p in enumerate(polys):
        if depth[i] % 2:
            continue
        children = [q for j, q in enumerate(polys) if depth[j] == depth[i] + 1 and inside(j, i)]
        filled.append(p.difference(unary_union(children)) if children else p)
    return unary_union(filled)


@lru_cache(maxsize=256)
def _raw_text(text: str, font_path: str):
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextPath

    prop = FontProperties(fname=font_path)
    return _nest(_flatten(TextPath((0, 0), text, size=1.0, prop=prop)))


def text_polygons(text: str, font: Font | None = None, mark: str = "none"):
    """The outline of `text` as a shapely geometry, digit height 1, bbox centred on the origin.

    Parameters
    ----------
    text : str
        The label; ``-`` and U+2212 both give a minus sign.
    font : Font, optional
        Default :func:`load_font`.
    mark : {"none", "bar", "period"}
        A bar under the text or a period after it (part of the outline, so
        fitting the label counts it).

    Returns
    -------
    shapely Polygon or MultiPolygon
        Units of the font's digit height.

    Raises
    ------
    FabricationError
        If the text is empty or the font lacks a character.
    """
    from shapely import affinity
    from shapely.geometry import box
    from shapely.ops import unary_union

    font = font or load_font()
    if not text.strip():
        raise FabricationError("label text is empty")
    if _has_glyph(font, MINUS):
        text, hyphen_as_bar = text.replace("-", MINUS), False
    else:
        text = text.replace(MINUS, "-")
        hyphen_as_bar = "-" in text
    for ch in text:
        if not ch.isspace() and not _has_glyph(font, ch):
            raise FabricationError(f"font {font.name} has no glyph for {ch!r} (U+{ord(ch):04X}) in label {text!r}")
    path = str(font.path)
    digit = _raw_text("0", path).bounds
    unit = digit[3] - digit[1]  # digit height in em
    geom = _raw_text(text, path)
    if hyphen_as_bar:
        geom = _widen_hyphens(geom, text, path)
    geom = affinity.scale(geom, 1 / unit, 1 / unit, origin=(0, 0))
    if mark not in MARKS:
        raise FabricationError(f"mark {mark!r} is not one of {', '.join(MARKS)}")
    if mark != "none":
        x0, y0, x1, _ = geom.bounds
        bar = stroke_width(geom)
        if mark == "bar":
            geom = unary_union([geom, box(x0, y0 - 2.2 * bar, x1, y0 - 1.2 * bar)])
        else:
            dot = 1.4 * bar
            geom = unary_union([geom, box(x1 + 0.6 * bar, y0, x1 + 0.6 * bar + dot, y0 + dot)])
    x0, y0, x1, y1 = geom.bounds
    return affinity.translate(geom, -(x0 + x1) / 2, -(y0 + y1) / 2)


def text_outline(text: str, font: Font | None = None):
    """The outline of `text` at font size 1 (em): baseline on y = 0, starting at x = 0, y up.

    For running text (a page's footer, edge letters); labels on faces use
    :func:`text_polygons`.  Returns None for blank text.
    """
    font = font or load_font()
    if not text.strip():
        return None
    for ch in text:
        if not ch.isspace() and not _has_glyph(font, ch):
            raise FabricationError(f"font {font.name} has no glyph for {ch!r} (U+{ord(ch):04X}) in {text!r}")
    return _raw_text(text, str(font.path))


@lru_cache(maxsize=1024)
def text_advance(text: str, font: Font | None = None) -> float:
    """Width of `text` at font size 1 (em), from the glyph outlines' extent (no polygons built)."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextPath

    font = font or load_font()
    if not text.strip():
        return 0.0
    path = TextPath((0, 0), text, size=1.0, prop=FontProperties(fname=str(font.path)))
    return float(path.vertices[:, 0].max()) if len(path.vertices) else 0.0


def _widen_hyphens(geom, text: str, path: str):
    """Replace each hyphen's short dash by a bar as wide as the font's ``+`` (fonts without U+2212)."""
    from shapely.geometry import box
    from shapely.ops import unary_union

    plus = _raw_text("+", path).bounds
    parts = list(getattr(geom, "geoms", [geom]))
    out = []
    for part in parts:
        x0, y0, x1, y1 = part.bounds
        is_dash = part.area > 0.9 * (x1 - x0) * (y1 - y0) and (x1 - x0) > 1.5 * (y1 - y0)
        if is_dash and "-" in text:
            cx = (x0 + x1) / 2
            half = (plus[2] - plus[0]) / 2
            out.append(box(cx - half, y0, cx + half, y1))
        else:
            out.append(part)
    return unary_union(out)


def stroke_width(geom) -> float:
    """Mean stroke width of a text outline: 2 area / perimeter.

    Exact for long strokes of constant width (a stroke of length L and width
    w has area L w and perimeter about 2 L); stroke ends make it a slight
    underestimate, which errs on the safe side for a printability warning.
    """
    perimeter = geom.length
    return 0.0 if perimeter == 0 else 2 * geom.area / perimeter


def thin_fraction(geom, width: float) -> float:
    """Fraction of the area of `geom` lying in parts thinner than `width`.

    The morphological opening (erode by width/2, dilate back) keeps exactly the
    parts a disc of diameter `width` can sweep; what it drops is thinner.
    """
    if geom.area == 0:
        return 0.0
    opened = geom.buffer(-width / 2, quad_segs=4).buffer(width / 2, quad_segs=4)
    return float(max(0.0, 1 - opened.area / geom.area))
