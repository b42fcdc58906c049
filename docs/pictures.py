"""Regenerate the pictures of the README and the docs: ``python docs/pictures.py [readme|design]``.

Runs the commands the docs show (``diefab net``, ``diefab stl --preview``,
``diefab validate --plot``) into a temporary folder and writes docs/img/.
``design`` draws the nets of the dice in benchmarks/results/design-dice/ (the
design files of a ``benchmarks/bench_design.py`` run; the designing page's pictures).
The studio's screenshots come from its browser tests:
``DIEFAB_SHOTS=docs/img python -m pytest tests/test_studio.py``.
"""

import subprocess
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

IMG = Path(__file__).parent / "img"
DESIGN_DICE = Path(__file__).parent.parent / "benchmarks" / "results" / "design-dice"


def diefab(*args: str) -> None:
    subprocess.run([sys.executable, "-m", "diefab", *args], check=True, stdout=subprocess.DEVNULL)


def crop(image, pad: int = 20):
    """The image cut to its drawn part (the net's pieces, not the page's margins and legend)."""
    import numpy as np

    ink = image[..., :3].min(axis=2) < 0.9
    rows = np.flatnonzero(ink[: int(0.85 * len(ink))].any(axis=1))
    cols = np.flatnonzero(ink[: int(0.85 * len(ink))].any(axis=0))
    page = (rows[0] + 2, cols[0] + 2)  # the page frame is ink too: skip it
    inner = ink[page[0] : int(0.85 * len(ink)), page[1] : cols[-1] - 2]
    r = np.flatnonzero(inner.any(axis=1)) + page[0]
    c = np.flatnonzero(inner.any(axis=0)) + page[1]
    return image[max(r[0] - pad, 0) : r[-1] + pad, max(c[0] - pad, 0) : c[-1] + pad]


def readme_pictures() -> None:
    IMG.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        diefab("net", "fudge-gem-paper", "--format", "png", "--out", str(out))
        diefab("stl", "fudge-gem-print", "--preview", "--out", str(out))
        net = crop(mpimg.imread(out / "fudge-gem-paper-net.png"))
        preview = mpimg.imread(out / "fudge-gem-print-preview.png")
        h, w = preview.shape[:2]
        die = preview[int(0.11 * h) : int(0.33 * h), : int(0.5 * w)]  # the two overviews of the printed die
        fig = Figure(figsize=(12, 5.2), dpi=110)
        a, b = fig.subplots(1, 2, width_ratios=[1, 1.25])
        a.imshow(net)
        a.set_title("diefab net fudge-gem-paper: cut, fold, glue", fontsize=11)
        b.imshow(die)
        b.set_title("diefab stl fudge-gem-print: print it", fontsize=11)
        for ax in (a, b):
            ax.axis("off")
        fig.tight_layout()
        fig.savefig(IMG / "net-and-die.png")
        for name in ("fudge-gem-paper-net.png", "fudge-gem-print-preview.png"):
            (IMG / name).write_bytes((out / name).read_bytes())
        diefab("design", "2d6", "--out", str(out))  # about a minute
        diefab("net", str(out / "bipyramid-2d6.toml"), "--format", "png", "--out", str(out))
        diefab("stl", str(out / "bipyramid-2d6.toml"), "--preview", "--out", str(out))
        for name in ("bipyramid-2d6-net.png", "bipyramid-2d6-preview.png"):
            (IMG / name).write_bytes((out / name).read_bytes())
        diefab("validate", "fudge-gem-print", "--sims", "10000", "--seed", "1", "--plot", str(IMG / "validate.png"))


def design_nets() -> None:
    """The net of every die in benchmarks/results/design-dice/, cut to its pieces."""
    figures = IMG / "figures"
    with tempfile.TemporaryDirectory() as tmp:
        for die in sorted(DESIGN_DICE.glob("*.toml")):
            diefab("net", str(die), "--format", "png", "--out", tmp)
            net = crop(mpimg.imread(Path(tmp) / f"{die.stem}-net.png"))
            mpimg.imsave(figures / f"design-{die.stem}-net.png", net[..., :3])


def main(which: list[str]) -> None:
    unknown = set(which) - {"readme", "design"}
    if unknown:
        print(f"pictures.py: unknown set {sorted(unknown)[0]!r} (readme, design)", file=sys.stderr)
        sys.exit(2)
    if not which or "readme" in which:
        readme_pictures()
    if not which or "design" in which:
        design_nets()


if __name__ == "__main__":
    main(sys.argv[1:])
