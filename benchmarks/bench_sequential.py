"""Anytime-valid verdicts: error rates under monitoring after every roll, and rolls to a verdict.

    python benchmarks/bench_sequential.py            # the full run (several minutes)
    python benchmarks/bench_sequential.py --quick    # fewer sequences

Prints, by simulation with fixed seeds, for the targets 4dF, 2d6 and a
uniform d6 (``diefab.stats.sequential``, alpha = 0.05):

1. type-I error under monitoring after every roll, up to a horizon:
   - a die exactly at the target, wrongly called "off by >= delta";
   - a die at TVD exactly delta (the target tilted exponentially towards
     high values), wrongly called "within delta";
   and the rate at which the confidence sequence misses the true die at any
   roll (an upper bound on both);
2. rolls to a verdict, for delta = 0.05 and 0.03:
   - "off": a die at TVD 2 delta (tilted), mean, median and 80th percentile
     of the roll at which the verdict is reached; beside the fixed-N chi-square
     test of the target at the same power (80 %, Monte-Carlo);
   - "within": a die exactly at the target; beside the rolls a fixed-N
     chi-square test needs to tell the target from a die at TVD delta with
     80 % power.

The chi-square test answers a weaker question (is the die *exactly* the
target?) at one pre-set N; the sequential test answers "within delta?" or
"off by at least delta?" and may be checked after every roll.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import brentq
from scipy.special import logsumexp

from diefab.dice.targets import parse_target
from diefab.stats.goodness import rolls_for_power, tvd
from diefab.stats.sequential import CONCENTRATIONS, FLOOR, PRIOR, SequentialTest, log_mixture_likelihood

ALPHA = 0.05
TARGETS = ("4df", "2d6", "uniform:6")


def tilted(t: np.ndarray, distance: float) -> np.ndarray:
    """The target tilted towards high values, p ∝ t exp(theta z), at TVD `distance` from it."""
    z = np.arange(len(t), dtype=float)
    z = (z - z.mean()) / z.std()

    def p(theta: float) -> np.ndarray:
        w = t * np.exp(theta * z)
        return w / w.sum()

    theta = brentq(lambda th: tvd(p(th), t) - distance, 0.0, 20.0, xtol=1e-14)
    return p(theta)


def coverage_misses(rolls: np.ndarray, p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Whether the confidence sequence ever excludes the true `p` over each row of rolls.

    Each Dirichlet(a) component predicts roll i with (count so far + a_x) / (i - 1 + sum a),
    so the mixture's log probability of every prefix is a cumulative sum.

    Parameters
    ----------
    rolls : (s, n) int value indices
    p : (k,) float, the die's true distribution
    t : (k,) float, the target (the mixture's centered components sit on it)

    Returns
    -------
    (s,) bool: the mixture likelihood ratio M_n(p) reached 1/alpha at some roll.
    """
    s, n = rolls.shape
    k = len(p)
    onehot = rolls[:, :, None] == np.arange(k)
    before = np.take_along_axis(np.cumsum(onehot, axis=1) - onehot, rolls[:, :, None], axis=2)[:, :, 0]
    priors = [np.full(k, PRIOR)] + [beta * t + FLOOR for beta in CONCENTRATIONS]
    parts = [np.cumsum(np.log((before + a[rolls]) / (np.arange(n) + a.sum())), axis=1) for a in priors]
    log_mix = logsumexp(np.stack(parts), axis=0) - np.log(len(parts))
    check = log_mixture_likelihood(np.bincount(rolls[0], minlength=k), t)
    assert abs(log_mix[0, -1] - check) < 1e-6 * max(1.0, abs(check))  # the same mixture as the library's
    return np.any(log_mix - np.cumsum(np.log(p[rolls]), axis=1) >= np.log(1 / ALPHA), axis=1)


def decided(rolls: np.ndarray, t: np.ndarray, delta: float, chunk: int = 2000) -> tuple[str, int | None]:
    """The library's verdict over one sequence, fed in chunks, checked after every roll."""
    test = SequentialTest(t, delta, ALPHA)
    for a in range(0, len(rolls), chunk):
        test.extend(rolls[a : a + chunk])
        if test.decided_at is not None:
            return test.decision, test.decided_at
    return "undecided", None


def type_one(spec: str, deltas, sequences: int, horizon: int, seed: int) -> None:
    t = parse_target(spec).probabilities
    cases = [("at target", t, None)] + [(f"at TVD {d:g}", tilted(t, d), d) for d in deltas]
    for name, p, boundary in cases:
        rng = np.random.default_rng([seed, len(name), int(1000 * (boundary or 0))])
        misses, wrong = 0, {d: 0 for d in deltas}
        start = time.perf_counter()
        for a in range(0, sequences, 50):
            rolls = rng.choice(len(t), size=(min(50, sequences - a), horizon), p=p)
            miss = coverage_misses(rolls, p, t)
            misses += int(miss.sum())
            # a wrong verdict needs a miss (the true die outside the set): check only those sequences
            for row in rolls[miss]:
                for d in deltas:
                    if boundary is not None and d != boundary:
                        continue
                    decision, _ = decided(row, t, d)
                    bad = "off" if boundary is None else "within"
                    wrong[d] += decision == bad
        took = time.perf_counter() - start
        errs = "  ".join(
            f"wrong '{'off' if boundary is None else 'within'}' at delta {d:g}: {wrong[d] / sequences:.4f}"
            for d in deltas
            if boundary is None or d == boundary
        )
        print(
            f"  {spec:10s} die {name:13s} {sequences} sequences x {horizon:,} rolls: "
            f"misses {misses / sequences:.4f}   {errs}   ({took:.0f} s)"
        )


def rolls_to_verdict(spec: str, delta: float, sequences: int, seed: int, cap: int) -> None:
    t = parse_target(spec).probabilities
    for name, p, want in (("off", tilted(t, 2 * delta), "off"), ("within", t, "within")):
        rng = np.random.default_rng([seed, int(delta * 1000), len(name)])
        stops, wrong, undecided = [], 0, 0
        start = time.perf_counter()
        for _ in range(sequences if want == "off" else max(sequences // 4, 10)):
            rolls = rng.choice(len(t), size=cap, p=p)
            decision, at = decided(rolls, t, delta)
            if decision == "undecided":
                undecided += 1
                stops.append(cap)
            else:
                wrong += decision != want
                stops.append(at)
        took = time.perf_counter() - start
        stops = np.array(stops)
        if want == "off":
            other = "chi2 N (80 % power vs this die)"
            n_chi2 = rolls_for_power(t, p, 0.8, ALPHA, method="monte-carlo", samples=4000, seed=seed)
        else:
            other = f"chi2 N (80 % power vs a die at TVD {delta:g})"
            n_chi2 = rolls_for_power(t, tilted(t, delta), 0.8, ALPHA, method="monte-carlo", samples=4000, seed=seed)
        mean, med, p80 = stops.mean(), np.median(stops), np.percentile(stops, 80)
        print(
            f"  {spec:10s} delta {delta:g}  '{want}' (die at TVD {2 * delta if want == 'off' else 0:g}): "
            f"{len(stops)} runs, mean {mean:,.0f}, median {med:,.0f}, 80th pct {p80:,.0f} rolls"
            f"{f', {undecided} undecided at {cap:,}' if undecided else ''}{f', {wrong} wrong' if wrong else ''}; "
            f"{other} {n_chi2:,}; ratio mean/chi2 {mean / n_chi2:.2f}, 80th pct/chi2 {p80 / n_chi2:.2f}"
            f"   ({took:.0f} s)"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer sequences (a rough check)")
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--part", type=int, choices=(1, 2), default=None, help="only part 1 or part 2")
    args = ap.parse_args()
    sequences, horizon = (200, 5_000) if args.quick else (1_000, 10_000)
    runs = 20 if args.quick else 60
    print(
        f"diefab.stats.sequential: mixture of Dirichlet({PRIOR}) and Dirichlet(beta t) for beta in {CONCENTRATIONS}, "
        f"alpha {ALPHA}, seed {args.seed}"
    )
    if args.part in (None, 1):
        print(f"1. type-I error under monitoring after every roll (up to {horizon:,} rolls)")
        for spec in TARGETS:
            type_one(spec, (0.05, 0.03), sequences, horizon, args.seed)
    if args.part in (None, 2):
        print("2. rolls to a verdict ('off': die at TVD 2 delta; 'within': die exactly at the target)")
        for delta in (0.05, 0.03):
            for spec in TARGETS:
                rolls_to_verdict(spec, delta, runs, args.seed, cap=200_000)


if __name__ == "__main__":
    main()
