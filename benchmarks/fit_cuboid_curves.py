"""How close any smooth law of the aspect ratio comes to the 15 published cuboids: a ceiling for every model.

    python benchmarks/fit_cuboid_curves.py --per-die | tee benchmarks/results/fit_cuboid_curves.txt

A landing model of fixed physics sees a square cuboid only through its
aspect ratio r = x/y, and gives its square faces a share p(r) that varies
smoothly with r.  So the best a model can do on these dice is bounded by
the best smooth curve through their counts.  Curves tried, each fitted by
binomial maximum likelihood (with p(1) = 1/3 where stated: a cube is fair):

- ``gibbs``: 1 / (1 + 2 exp((r - 1) / 2T)), the Gibbs law with the centre
  of mass's rest height as the energy (one parameter, T);
- ``logit k``: logit p polynomial of degree k in log r;
- ``two-sided logit k``: one such polynomial for r < 1 (square faces the
  larger) and another for r > 1, meeting at the fair cube.

Each is scored in-sample and held out (each die from a fit on the other 14),
by its mean TVD over the mean sampling noise (and, with ``--per-die``, each
die's held-out TVD over its own noise), and by Pearson's chi-square of
the counts about the in-sample fit, with its p-value: a small p-value says
the dice scatter about the curve more than binomial sampling allows (the
dice differ in more than their ratio: their throwers, their surface, their
finish), and then no model of the ratio alone can come within the noise.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.optimize import minimize
from scipy.special import expit
from scipy.stats import chi2

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from diefab.search.fidelity import noise_tvd  # noqa: E402
from diefab.search.published import square_cuboid_dice  # noqa: E402


def curves(r: np.ndarray) -> dict[str, tuple]:
    """Each curve's p(square) at the ratios `r` as a function of its parameters, and its start."""
    u = np.log(r)

    def logit(degree: int, fair: bool):
        def p(theta: np.ndarray) -> np.ndarray:
            offset = np.log(2.0) if fair else theta[-1]
            return expit(-(offset + sum(t * u ** (k + 1) for k, t in enumerate(theta[:degree]))))

        return p, np.r_[3.0, np.zeros(degree - 1), [] if fair else [np.log(2.0)]]

    def two_sided(degree: int):
        def p(theta: np.ndarray) -> np.ndarray:
            below, above = (sum(t * u ** (k + 1) for k, t in enumerate(half)) for half in np.split(theta, 2))
            return expit(-(np.log(2.0) + np.where(u < 0, below, above)))

        return p, np.tile(np.r_[3.0, np.zeros(degree - 1)], 2)

    return {"gibbs (p(1) = 1/3)": (lambda t: expit(-(np.log(2.0) + (r - 1) / (2 * np.exp(t[0])))), np.array([-2.0])),
            **{f"logit {k} (p(1) = 1/3)": logit(k, True) for k in (1, 2, 3)},
            **{f"logit {k}": logit(k, False) for k in (1, 2, 3)},
            **{f"two-sided logit {k}": two_sided(k) for k in (1, 2)}}  # fmt: skip


def fit(p, start: np.ndarray, square: np.ndarray, n: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The parameters of greatest binomial likelihood of the counts of `rows`."""

    def nll(theta: np.ndarray) -> float:
        q = np.clip(p(theta)[rows], 1e-12, 1 - 1e-12)
        return -float(np.sum(square[rows] * np.log(q) + (n - square)[rows] * np.log1p(-q)))

    options = {"maxfev": 20_000, "xatol": 1e-9, "fatol": 1e-10}
    return minimize(nll, start, method="Nelder-Mead", options=options).x


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-die", action="store_true", help="also each die's held-out TVD over its noise")
    args = parser.parse_args(argv)
    dice = square_cuboid_dice()
    n = np.array([d.n for d in dice])
    square = np.array([d.counts[1] for d in dice])
    r = np.array([float(d.name.removeprefix("cuboid-")) for d in dice])
    noise = np.array([noise_tvd(d) for d in dice])

    def tvd(i: int, q: float) -> float:
        return dice[i].tvd(np.array([1 - q, q]))

    everyone = np.arange(len(dice))
    per_die = {}
    print(f"the {len(dice)} published square cuboids ({n.sum()} rolls): smooth laws p_square(x/y), "
          f"mean noise {noise.mean():.4f}\n")  # fmt: skip
    print(f"{'curve':<24} {'params':>6} {'in-sample':>17} {'held out':>17} "
          f"{'chi-square':>11} {'dof':>4} {'p-value':>8}")  # fmt: skip
    for name, (p, start) in curves(r).items():
        q = p(fit(p, start, square, n, everyone))
        inside = np.mean([tvd(i, q[i]) for i in everyone])
        held_each = np.array([tvd(i, p(fit(p, start, square, n, everyone[everyone != i]))[i]) for i in everyone])
        held = held_each.mean()
        per_die[name] = held_each / noise
        pearson = float(np.sum((square - n * q) ** 2 / (n * q * (1 - q))))
        dof = len(dice) - len(start)
        print(f"{name:<24} {len(start):>6} {inside:>8.4f} ({inside / noise.mean():.2f}x) "
              f"{held:>8.4f} ({held / noise.mean():.2f}x) "
              f"{pearson:>11.1f} {dof:>4} {chi2.sf(pearson, dof):>8.1e}")  # fmt: skip
    print(
        "\nin-sample: fitted on all 15; held out: each die from a fit on the other 14; "
        "chi-square: Pearson's, of the counts about the in-sample fit"
    )
    if args.per_die:
        print("\neach die held out, its TVD over its own sampling noise:")
        print(f"{'curve':<24} " + " ".join(f"{x:>5.2f}" for x in r))
        for name, ratio in per_die.items():
            print(f"{name:<24} " + " ".join(f"{x:>5.1f}" for x in ratio))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
