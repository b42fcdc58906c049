"""A fast landing model calibrated against the physics validator.

The solid-angle model (the paper's) says where the die first touches down:
the face hit by the downward ray from the centre of mass.  A real die then
bounces and rolls, and leaves a face more easily the less its centre of mass
must rise to tip over an edge.  This model adds those two effects:

1. **Quasi-static toppling.**  A face whose stability margin is negative
   cannot hold the die: its solid-angle share flows, edge by edge, to the
   face it topples onto (across the edge that the centre of mass projects
   furthest beyond), down the gravity-descent graph until a stable face.
2. **Energy-barrier tumbling.**  From a stable face *f* the die tips over
   edge *e* onto its neighbour *g* at rate

   ``k_fe = theta_fe / (2 pi) * exp(-B_fe / T) * (A_g / A_f) ** AREA_POWER * eta_e ** ROLL_POWER``,

   where ``B_fe = dist(center, edge line) - dist(center, plane of f)`` is the
   height the centre of mass must rise to tip over *e*, ``theta_fe`` is the
   angle the edge subtends at the foot of the centre of mass in *f* (the
   share of horizontal directions that lead over that edge) and A are face
   areas (a larger face catches a tipping die more easily).  ``eta_e`` is
   the share of kinetic energy a die keeps when it rolls over *e*: in the
   plastic impact that ends the roll, angular momentum about the new contact
   line is conserved, so the spin drops by the factor
   ``(k_e**2 + r_e**2 cos phi_e) / (k_e**2 + r_e**2)`` (the rolling-polygon
   impact law), ``eta_e`` its square, with ``phi_e`` the turn between the
   two faces (angle between their normals), ``r_e`` the distance from the
   centre of mass to the edge line and ``k_e`` the radius of gyration about
   the axis through the centre of mass parallel to *e* (uniform solid).
   Edges that keep the energy (shallow turns, long lever arms) are crossed
   by rolling as well as by thermal hops.  ``eta_e`` is the same from both
   sides of the edge.  The landing
   distribution is the first-contact distribution carried by this chain for
   a time ``TAU``, ``p0 expm(TAU Q)``,
3. **weighted by rest height**: times ``exp(-HEIGHT_WEIGHT * h_f)`` (h_f the
   height of the centre of mass resting on f, above the lowest rest), and
   normalized.

Five constants, :data:`TEMPERATURE`, :data:`TAU`, :data:`AREA_POWER`,
:data:`ROLL_POWER` and :data:`HEIGHT_WEIGHT`, are fitted to pybullet.  They are in the simulator's
units (model units, gravity 9.81 units/s², the paper's drop from ~5 units),
which is what :func:`diefab.physics.simulate.simulate` uses for every design, so no
rescaling is needed.  By symmetry a Platonic
solid stays uniform and mirror-image faces stay equal.

This chain applies to any convex die, but it is coarse: its error against
pybullet varies with the shape in ways no per-face geometric term captured
(a median TVD of 0.04-0.06 on random gems, more on other families).  What
it misses is learned from simulations, one of two ways (:func:`fast_model`):

4. **the gem discrepancy** (:class:`Discrepancy`), for the gem family:
   simulated frequencies minus the chain's probabilities at random stable
   gems (800 in the packaged data), interpolated by a smoothed thin-plate
   spline over the parameters and the chain's own margins and
   probabilities, are added to the chain's probabilities;
5. **the general correction** (:mod:`diefab.models.correction`), for every other
   convex die: a per-face logit correction, a function of features every
   polyhedron has (margins, barriers, areas, the chain's own shares ...),
   fitted to random dice of every family.

A gem made of card or printed (a ``fill``) gets one more learned layer,
its fill's :class:`FillCorrection`: what the model with the body's centre
and inertia still misses for that fill, a regularized linear function of
the shape, proportional to the body's inertia excess over the solid.

The model of the physics *is* then partly a surrogate of the simulator.

Examples
--------
>>> from diefab.dice.design import load_design
>>> d6 = load_design("d6")
>>> p = fast_model(d6.polyhedron, d6.mass_properties().center)
>>> bool(np.allclose(p, 1 / 6))
True
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache, cached_property
from importlib import resources

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.families import GEM, gem_parameters
from diefab.geometry.polyhedron import Polyhedron, face_margins, resting_faces, solid_angles
from diefab.made.mass import Fill

__all__ = [
    "AREA_POWER",
    "DISCREPANCY_FILE",
    "FILL_COORDINATES",
    "FILL_LAYERS",
    "HEIGHT_WEIGHT",
    "ROLL_POWER",
    "TAU",
    "TEMPERATURE",
    "DISCREPANCY_AT",
    "Discrepancy",
    "FillCorrection",
    "body_excess",
    "calibrate",
    "fast_model",
    "fill_discrepancy",
    "fill_discrepancy_file",
    "gem_discrepancy",
    "landing_probabilities",
    "made_gem_base",
    "roll_retention",
    "tipping_barriers",
]

# Calibrated constants.  Fitted by
#     python benchmarks/bench_fastmodel.py --calibrate
# which minimizes the mean TVD to pybullet (default PhysicsSettings, 4,000
# drops each, physics seed 0) over the first 20 random stable gems of the
# training set, drawn uniformly in the box of a, b, c, d and e (design seed
# 101), with adaptive Nelder--Mead (see :func:`calibrate`); the fit reached a
# mean TVD of 0.0571 on those gems.  The rolling term was chosen by 5-fold
# cross-validation over those training designs only (mean held-out TVD
# 0.0649 against 0.0673 without it, on the gems as simulated by the previous
# physics version).  On 20 *other* random gems at 30,000 drops each (design
# seed 202) the chain alone has a median TVD of 0.042 (solid angles 0.177),
# at about 0.35 ms per evaluation; on 20 more (design seed 303) 0.064.
#: Energy scale of the tumbling, model units of height.
TEMPERATURE = 0.0481
#: How long the tumbling lasts, in units of the rate at zero barrier.
TAU = 18.19
#: Larger faces catch a tipping die: rates scale as (area ratio) ** AREA_POWER.
AREA_POWER = 0.334
#: Rolling over edges that keep the energy: rates scale as (energy retention) ** ROLL_POWER.
ROLL_POWER = 2.019
#: Resting lower is likelier: weight exp(-HEIGHT_WEIGHT * height above the lowest rest).
HEIGHT_WEIGHT = 1.033


#: Floor of the energy retention under a power (an edge that keeps nothing is still crossed by hops).
_TINY = 1e-9


def _neighbors(poly: Polyhedron) -> np.ndarray:
    """(r,) int: for each directed edge of ``poly._ring``, the face across it."""
    tail, head, face, _ = poly._ring
    n = len(poly.vertices)
    code = tail * n + head
    order = np.argsort(code)
    back = np.searchsorted(code[order], head * n + tail)
    return face[order[back]]


def tipping_barriers(poly: Polyhedron, center: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per directed edge of every face: barrier, direction share and the face across.

    Returns
    -------
    barrier : (r,) float, model units
        Height the centre of mass rises when the die, resting on the edge's
        face, tips over the edge (negative when the face is unstable there).
    share : (r,) float
        Angle the edge subtends at the foot of the centre of mass in the
        face, over 2 pi (they sum to 1 over a stable face's edges).
    across : (r,) int
        The neighbouring face across the edge.
    """
    center = np.asarray(center, dtype=float)
    tail, head, face, _ = poly._ring
    n = poly.normals[face]
    height = poly.offsets[face] - n @ center
    foot = center + height[:, None] * n
    p0, p1 = poly.vertices[tail], poly.vertices[head]
    edge = p1 - p0
    cross = np.cross(center - p0, edge)
    reach = np.linalg.norm(cross, axis=1) / np.linalg.norm(edge, axis=1)
    a, b = p0 - foot, p1 - foot
    share = np.arctan2(np.einsum("ij,ij->i", n, np.cross(a, b)), np.einsum("ij,ij->i", a, b)) / (2 * np.pi)
    # The centre of mass beyond the edge line (seen from inside the face): no barrier, it falls.
    inward = np.cross(n, edge)
    side = np.einsum("ij,ij->i", foot - p0, inward)
    barrier = np.where(side >= 0, reach - height, -(reach - height))
    return barrier, share, _neighbors(poly)


def roll_retention(poly: Polyhedron, center: np.ndarray, inertia: np.ndarray | None = None) -> np.ndarray:
    """(r,) float in [0, 1]: per directed edge, the kinetic-energy share a die keeps rolling over it.

    ``((k**2 + r**2 cos phi) / (k**2 + r**2)) ** 2`` (clipped at 0), with
    ``phi`` the angle between the normals of the edge's two faces, ``r`` the
    distance from ``center`` to the edge line and ``k**2`` the moment of
    inertia about the axis through ``center`` parallel to the edge, per unit
    mass: of `inertia` (the body's tensor about its centre of mass over its
    mass, model units²) if given, else of the uniform solid moved to
    ``center``.  The same on both sides of an edge.
    """
    center = np.asarray(center, dtype=float)
    tail, head, face, _ = poly._ring
    if inertia is None:
        from diefab.made.mass import mass_properties

        props = mass_properties(poly)
        shift = center - props.center  # parallel-axis theorem: inertia about `center`
        inertia = (props.inertia + props.mass * (shift @ shift * np.eye(3) - np.outer(shift, shift))) / props.mass
    edge = poly.vertices[head] - poly.vertices[tail]
    edge /= np.linalg.norm(edge, axis=1)[:, None]
    k2 = np.einsum("ij,jk,ik->i", edge, np.asarray(inertia, dtype=float), edge)
    r2 = np.sum(np.cross(center - poly.vertices[tail], edge) ** 2, axis=1)
    cos = np.einsum("ij,ij->i", poly.normals[face], poly.normals[_neighbors(poly)])
    return np.clip((k2 + r2 * cos) / (k2 + r2), 0, None) ** 2


def _topple_targets(poly: Polyhedron, center: np.ndarray, barrier: np.ndarray, across: np.ndarray) -> np.ndarray:
    """(m,) int: the stable face each face ends on by quasi-static toppling (itself if stable)."""
    m = len(poly.faces)
    _, _, face, start = poly._ring
    step = np.arange(m)
    for f in np.flatnonzero(~resting_faces(poly, center)):
        # over the edge the centre of mass lies furthest beyond (most negative barrier)
        lo, hi = start[f], start[f + 1] if f + 1 < m else len(face)
        step[f] = across[lo + int(np.argmin(barrier[lo:hi]))]
    final = step.copy()
    for _ in range(m):  # follow the descent graph; it cannot be longer than m
        nxt = step[final]
        if np.array_equal(nxt, final):
            break
        final = nxt
    return final


def landing_probabilities(
    poly: Polyhedron,
    center: np.ndarray,
    *,
    temperature: float = TEMPERATURE,
    tau: float = TAU,
    area_power: float = AREA_POWER,
    roll_power: float = ROLL_POWER,
    height_weight: float = HEIGHT_WEIGHT,
    inertia: np.ndarray | None = None,
) -> np.ndarray:
    """(m,) float: probability of coming to rest on each face (see the module docstring).

    Parameters
    ----------
    poly : Polyhedron
    center : (3,) float
        Centre of mass, model units.
    temperature : float
        Energy scale T of the barrier weighting, model units (> 0).
    tau : float
        Duration of the tumbling (>= 0); 0 gives the toppled solid angles.
    area_power : float
        Exponent of the area ratio (destination over origin) in the tipping rate.
    roll_power : float
        Exponent of the edge's energy retention (:func:`roll_retention`) in the tipping rate.
    height_weight : float
        Per model unit: the result is weighted by ``exp(-height_weight * h)``,
        h the height of the centre of mass resting on the face.
    inertia : (3, 3) float, optional
        The body's inertia tensor about its centre of mass over its mass,
        model units² (:func:`roll_retention`); default the uniform solid's.
    """
    m = len(poly.faces)
    omega = solid_angles(poly, center)
    p0 = np.clip(omega, 0, None)
    p0 = p0 / p0.sum()
    barrier, share, across = tipping_barriers(poly, center)
    _, _, face, _ = poly._ring
    target = _topple_targets(poly, center, barrier, across)
    flowed = np.bincount(target, weights=p0, minlength=m)
    stable = target == np.arange(m)
    # rates between stable faces; tipping onto an unstable face continues to where it topples
    ok = stable[face]
    dest = target[across[ok]]
    rate = np.clip(share[ok], 0, None) * np.exp(-np.clip(barrier[ok], 0, None) / temperature)
    rate *= (poly.areas[dest] / poly.areas[face[ok]]) ** area_power
    if roll_power:
        rate *= np.maximum(roll_retention(poly, center, inertia)[ok], _TINY) ** roll_power
    q = np.zeros((m, m))
    np.add.at(q, (face[ok], dest), rate)
    np.fill_diagonal(q, 0.0)
    q -= np.diag(q.sum(axis=1))
    p = _evolve(flowed, tau * q)
    height = poly.offsets - poly.normals @ np.asarray(center, dtype=float)
    p = np.clip(p, 0, None) * np.exp(-height_weight * (height - height.min()))
    return p / p.sum()


def _evolve(p0: np.ndarray, generator: np.ndarray) -> np.ndarray:
    """``p0 @ expm(generator)`` for a rate matrix, by uniformization.

    With ``lam`` the largest exit rate, ``expm(G) = sum_k Poisson(k; lam) P^k``
    with the stochastic matrix ``P = I + G / lam``: every term is >= 0, and
    for a 9-face die it is far faster than a general matrix exponential.
    """
    lam = float(-np.diag(generator).min(initial=0.0))
    if lam <= 0:
        return p0.copy()
    if lam > 200:  # exp(-lam) would underflow: evolve in two halves
        return _evolve(_evolve(p0, generator / 2), generator / 2)
    step = np.eye(len(p0)) + generator / lam
    weight = np.exp(-lam)
    term, out = p0.copy(), weight * p0
    for k in range(1, int(lam + 12 * np.sqrt(lam) + 30)):
        term = term @ step
        weight *= lam / k
        out += weight * term
    return out


def fast_model(poly: Polyhedron, center: np.ndarray, *, fill: Fill | None = None,
               inertia: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """(m,) float: the calibrated fast model (``MODELS["fast"]``).

    The chain model (:func:`landing_probabilities`, with the body's
    `inertia` if given) with a learned correction.  For a gem inside the
    family box with every face stable, the gem family's discrepancy
    (:func:`gem_discrepancy`), and for a gem made with a `fill` that has a
    learned correction of its own (:func:`fill_discrepancy`: paper,
    print, shell), that as well, in proportion to how far the body's
    inertia lies from the solid's (a body with the solid's inertia gets
    the solid's prediction).  Every other die gets the per-face logit correction
    learned from random dice of every family
    (:func:`diefab.models.correction.corrected`).  A gem is recognized by
    :func:`~diefab.dice.families.gem_parameters`: built by the gem family, not the
    same shape given as a ``convex`` or ``mesh`` design, which gets the
    general correction.

    Parameters
    ----------
    poly : Polyhedron
    center : (3,) float
        Centre of mass, model units.
    fill : Fill, optional
        How the die is made (default solid).
    inertia : (3, 3) float, optional
        Inertia tensor about the centre of mass over the mass, model units²
        (default: the uniform solid's).
    """
    from diefab.models.correction import corrected

    params = gem_parameters(poly)
    if params is not None:
        margins = face_margins(poly, center)
        if gem_discrepancy().covers(params, margins):
            layer = fill_discrepancy(fill.kind) if fill is not None else None
            excess = body_excess(poly, inertia) if layer is not None else 0.0
            if excess == 0:  # a solid, or a body with the solid's inertia: the solid gems' model
                return gem_discrepancy().correct(landing_probabilities(poly, center, inertia=inertia), params, margins)
            p = made_gem_base(poly, center, inertia, params, margins, layer.discrepancy_at)
            return layer.correct(p, params, margins, excess)
    return corrected(poly, center, inertia=inertia)


# ---------------------------------------------------------------------------
# What the chain misses, learned from simulation

#: The gem family's discrepancy data, in the package (written by ``bench_fastmodel.py --learn``).
DISCREPANCY_FILE = "gem-discrepancy.json"

#: Mirror-image faces of every gem (x -> -x: f2 <-> f4, f7 <-> f9; z -> -z: f1 <-> f3, f6 <-> f8).
_GEM_MIRRORS = ((0, 2), (1, 3), (5, 7), (6, 8))


def _table_json(table, scalars: tuple[str, ...], digits: int) -> str:
    """JSON of a learned table: its `scalars` and box, then one training gem per line in each of its ``_ARRAYS``."""
    head = {k: getattr(table, k) for k in scalars} | {"lower": table.lower.tolist(), "upper": table.upper.tolist()}
    body = json.dumps(head, indent=1, sort_keys=True)[:-2]
    for name in table._ARRAYS:
        rows = ",\n".join(json.dumps(r) for r in np.round(getattr(table, name), digits).tolist())
        body += f',\n "{name}": [\n{rows}\n]'
    return body + "\n}\n"


@dataclass(frozen=True, eq=False)
class Discrepancy:
    """Simulated minus chain-model face probabilities, interpolated over the gem family's box.

    The chain model is general but coarse: its error varies with the shape
    in ways no per-face geometric term captured (see the README).  Over the
    gem family the error is a smooth function of the shape, so it can be
    learned from simulations: at each training design ``i`` the residual
    ``q_i - p_i`` between simulated frequencies and the chain's
    probabilities is averaged over mirror-image faces and interpolated by a
    thin-plate-spline radial basis function with ``smoothing``
    (:class:`scipy.interpolate.RBFInterpolator`).

    The interpolation coordinates are the parameters, scaled to the unit
    box, together with the physics the chain already computes: each mirror
    class's stability margin and chain probability, scaled to [0, 1] over
    the training designs (``physics_coordinates=False``: the parameters
    alone).  The residual changes fastest where a face is barely stable, and
    there the margins pull apart designs that the parameters alone would call
    neighbors (``bench_fastmodel.py --ablation`` compares the two).  The
    interpolant is linear in the residuals, so mirror-image faces stay equal
    (to rounding).

    Every training design rests on every face with a margin of at least
    ``margins.min()``; a design with a smaller margin lies outside what was
    learned, so the correction fades out linearly as its smallest margin goes
    from that floor to 0, and a design with an unstable face gets the chain
    alone.

    Attributes
    ----------
    parameters : tuple of str
        The family parameters, in the column order of `points`.
    lower, upper : (k,) float
        The family box; outside it no correction is applied.
    points : (n, k) float
        Parameters of the training designs.
    margins, chain : (n, 9) float
        Stability margins (model units) and chain probabilities of the
        training designs.
    residuals : (n, 9) float
        Simulated frequency minus chain probability, per face.
    smoothing : float
        RBF smoothing (chosen by cross-validation when learned).
    physics_coordinates : bool
        Interpolate over the margins and chain probabilities as well as the
        parameters (default).
    kernel : str
        The RBF kernel (:class:`scipy.interpolate.RBFInterpolator`, its
        least polynomial degree): ``thin_plate_spline`` (default) or, for a
        correction learned from few designs, ``linear``.
    info : dict
        How the data were made: drops per design, physics version and
        settings, chain constants, cross-validated error.
    """

    parameters: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    points: np.ndarray
    margins: np.ndarray
    chain: np.ndarray
    residuals: np.ndarray
    smoothing: float
    physics_coordinates: bool = True
    info: dict = field(default_factory=dict)
    kernel: str = "thin_plate_spline"

    #: One face of each mirror class (f1, f2, f5, f6, f7): the coordinates need no duplicates.
    CLASSES = (0, 1, 4, 5, 6)
    _ARRAYS = ("points", "margins", "chain", "residuals")

    @classmethod
    def learn(
        cls,
        points: np.ndarray,
        margins: np.ndarray,
        chain: np.ndarray,
        frequencies: np.ndarray,
        *,
        smoothing: float,
        physics_coordinates: bool = True,
        info: Mapping | None = None,
        kernel: str = "thin_plate_spline",
    ) -> Discrepancy:
        """The gem discrepancy from simulated `frequencies` (n, 9) at designs with parameters `points` (n, 5).

        `margins` and `chain` (n, 9) are the designs' stability margins and
        chain probabilities; every margin must be positive (stable designs).
        """
        names = tuple(p.name for p in GEM.parameters)
        points = np.asarray(points, dtype=float)
        margins, chain = np.asarray(margins, dtype=float), np.asarray(chain, dtype=float)
        frequencies = np.asarray(frequencies, dtype=float)
        n = len(points)
        for name, a, width in (("points", points, len(names)), ("margins", margins, 9), ("chain", chain, 9),
                               ("frequencies", frequencies, 9)):  # fmt: skip
            if a.shape != (n, width) or not np.all(np.isfinite(a)):
                raise DesignError(f"{name} must be a finite ({n}, {width}) array, got shape {a.shape}")
        dims = len(names) + (2 * len(cls.CLASSES) if physics_coordinates else 0)
        if n <= dims + 1:
            raise DesignError(f"need more than {dims + 1} training designs for {dims} coordinates, got {n}")
        if margins.min() <= 0:
            raise DesignError(f"training designs must be stable on every face; smallest margin {margins.min():g}")
        residuals = frequencies - chain
        for i, j in _GEM_MIRRORS:
            residuals[:, [i, j]] = residuals[:, [i, j]].mean(axis=1, keepdims=True)
        bounds = GEM.bounds(list(names))
        return cls(
            names, bounds[:, 0], bounds[:, 1], points, margins, chain, residuals, float(smoothing),
            bool(physics_coordinates), dict(info or {}), str(kernel),
        )  # fmt: skip

    @classmethod
    def from_json(cls, text: str) -> Discrepancy:
        data = json.loads(text)
        arrays = [np.array(data[k], dtype=float) for k in ("lower", "upper", *cls._ARRAYS)]
        physics = bool(data.get("physics_coordinates", True))
        kernel = str(data.get("kernel", "thin_plate_spline"))
        return cls(tuple(data["parameters"]), *arrays, float(data["smoothing"]), physics, data["info"], kernel)

    def to_json(self) -> str:
        """JSON text, one training design per line in each array (:meth:`from_json` reads it back)."""
        return _table_json(self, ("parameters", "smoothing", "physics_coordinates", "info", "kernel"), 6)

    @cached_property
    def _feature_range(self) -> tuple[np.ndarray, np.ndarray]:
        f = np.hstack([self.margins[:, self.CLASSES], self.chain[:, self.CLASSES]])
        span = np.ptp(f, axis=0)
        return f.min(axis=0), np.where(span > 0, span, 1.0)  # a constant feature adds nothing either way

    def _coordinates(self, points: np.ndarray, margins: np.ndarray, chain: np.ndarray) -> np.ndarray:
        """(n, d) float: interpolation coordinates (see the class docstring)."""
        unit = (points - self.lower) / (self.upper - self.lower)
        if not self.physics_coordinates:
            return unit
        lo, span = self._feature_range
        features = np.hstack([margins[:, self.CLASSES], chain[:, self.CLASSES]])
        return np.hstack([unit, (features - lo) / span])

    def _point(self, params: Mapping[str, float]) -> np.ndarray:
        """(k,) float: `params` in the column order of `points` (e, if left out, is a*b)."""
        params = GEM.complete(params)
        return np.array([params[n] for n in self.parameters], dtype=float)

    def distance(self, params: Mapping[str, float], margins: np.ndarray, chain: np.ndarray) -> float:
        """Distance from a design to the nearest training design, in interpolation coordinates."""
        here = self._coordinates(self._point(params)[None], np.atleast_2d(margins), np.atleast_2d(chain))
        return float(np.sqrt(((self._interpolator.y - here) ** 2).sum(axis=1).min()))

    @cached_property
    def _interpolator(self):
        from scipy.interpolate import RBFInterpolator

        x = self._coordinates(self.points, self.margins, self.chain)
        return RBFInterpolator(x, self.residuals, kernel=self.kernel, smoothing=self.smoothing)

    def __call__(self, params: Mapping[str, float], margins: np.ndarray, chain: np.ndarray) -> np.ndarray | None:
        """(m,) float: the learned residual of a design, or None outside the box.

        Parameters
        ----------
        params : mapping
            The design's family parameters (e may be left out, as in a design file).
        margins, chain : (m,) float
            Its stability margins and chain probabilities.
        """
        x = self._point(params)
        if np.any(x < self.lower) or np.any(x > self.upper):
            return None
        return self._interpolator(self._coordinates(x[None], np.atleast_2d(margins), np.atleast_2d(chain)))[0]

    def covers(self, params: Mapping[str, float], margins: np.ndarray) -> bool:
        """Whether :meth:`correct` applies a correction: inside the box, every face with a positive margin."""
        x = self._point(params)
        return bool(np.all(x >= self.lower) and np.all(x <= self.upper) and np.min(margins) > 0)

    def correct(self, p: np.ndarray, params: Mapping[str, float], margins: np.ndarray) -> np.ndarray:
        """Chain probabilities `p` plus the learned residual (faded out below the training margins).

        Faces the die cannot rest on stay at 0; the result is renormalized.
        """
        weight = float(np.clip(margins.min() / self.margins.min(), 0.0, 1.0))
        # The training gems are mirror-symmetric, so their coordinates are too; a centre of mass a little off
        # the mirror planes (a paper die's glue tabs) must not take the interpolant off that set, where it is
        # steep: the coordinates are the mirror-class means.
        sym_margins, sym_p = np.array(margins, dtype=float), np.array(p, dtype=float)
        for i, j in _GEM_MIRRORS:
            sym_margins[[i, j]] = sym_margins[[i, j]].mean()
            sym_p[[i, j]] = sym_p[[i, j]].mean()
        r = self(params, sym_margins, sym_p) if weight > 0 else None
        if r is None:
            return p
        out = np.clip(p + weight * r, 0, None)
        out[margins < 0] = 0.0
        total = out.sum()
        return out / total if total > 0 else p


@cache
def gem_discrepancy() -> Discrepancy:
    """The gem family's :class:`Discrepancy` packaged with diefab (read once)."""
    return Discrepancy.from_json(resources.files("diefab").joinpath("data", DISCREPANCY_FILE).read_text())


# ---------------------------------------------------------------------------
# The fill correction: what a card or printed gem does that the solid gems' discrepancy misses

#: The fills with a learned correction of their own (each learned in that fill at its default settings).
FILL_LAYERS = ("paper", "print", "shell")

#: For each face, the index of its mirror class in :attr:`Discrepancy.CLASSES` (f1, f2, f5, f6, f7).
_CLASS_OF_FACE = np.array([0, 1, 0, 1, 2, 3, 4, 3, 4])

#: Fewest training gems a fill correction is learned from (the ridge penalty keeps any coordinates well posed).
_FILL_MIN_GEMS = 8

#: Where a made gem's base model evaluates the solid gems' discrepancy (:func:`made_gem_base`).
DISCREPANCY_AT = ("body", "solid")

#: Coordinates a fill correction can be a linear function of (:meth:`FillCorrection.learn`), simplest first.
FILL_COORDINATES = ("constant", "shape", "physics")


def fill_discrepancy_file(kind: str) -> str:
    """Name of the packaged correction learned in the fill `kind` (one of :data:`FILL_LAYERS`)."""
    return f"gem-discrepancy-{kind}.json"


def _mirror_means(x: np.ndarray) -> np.ndarray:
    """`x` (..., 9) with each mirror pair of faces replaced by its mean."""
    x = np.array(x, dtype=float)
    for i, j in _GEM_MIRRORS:
        x[..., [i, j]] = x[..., [i, j]].mean(axis=-1, keepdims=True)
    return x


def made_gem_base(
    poly: Polyhedron,
    center: np.ndarray,
    inertia: np.ndarray | None,
    params: Mapping[str, float],
    margins: np.ndarray,
    at: str = "body",
) -> np.ndarray:
    """(9,) float: the fast model of a gem made in a fill, before the fill's own correction.

    The chain with the body's centre and inertia, plus the solid gems'
    discrepancy (:func:`gem_discrepancy`) evaluated ``at``:

    - ``"body"``: at the body's own coordinates (the shape, and the margins
      and chain probabilities of its centre), as for a solid;
    - ``"solid"``: where it was learned, at the solid gem of the same shape.
      A made body's centre takes the body's coordinates off the set the
      solid gems span, where the interpolant extrapolates, while the change
      the body brings is what the chain models.  A shape whose solid rests
      unstably on a face gets it at the body's coordinates.

    Parameters
    ----------
    poly : Polyhedron
        A gem (:func:`~diefab.dice.families.gem_parameters` of it is `params`).
    center : (3,) float
        The body's centre of mass, model units.
    inertia : (3, 3) float or None
        The body's inertia about its centre over its mass (None: the solid's).
    params : mapping
        The gem's parameters.
    margins : (9,) float
        The body's stability margins (:func:`~diefab.geometry.polyhedron.face_margins` at `center`).
    at : {"body", "solid"}
    """
    found = gem_discrepancy()
    p = landing_probabilities(poly, center, inertia=inertia)
    if at == "body":
        return found.correct(p, params, margins)
    if at != "solid":
        raise DesignError(f"at={at!r} is not one of {', '.join(DISCREPANCY_AT)}")
    from diefab.made.mass import mass_properties

    solid_center = mass_properties(poly).center
    solid_margins = face_margins(poly, solid_center)
    if not found.covers(params, solid_margins):
        return found.correct(p, params, margins)
    solid_chain = landing_probabilities(poly, solid_center)
    weight = float(np.clip(solid_margins.min() / found.margins.min(), 0.0, 1.0))
    residual = found(params, _mirror_means(solid_margins), _mirror_means(solid_chain))
    out = np.clip(p + weight * residual, 0, None)
    out[np.asarray(margins) < 0] = 0.0
    total = out.sum()
    return out / total if total > 0 else p


def body_excess(poly: Polyhedron, inertia: np.ndarray | None) -> float:
    """How far a body's inertia lies from the uniform solid's: ``tr(I) / tr(I_solid) - 1``.

    Both tensors about their own centre of mass and per unit mass (model
    units²); `inertia` None is the solid's (0).  A card shell carries its
    mass on the surface (about 0.5-0.8 for a gem), a print on its walls
    (about 0.2-0.3 at the default settings); a print at 100 % infill
    without labels is the solid (0).
    """
    if inertia is None:
        return 0.0
    from diefab.made.mass import mass_properties

    solid = mass_properties(poly)
    return float(np.trace(np.asarray(inertia, dtype=float)) / (np.trace(solid.inertia) / solid.mass) - 1.0)


@dataclass(frozen=True, eq=False)
class FillCorrection:
    """A fill's correction of the gem's fast model: a regularized linear function, proportional to the body's excess.

    A gem made of card or printed rolls unlike the solid gem of the same
    centre of mass, because its mass sits further out (a larger radius of
    gyration keeps more energy over an edge).  The fast model without this
    layer (the chain with the body's centre and inertia, corrected by the
    solid gems' :class:`Discrepancy`: :func:`made_gem_base`) misses part of
    the effect.  What it misses, the simulated frequencies minus its
    probabilities at random stable gems simulated in the fill, is fitted by
    ridge regression as

    ``r = s / s_mean * (W @ phi + sum_j alpha_j k(z, z_j))``

    per mirror class of faces, where ``s`` is the body's inertia excess
    (:func:`body_excess`, ``s_mean`` its mean over the training gems) and
    ``phi`` the coordinates: 1 alone (``constant``), with the parameters
    scaled to the unit box (``shape``), or with each mirror class's
    stability margin and probability as well (``physics``).  The optional
    kernel term (``kernel_length`` > 0) is kernel ridge regression of what
    the linear part leaves, per unit of relative excess: ``z`` are the
    coordinates (without the constant) standardized over the training gems
    ``z_j``, and ``k(z, z') = exp(-|z - z'|² / (2 dim kernel_length²))``,
    with penalty ``kernel_penalty`` per training gem.  It follows what a
    linear function cannot (the error grows fast on a shallow bottom, small
    d).  Because ``r`` is proportional to ``s``, a body with the solid's
    inertia gets no correction, and the correction shrinks with the fill's
    excess (a print with more infill); ``s`` is clipped to [0, the training
    gems' largest].  The coordinates, the penalties and the kernel's length
    are chosen by cross-validation over gems
    (``benchmarks/learn_fill_correction.py``).

    Mirror-image faces get the same residual, which sums to 0 over the
    faces (the training residuals do, and the fit is linear in them).  Like
    :class:`Discrepancy`, it applies inside the family box to gems that rest
    on every face, and fades out as the smallest margin goes from the
    training gems' least to 0.

    Attributes
    ----------
    kind : str
        The fill it was learned in.
    coordinates : str
        One of :data:`FILL_COORDINATES`.
    penalty : float
        Ridge penalty (on standardized coordinates; the constant is not penalized).
    lower, upper : (5,) float
        The family box of a, b, c, d, e.
    points : (n, 5) float
        Parameters of the training gems.
    margins, base : (n, 9) float
        Their stability margins (model units) and probabilities of the base
        model (:func:`made_gem_base` with `discrepancy_at`), in the fill.
    excess : (n,) float
        Their :func:`body_excess`.
    residuals : (n, 9) float
        Simulated frequency minus `base` (mirror pairs averaged).
    info : dict
        How the data were made: fill settings, drops, seeds, physics, the
        bodies of the first training gems (centre and inertia, to tell when
        the body model has changed since), cross-validated error.
    discrepancy_at : {"body", "solid"}
        Where the base model evaluates the solid gems' discrepancy
        (:func:`made_gem_base`; chosen by cross-validation with the rest).
    kernel_length : float
        Length of the kernel term in standardized coordinates (0: no kernel term).
    kernel_penalty : float
        Its ridge penalty per training gem (> 0 when `kernel_length` is).
    """

    kind: str
    coordinates: str
    penalty: float
    lower: np.ndarray
    upper: np.ndarray
    points: np.ndarray
    margins: np.ndarray
    base: np.ndarray
    excess: np.ndarray
    residuals: np.ndarray
    info: dict = field(default_factory=dict)
    discrepancy_at: str = "body"
    kernel_length: float = 0.0
    kernel_penalty: float = 0.0

    _ARRAYS = ("points", "margins", "base", "excess", "residuals")

    @classmethod
    def learn(
        cls,
        kind: str,
        points: np.ndarray,
        margins: np.ndarray,
        base: np.ndarray,
        excess: np.ndarray,
        frequencies: np.ndarray,
        *,
        coordinates: str = "physics",
        penalty: float = 1.0,
        info: Mapping | None = None,
        discrepancy_at: str = "body",
        kernel_length: float = 0.0,
        kernel_penalty: float = 0.0,
    ) -> FillCorrection:
        """The correction from simulated `frequencies` (n, 9) of gems made in fill `kind`.

        `points` (n, 5) are their parameters, `margins` and `base` (n, 9)
        their margins and fast-model probabilities without this layer,
        `excess` (n,) their :func:`body_excess` (all positive); `base` was
        computed by :func:`made_gem_base` with `discrepancy_at`.  A
        `kernel_length` > 0 adds the kernel term (needs coordinates other
        than ``constant`` and a `kernel_penalty` > 0).
        """
        if kind not in FILL_LAYERS:
            raise DesignError(f"fill kind={kind!r} is not one of {', '.join(FILL_LAYERS)}")
        if discrepancy_at not in DISCREPANCY_AT:
            raise DesignError(f"discrepancy_at={discrepancy_at!r} is not one of {', '.join(DISCREPANCY_AT)}")
        if coordinates not in FILL_COORDINATES:
            raise DesignError(f"coordinates={coordinates!r} is not one of {', '.join(FILL_COORDINATES)}")
        if not (np.isfinite(penalty) and penalty >= 0):
            raise DesignError(f"penalty={penalty!r} must be a number >= 0")
        if not (np.isfinite(kernel_length) and kernel_length >= 0):
            raise DesignError(f"kernel_length={kernel_length!r} must be a number >= 0")
        if kernel_length > 0 and not (np.isfinite(kernel_penalty) and kernel_penalty > 0):
            raise DesignError(f"kernel_penalty={kernel_penalty!r} must be a number > 0 with a kernel")
        if kernel_length > 0 and coordinates == "constant":
            raise DesignError("a kernel term needs coordinates other than 'constant'")
        points = np.asarray(points, dtype=float)
        n = len(points)
        arrays = {"points": (points, 5), "margins": (margins, 9), "base": (base, 9), "frequencies": (frequencies, 9)}
        for name, (a, width) in arrays.items():
            a = np.asarray(a, dtype=float)
            if a.shape != (n, width) or not np.all(np.isfinite(a)):
                raise DesignError(f"{name} must be a finite ({n}, {width}) array, got shape {a.shape}")
        excess = np.asarray(excess, dtype=float)
        if excess.shape != (n,) or not np.all(np.isfinite(excess)) or excess.min(initial=1.0) <= 0:
            raise DesignError(f"excess must be ({n},) positive numbers (bodies unlike the solid)")
        if n < _FILL_MIN_GEMS:
            raise DesignError(f"need at least {_FILL_MIN_GEMS} training gems, got {n}")
        margins = np.asarray(margins, dtype=float)
        if margins.min() <= 0:
            raise DesignError(f"training gems must be stable on every face; smallest margin {margins.min():g}")
        base = np.asarray(base, dtype=float)
        residuals = _mirror_means(np.asarray(frequencies, dtype=float) - base)
        bounds = GEM.bounds([p.name for p in GEM.parameters])
        return cls(
            kind, coordinates, float(penalty), bounds[:, 0], bounds[:, 1], points, margins, base, excess, residuals,
            dict(info or {}), discrepancy_at, float(kernel_length), float(kernel_penalty) if kernel_length else 0.0,
        )  # fmt: skip

    @classmethod
    def from_json(cls, text: str) -> FillCorrection:
        data = json.loads(text)
        arrays = [np.array(data[k], dtype=float) for k in ("lower", "upper", *cls._ARRAYS)]
        at = str(data.get("discrepancy_at", "body"))
        kernel = float(data.get("kernel_length", 0.0)), float(data.get("kernel_penalty", 0.0))
        return cls(data["kind"], data["coordinates"], float(data["penalty"]), *arrays, data["info"], at, *kernel)

    def to_json(self) -> str:
        """JSON text, one training gem per line in each array (:meth:`from_json` reads it back)."""
        scalars = ("kind", "coordinates", "penalty", "discrepancy_at", "kernel_length", "kernel_penalty", "info")
        return _table_json(self, scalars, 8)

    def _phi(self, points: np.ndarray, margins: np.ndarray, base: np.ndarray) -> np.ndarray:
        """(n, k) float: the coordinates (mirror-class means of margins and probabilities)."""
        cols = [np.ones((len(points), 1))]
        if self.coordinates != "constant":
            cols.append((points - self.lower) / (self.upper - self.lower))
        if self.coordinates == "physics":
            classes = list(Discrepancy.CLASSES)
            cols += [_mirror_means(margins)[:, classes], _mirror_means(base)[:, classes]]
        return np.hstack(cols)

    @cached_property
    def _weights(self) -> tuple[np.ndarray, float]:
        """(k, 5) ridge weights of the mirror classes' residuals, and the training gems' mean excess."""
        scale = float(self.excess.mean())
        x = self._phi(self.points, self.margins, self.base) * (self.excess / scale)[:, None]
        y = self.residuals[:, list(Discrepancy.CLASSES)]
        size = np.sqrt((x**2).mean(axis=0))
        size[size == 0] = 1.0
        xs = x / size
        ridge = self.penalty * len(x) * np.eye(x.shape[1])
        ridge[0, 0] = 0.0  # the constant is not penalized
        w = np.linalg.solve(xs.T @ xs + ridge, xs.T @ y)
        return w / size[:, None], scale

    @cached_property
    def _kernel_term(self):
        """The kernel term: the coordinates' mean and spread over the training gems, and the kernel ridge fit.

        Gaussian kernel ridge regression is :class:`scipy.interpolate.RBFInterpolator`
        with the ``gaussian`` kernel, no polynomial, and the penalty as its smoothing.
        """
        from scipy.interpolate import RBFInterpolator

        w, scale = self._weights
        phi = self._phi(self.points, self.margins, self.base)
        t = self.excess / scale
        rest = self.residuals[:, list(Discrepancy.CLASSES)] / t[:, None] - phi @ w  # per unit of relative excess
        z = phi[:, 1:]
        mean, spread = z.mean(axis=0), z.std(axis=0)
        spread[spread == 0] = 1.0
        z = (z - mean) / spread
        # exp(-|z - z'|² / (2 dim length²)) is RBFInterpolator's exp(-(epsilon r)²)
        epsilon = 1.0 / (self.kernel_length * np.sqrt(2.0 * z.shape[1]))
        fit = RBFInterpolator(z, rest, kernel="gaussian", epsilon=epsilon, smoothing=self.kernel_penalty * len(z),
                              degree=-1)  # fmt: skip
        return mean, spread, fit

    def residual(self, params: Mapping[str, float], margins: np.ndarray, p: np.ndarray, excess: float) -> np.ndarray:
        """(9,) float: the learned residual of a gem (see the class docstring), without the fade-out."""
        point = np.array([GEM.complete(params)[n] for n in ("a", "b", "c", "d", "e")], dtype=float)
        w, scale = self._weights
        phi = self._phi(point[None], np.atleast_2d(margins), np.atleast_2d(p))
        r5 = (phi @ w)[0]
        if self.kernel_length > 0:
            mean, spread, fit = self._kernel_term
            r5 = r5 + fit((phi[:, 1:] - mean) / spread)[0]
        return (excess / scale) * r5[_CLASS_OF_FACE]

    def covers(self, params: Mapping[str, float], margins: np.ndarray) -> bool:
        """Whether :meth:`correct` applies: inside the box, every face with a positive margin."""
        point = np.array([GEM.complete(params)[n] for n in ("a", "b", "c", "d", "e")], dtype=float)
        return bool(np.all(point >= self.lower) and np.all(point <= self.upper) and np.min(margins) > 0)

    def correct(self, p: np.ndarray, params: Mapping[str, float], margins: np.ndarray, excess: float) -> np.ndarray:
        """Probabilities `p` (the fast model without this layer) plus the learned residual, renormalized."""
        # no extrapolation beyond the bodies learned from; a body no further out than the solid gets nothing
        excess = float(np.clip(excess, 0.0, self.excess.max()))
        if excess == 0 or not self.covers(params, margins):
            return p
        weight = float(np.clip(np.min(margins) / self.margins.min(), 0.0, 1.0))
        out = np.clip(p + weight * self.residual(params, margins, p, excess), 0, None)
        out[np.asarray(margins) < 0] = 0.0
        total = out.sum()
        return out / total if total > 0 else p


def fill_discrepancy(kind: str) -> FillCorrection | None:
    """The gem correction learned in the fill `kind` (:class:`FillCorrection`); None for a fill without one.

    ``paper``, ``print`` and ``shell`` each have their own, learned at the
    fill's default settings (``info["fill"]``) and applied, in proportion to
    the body's inertia excess, at any settings of that fill.
    """
    return _packaged_layer(kind) if kind in FILL_LAYERS else None


@cache
def _packaged_layer(kind: str) -> FillCorrection | None:
    path = resources.files("diefab").joinpath("data", fill_discrepancy_file(kind))
    return FillCorrection.from_json(path.read_text()) if path.is_file() else None


def calibrate(
    designs: Sequence,
    counts: Sequence[np.ndarray],
    x0=(TEMPERATURE, TAU, AREA_POWER, HEIGHT_WEIGHT, ROLL_POWER),
    *,
    maxfev: int = 3000,
) -> dict[str, float]:
    """Fit the model's five constants to simulated face counts by least mean TVD.

    Nelder--Mead (adaptive) on (log T, log tau, area power, height weight,
    roll power), from `x0` with a simplex of 0.3 along each coordinate.

    Parameters
    ----------
    designs : sequence of Design
    counts : sequence of (m,) int
        Simulated landings per face of each design (polyhedron order).
    x0 : (5,) float
        Start: temperature, tau, area_power, height_weight, roll_power.
    maxfev : int
        Most evaluations of the mean TVD.

    Returns
    -------
    dict with ``temperature``, ``tau``, ``area_power``, ``height_weight``,
    ``roll_power`` and the fitted ``mean_tvd``.
    """
    from scipy.optimize import minimize

    cases = [(d.polyhedron, d.mass_properties().center, np.asarray(c) / np.sum(c)) for d, c in zip(designs, counts)]

    def constants(x: np.ndarray) -> dict[str, float]:
        return {"temperature": float(np.exp(x[0])), "tau": float(np.exp(x[1])), "area_power": float(x[2]),
                "height_weight": float(x[3]), "roll_power": float(x[4])}  # fmt: skip

    def loss(x: np.ndarray) -> float:
        kw = constants(x)
        return float(np.mean([0.5 * np.abs(landing_probabilities(poly, c, **kw) - q).sum() for poly, c, q in cases]))

    start = np.array([np.log(x0[0]), np.log(x0[1]), x0[2], x0[3], x0[4]])
    simplex = np.vstack([start, start + 0.3 * np.eye(len(start))])
    options = {"xatol": 1e-3, "fatol": 1e-6, "maxfev": maxfev, "adaptive": True, "initial_simplex": simplex}
    res = minimize(loss, start, method="Nelder-Mead", options=options)
    return {**constants(res.x), "mean_tvd": float(res.fun)}
