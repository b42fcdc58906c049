"""A response surface of simulated probabilities, and physics settings fitted through it.

Simulating every candidate setting is what calibration costs.  A quadratic
surface in the settings, fitted to a design of simulated points per die
(:func:`fit_surface`), predicts each die's face probabilities between them;
:func:`fit_settings` then minimizes the real dice's deviance over the
surface, with a prior toward the starting settings (:func:`prior_penalty`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from diefab.search.likelihood import SMOOTHING, deviance
from diefab.search.realdie import CalibrationError, RealDie

__all__ = ["ResponseSurface", "fit_settings", "fit_surface", "prior_penalty", "quadratic_features"]


def quadratic_features(x: np.ndarray, cross: bool = True) -> np.ndarray:
    """(m, d) points of the unit cube -> features 1, x and the products x_i x_j (i <= j).

    That is 1 + d + d(d+1)/2 features; without `cross`, only the squares
    x_i² (1 + 2d).  The points are centred on the cube's middle first, so
    the linear terms are the slopes there.

    Examples
    --------
    >>> quadratic_features(np.array([[1.0, 0.5]])).tolist()
    [[1.0, 0.5, 0.0, 0.25, 0.0, 0.0]]
    >>> quadratic_features(np.array([[1.0, 0.5]]), cross=False).tolist()
    [[1.0, 0.5, 0.0, 0.25, 0.0]]
    """
    x = np.atleast_2d(np.asarray(x, dtype=float)) - 0.5
    if not cross:
        return np.hstack([np.ones((len(x), 1)), x, x**2])
    iu = np.triu_indices(x.shape[1])
    return np.hstack([np.ones((len(x), 1)), x, (x[:, :, None] * x[:, None, :])[:, iu[0], iu[1]]])


@dataclass(frozen=True)
class ResponseSurface:
    """Value probabilities of a die as a smooth function of the calibration parameters.

    ``p(x) = softmax(features(x) @ coef)``, quadratic in the logits: a
    multinomial logistic regression of simulated counts on the unit-cube
    point of the settings that produced them (:func:`fit_surface`).  It
    pools the simulations of every candidate setting, so its probabilities
    carry far less simulation noise than any one candidate's counts and can
    be minimized over the whole box, not only at the simulated points.
    """

    coef: np.ndarray  # (features, k)
    drops: int  # drops per simulated point (sets the smoothing)
    cross: bool = True  # products of different settings among the features (quadratic_features)

    def probabilities(self, x: np.ndarray) -> np.ndarray:
        """(m, d) or (d,) unit-cube points -> (m, k) or (k,) probabilities."""
        single = np.ndim(x) == 1
        z = quadratic_features(x, self.cross) @ self.coef
        z -= z.max(axis=1, keepdims=True)
        p = np.exp(z)
        p /= p.sum(axis=1, keepdims=True)
        return p[0] if single else p

    def smoothed(self, x: np.ndarray) -> np.ndarray:
        """:meth:`probabilities` smoothed like :func:`smoothed`, at the simulated drop count."""
        p = self.probabilities(x)
        k = p.shape[-1]
        return (p * self.drops + SMOOTHING) / (self.drops + SMOOTHING * k)


def fit_surface(xs: np.ndarray, counts: np.ndarray, *, ridge: float = 1e-2, cross: bool | None = None
                ) -> ResponseSurface:  # fmt: skip
    """Fit a :class:`ResponseSurface` to simulated `counts` (m, k) at unit-cube points `xs` (m, d).

    Maximizes the multinomial likelihood of the counts with a ridge penalty
    ``ridge / 2 * |coef|²`` on the non-constant coefficients (which keeps a
    value never simulated at a finite logit).  The first value's logits are
    fixed at zero.  `cross` (default: when there are at least twice as many
    points as full quadratic features) keeps the products of different
    settings; without them the surface has 1 + 2d coefficients per value.

    Examples
    --------
    A coin whose heads probability rises linearly over a 1-d box:

    >>> xs = np.linspace(0, 1, 11)[:, None]
    >>> heads = np.round(1000 * (0.3 + 0.4 * xs[:, 0])).astype(int)
    >>> s = fit_surface(xs, np.c_[1000 - heads, heads])
    >>> [round(float(v), 2) for v in s.probabilities(np.array([[0.0], [0.5], [1.0]]))[:, 1]]
    [0.3, 0.5, 0.7]
    """
    from scipy.optimize import minimize

    xs = np.atleast_2d(np.asarray(xs, dtype=float))
    counts = np.asarray(counts, dtype=float)
    if counts.ndim != 2 or len(counts) != len(xs) or counts.shape[1] < 2:
        raise CalibrationError(f"counts of shape {counts.shape} do not match {len(xs)} points with 2 or more values")
    if cross is None:
        cross = len(xs) >= 2 * quadratic_features(xs[:1]).shape[1]
    phi = quadratic_features(xs, cross)
    f, k = phi.shape[1], counts.shape[1]
    n = counts.sum(axis=1, keepdims=True)
    penalty = np.ones((f, 1))
    penalty[0] = 0.0
    scale = float(n.sum())  # the likelihood per drop keeps the optimizer's tolerances meaningful

    def loss(theta: np.ndarray) -> tuple[float, np.ndarray]:
        coef = np.zeros((f, k))
        coef[:, 1:] = theta.reshape(f, k - 1)
        z = phi @ coef
        z -= z.max(axis=1, keepdims=True)
        logp = z - np.log(np.exp(z).sum(axis=1, keepdims=True))
        nll = -float(np.sum(counts * logp)) + 0.5 * ridge * float(np.sum(penalty * coef**2))
        grad = phi.T @ (n * np.exp(logp) - counts) + ridge * penalty * coef
        return nll / scale, grad[:, 1:].ravel() / scale

    # start from the pooled frequencies
    pooled = counts.sum(axis=0) + SMOOTHING
    theta0 = np.zeros((f, k - 1))
    theta0[0] = np.log(pooled[1:] / pooled[0])
    res = minimize(loss, theta0.ravel(), jac=True, method="L-BFGS-B", options={"maxiter": 5000})
    coef = np.zeros((f, k))
    coef[:, 1:] = res.x.reshape(f, k - 1)
    return ResponseSurface(coef, int(round(float(n.mean()))), bool(cross))


def prior_penalty(x: np.ndarray, x0: np.ndarray, sigma: float) -> float:
    """``Σ ((x - x0) / sigma)²``: minus twice the log of a normal prior around `x0` (unit cube), in deviance units."""
    if not np.isfinite(sigma):
        return 0.0
    return float(np.sum(((np.asarray(x) - np.asarray(x0)) / sigma) ** 2))


def fit_settings(
    dice: Sequence[RealDie],
    surfaces: Sequence[ResponseSurface],
    x0: np.ndarray,
    *,
    sigma: float = math.inf,
    starts: Sequence[np.ndarray] = (),
) -> tuple[np.ndarray, float]:
    """The unit-cube point that minimizes the dice's total deviance under their response surfaces.

    The deviance of each die's real counts against its surface's smoothed
    probabilities (averaged within its groups), summed over the dice, plus
    :func:`prior_penalty` toward `x0` with width `sigma` (infinite: no
    prior).  L-BFGS-B in the unit cube from `x0` and each of `starts`.

    Returns
    -------
    x : (d,) float
    objective : float
        The total deviance plus the penalty at `x`.
    """
    from scipy.optimize import minimize

    x0 = np.asarray(x0, dtype=float)

    def total(x: np.ndarray) -> float:
        dev = sum(deviance(d.counts, d.symmetrized(s.smoothed(x))) for d, s in zip(dice, surfaces))
        return dev + prior_penalty(x, x0, sigma)

    best_x, best_f = x0, total(x0)
    for start in [x0, *starts]:
        res = minimize(total, np.asarray(start, dtype=float), method="L-BFGS-B", bounds=[(0.0, 1.0)] * len(x0))
        if res.fun < best_f:
            best_x, best_f = np.clip(res.x, 0.0, 1.0), float(res.fun)
    return best_x, best_f
