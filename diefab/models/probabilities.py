"""Landing-probability models.

A model maps a polyhedron and its centre of mass to the probability of
resting on each face.  ``solid-angle`` is the paper's: the solid angle each
face subtends at the centre of mass, over 4 pi.  More models register
themselves in :data:`MODELS`.

Every model gives a transitional face (one the die cannot rest on, see
:func:`~diefab.geometry.polyhedron.resting_faces`) probability 0.

Examples
--------
>>> from diefab.dice.design import load_design
>>> probs = value_probabilities(load_design("d6"), "solid-angle")
>>> bool(np.allclose(probs, 1 / 6))
True
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.design import Design
from diefab.geometry.polyhedron import Polyhedron, resting_faces, solid_angles
from diefab.made.mass import Fill, MassProperties
from diefab.models.basins import RestBasins

__all__ = [
    "FILL_MODELS",
    "MODELS",
    "basin_shares",
    "basins_model",
    "face_probabilities",
    "model_probabilities",
    "solid_angle_model",
    "to_values",
    "value_probabilities",
]

Model = Callable[[Polyhedron, np.ndarray], np.ndarray]


def solid_angle_model(poly: Polyhedron, center: np.ndarray) -> np.ndarray:
    """(m,) float: solid angle of each face at `center` over 4 pi.

    The die first touches down on the face the downward ray from the centre
    of mass meets.  If that face is transitional it tips off it and rolls
    downhill; its share goes to the resting face where that quasi-static
    flow ends (:attr:`RestBasins.targets <diefab.models.basins.RestBasins>`).
    """
    omega = solid_angles(poly, center)
    p = omega / omega.sum()
    if resting_faces(poly, center).all():
        return p
    return np.bincount(RestBasins.of(poly, center).targets, weights=p, minlength=len(p))


def basin_shares(poly: Polyhedron, center: np.ndarray) -> tuple[np.ndarray, float]:
    """(m,) float and its error bound: the share of orientations whose downhill flow ends on each face.

    The quasi-static model of Baktash et al.: a die let go in a uniformly
    random orientation creeps downhill, without bouncing, to the resting
    face whose basin that orientation lies in (:class:`RestBasins`).  The
    basins are measured as spherical polygons
    (:meth:`RestBasins.exact_shares`): exact up to a bisection of their rims,
    whose remaining share of the sphere is the bound (about 1e-14).  The
    adaptive cube map (:meth:`RestBasins.shares`, bound about 1e-3) is the
    slower cross-check.
    """
    return RestBasins.of(poly, center).exact_shares()


def basins_model(poly: Polyhedron, center: np.ndarray) -> np.ndarray:
    """(m,) float: :func:`basin_shares` without the bound (``MODELS["basins"]``)."""
    return basin_shares(poly, center)[0]


from diefab.models.fast import fast_model  # noqa: E402 -- calibrated against pybullet

MODELS: dict[str, Model] = {"solid-angle": solid_angle_model, "fast": fast_model, "basins": basins_model}
#: Models that take the fill and the body's inertia (keywords ``fill`` and ``inertia``) as well.
FILL_MODELS = {"fast"}


def _model(name: str) -> Model:
    try:
        return MODELS[name]
    except KeyError:
        raise DesignError(f"unknown model {name!r} (models: {', '.join(MODELS)})") from None


def model_probabilities(name: str, poly: Polyhedron, body: MassProperties, fill: Fill | None = None) -> np.ndarray:
    """(m,) float: model `name` at a die made of `fill` whose mass properties are `body`.

    Models in :data:`FILL_MODELS` are given the fill and the inertia as
    well; the others see the centre of mass alone.
    """
    fn = _model(name)
    if name in FILL_MODELS:
        return fn(poly, body.center, fill=fill, inertia=body.inertia / body.mass)
    return fn(poly, body.center)


def face_probabilities(design: Design, model: str = "solid-angle", fill: Fill | None = None) -> np.ndarray:
    """(m,) float: probability of resting on each face, in face order."""
    return model_probabilities(model, design.polyhedron, design.mass_properties(fill), fill or design.fill)


def to_values(design: Design, face_probs: np.ndarray) -> np.ndarray:
    """Sum face probabilities (or counts) into the design's values, increasing (transitional faces left out)."""
    index = {v: i for i, v in enumerate(design.support)}
    names = design.polyhedron.names
    which = [index[design.values[n]] for n in names if n in design.values]
    return np.bincount(which, weights=np.asarray(face_probs)[design.resting_mask()], minlength=len(index))


def value_probabilities(design: Design, model: str = "solid-angle", fill: Fill | None = None) -> np.ndarray:
    """(k,) float: probability of each value of ``design.support``."""
    return to_values(design, face_probabilities(design, model, fill))
