"""The chain model: first contact, quasi-static toppling and energy-barrier tumbling, for any convex die.

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

:mod:`diefab.models.fast` adds what the chain misses, learned from simulation.

Examples
--------
>>> from diefab.dice.design import load_design
>>> d6 = load_design("d6")
>>> p = landing_probabilities(d6.polyhedron, d6.mass_properties().center)
>>> bool(np.allclose(p, 1 / 6))
True
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from diefab.geometry.moments import properties, solid_moments
from diefab.geometry.polyhedron import Polyhedron, resting_faces, solid_angles

__all__ = [
    "AREA_POWER",
    "HEIGHT_WEIGHT",
    "ROLL_POWER",
    "TAU",
    "TEMPERATURE",
    "calibrate",
    "fit_constants",
    "landing_probabilities",
    "roll_retention",
    "tipping_barriers",
    "topple_targets",
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
        props = properties(*solid_moments(poly))
        shift = center - props.center  # parallel-axis theorem: inertia about `center`
        inertia = (props.inertia + props.mass * (shift @ shift * np.eye(3) - np.outer(shift, shift))) / props.mass
    edge = poly.vertices[head] - poly.vertices[tail]
    edge /= np.linalg.norm(edge, axis=1)[:, None]
    k2 = np.einsum("ij,jk,ik->i", edge, np.asarray(inertia, dtype=float), edge)
    r2 = np.sum(np.cross(center - poly.vertices[tail], edge) ** 2, axis=1)
    cos = np.einsum("ij,ij->i", poly.normals[face], poly.normals[_neighbors(poly)])
    return np.clip((k2 + r2 * cos) / (k2 + r2), 0, None) ** 2


def topple_targets(poly: Polyhedron, center: np.ndarray, barrier: np.ndarray, across: np.ndarray) -> np.ndarray:
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
    target = topple_targets(poly, center, barrier, across)
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


def fit_constants(
    loss: Callable[[dict[str, float]], float],
    x0=(TEMPERATURE, TAU, AREA_POWER, HEIGHT_WEIGHT, ROLL_POWER),
    *,
    maxfev: int = 3000,
    fatol: float = 1e-6,
) -> tuple[dict[str, float], float]:
    """The model's five constants of least `loss`, and that loss.

    Nelder--Mead (adaptive) on (log T, log tau, area power, height weight,
    roll power), from `x0` with a simplex of 0.3 along each coordinate.

    Parameters
    ----------
    loss : callable
        Maps the constants, as :func:`landing_probabilities`'s keywords
        (``temperature``, ``tau``, ``area_power``, ``height_weight``,
        ``roll_power``), to the number to minimise.
    x0 : (5,) float
        Start: temperature, tau, area_power, height_weight, roll_power.
    maxfev : int
        Most evaluations of `loss`.
    fatol : float
        Change in `loss` below which the simplex has converged.
    """
    from scipy.optimize import minimize

    def constants(x: np.ndarray) -> dict[str, float]:
        return {"temperature": float(np.exp(x[0])), "tau": float(np.exp(x[1])), "area_power": float(x[2]),
                "height_weight": float(x[3]), "roll_power": float(x[4])}  # fmt: skip

    start = np.array([np.log(x0[0]), np.log(x0[1]), x0[2], x0[3], x0[4]])
    simplex = np.vstack([start, start + 0.3 * np.eye(len(start))])
    options = {"xatol": 1e-3, "fatol": fatol, "maxfev": maxfev, "adaptive": True, "initial_simplex": simplex}
    res = minimize(lambda x: loss(constants(x)), start, method="Nelder-Mead", options=options)
    return constants(res.x), float(res.fun)


def calibrate(
    designs: Sequence,
    counts: Sequence[np.ndarray],
    x0=(TEMPERATURE, TAU, AREA_POWER, HEIGHT_WEIGHT, ROLL_POWER),
    *,
    maxfev: int = 3000,
) -> dict[str, float]:
    """Fit the model's five constants to simulated face counts by least mean TVD (:func:`fit_constants`).

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
    cases = [(d.polyhedron, d.mass_properties().center, np.asarray(c) / np.sum(c)) for d, c in zip(designs, counts)]

    def loss(kw: dict[str, float]) -> float:
        return float(np.mean([0.5 * np.abs(landing_probabilities(poly, c, **kw) - q).sum() for poly, c, q in cases]))

    fitted, mean_tvd = fit_constants(loss, x0, maxfev=maxfev)
    return {**fitted, "mean_tvd": mean_tvd}
