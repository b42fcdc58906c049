"""A fast landing model calibrated against the physics validator.

It starts from the chain model (:mod:`diefab.models.chain`): the first contact
of the solid-angle model, carried by quasi-static toppling and energy-barrier
tumbling, weighted by rest height, with five constants fitted to pybullet.

This chain applies to any convex die, but it is coarse: its error against
pybullet varies with the shape in ways no per-face geometric term captured
(a median TVD of 0.04-0.06 on random gems, more on other families).  What
it misses is learned from simulations, one of two ways (:func:`fast_model`):

1. **the gem discrepancy** (:class:`~diefab.models.discrepancy.Discrepancy`), for the gem family:
   simulated frequencies minus the chain's probabilities at random stable
   gems (800 in the packaged data), interpolated by a smoothed thin-plate
   spline over the parameters and the chain's own margins and
   probabilities, are added to the chain's probabilities;
2. **the general correction** (:mod:`diefab.models.correction`), for every other
   convex die: a per-face logit correction, a function of features every
   polyhedron has (margins, barriers, areas, the chain's own shares ...),
   fitted to random dice of every family, and applied only to dice like
   those (every hull face a resting face, features within the training
   range); any other die gets the chain alone.

A gem made of card or printed (a ``fill``) gets one more learned layer,
its fill's :class:`~diefab.models.fills.FillCorrection`: what the model with the body's centre
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

import numpy as np

from diefab.dice.families import gem_parameters
from diefab.geometry.polyhedron import Polyhedron, face_margins
from diefab.made.fill import Fill
from diefab.models.chain import landing_probabilities
from diefab.models.correction import corrected
from diefab.models.discrepancy import gem_discrepancy
from diefab.models.fills import body_excess, fill_discrepancy, made_gem_base

__all__ = ["fast_model"]


def fast_model(poly: Polyhedron, center: np.ndarray, *, fill: Fill | None = None,
               inertia: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """(m,) float: the calibrated fast model (``MODELS["fast"]``).

    The chain model (:func:`landing_probabilities`, with the body's
    `inertia` if given) with a learned correction.  For a gem inside the
    family box with every face stable, the gem family's discrepancy
    (:func:`~diefab.models.discrepancy.gem_discrepancy`), and for a gem made with a `fill` that has a
    learned correction of its own (:func:`~diefab.models.fills.fill_discrepancy`: paper,
    print, shell), that as well, in proportion to how far the body's
    inertia lies from the solid's (a body with the solid's inertia gets
    the solid's prediction).  Every other die gets the per-face logit correction
    learned from random dice of every family
    (:func:`diefab.models.correction.corrected`) when it lies in that correction's
    domain (no transitional face, features within the training range), and
    the chain alone otherwise: real printed dice with transitional faces
    are predicted better by the chain than by the correction extrapolated.  A gem is recognized by
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
