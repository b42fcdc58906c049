"""Reading marked dice from rendered frames: accuracy on rests, rolls counted in videos, frames per second.

    python benchmarks/bench_read.py [--rests 2000] [--drops 200] [--dice gem,d6,bipyramid24,d20] [--seed 1]
    python benchmarks/bench_read.py --rests 0 --drops 0 --others 50

(`--rests 0` or `--drops 0` leaves that part out, so the parts may run side by side.)
`--others N`: N rendered rests of each die read as each other die of `--dice` (its markers numbered
from the same dictionary): how many are read, which is always wrong, and how many are unread.

For each die: `--rests` rendered rests (a resting face drawn uniformly, any
yaw, random camera tilt up to 6 degrees, lens 55-75 degrees while the reader
assumes 65, light, blur, noise, JPEG, and in 15 % of frames a finger from
outside reaching to 0.6-1 image radius of the die's centre) read one by one
over the whole frame: read correctly, wrong values, unread (and unread with a
clear view, no finger over the die).  Then a rendered video of `--drops` simulated drops (one
fixed camera, a hand takes the die away before each drop, motion blur):
drops counted exactly once, missed, counted twice, wrong.  Frames per second
of the reader at 1280x720 on one core (OpenCV limited to one thread; the
process's CPU time, so a machine shared with other jobs gives the figure a
core of its own would), beside the straightforward baseline that detects and
solves every frame in full.
"""

from __future__ import annotations

import argparse
import sys
import time


def _progress(what: str, done: int, total: int, start: float, so_far: str = "") -> None:
    """One line on stderr: how far, the figures so far, and the time left at the rate so far."""
    spent = time.perf_counter() - start
    left = spent / done * (total - done) if done else float("nan")
    print(f"  {what}: {done}/{total}{so_far}, {spent:.0f} s, about {left:.0f} s left", file=sys.stderr, flush=True)


def dice():
    from diefab import Design, load_design

    bipyramid = Design(
        name="bipyramid-24", family="bipyramid", params={"n": 12, "h": 1.0},
        values={f"f{i + 1}": i + 1 for i in range(24)}, target="uniform:24", size_mm=30.0,
    )  # fmt: skip
    return {
        "gem": load_design("fudge-gem"),
        "d6": load_design("d6"),
        "bipyramid24": bipyramid,
        "d20": load_design("d20"),
    }


def bench_rests(design, n: int, seed: int) -> dict:
    from diefab.camera.pose import Camera, MarkerDetector, read_frame
    from diefab.camera.rig import rendered_rests
    from diefab.dice.markers import marker_layout

    layout = marker_layout(design)
    detector = MarkerDetector(layout)
    camera = Camera.from_fov(1280, 720)
    ok = wrong = unread = occluded = unread_occluded = 0
    spent = 0.0
    start = time.perf_counter()
    for i, rest in enumerate(rendered_rests(design, layout, n, seed)):
        if i and i % 50 == 0:
            so_far = f" (read {ok}, wrong {wrong}, unread {unread}, {unread_occluded} of them under a finger)"
            _progress(f"{design.name} rests", i, n, start, so_far)
        t = time.process_time()
        read = read_frame(rest.image, design, detector, camera)
        spent += time.process_time() - t
        occluded += rest.occluded
        if read.value is None:
            unread += 1
            unread_occluded += rest.occluded
        elif read.value == rest.value:
            ok += 1
        else:
            wrong += 1
    return {
        "n": n, "ok": ok, "wrong": wrong, "unread": unread, "ms_per_frame": 1000 * spent / n,
        "occluded": occluded, "unread_occluded": unread_occluded,
    }  # fmt: skip


def bench_video(design, drops: int, seed: int) -> dict:
    from diefab.camera.pose import Camera, MarkerDetector, read_frame
    from diefab.camera.reader import RollReader
    from diefab.camera.rig import roll_video
    from diefab.dice.markers import marker_layout

    layout = marker_layout(design)
    _, truth, frames = roll_video(design, layout, drops, seed)
    reader = RollReader(design)
    baseline = MarkerDetector(layout)
    camera = Camera.from_fov(1280, 720)
    counted: dict[int, list] = {i: [] for i in range(drops)}
    n = 0
    spent = base_spent = 0.0
    reported: set[int] = set()
    start = time.perf_counter()
    for f in frames:
        n += 1
        if f.drop and f.drop % 5 == 0 and f.drop not in reported:
            reported.add(f.drop)
            done = [counted[i] for i in range(f.drop)]
            so_far = (
                f" (counted once {sum(len(c) == 1 for c in done)}, twice {sum(len(c) > 1 for c in done)}, wrong "
                f"{sum(any(r.value is not None and r.value != truth[i] for r in c) for i, c in enumerate(done))}, "
                f"unread {sum(any(r.value is None for r in c) for c in done)}; reader {n / max(spent, 1e-9):.0f} "
                f"frames/s, baseline {n / max(base_spent, 1e-9):.1f} frames/s)"
            )
            _progress(f"{design.name} drops", f.drop, drops, start, so_far)
        t = time.process_time()
        _, roll = reader.feed(f.image)
        spent += time.process_time() - t
        if n % 10 == 0:  # the baseline on a sample of the frames: detect and solve the whole frame
            t = time.process_time()
            read_frame(f.image, design, baseline, camera)
            base_spent += 10 * (time.process_time() - t)
        if roll is not None:
            counted[f.drop].append(roll)
    once = sum(len(c) == 1 for c in counted.values())
    missed = sum(len(c) == 0 for c in counted.values())
    twice = sum(len(c) > 1 for c in counted.values())
    right = sum(len(c) == 1 and c[0].value == truth[i] for i, c in counted.items())
    wrong = sum(any(r.value is not None and r.value != truth[i] for r in c) for i, c in counted.items())
    unread = sum(any(r.value is None for r in c) for c in counted.values())
    cocked = sum(t is None for t in truth)
    return {
        "drops": drops, "frames": n, "once": once, "missed": missed, "twice": twice, "right": right,
        "wrong": wrong, "unread": unread, "cocked": cocked, "fps": n / spent, "baseline_fps": n / base_spent,
    }  # fmt: skip


def bench_others(table: dict, n: int, seed: int) -> None:
    """Print, for each pair of dice, how many of `n` rests of the first are read as rolls of the second."""
    from diefab.camera.pose import Camera, MarkerDetector, read_frame
    from diefab.camera.rig import rendered_rests
    from diefab.dice.markers import marker_layout

    camera = Camera.from_fov(1280, 720)
    readers = {name: (d, MarkerDetector(marker_layout(d))) for name, d in table.items()}
    total = wrong = 0
    for shown, design in table.items():
        images = [r.image for r in rendered_rests(design, marker_layout(design), n, seed, finger=0.0)]
        cells = []
        for name, (d, detector) in readers.items():
            if name == shown:
                continue
            read = sum(read_frame(image, d, detector, camera).value is not None for image in images)
            cells.append(f"as {name} {read}")
            total, wrong = total + n, wrong + read
        print(f"{shown:12s} {n} rests read as another die: " + ", ".join(cells), flush=True)
    print(f"read as another die (always wrong): {wrong} of {total}", flush=True)


def main() -> None:
    import cv2

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rests", type=int, default=2000)
    parser.add_argument("--drops", type=int, default=200)
    parser.add_argument("--dice", default="gem,d6,bipyramid24,d20")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--others", type=int, default=0)
    args = parser.parse_args()
    cv2.setNumThreads(1)
    print(f"OpenCV {cv2.__version__}, one thread, CPU time; frames 1280x720; seed {args.seed}")
    table = dice()
    for name in args.dice.split(","):
        design = table[name]
        if args.rests:
            _print_rests(name, bench_rests(design, args.rests, args.seed))
        if args.drops:
            _print_video(name, bench_video(design, args.drops, args.seed))
    if args.others:
        bench_others({name: table[name] for name in args.dice.split(",")}, args.others, args.seed)


def _print_rests(name: str, r: dict) -> None:
    clear = r["unread"] - r["unread_occluded"]
    print(
        f"{name:12s} rests: {r['n']} read {r['ok']} ({100 * r['ok'] / r['n']:.2f} %), wrong {r['wrong']}, "
        f"unread {r['unread']} ({100 * r['unread'] / r['n']:.2f} %; {r['unread_occluded']} of them under a finger, "
        f"which covers {r['occluded']} rests; with a clear view {clear} of {r['n'] - r['occluded']}, "
        f"{100 * clear / max(r['n'] - r['occluded'], 1):.2f} %)"
        f"; whole-frame read {r['ms_per_frame']:.1f} ms",
        flush=True,
    )


def _print_video(name: str, v: dict) -> None:
    print(
        f"{name:12s} video: {v['drops']} drops, {v['frames']} frames: counted once {v['once']}, missed "
        f"{v['missed']}, twice {v['twice']}; right {v['right']}, wrong {v['wrong']}, unread {v['unread']} "
        f"(cocked in the physics: {v['cocked']}); reader {v['fps']:.0f} frames/s vs whole-frame baseline "
        f"{v['baseline_fps']:.1f} frames/s ({v['fps'] / v['baseline_fps']:.1f}x)",
        flush=True,
    )


if __name__ == "__main__":
    main()
