"""How hard real dice are thrown, and how much the table takes: fitted on some real dice, scored on others.

    nice -n 10 python benchmarks/bench_throw.py --workers 2 | tee benchmarks/results/bench_throw.txt
    nice -n 10 python benchmarks/bench_throw.py --workers 2 --vigor 1,1.5,2,2.5,3 \
        --capture 0,0.01,0.04,0.09,0.16,0.25,0.36,0.64,1 --each | tee benchmarks/results/bench_throw_capture.txt
    nice -n 10 python benchmarks/bench_throw.py --workers 2 --rest fast | tee benchmarks/results/bench_throw_rest.txt
    nice -n 10 python benchmarks/bench_throw.py --workers 2 --vigor 0.5,1,1.5,2 --slide 0,10,20,30 \
        | tee benchmarks/results/bench_throw_slide.txt
    nice -n 10 python benchmarks/bench_throw.py --workers 2 --vigor 0.5,1,1.5,2 --slide 0,10,20,30 --rest fast \
        --more | tee benchmarks/results/bench_throw_slide_more.txt
    nice -n 10 python benchmarks/bench_throw.py --workers 2 --rest fast \
        --more hendecahedron_2d6_sla,hendecahedron_2d6_v5 | tee benchmarks/results/bench_throw_more_2d6.txt
    nice -n 10 python benchmarks/bench_throw.py --workers 2 --vigor 0.5,1,1.5,2 --slide 0,10,20,30 --rest fast \
        --more --score-drops 3000 | tee benchmarks/results/bench_throw_slide_more_fresh.txt
    nice -n 10 python benchmarks/bench_throw.py --workers 2 --vigor 0.5,1,1.5,2 --slide 0,10,20,30 --rest fast \
        --more --drops 3000 --seed 6 | tee benchmarks/results/bench_throw_slide_more_3000.txt

(Each prints from the cache in under a minute to five minutes, most of it
the nested score refitting mixtures of up to 47 candidates.)

The throw is one number, its vigor (:func:`diefab.physics.throw.throw_settings`):
0.5 halfway from the source's gentle release, 1 the paper's drop (the
default), 2 a hard throw (twice the height and spin, a bouncier table), 3
as far again.  The table's quasi-static capture (``capture_energy``: a die
with less energy than this above rest stays in the basin it is in) is a
second axis, ``--capture``; the horizontal speed a die leaves the hand
with (``linear_velocity``, uniform from 0 to the candidate's, in any
direction) a third, ``--slide`` (the prior counts :data:`SLIDE_UNIT` as one
unit of vigor); the radius its edges and corners are rounded to
(``edge_radius``, model units) a fourth, ``--edge`` (:data:`EDGE_UNIT` one unit
of vigor); ``--flat-faces`` holds the faces a die rests on
flat (``flat_faces``) at every candidate.  ``--rest MODEL`` adds a landing model
(``fast``, ``basins``: what ``diefab predict`` gives) as one more candidate, the
quasi-static limit of the gentlest throw: its probabilities are weighted as if
drawn from ``--drops`` drops, and the prior places it at vigor 0 on a table
that keeps every die (capture 1).  Every die is simulated at every candidate
(``--drops`` drops, seed ``--seed``; cached with the other held-out
benchmarks in ``benchmarks/results/calibrate_loo_cache.jsonl``).  The sets
of real dice:

- *the eight*: the paper's gem and the seven shared dice (``--data``);
- *the cuboids*: the 15 published steel square cuboids
  (:func:`diefab.search.published.square_cuboid_dice`);
- with ``--more`` (or ``--more NAME,...`` for some of them), *the source's further dice*: the printed dice shipped
  from the source of the eight (:func:`diefab.search.published.printed_dice`),
  taken as rolled on the source's table, where the files do not say.

A die's candidate is the one of least deviance of the real counts of the
dice it is fitted on, plus a normal prior toward the default (vigor 1, no
capture, no slide, sharp edges; sd ``--prior`` in vigor, in the square root
of the capture, in slide over :data:`SLIDE_UNIT` and in edge radius over
:data:`EDGE_UNIT`),
or a mixture of the candidates (:func:`diefab.search.mixture.fit_weights`).  It is
scored on its own simulated drops at that candidate, which took no part in the
choice.  Rules, none of which sees the die it scores:

- ``loo``: fitted on every other die (22 without ``--more``);
- ``other set``: fitted on the dice of the other sets (the eight on the 15
  cuboids, the cuboids on the eight): a whole set held out;
- ``loo in set``: fitted on the other dice of its own set;
- ``mix loo``: the mixture fitted on every other die;
- ``hier``: two levels, surface and population.  The population's
  candidate is fitted on every other die; the die's is fitted on the
  other dice rolled on its surface (:data:`bench_heldout.SURFACE`; the
  cuboids share one) with the prior centred on the population's
  candidate, which alone decides for a die with no other die on its
  surface;
- ``nested``: the rule, and the part of the grid it chooses among (all;
  vigor up to 2; no capture; no slide; no rounding; no landing model), chosen for each die by an inner
  leave-one-out over every other die
  (:func:`diefab.search.crossval.nested_choices`, inner loss the TVD on
  their own drops): the held-out score of choosing, too.

Then the goal's checks on each set with the source's own columns, and on
every die together when there is more than one set.  With
``--score-drops N``, ``hier`` and ``nested`` are scored once more on N
fresh drops of each die (seed ``--score-seed``) at the candidates they
chose, beside the default: the choices stand, and the simulation's own
noise in the score shrinks.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_calibrate import Simulations  # noqa: E402
from bench_heldout import CACHE, REALROLLS, perfect_tvd, surface, table  # noqa: E402
from bench_mixture import goal  # noqa: E402

from diefab.core.errors import PhysicsError  # noqa: E402
from diefab.models.probabilities import value_probabilities  # noqa: E402
from diefab.physics.simulate import PhysicsSettings, shutdown_pool  # noqa: E402
from diefab.physics.throw import MAX_VIGOR, throw_settings  # noqa: E402
from diefab.search.crossval import nested_choices, pick_candidate  # noqa: E402
from diefab.search.fidelity import LANDING_MODELS, load_real_dice, noise_tvd  # noqa: E402
from diefab.search.likelihood import deviance, smoothed  # noqa: E402
from diefab.search.mixture import fit_weights, prior_penalty  # noqa: E402
from diefab.search.published import printed_dice, square_cuboid_dice  # noqa: E402

#: A landing-model candidate's "vigor" (its capture slot holds the model's name).
REST = -1.0
#: Its coordinates for the prior: the gentlest throw (vigor 0) on a table that keeps every die
#: in the first basin it rests in (capture 1), with no slide, the quasi-static limit these models assume.
REST_COORDS = (0.0, 1.0, 0.0, 0.0)
#: Horizontal speed (units/s) the prior counts as one unit of vigor: about the speed of a fall of 5 units.
SLIDE_UNIT = 10.0
#: Edge radius (model units, L) the prior counts as one unit of vigor: about 0.8 mm on a die of 30 mm.
EDGE_UNIT = 0.05


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vigor", default="0.5,1,1.5,2", help="the candidates' vigor, comma-separated (1 must be one)")
    ap.add_argument("--capture", default="0", help="the candidates' capture energy (m g L), comma-separated (0 one)")
    ap.add_argument("--slide", default="0",
                    help="the candidates' horizontal speed at release, units/s, comma-separated (0 one): the upper "
                         "end of a uniform range from 0 (linear_velocity), in any direction")  # fmt: skip
    ap.add_argument("--edge", default="0",
                    help="the candidates' edge and corner radius, model units, comma-separated (0 one): the die "
                         "rounded (edge_radius)")  # fmt: skip
    ap.add_argument("--flat-faces", action="store_true", help="hold the resting faces flat (flat_faces)")
    ap.add_argument("--each", action="store_true", help="also print every candidate on its own drops, in-sample")
    ap.add_argument("--rest", default="", help="landing models as candidates too, comma-separated (basins, fast)")
    ap.add_argument(
        "--more",
        nargs="?",
        const="all",
        default="",
        metavar="DICE",
        help="add the source's further printed dice (diefab.search.published.printed_dice) as a set: all of "
        "them, or those named (comma-separated)",
    )
    ap.add_argument("--drops", type=int, default=1000, help="simulated drops per die and candidate")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--score-drops", type=int, default=0,
                    help="also score hier and nested on this many fresh drops of each die at its chosen "
                         "candidates, and the default beside them (0: not)")  # fmt: skip
    ap.add_argument("--score-seed", type=int, default=5, help="the seed of those fresh drops")
    ap.add_argument(
        "--prior", type=float, default=0.5, help="prior sd toward the default, in vigor and sqrt(capture) (inf: none)"
    )
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--data", type=Path, default=REALROLLS)
    args = ap.parse_args()
    try:
        vigor = [float(v) for v in args.vigor.split(",")]
        capture = [float(c) for c in args.capture.split(",")]
        slide = [float(u) for u in args.slide.split(",")]
        edge = [float(r) for r in args.edge.split(",")]
    except ValueError:
        raise SystemExit(f"--vigor {args.vigor!r}, --capture {args.capture!r}, --slide {args.slide!r}, --edge "
                         f"{args.edge!r}: numbers separated by commas") from None  # fmt: skip
    if 1.0 not in vigor or 0.0 not in capture or 0.0 not in slide or 0.0 not in edge:
        raise SystemExit(f"--vigor {args.vigor!r} must include 1, --capture {args.capture!r}, --slide "
                         f"{args.slide!r} and --edge {args.edge!r} 0: the defaults")  # fmt: skip
    if not all(0 <= v <= MAX_VIGOR for v in vigor) or not all(0 <= c <= 1 for c in capture):
        raise SystemExit(f"--vigor in [0, {MAX_VIGOR:g}] and --capture in [0, 1]")
    try:  # the speeds the physics takes
        for u in slide:
            PhysicsSettings(linear_velocity=(0.0, u))
    except PhysicsError as exc:
        raise SystemExit(f"--slide {args.slide!r}: {exc}") from None
    try:
        for r in edge:
            PhysicsSettings(edge_radius=r)
    except PhysicsError as exc:
        raise SystemExit(f"--edge {args.edge!r}: {exc}") from None
    rest = [m for m in args.rest.split(",") if m]
    if not set(rest) <= set(LANDING_MODELS):
        raise SystemExit(f"--rest {args.rest!r}: landing models among {', '.join(LANDING_MODELS)}")
    cands = [(v, c, u, r) for v in vigor for c in capture for u in slide for r in edge]
    cands += [(REST, m, 0.0, 0.0) for m in rest]
    if not args.data.is_dir():
        raise SystemExit(f"no real-rolls folder {args.data}")
    if args.score_drops < 0:
        raise SystemExit(f"--score-drops {args.score_drops} must be >= 0")
    if args.score_drops and args.score_seed == args.seed:
        raise SystemExit(f"--score-seed {args.score_seed} must differ from --seed: fresh drops")
    if not args.prior > 0:
        raise SystemExit(f"--prior {args.prior} must be > 0 (inf: none)")
    further = printed_dice() if args.more else []
    if args.more and args.more != "all":
        wanted = args.more.split(",")
        if unknown := set(wanted) - {d.name for d in further}:
            raise SystemExit(f"--more {args.more!r}: no further die {', '.join(sorted(unknown))} "
                             f"(the dice: {', '.join(d.name for d in further)})")  # fmt: skip
        further = [d for d in further if d.name in wanted]
    started = time.perf_counter()
    groups = {"the eight": load_real_dice(args.data), "the published cuboids": square_cuboid_dice(),
              "the source's further dice": further}  # fmt: skip
    dice = [d for group in groups.values() for d in group]
    set_of = [k for k, group in enumerate(groups.values()) for _ in group]
    sets = [[i for i in range(len(dice)) if set_of[i] == k] for k in range(len(groups))]
    surfaces = [surface(d.name) if set_of[i] != 1 else "the cuboids' table" for i, d in enumerate(dice)]
    sims = Simulations(CACHE, args.workers)
    freq = np.zeros((len(dice), len(cands)), dtype=object)
    probs = np.zeros((len(dice), len(cands)), dtype=object)
    for k, (v, cap, u, r) in enumerate(cands):
        if v == REST:  # the landing model's probabilities, weighted as if drawn from as many drops
            for i, d in enumerate(dice):
                p = value_probabilities(d.design, cap)
                freq[i, k], probs[i, k] = p, d.symmetrized(smoothed(p * args.drops))
            print(f"  {label(v, cap, u, r)}: predicted  ({time.perf_counter() - started:.0f} s)", flush=True)
            continue
        for i, d in enumerate(dice):
            c = sims.counts_at(d, candidate_settings(cands[k], args.flat_faces), args.drops, args.seed)
            freq[i, k], probs[i, k] = c / c.sum(), d.symmetrized(smoothed(c))
        print(f"  {label(v, cap, u, r)}: simulated  ({time.perf_counter() - started:.0f} s)", flush=True)
    shutdown_pool()
    coords = np.array([REST_COORDS if v == REST else (v, np.sqrt(c), u / SLIDE_UNIT, r / EDGE_UNIT)
                       for v, c, u, r in cands])  # fmt: skip
    x0 = np.array([1.0, 0.0, 0.0, 0.0])
    dev = np.array([[deviance(d.counts, probs[i, k]) for k in range(len(cands))] for i, d in enumerate(dice)])
    default = cands.index((1.0, 0.0, 0.0, 0.0))

    everyone = np.ones(len(cands), dtype=bool)

    def grid(train: list[int], centre: np.ndarray = x0, among: np.ndarray = everyone) -> np.ndarray:
        w, ks = np.zeros(len(cands)), np.flatnonzero(among)
        w[ks[pick_candidate(dev[:, ks], train, coords[ks], centre, args.prior)]] = 1.0
        return w

    mixtures: dict[tuple[frozenset[int], bytes], np.ndarray] = {}  # the nested score refits the same sets twice

    def mix(train: list[int], among: np.ndarray = everyone) -> np.ndarray:
        key = (frozenset(train), among.tobytes())
        if key not in mixtures:
            w, ks = np.zeros(len(cands)), np.flatnonzero(among)
            penalty = prior_penalty(coords[ks], x0, args.prior)
            w[ks] = fit_weights([dice[j].counts for j in train], [np.array(list(probs[j, ks])) for j in train],
                                penalty)  # fmt: skip
            mixtures[key] = w
        return mixtures[key]

    def hier(rows: list[int], i: int, among: np.ndarray = everyone) -> np.ndarray:
        population = coords[int(np.argmax(grid(rows, among=among)))]
        return grid([j for j in rows if surfaces[j] == surfaces[i]], population, among)

    def scored(i: int, w: np.ndarray) -> float:
        """TVD of die `i`'s real rolls to its own simulated drops under the candidate weights `w`."""
        return dice[i].tvd(sum(w[k] * freq[i, k] for k in range(len(cands))))

    def in_set(i: int) -> int:
        return set_of[i]

    # a method predicts die `i` from the dice `rows` only (rows never hold i), among some of the candidates
    methods = {
        "loo": lambda rows, i, among: grid(rows, among=among),
        "other set": lambda rows, i, among: grid([j for j in rows if in_set(j) != in_set(i)], among=among),
        "loo in set": lambda rows, i, among: grid([j for j in rows if in_set(j) == in_set(i)], among=among),
        "mix loo": lambda rows, i, among: mix(rows, among),
        "hier": hier,
    }
    weights = {name: [m([j for j in range(len(dice)) if j != i], i, everyone) for i in range(len(dice))]
               for name, m in methods.items()}  # fmt: skip
    # the nested score: which rule, over which part of the grid, is itself chosen without the held-out die
    grids = {"": everyone, " vigor<=2": np.array([v <= 2.0 for v, c, u, r in cands]),
             " no capture": np.array([c == 0.0 for v, c, u, r in cands]),
             " no slide": np.array([u == 0.0 for v, c, u, r in cands]),
             " no edge": np.array([r == 0.0 for v, c, u, r in cands]),
             " no rest": np.array([v != REST for v, c, u, r in cands])}  # fmt: skip
    grids = {g: among for g, among in grids.items() if g == "" or not among.all()}
    choices = nested_choices(
        len(dice), {name + g: (lambda rows, i, m=m, among=among: m(list(rows), i, among))
                    for name, m in methods.items() for g, among in grids.items()},
        scored)  # fmt: skip
    weights["nested"] = [w for _, w, _ in choices]
    columns = {"perfect": [perfect_tvd(d, args.drops) for d in dice]}
    shown = [k for k, (v, cap, u, r) in enumerate(cands) if (cap == 0.0 and r == 0.0) or v == REST]  # others: too wide
    columns |= {label(*cands[k]): [d.tvd(freq[i, k]) for i, d in enumerate(dice)] for k in shown}
    for name, ws in weights.items():
        columns[name] = [scored(i, w) for i, w in enumerate(ws)]
    columns |= {k: [d.tvd(d.reference[k]) if k in d.reference else np.nan for d in dice]
                for k in ("ours", "bullet")}  # fmt: skip
    noise = [noise_tvd(d) for d in dice]

    if args.each:
        each_candidate(dice, groups, sets, cands, freq)
    slid = slide != [0.0]
    grid_text = f"vigor {args.vigor} x capture {args.capture}" + (f" x slide {args.slide}" if slid else "")
    grid_text += f" x edge {args.edge}" if edge != [0.0] else ""
    prior_text = "toward vigor 1 without capture" + (f" or slide (slide in {SLIDE_UNIT:g} units/s)" if slid else "")
    print(f"\nTVD to the real rolls, each die scored on its own {args.drops} drops (seed {args.seed}); "
          f"candidates: {grid_text}{', flat faces' * args.flat_faces}; prior sd {args.prior:g} {prior_text}; "
          f"perfect: a perfect model at {args.drops} drops")  # fmt: skip
    for heading, rows in zip(groups, sets):
        if not rows:
            continue
        print(f"\n{heading}:")
        shown = [c for c in columns if not np.isnan([columns[c][i] for i in rows]).all()]  # the source's, where given
        table([dice[i] for i in rows], {c: [columns[c][i] for i in rows] for c in shown}, [noise[i] for i in rows])
        mean_noise = np.mean([noise[i] for i in rows])
        for name in ("perfect", label(*cands[default]), *weights):
            m = np.nanmean([columns[name][i] for i in rows])
            print(f"  {name:<11} mean {m:.4f} = {m / mean_noise:.2f}x the noise")
        for name in weights:
            chosen = [chosen_label(weights[name][i], cands) for i in rows]
            print(f"  {name:<11} chosen per die: " + ", ".join(f"{dice[i].name} {c}" for i, c in zip(rows, chosen)))
        print("  nested      method per die: " + ", ".join(f"{dice[i].name} {choices[i][0]}" for i in rows))
    for heading, rows in goal_sets(dice, groups, sets):
        print(f"\ngoal checks on {heading}:")
        for name in weights:
            goal([dice[i] for i in rows], [columns[name][i] for i in rows],
                 [columns[label(*cands[default])][i] for i in rows], [noise[i] for i in rows], name)  # fmt: skip
    if args.score_drops:
        fresh_scores(dice, groups, sets, cands, weights, default, noise, sims, args, started)
    print(f"\n({time.perf_counter() - started:.0f} s)")
    return 0


def goal_sets(dice, groups, sets) -> list[tuple[str, list[int]]]:
    """The sets the goal is checked on: each with the source's own columns, and every die when there are several."""
    checked = [(h, rows) for h, rows in zip(groups, sets) if any("ours" in dice[i].reference for i in rows)]
    if sum(1 for rows in sets if rows) > 1:  # the goal is stated over every die with real rolls
        checked.append((f"every die of the run ({len(dice)})", list(range(len(dice)))))
    return checked


def candidate_settings(cand: tuple[float, float, float], flat_faces: bool) -> PhysicsSettings:
    """The physics of a simulated candidate (vigor, capture, slide, edge radius)."""
    v, cap, u, r = cand
    return throw_settings(v, PhysicsSettings(capture_energy=cap, flat_faces=flat_faces, linear_velocity=(0.0, u),
                                             edge_radius=r))  # fmt: skip


def fresh_scores(dice, groups, sets, cands, weights, default, noise, sims, args, started) -> None:
    """hier and nested scored on ``--score-drops`` fresh drops at each die's chosen candidates, beside the default.

    The choices stand as made; only the score is drawn afresh, so that the
    simulation's own noise (a perfect model's floor) is small beside the
    real rolls'.  A landing model has no simulation noise: it scores as before.
    """
    rules = ("hier", "nested")
    need = sorted({(i, int(k)) for r in rules for i, w in enumerate(weights[r]) for k in np.flatnonzero(w)}
                  | {(i, default) for i in range(len(dice))})  # fmt: skip
    fresh = {}
    for n, (i, k) in enumerate(need, 1):
        v, cap, _, _ = cands[k]
        if v == REST:
            fresh[i, k] = value_probabilities(dice[i].design, cap)
            continue
        c = sims.counts_at(dice[i], candidate_settings(cands[k], args.flat_faces), args.score_drops, args.score_seed)
        fresh[i, k] = c / c.sum()
        if n % 10 == 0 or n == len(need):
            print(f"  fresh drops: {n}/{len(need)} dice and candidates  ({time.perf_counter() - started:.0f} s)",
                  flush=True)  # fmt: skip
    shutdown_pool()
    columns = {"perfect": [perfect_tvd(d, args.score_drops) for d in dice],
               label(*cands[default]): [d.tvd(fresh[i, default]) for i, d in enumerate(dice)]}  # fmt: skip
    for r in rules:
        columns[r] = [d.tvd(sum(w[k] * fresh[i, k] for k in np.flatnonzero(w)))
                      for i, (d, w) in enumerate(zip(dice, weights[r]))]  # fmt: skip
    print(f"\nthe same choices, scored on {args.score_drops} fresh drops of each die (seed {args.score_seed}); "
          f"perfect: a perfect model at {args.score_drops} drops")  # fmt: skip
    for heading, rows in zip(groups, sets):
        if not rows:
            continue
        print(f"\n{heading}:")
        table([dice[i] for i in rows], {c: [columns[c][i] for i in rows] for c in columns}, [noise[i] for i in rows])
        mean_noise = np.mean([noise[i] for i in rows])
        for name, col in columns.items():
            m = np.mean([col[i] for i in rows])
            print(f"  {name:<11} mean {m:.4f} = {m / mean_noise:.2f}x the noise")
    for heading, rows in goal_sets(dice, groups, sets):
        print(f"\ngoal checks on {heading}, on the fresh drops:")
        for r in rules:
            goal([dice[i] for i in rows], [columns[r][i] for i in rows],
                 [columns[label(*cands[default])][i] for i in rows], [noise[i] for i in rows], r)  # fmt: skip


def each_candidate(dice, groups, sets, cands, freq) -> None:
    """Every candidate on its own drops, in-sample: TVD per die of the first set, and each set's mean."""
    first = sets[0]
    heads = [dice[i].name for i in first] + [f"mean {h.split()[-1]}" for h, rows in zip(groups, sets) if rows]
    print("\nevery candidate on its own drops (in-sample): TVD per die of " + list(groups)[0] + ", and each set's mean")
    print(f"  {'candidate':<16} " + " ".join(f"{h:>13}" for h in heads))
    for k, cand in enumerate(cands):
        t = [d.tvd(freq[i, k]) for i, d in enumerate(dice)]
        means = [np.mean([t[i] for i in rows]) for rows in sets if rows]
        print(f"  {label(*cand):<16} " + " ".join(f"{x:>13.4f}" for x in [t[i] for i in first] + means))


def chosen_label(w: np.ndarray, cands: list[tuple[float, float | str, float, float]]) -> str:
    """The candidates of weights `w` of at least 0.2, with their weights when mixed."""
    return "+".join(f"{x:.2f} {label(*cands[k])}" if x < 1 else label(*cands[k]) for k, x in enumerate(w) if x >= 0.2)


def label(vigor: float, capture: float | str, slide: float = 0.0, edge: float = 0.0) -> str:
    """A candidate's column: its vigor, and its capture, slide and edge radius where set; or the landing model."""
    if vigor == REST:
        return capture
    return (f"v={vigor:g}" + (f" c={capture:g}" if capture else "") + (f" u={slide:g}" if slide else "")
            + (f" r={edge:g}" if edge else ""))  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
