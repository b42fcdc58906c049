"""Draw docs/images/roll.svg: ``diefab roll fudge-gem-paper`` after 300 rolls of the paper's die.

    python docs/images/roll_screenshot.py

The rolls are drawn (seed 0) from the frequencies of the paper's 405 real rolls (its Table 2).
"""

from __future__ import annotations

import asyncio
import os
import tempfile
from pathlib import Path

import numpy as np

from diefab.cli.roll import roll_app
from diefab.dice.design import load_design
from diefab.stats.rolllog import repair_log
from diefab.stats.tally import Tally

HERE = Path(__file__).resolve().parent
TABLE_2 = np.array([0, 20, 48, 80, 89, 83, 66, 17, 2])


async def main() -> None:
    design = load_design("fudge-gem-paper")
    goal = design.target_distribution.aligned(design.support)
    rolls = np.random.default_rng(0).choice(design.support, size=300, p=TABLE_2 / TABLE_2.sum())
    os.chdir(tempfile.mkdtemp())  # the log's path shows as the user's would: rolls/NAME-rolls.csv
    Path("rolls").mkdir()
    log = Path("rolls/fudge-gem-paper-rolls.csv")
    repair_log(log)
    tally = Tally(design.support, goal, 0.05)
    app = roll_app(tally, log, "fudge-gem-paper against 4dF", "4dF")
    async with app.run_test(size=(100, 24)) as pilot:
        await pilot.press(*[tally.key_of(v) for v in rolls])
        await pilot.pause()
        out = HERE / "roll.svg"
        app.save_screenshot(filename=out.name, path=str(out.parent))
    print(f"wrote {out}")


if __name__ == "__main__":
    asyncio.run(main())
