"""A learned per-face correction of the chain model, for any convex die.

The chain model (:func:`diefab.models.fast.landing_probabilities`) is general
but coarse, and its five constants were fitted to gems.  Here they are
refitted to random dice of every family dropped in pybullet, and what the
chain still misses is learned from the same dice: every face the die can
rest on gets a logit correction ``g_f`` that is a function of the face's
own geometry and physics, and

``p_f  ∝  chain_f * exp(g_f)``

over the resting faces (transitional faces stay at 0).  The features
(:func:`face_features`) are things every convex polyhedron has: the chain's
and the toppled solid angle's share, the stability margin, the lowest
tipping barrier, the rest height, the face's area and its inertia about its
normal, its neighbours' chain shares, how far the centre of mass stands off
the face's centroid, the face's share of first contacts at corners
(:func:`corner_shares`), and the die's face count, anisotropy and size as
interactions with the chain's share.  All are computed from the
geometry and the centre of mass alone, so faces that a symmetry of the die
maps onto each other get equal features and equal probabilities (a Platonic
solid stays uniform), and the model is deterministic.

``g`` is linear in the standardized features (``expansion="linear"``; the
first six of them, ``"small"``), or in them and their pairwise products
(``"quadratic"``), or in them and Gaussian kernels centred on training
faces (``"rbf"``).  The weights minimize the cross-entropy between the
simulated frequencies and ``p``, averaged over the training dice, plus a
ridge penalty; the expansion and the penalty are chosen by cross-validation
grouped by die
(``benchmarks/learn_correction.py --fit``).

Examples
--------
>>> from diefab.dice.design import load_design
>>> d8 = load_design("d8")
>>> p = corrected(d8.polyhedron, d8.mass_properties().center)
>>> bool(np.allclose(p, 1 / 8))
True
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources

import numpy as np

from diefab.core.errors import DesignError
from diefab.geometry.polyhedron import Polyhedron, face_margins, resting_faces, solid_angles

__all__ = [
    "CORRECTION_FILE",
    "FEATURES",
    "Correction",
    "corner_shares",
    "corrected",
    "face_features",
    "packaged_correction",
]

#: The fitted correction, in the package (written by ``benchmarks/learn_correction.py --fit``).
CORRECTION_FILE = "correction.json"

#: Names of the base features, in the columns of :func:`face_features`.
FEATURES = (
    "log_chain",  # log of the chain's probability
    "log_solid",  # log of the toppled solid-angle share
    "margin",  # stability margin / L
    "barrier",  # lowest tipping barrier over the face's edges / L
    "height",  # rest height of the centre of mass above the lowest rest / L
    "log_area",  # log of the face's area over the mean resting face's
    "spin",  # inertia about the face normal over the mean principal moment, minus 1
    "edges",  # the face's edge count over the mean resting face's
    "neighbors",  # mean log chain probability of the faces across its edges
    "log_chain_x_faces",  # log_chain times log(resting faces)
    "log_chain_x_anisotropy",  # log_chain times log(largest / smallest principal moment)
    "log_chain_x_size",  # log_chain times L (the cube root of the volume, model units)
    "offcenter",  # distance from the face's centroid to the foot of the centre of mass / sqrt(area)
    "log_corner",  # log of the face's share of first contacts at its corners (corner_shares)
)
#: Floor of a probability under a logarithm.
_FLOOR = 1e-4


def face_features(
    poly: Polyhedron, center: np.ndarray, chain: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Per-face features of the correction (:data:`FEATURES`) and the resting mask.

    Parameters
    ----------
    poly : Polyhedron
    center : (3,) float
        Centre of mass, model units.
    chain : (m,) float, optional
        The chain model's probabilities (default: with the module's constants;
        a :class:`Correction` passes its own chain's).  The inertia terms are
        the uniform solid's about `center`, as on the training dice.

    Returns
    -------
    features : (m, len(FEATURES)) float
        Rows of transitional faces are 0.
    resting : (m,) bool
    """
    from diefab.made.mass import mass_properties
    from diefab.models.fast import landing_probabilities, tipping_barriers

    center = np.asarray(center, dtype=float)
    m = len(poly.faces)
    resting = resting_faces(poly, center)
    if chain is None:
        chain = landing_probabilities(poly, center)
    props = mass_properties(poly)
    shift = center - props.center  # inertia about the stated centre of mass (parallel axes)
    inertia = (props.inertia + props.mass * (shift @ shift * np.eye(3) - np.outer(shift, shift))) / props.mass
    moments = np.linalg.eigvalsh(inertia)
    size = float(np.cbrt(poly.volume))

    barrier, _, across = tipping_barriers(poly, center)
    _, _, face, start = poly._ring
    lowest = np.minimum.reduceat(barrier, start)
    omega = np.clip(solid_angles(poly, center), 0, None)
    from diefab.models.fast import _topple_targets  # the share a transitional face passes on

    solid = np.bincount(_topple_targets(poly, center, barrier, across), weights=omega / omega.sum(), minlength=m)
    height = poly.offsets - poly.normals @ center
    log_chain = np.log(np.clip(chain, _FLOOR, None))
    edges = np.diff(np.append(start, len(face))).astype(float)
    neighbors = np.bincount(face, weights=log_chain[across], minlength=m) / edges
    spin = np.einsum("ij,jk,ik->i", poly.normals, inertia, poly.normals) / moments.mean() - 1
    foot = center + height[:, None] * poly.normals
    offcenter = np.linalg.norm(poly.face_centroids - foot, axis=1) / np.sqrt(poly.areas)
    r = resting
    out = np.column_stack(
        [
            log_chain,
            np.log(np.clip(solid, _FLOOR, None)),
            face_margins(poly, center) / size,
            np.clip(lowest, 0, None) / size,
            (height - height[r].min()) / size,
            np.log(poly.areas / poly.areas[r].mean()),
            spin,
            edges / edges[r].mean(),
            neighbors,
            log_chain * np.log(r.sum()),
            log_chain * np.log(moments[-1] / moments[0]),
            log_chain * size,
            offcenter,
            np.log(np.clip(corner_shares(poly), _FLOOR, None)),
        ]
    )
    out[~r] = 0.0
    return out, resting


def corner_shares(poly: Polyhedron) -> np.ndarray:
    """(m,) float: each face's share of the first contacts at corners, for a uniformly random orientation.

    A convex body dropped in a uniformly random orientation first touches
    the floor with its lowest vertex, and vertex *v* is the lowest for a
    solid angle of down directions equal to its angle defect (``2 pi`` minus
    the face angles at *v*; they sum to ``4 pi``).  Each vertex's share is
    split among its faces in proportion to their angles at it.  The shares
    sum to 1 and depend on the shape alone.
    """
    tail, head, face, start = poly._ring
    nxt = np.arange(len(face)) + 1
    ends = np.append(start[1:], len(face))
    nxt[ends - 1] = start  # the edge after a face's last one is its first
    a = poly.vertices[tail] - poly.vertices[head]
    b = poly.vertices[head[nxt]] - poly.vertices[head]
    cos = np.einsum("ij,ij->i", a, b) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
    angle = np.arccos(np.clip(cos, -1, 1))  # the face's angle at `head`
    total = np.bincount(head, weights=angle, minlength=len(poly.vertices))
    defect = 2 * np.pi - total
    return np.bincount(face, weights=defect[head] * angle / total[head], minlength=len(poly.faces)) / (4 * np.pi)


#: The base features the ``"small"`` expansion keeps (the first six: shares, margin, barrier, height, area).
SMALL = 6


#: Most kernel centres an ``"rbf"`` correction keeps.
CENTERS = 400


def _expand(x: np.ndarray, expansion: str, centers: np.ndarray | None = None, width: float = 1.0) -> np.ndarray:
    """(n, k) standardized features -> the regression's columns."""
    if expansion == "rbf":
        d2 = ((x[:, None, :] - centers[None, :, :]) ** 2).sum(axis=2)
        return np.hstack([x, np.exp(-d2 / (2 * width**2 * x.shape[1]))])
    if expansion == "small":
        return x[:, :SMALL]
    if expansion == "linear":
        return x
    if expansion == "quadratic":
        i, j = np.triu_indices(x.shape[1])
        return np.hstack([x, x[:, i] * x[:, j]])
    raise DesignError(f"expansion={expansion!r} is not 'small', 'linear', 'quadratic' or 'rbf'")


def _softmax_segments(z: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Softmax of `z` within each segment beginning at `starts`."""
    seg = np.repeat(np.arange(len(starts)), np.diff(np.append(starts, len(z))))
    e = np.exp(z - np.maximum.reduceat(z, starts)[seg])
    return e / np.add.reduceat(e, starts)[seg]


@dataclass(frozen=True, eq=False)
class Correction:
    """A fitted per-face logit correction (see the module docstring).

    Attributes
    ----------
    expansion : str
        ``"small"``, ``"linear"``, ``"quadratic"`` or ``"rbf"``.
    mean, scale : (k,) float
        Standardization of the base features (training means and deviations).
    weights : (c,) float
        Weights of the expanded columns.
    penalty : float
        The ridge penalty it was fitted with.
    chain : dict
        The chain's constants (keywords of
        :func:`~diefab.models.fast.landing_probabilities`) this correction
        corrects: refitted to the same training dice as the correction
        (empty: the module's constants).
    info : dict
        How it was made: training dice, drops, physics version, cross-validation.
    centers : (c, k) float, optional
        Kernel centres of an ``"rbf"`` correction (standardized features of training faces).
    width : float
        Their width, in standard deviations per feature.
    """

    expansion: str
    mean: np.ndarray
    scale: np.ndarray
    weights: np.ndarray
    penalty: float
    chain: dict = field(default_factory=dict)
    info: dict = field(default_factory=dict)
    centers: np.ndarray | None = None
    width: float = 1.0

    @classmethod
    def fit(
        cls,
        features: Sequence[np.ndarray],
        chains: Sequence[np.ndarray],
        frequencies: Sequence[np.ndarray],
        *,
        expansion: str = "linear",
        penalty: float = 1e-3,
        chain: dict | None = None,
        width: float = 1.0,
        info: dict | None = None,
    ) -> Correction:
        """Fit to training dice.

        Parameters
        ----------
        features : sequence of (m_i, k) float
            :func:`face_features` of each die's resting faces.
        chains : sequence of (m_i,) float
            The chain's probabilities of those faces (with the constants `chain`).
        frequencies : sequence of (m_i,) float
            Simulated frequencies of those faces (each sums to 1).
        expansion, penalty, chain, width
            See the class attributes (the centres of ``"rbf"`` are at most
            :data:`CENTERS` training faces, evenly taken).
        """
        from scipy.optimize import minimize

        if not len(features) == len(chains) == len(frequencies) or not features:
            raise DesignError("features, chains and frequencies must be equally long, non-empty sequences")
        x = np.vstack(features)
        mean, scale = x.mean(axis=0), x.std(axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        z = (x - mean) / scale
        centers = None
        if expansion == "rbf":
            centers = z[np.linspace(0, len(z) - 1, min(CENTERS, len(z))).round().astype(int)]
        a = _expand(z, expansion, centers, width)
        offset = np.log(np.clip(np.concatenate(chains), _FLOOR, None))
        q = np.concatenate(frequencies)
        sizes = np.array([len(f) for f in features])
        starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
        n = len(features)

        def loss(w: np.ndarray) -> tuple[float, np.ndarray]:
            z = offset + a @ w
            p = _softmax_segments(z, starts)
            logp = np.log(np.clip(p, 1e-300, None))
            value = -(q * logp).sum() / n + penalty * (w @ w)
            grad = a.T @ (p - q) / n + 2 * penalty * w  # each die's q sums to 1
            return value, grad

        options = {"maxiter": 10_000, "ftol": 1e-15, "gtol": 1e-10}
        res = minimize(loss, np.zeros(a.shape[1]), jac=True, method="L-BFGS-B", options=options)
        return cls(expansion, mean, scale, res.x, float(penalty), dict(chain or {}), dict(info or {}), centers,
                   float(width))  # fmt: skip

    def logits(self, features: np.ndarray) -> np.ndarray:
        """(m,) float: the logit correction of each row of base features."""
        return _expand((features - self.mean) / self.scale, self.expansion, self.centers, self.width) @ self.weights

    def correct(self, chain: np.ndarray, features: np.ndarray, resting: np.ndarray) -> np.ndarray:
        """(m,) float: the chain's probabilities `chain` corrected, 0 off the `resting` faces."""
        out = np.zeros(len(chain))
        if not resting.any():
            return out
        z = np.log(np.clip(chain[resting], _FLOOR, None)) + self.logits(features[resting])
        e = np.exp(z - z.max())
        out[resting] = e / e.sum()
        return out

    def __call__(
        self, poly: Polyhedron, center: np.ndarray, chain: np.ndarray | None = None, inertia: np.ndarray | None = None
    ) -> np.ndarray:
        """(m,) float: the corrected probabilities of `poly` with its centre of mass at `center`.

        `chain`, if given, must be the chain's probabilities with :attr:`chain`'s
        constants; `inertia` is the body's tensor about its centre of mass over
        its mass, which the chain takes (the features take the uniform solid's).
        """
        from diefab.models.fast import landing_probabilities

        if chain is None:
            chain = landing_probabilities(poly, center, inertia=inertia, **self.chain)
        features, resting = face_features(poly, center, chain)
        return self.correct(chain, features, resting)

    def to_json(self) -> str:
        data = {
            "expansion": self.expansion,
            "features": list(FEATURES),
            "penalty": self.penalty,
            "mean": self.mean.tolist(),
            "scale": self.scale.tolist(),
            "weights": self.weights.tolist(),
            "chain": self.chain,
            "info": self.info,
        }
        if self.centers is not None:
            data |= {"width": self.width, "centers": np.round(self.centers, 5).tolist()}
        return json.dumps(data, indent=1) + "\n"

    @classmethod
    def from_json(cls, text: str) -> Correction:
        data = json.loads(text)
        if data.get("features") != list(FEATURES):
            raise DesignError(f"the correction's features {data.get('features')} are not this version's {FEATURES}")
        arrays = (np.array(data[k], dtype=float) for k in ("mean", "scale", "weights"))
        centers = np.array(data["centers"], dtype=float) if "centers" in data else None
        return cls(data["expansion"], *arrays, float(data["penalty"]), data.get("chain", {}), data.get("info", {}),
                   centers, float(data.get("width", 1.0)))  # fmt: skip


@cache
def packaged_correction() -> Correction:
    """The :class:`Correction` packaged with diefab (read once)."""
    return Correction.from_json(resources.files("diefab").joinpath("data", CORRECTION_FILE).read_text())


def corrected(poly: Polyhedron, center: np.ndarray, *, inertia: np.ndarray | None = None) -> np.ndarray:
    """(m,) float: the chain model with the packaged correction (:func:`packaged_correction`).

    `inertia`: the body's inertia tensor about its centre of mass over its mass (default: the uniform solid's).
    """
    return packaged_correction()(poly, center, inertia=inertia)
