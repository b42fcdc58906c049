"""Learned corrections of gems made of card or printed: what a fill does that the solid gems' model misses.

Each of :data:`FILL_LAYERS` has its :class:`FillCorrection`, learned in that
fill at its default settings: a regularized linear function of the shape,
applied in proportion to the body's inertia excess over the solid
(:func:`body_excess`), on top of the chain with the body's centre and inertia
corrected by the gem discrepancy (:func:`made_gem_base`).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache, cached_property
from importlib import resources

import numpy as np

from diefab.core.errors import DesignError
from diefab.dice.families import GEM
from diefab.geometry.polyhedron import Polyhedron, face_margins
from diefab.models.chain import landing_probabilities
from diefab.models.discrepancy import GEM_MIRRORS, Discrepancy, gem_discrepancy, table_json

__all__ = [
    "DISCREPANCY_AT",
    "FILL_COORDINATES",
    "FILL_LAYERS",
    "FillCorrection",
    "body_excess",
    "fill_discrepancy",
    "fill_discrepancy_file",
    "made_gem_base",
]

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
    for i, j in GEM_MIRRORS:
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
        return table_json(self, scalars, 8)

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
