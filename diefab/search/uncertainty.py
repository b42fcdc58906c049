"""The uncertainty of fitted physics settings: curvature of the deviance, and the grid's likelihood interval.

`spec` below is the run's :class:`diefab.search.calibrate.CalibrationSpec`
(its ``names`` and its map ``values`` from the unit cube to the settings).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["curvature", "grid_interval"]


def curvature(
    records: Sequence[Mapping[str, Any]], spec, best: Mapping[str, Any]
) -> dict[str, dict[str, float | None]]:
    """Standard errors of the fitted parameters from the curvature of the deviance (plus the prior) at `best`.

    A quadratic in the parameters is fitted by least squares to the total
    deviance of the feasible evaluations at `best`'s drop count nearest to
    it (at least three per coefficient); the covariance is ``2 H⁻¹``.
    Returns ``{name: {"value", "se"}}``; ``se`` is None for a parameter
    that leans on a direction along which the fitted deviance is flat or
    curved downwards (a standard error there would exceed the searched
    range: the counts do not determine it), and for every parameter when
    too few evaluations are near.
    """
    names = spec.names
    d = len(names)
    value = dict(best["params"])
    out: dict[str, dict[str, float | None]] = {n: {"value": float(value[n]), "se": None} for n in names}
    pts = [r for r in records if r.get("feasible") and r.get("drops") == best["drops"] and "deviance" in r]
    ncoef = (d + 1) * (d + 2) // 2
    if len(pts) < ncoef + 2:
        return out
    x0 = np.array(best["x"])
    xs = np.array([r["x"] for r in pts])
    order = np.argsort(np.linalg.norm(xs - x0, axis=1))[: max(3 * ncoef, 20)]
    xs = xs[order] - x0
    ys = np.array([pts[i]["deviance"] + pts[i].get("prior", 0.0) for i in order])
    iu = np.triu_indices(d)
    quad = np.einsum("ni,nj->nij", xs, xs)[:, iu[0], iu[1]]
    design = np.hstack([np.ones((len(xs), 1)), xs, quad])
    coef, *_ = np.linalg.lstsq(design, ys, rcond=None)
    h = np.zeros((d, d))
    h[iu] = coef[1 + d :]
    h = h + h.T  # the diagonal's coefficient is h_ii / 2, an off-diagonal's is h_ij
    w, v = np.linalg.eigh(h)
    # a direction whose standard error would exceed the whole searched range is not determined
    good = w > 2.0
    for i, n in enumerate(names):
        if np.all(np.abs(v[i, ~good]) < 0.1):
            se = float(np.sqrt(2.0 * np.sum(v[i, good] ** 2 / w[good])))
            # unit cube -> parameter units: half the image of x ± se (the slope, where the map is linear)
            hi, lo = x0.copy(), x0.copy()
            hi[i], lo[i] = min(x0[i] + se, 1.0), max(x0[i] - se, 0.0)
            span = (spec.values(hi)[i] - spec.values(lo)[i]) / (hi[i] - lo[i]) if hi[i] > lo[i] else 0.0
            out[n]["se"] = float(se * span)
    return out


def grid_interval(records: Sequence[Mapping[str, Any]], spec, best: Mapping[str, Any],
                  rise: float = 1.0) -> dict[str, tuple[float, float]] | None:  # fmt: skip
    """Each parameter's range over the grid points whose deviance (plus the prior) is within `rise` of `best`'s.

    Each point counts with its deviance at the most drops it was dropped
    with (a point the halving dropped early keeps its early, noisier value).
    With ``rise=1`` it is the grid's picture of the one-sigma
    likelihood-ratio interval (ΔG² = 1 for one parameter); its ends are grid
    points, so it is no finer than the grid.  None when fewer than three
    points were evaluated.
    """
    latest: dict[tuple, tuple[int, float, np.ndarray]] = {}
    for r in records:
        if r.get("feasible") and "deviance" in r:
            key = tuple(np.round(r["x"], 9))
            if key not in latest or r["drops"] >= latest[key][0]:
                latest[key] = (r["drops"], r["deviance"] + r.get("prior", 0.0), spec.values(r["x"]))
    if len(latest) < 3:
        return None
    least = best["deviance"] + best.get("prior", 0.0)
    near = np.array([v for _n, dev, v in latest.values() if dev <= least + rise])
    return {n: (float(near[:, i].min()), float(near[:, i].max())) for i, n in enumerate(spec.names)}
