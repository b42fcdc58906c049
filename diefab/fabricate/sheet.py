"""What goes on each printed page of a net: shapes, lines and text outlines, in mm.

:func:`layout_sheets` turns one or more copies of a
:class:`~diefab.made.unfold.Net` into one :class:`Sheet` per page; the
SVG and PDF renderers draw the same sheets, so both outputs carry the same
labels in the same places.  Every piece of text is a shapely outline of the
real font (:mod:`.text`), so what is measured is what is printed, and an SVG
needs no font installed.

* **Value labels** sit in each face's die frame (:mod:`.labels`): upright
  when the folded die is held axis vertical, exactly as on the printed die,
  all at one height (the smallest that fits every value face), a mark only
  where a label reads as another label upside down.
* **Edge letters** run along their edge, inside the face, foot towards the
  face's middle; the matching tab carries the same letter.
* **Footer**: title and size, how to read the die, the line legend, "page
  n/N" and a 10 mm calibration bar, wrapped to the page's width so it
  never overlaps or runs off the page.

All coordinates are page millimetres with y pointing down.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from diefab.made.labels import MARK_FRACTION, face_frame, fit_label, label_shape, mark_frame
from diefab.made.text import Font, load_font, text_advance, text_outline
from diefab.made.unfold import Net

__all__ = ["FooterPlan", "Sheet", "Text", "layout_sheets", "plan_footer"]

#: Largest value-label height (digit height), mm.
MAX_FACE_TEXT = 14.0
#: Edge and tab letters: cap height, mm (less on short edges).
EDGE_TEXT = 2.2
#: Footer font size (em), mm, and the distance between its rows.
INFO_TEXT = 3.0
ROW = 4.4
#: Free border between a face's edge and its label, mm.
FACE_MARGIN = 1.0
#: Smallest label printed on paper (cap height), mm: a label that fits only smaller is refused, never left out.
MIN_FACE_TEXT = 0.5
#: A value label is at most this fraction of the diameter of the face's inscribed circle high
#: (about what commercial dice print: a 16 mm d6 carries 8 mm numbers).
FACE_TEXT_FRACTION = 0.5
#: Clearance around edge letters, mm.
LETTER_CLEARANCE = 0.6
#: Edge letters are at most this fraction of the face's inscribed radius high, so small faces keep room.
LETTER_FRACTION = 0.25
#: Width reserved at the footer's right for "page n/N" and the calibration bar, mm.
RIGHT_COLUMN = 22.0
#: Where an edge letter may sit along its edge (fraction from its start): the middle, else beside a marker.
LETTER_SPOTS = (0.5, 0.38, 0.62, 0.29, 0.71, 0.2, 0.8)
#: Face-name height as a fraction of the value height.
NAME_RATIO = 0.3
_LEGEND = (
    ("cut", "cut"),
    ("score", "score, fold away from you"),
    ("swatch", "glue tab: goes under the edge with its letter"),
)


@dataclass(frozen=True, eq=False)
class Text:
    """A piece of text as drawn: its outline in page mm (y down).

    kind : face, corner (a value read at a corner), along-edge (one read along an edge), name, edge (an edge
    letter), tab or info.  height : digit/cap height, mm.
    """

    text: str
    kind: str
    shape: Any
    face: str = ""
    height: float = 0.0


@dataclass
class Sheet:
    """One page: width, height (mm) and what is drawn on it."""

    width: float
    height: float
    number: int
    pages: int
    faces: list[tuple[str, np.ndarray]] = field(default_factory=list)
    tabs: list[tuple[str, np.ndarray]] = field(default_factory=list)
    cut: list[np.ndarray] = field(default_factory=list)  # one closed ring (k, 2) per piece
    score: list[np.ndarray] = field(default_factory=list)  # (2, 2) segments
    texts: list[Text] = field(default_factory=list)
    legend: list[tuple[str, np.ndarray]] = field(default_factory=list)  # (style, points): cut/score/bar/swatch


# ----------------------------------------------------------------------
# placing outlines


def _em_width(text: str, font: Font) -> float:
    return text_advance(text, font)


def _running(text: str, x: float, baseline: float, size: float, font: Font):
    """`text` at font size `size` (mm), starting at x with its baseline at `baseline` (page, y down)."""
    from shapely import affinity

    shape = text_outline(text, font)
    return None if shape is None else affinity.affine_transform(shape, [size, 0, 0, -size, x, baseline])


def _framed(shape, origin, x_axis, y_axis):
    """`shape` (frame coordinates, y up) drawn with its x along `x_axis` and y along `y_axis` (page vectors)."""
    from shapely import affinity

    return affinity.affine_transform(
        shape, [x_axis[0], y_axis[0], x_axis[1], y_axis[1], float(origin[0]), float(origin[1])]
    )


def _unframed(shape, origin, x_axis, y_axis):
    """Inverse of :func:`_framed`."""
    from shapely import affinity

    inv = np.linalg.inv(np.column_stack([x_axis, y_axis]))
    off = -inv @ np.asarray(origin, dtype=float)
    return affinity.affine_transform(shape, [inv[0, 0], inv[0, 1], inv[1, 0], inv[1, 1], off[0], off[1]])


def _scaled(shape, height, cx, cy):
    from shapely import affinity

    return affinity.translate(affinity.scale(shape, height, height, origin=(0, 0)), cx, cy)


def _letter(text: str, font: Font):
    """A letter outline at cap height 1, its box centred on the origin."""
    from shapely import affinity

    shape = text_outline(text, font)
    cap = text_outline("H", font).bounds
    x0, y0, x1, y1 = shape.bounds
    s = 1 / (cap[3] - cap[1])
    return affinity.scale(affinity.translate(shape, -(x0 + x1) / 2, -(y0 + y1) / 2), s, s, origin=(0, 0))


def _edge_axes(p, q, inward):
    """Frame of a letter along edge p->q: x along the edge, y (up) away from `inward`, not mirrored."""
    d = (q - p) / np.linalg.norm(q - p)
    up = np.array([-d[1], d[0]])
    if up @ inward > 0:
        up = -up
    # page y points down: an unmirrored frame has a negative determinant there
    if d[0] * up[1] - d[1] * up[0] > 0:
        d = -d
    return d, up


# ----------------------------------------------------------------------
# footer


@dataclass(frozen=True)
class FooterPlan:
    """Rows of the footer: each a list of (kind, x, payload); kind text/legend, x from the left margin."""

    rows: tuple[tuple[tuple[str, float, str], ...], ...]

    @property
    def height(self) -> float:
        return max(3, len(self.rows)) * ROW + 1.0


def _wrap(text: str, width: float, size: float, font: Font) -> list[str]:
    lines: list[str] = []
    for word in text.split():
        if lines and _em_width(f"{lines[-1]} {word}", font) * size <= width:
            lines[-1] = f"{lines[-1]} {word}"
        else:
            lines.append(word)
    return lines


def plan_footer(width: float, margin: float, title: str, note: str, font: Font | None = None) -> FooterPlan:
    """Lay out the footer for a page `width` mm wide: title and note wrapped, legend items flowed."""
    font = font or load_font(bold=False)
    room = width - 2 * margin - RIGHT_COLUMN - 2.0
    small = INFO_TEXT * 0.85
    rows: list[list[tuple[str, float, str]]] = [[("text", 0.0, line)] for line in _wrap(title, room, INFO_TEXT, font)]
    rows += [[("note", 0.0, line)] for line in _wrap(note[:1].upper() + note[1:] + ".", room, small, font)]
    x, current = 0.0, []
    for style, words in _LEGEND:
        sample = 6.0 if style == "swatch" else 10.0
        item = sample + 1.5 + _em_width(words, font) * small
        if current and x + item > room:
            rows.append(current)
            x, current = 0.0, []
        current.append((style, x, words))
        x += item + 4.0
    rows.append(current)
    return FooterPlan(tuple(tuple(r) for r in rows))


def _draw_footer(sheet: Sheet, plan: FooterPlan, page, font: Font) -> None:
    from shapely.geometry import box

    top = page.height - page.margin - plan.height + 1.0
    left, right = page.margin, page.width - page.margin
    small = INFO_TEXT * 0.85
    for r, row in enumerate(plan.rows):
        base = top + (r + 1) * ROW - 1.0
        mid = base - 0.35 * INFO_TEXT * 0.85
        for kind, x, payload in row:
            x += left
            if kind in ("text", "note"):
                size = INFO_TEXT if kind == "text" else small
                sheet.texts.append(Text(payload, "info", _running(payload, x, base, size, font)))
                continue
            sample = 6.0 if kind == "swatch" else 10.0
            if kind == "swatch":
                sheet.legend.append(("swatch", np.array(box(x, mid - 1.5, x + sample, mid + 1.5).exterior.coords)[:-1]))
            else:
                sheet.legend.append((kind, np.array([[x, mid], [x + sample, mid]])))
            sheet.texts.append(Text(payload, "info", _running(payload, x + sample + 1.5, base, small, font)))
    page_text = f"page {sheet.number}/{sheet.pages}"
    w = _em_width(page_text, font) * INFO_TEXT
    sheet.texts.append(Text(page_text, "info", _running(page_text, right - w, top + ROW - 1.0, INFO_TEXT, font)))
    w = _em_width("10 mm", font) * small
    sheet.texts.append(Text("10 mm", "info", _running("10 mm", right - 5 - w / 2, top + 2 * ROW - 1.0, small, font)))
    y = top + 2 * ROW + 1.0
    sheet.legend.append(("bar", np.array([[right - 10, y], [right, y]])))


# ----------------------------------------------------------------------
# the die's texts, on the first copy


def check_text_fits(text: str, face: str, height: float) -> None:
    """Refuse a label that fits `face` only below :data:`MIN_FACE_TEXT` high (`height`, mm)."""
    from diefab.core.errors import FabricationError

    if not height > MIN_FACE_TEXT:
        raise FabricationError(
            f"label {text!r} does not fit on face {face}: at most {max(height, 0.0):.2f} mm high, below the "
            f"smallest printed text {MIN_FACE_TEXT:g} mm (use a larger --size or a shorter label)"
        )


def _face_map(net: Net, k: int, axis: np.ndarray):
    """Origin and page images of the face's die frame (u, v) for face k of `net`."""
    poly = net.poly
    ring = poly.vertices[poly.faces[k]] * net.mm_per_unit
    u, v = face_frame(ring, poly.normals[k], axis)
    local = np.column_stack([(ring - ring[0]) @ u, (ring - ring[0]) @ v])
    page = net.faces[k]
    m, *_ = np.linalg.lstsq(local, page - page[0], rcond=None)
    return page[0], m[0], m[1]


def _edge_letter(shape, size, p, q, d, up, face, clear, others=None):
    """`shape` at `size` along edge p->q inside `face`, clear of `clear` and `others` (shapely or None).

    The middle of the edge; on a face with a marker (`clear`: its quiet
    zone), the free spot farthest from the room the marker leaves for the
    value label.
    """
    from shapely.ops import polylabel

    half = (shape.bounds[3] - shape.bounds[1]) * size / 2
    spots = []
    for t in LETTER_SPOTS:
        placed = _framed(_scaled(shape, size, 0, 0), p + t * (q - p) - up * (half + 0.4), d, up)
        if face.buffer(-0.2).contains(placed) and not any(
            z is not None and placed.intersects(z) for z in (clear, others)
        ):
            if clear is None:
                return placed
            spots.append(placed)
    if not spots:
        return None
    room = face.buffer(-FACE_MARGIN, join_style="mitre").difference(clear)
    if room.geom_type != "Polygon":
        room = max(getattr(room, "geoms", [room]), key=lambda g: g.area)
    if room.is_empty:
        return spots[0]
    middle = polylabel(room, 0.05)
    return max(spots, key=lambda placed: placed.distance(middle))


def _die_texts(net: Net, labels: dict[str, str], axis, *, face_names, mark, pips, values, font, bold, marks=(),
               markers=()):  # fmt: skip
    """Texts of one copy: markers, edge and tab letters, values at corners and edges, face labels (page mm)."""
    from shapely.geometry import Polygon
    from shapely.ops import polylabel, unary_union

    poly = net.poly
    names = poly.names
    tab_of: dict[int, list] = {}
    for t in net.tabs:
        tab_of.setdefault(t.edge, []).append(t)
    folds = set(int(e) for e in net.fold_edges)
    out: list[Text] = []
    occupied: dict[int, list] = {k: [] for k in range(len(net.faces))}
    clear: dict[int, Any] = {}
    for m in markers:  # each marker and its quiet zone first: letters and labels keep out of them
        k = poly.face_index(m.face)
        out.append(Text(f"marker {m.marker_id}", "marker", m.outline, m.face, m.side_mm))
        occupied[k].append(m.keep_clear())
        clear[k] = m.keep_clear() if k not in clear else clear[k].union(m.keep_clear())
    corner_zones: dict[int, list] = {}
    for m in marks if markers else ():
        k = poly.face_index(m.face)
        ring = list(poly.faces[k])
        zone = mark_frame(net.faces[k], tuple(ring.index(v) for v in m.at), y_down=True)[0]
        corner_zones.setdefault(k, []).append(zone)
    for k, ring in enumerate(net.faces):
        face = Polygon(ring)
        centre = np.asarray(face.centroid.coords[0])
        inradius = face.exterior.distance(polylabel(face, 0.01))
        for i, e in enumerate(net.face_edges(k)):
            if e in folds or any(t.face == k for t in tab_of.get(e, [])):
                continue
            p, q = ring[i], ring[(i + 1) % len(ring)]
            length = float(np.hypot(*(q - p)))
            size = min(EDGE_TEXT, 0.25 * length, LETTER_FRACTION * inradius)
            letter = net.edge_labels[e]
            d, up = _edge_axes(p, q, centre - (p + q) / 2)
            others = None
            if k in clear:  # a letter slid along its edge keeps off the other letters and the values in corners
                others = unary_union([*occupied[k], *corner_zones.get(k, [])])
            placed = _edge_letter(_letter(letter, font), size, p, q, d, up, face, clear.get(k), others)
            if placed is not None:
                out.append(Text(letter, "edge", placed, names[k], size))
                occupied[k].append(placed.buffer(LETTER_CLEARANCE))
    for t in net.tabs:
        p, q = t.polygon[0], t.polygon[1]
        tab = Polygon(t.polygon)
        d, up = _edge_axes(p, q, (p + q) / 2 - np.asarray(tab.centroid.coords[0]))
        up = -up  # the letter's foot is on the fold, so it reads from the face it glues under
        if d[0] * up[1] - d[1] * up[0] > 0:
            d = -d
        region = _unframed(tab.buffer(-0.3), (p + q) / 2, d, up)
        size, cx, cy = fit_label(region, _letter(t.label, font), EDGE_TEXT)
        if size > 0.5:
            shape = _framed(_scaled(_letter(t.label, font), size, cx, cy), (p + q) / 2, d, up)
            out.append(Text(t.label, "tab", shape, names[t.face], size))

    # values read at a corner or along an edge, in their corner of each face; the face labels keep clear of them
    for m in marks:
        k = poly.face_index(m.face)
        ring = list(poly.faces[k])
        zone, origin, xa, ya = mark_frame(net.faces[k], tuple(ring.index(v) for v in m.at), y_down=True)
        whole = Polygon(net.faces[k])
        region = zone.intersection(whole.buffer(-FACE_MARGIN, join_style="mitre"))
        shape = label_shape(m.text, bold, others=labels.values(), mark=mark, pips=pips)
        cap = MARK_FRACTION * 2 * whole.exterior.distance(polylabel(whole, 0.01))
        height, cx, cy = fit_label(_unframed(region, origin, xa, ya), shape, cap)
        if height > 0.5:
            placed = _framed(_scaled(shape, height, cx, cy), origin, xa, ya)
            out.append(Text(m.text, "corner" if len(m.at) == 1 else "along-edge", placed, m.face, height))
            occupied[k].append(placed.buffer(LETTER_CLEARANCE))

    # face labels: fit each, then one height for all value labels
    fits = {}
    for k, name in enumerate(names):
        text = labels.get(name, "")
        if not text and not face_names:
            continue
        origin, xa, ya = _face_map(net, k, axis)
        whole = Polygon(net.faces[k])
        largest = min(MAX_FACE_TEXT, 2 * FACE_TEXT_FRACTION * whole.exterior.distance(polylabel(whole, 0.01)))
        region = _unframed(Polygon(net.faces[k]).buffer(-FACE_MARGIN, join_style="mitre"), origin, xa, ya)
        for box in occupied[k]:
            region = region.difference(_unframed(box, origin, xa, ya))
        if text:
            shape = label_shape(text, bold, others=labels.values(), mark=mark, pips=pips)
            fits[name] = (text, shape, region, (origin, xa, ya), fit_label(region, shape, largest))
        else:
            fits[name] = (name, None, region, (origin, xa, ya), None)
    for name, (text, shape, *_, fit) in fits.items():
        if shape is not None:
            check_text_fits(text, name, fit[0])
    value_heights = [f[4][0] for n, f in fits.items() if f[1] is not None and n in values]
    common = min(value_heights) if value_heights else math.inf
    for name, (text, shape, region, frame, fit) in fits.items():
        used = None
        if shape is not None:
            height, cx, cy = fit
            if name in values:
                height = min(height, common)
            used = _scaled(shape, height, cx, cy)
            out.append(Text(text, "face", _framed(used, *frame), name, height))
        if face_names:
            small = _letter(name, font)
            rest = region if used is None else region.difference(used.buffer(0.6))
            cap = MAX_FACE_TEXT if used is None else max(1.2, NAME_RATIO * out[-1].height)
            h, cx, cy = fit_label(rest, small, cap)
            if h > 0.6:
                out.append(Text(name, "name", _framed(_scaled(small, h, cx, cy), *frame), name, h))
    return out


def _cut_rings(net: Net) -> list[tuple[int, np.ndarray]]:
    """One closed cut outline per piece: (page, (k, 2) ring)."""
    from scipy.spatial import cKDTree

    segs: dict[int, list[np.ndarray]] = {}
    tab_at = {(t.edge, t.face) for t in net.tabs}
    folds = set(int(e) for e in net.fold_edges)
    for k, ring in enumerate(net.faces):
        for i, e in enumerate(net.face_edges(k)):
            if e not in folds and (e, k) not in tab_at:
                segs.setdefault(int(net.face_piece[k]), []).append(np.array([ring[i], ring[(i + 1) % len(ring)]]))
    for t in net.tabs:
        p = t.polygon
        for a, b in ((1, 2), (2, 3), (3, 0)):
            segs.setdefault(int(net.face_piece[t.face]), []).append(np.array([p[a], p[b]]))
    out = []
    for piece, items in sorted(segs.items()):
        pts = np.concatenate(items)
        ids = np.arange(len(pts))
        for i, j in sorted(cKDTree(pts).query_pairs(1e-5)):
            ids[ids == ids[j]] = ids[i]
        ends = ids.reshape(-1, 2)
        adjacent: dict[int, list[int]] = {}
        for s, (a, b) in enumerate(ends):
            adjacent.setdefault(int(a), []).append(s)
            adjacent.setdefault(int(b), []).append(s)
        start = int(ends[0, 0])
        page = int(net.face_page[np.flatnonzero(net.face_piece == piece)[0]])
        out.append((page, pts[_walk(ends, adjacent, start)]))
    return out


def _walk(ends: np.ndarray, adjacent: dict[int, list[int]], start: int) -> list[int]:
    """Point ids along the closed walk that uses every segment once, from `start`."""
    used = np.zeros(len(ends), dtype=bool)
    order, at = [start], start
    while True:
        nxt = next((s for s in adjacent[at] if not used[s]), None)
        if nxt is None:
            break
        used[nxt] = True
        a, b = ends[nxt]
        at = int(b if a == at else a)
        order.append(at)
    return order[:-1] if order[-1] == start else order


def layout_sheets(
    nets,
    *,
    labels: dict[str, str],
    axis: np.ndarray,
    plan: FooterPlan,
    values=(),
    face_names: bool = False,
    mark: str = "bar",
    pips: bool = False,
    marks=(),
    markers=(),
) -> list[Sheet]:
    """One :class:`Sheet` per page for the copies `nets` of one die (see :func:`~.unfold.pack_copies`).

    Parameters
    ----------
    labels : face name -> text printed on it (``Design.label_of``).
    axis : (3,) float, the die's up axis (:func:`~diefab.dice.design.design_axis`).
    plan : the footer (:func:`plan_footer`; the page's ``footer`` is its height).
    values : faces whose labels are values, given one common height.
    face_names : print the small face names (f1, f2, ...) too.
    mark, pips : see :func:`~.labels.label_shape`.
    marks : values read at a corner or along an edge (:func:`~diefab.dice.design.placed_marks`).
    markers : the die's markers on the first copy (:func:`~diefab.fabricate.markers.net_markers`);
        the value labels and edge letters keep out of each marker's quiet zone.
    """
    from shapely import affinity

    nets = list(nets) if not isinstance(nets, Net) else [nets]
    first = nets[0]
    page = first.page
    n_pages = max(n.n_pages for n in nets)
    sheets = [Sheet(page.width, page.height, k + 1, n_pages) for k in range(n_pages)]
    font, bold = load_font(bold=False), load_font()
    texts = _die_texts(first, labels, axis, face_names=face_names, mark=mark, pips=pips, values=set(values),
                       font=font, bold=bold, marks=marks, markers=markers)  # fmt: skip
    rings = _cut_rings(first)
    names = first.poly.names
    index = {name: k for k, name in enumerate(names)}
    for net in nets:
        shift = [net.faces[k][0] - first.faces[k][0] for k in range(len(names))]
        for k, poly in enumerate(net.faces):
            sheets[net.face_page[k]].faces.append((names[k], poly))
        for t in net.tabs:
            sheets[t.page].tabs.append((t.label, t.polygon))
        for pg, seg in net.lines()["fold"]:
            sheets[pg].score.append(seg)
        for piece, (_, ring) in enumerate(rings):
            k = int(np.flatnonzero(first.face_piece == piece)[0])
            sheets[net.face_page[k]].cut.append(ring + shift[k])
        for t in texts:
            k = index[t.face]
            dx, dy = shift[k]
            moved = affinity.translate(t.shape, float(dx), float(dy))
            sheets[net.face_page[k]].texts.append(Text(t.text, t.kind, moved, t.face, t.height))
    for sheet in sheets:
        _draw_footer(sheet, plan, page, font)
    return sheets
