"""Solids cut by planes, built for the optimizer: each face's basis and each edge's head at once, against per face.

Run:  python benchmarks/bench_planes.py [--dice 300] [--repeat 5] [--no-design]

Every optimizer evaluation of a prism, bipyramid, trapezohedron, cuboid or
free-form die builds its solid from its planes
(:func:`diefab.dice.families.planes.polyhedron_from_planes`) and walks its
faces' edges (``Polyhedron._ring``).  Two steps of that are timed here
against the straightforward per-face code, on the same random solids
(12-24 planes each), and checked equal to it, index for index:

- ordering each face's vertices (:func:`~diefab.dice.families.planes.face_rings`):
  one row-wise cross product for every face's basis, against two
  ``np.cross`` calls per face;
- each directed edge's head: one index array for the whole solid, against
  ``np.roll`` per face.

Then ``diefab design 3d6 --checkpoint DIR`` is timed as a cold process
twice: once to fill DIR, once more on the full DIR, where every drop is
found and what is left is the search's model work (which these steps
serve).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from diefab.core.errors import GeometryError  # noqa: E402
from diefab.dice.families.planes import face_rings, polyhedron_from_planes, unit  # noqa: E402


def rings_per_face(points: np.ndarray, normals: np.ndarray, on: np.ndarray) -> tuple[np.ndarray, ...]:
    """The baseline of :func:`face_rings`: each face's basis from two ``np.cross`` calls of its own."""
    faces = []
    for k in range(len(normals)):
        ring = np.flatnonzero(on[:, k])
        u = np.cross(normals[k], [1.0, 0, 0] if abs(normals[k, 0]) < 0.9 else [0, 1.0, 0])
        v = np.cross(normals[k], u)
        rel = points[ring] - points[ring].mean(axis=0)
        faces.append(ring[np.argsort(np.arctan2(rel @ v, rel @ u))])
    return tuple(faces)


def heads_per_face(faces) -> np.ndarray:
    """The baseline of the edges' heads: every face's ring rolled by one."""
    return np.concatenate([np.roll(f, -1) for f in faces])


def random_solids(n: int, seed: int = 0) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, object]]:
    """`n` bounded solids of 12-24 random planes: (points, unit normals, points on each plane, the solid)."""
    rng = np.random.default_rng(seed)
    solids = []
    while len(solids) < n:
        m = int(rng.integers(12, 25))
        normals, offsets = unit(rng.normal(size=(m, 3))), rng.uniform(0.7, 1.3, m)
        try:
            poly = polyhedron_from_planes(normals, offsets)
        except GeometryError:  # a plane that cuts no face of its own: not a solid of m faces
            continue
        on = np.abs(poly.vertices @ normals.T - offsets) < 1e-9
        solids.append((np.asarray(poly.vertices), normals, on, poly))
    return solids


def best_of(repeat: int, fn) -> float:
    """The least wall time of `repeat` calls of `fn`."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def design_seconds(folder: str, out: str) -> float:
    """Wall seconds of ``diefab design 3d6 --checkpoint FOLDER`` as a cold process."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "diefab", "design", "3d6", "--workers", "2", "--checkpoint", folder,
                           "--out", out, "--json"], cwd=ROOT, capture_output=True, text=True)  # fmt: skip
    if done.returncode not in (0, 3):
        sys.exit(f"bench_planes: design ended with status {done.returncode}: {done.stderr.strip()[-300:]}")
    return time.perf_counter() - start


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dice", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--design", action=argparse.BooleanOptionalAction, default=True,
                    help="also time `diefab design 3d6` (cold): filling a checkpoint, then on it")  # fmt: skip
    args = ap.parse_args()
    if args.dice < 1 or args.repeat < 1:
        raise SystemExit("--dice and --repeat must be >= 1")
    solids = random_solids(args.dice)
    faces = sum(len(n) for _, n, _, _ in solids)
    rings = all(all(np.array_equal(a, b) for a, b in zip(face_rings(p, n, on), rings_per_face(p, n, on)))
                for p, n, on, _ in solids)  # fmt: skip
    heads = all(np.array_equal(poly._ring[1], heads_per_face(poly.faces)) for *_, poly in solids)
    print(f"{len(solids)} random solids, {faces} faces; identical to the per-face code: rings {rings}, heads {heads}")
    for step, shipped, baseline in (
        ("face rings", lambda: [face_rings(p, n, on) for p, n, on, _ in solids],
         lambda: [rings_per_face(p, n, on) for p, n, on, _ in solids]),
        ("edge heads", lambda: [type(poly).__dict__["_ring"].func(poly) for *_, poly in solids],
         lambda: [heads_per_face(poly.faces) for *_, poly in solids]),
    ):  # fmt: skip
        fast, slow = best_of(args.repeat, shipped), best_of(args.repeat, baseline)
        print(f"  {step:<10}: {1e6 * fast / len(solids):7.1f} us per solid, per face {1e6 * slow / len(solids):7.1f} "
              f"us: {slow / fast:.2f}x (best of {args.repeat})")  # fmt: skip
    if args.design:
        with tempfile.TemporaryDirectory() as tmp:
            first = design_seconds(f"{tmp}/drops", f"{tmp}/a")
            again = design_seconds(f"{tmp}/drops", f"{tmp}/b")
        print(f"diefab design 3d6 --workers 2 --checkpoint DIR (cold process): {first:.1f} s; again on the full DIR, "
              f"every drop found: {again:.1f} s")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
