"""The gem family's discrepancy: what the chain model misses on gems, learned from simulation.

Simulated frequencies minus the chain's probabilities at random stable gems
(800 in the packaged data), interpolated by a smoothed thin-plate spline over
the parameters and the chain's own margins and probabilities
(:class:`Discrepancy`); :func:`diefab.models.fast.fast_model` adds it to the
chain's probabilities for a gem inside the family box.
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

__all__ = ["DISCREPANCY_FILE", "GEM_MIRRORS", "Discrepancy", "gem_discrepancy", "table_json"]

#: The gem family's discrepancy data, in the package (written by ``bench_fastmodel.py --learn``).
DISCREPANCY_FILE = "gem-discrepancy.json"

#: Mirror-image faces of every gem (x -> -x: f2 <-> f4, f7 <-> f9; z -> -z: f1 <-> f3, f6 <-> f8).
GEM_MIRRORS = ((0, 2), (1, 3), (5, 7), (6, 8))


def table_json(table, scalars: tuple[str, ...], digits: int) -> str:
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
        for i, j in GEM_MIRRORS:
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
        return table_json(self, ("parameters", "smoothing", "physics_coordinates", "info", "kernel"), 6)

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
        for i, j in GEM_MIRRORS:
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
