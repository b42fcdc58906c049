"""Hand tally and roll logs: keys to state, durable appends and undo, the terminal app, the commands."""

from __future__ import annotations

import asyncio
import json
import os
import signal

import numpy as np
import pytest

from diefab.core.errors import StatsError
from diefab.dice.targets import parse_target
from diefab.stats.goodness import read_roll_column
from diefab.stats.rolllog import HEADER, Roll, append_roll, read_log, remove_last_roll, repair_log
from diefab.stats.tally import Tally, value_keys

FOUR_DF = parse_target("4df")


def test_keys_are_the_values_for_digits_else_in_order():
    assert value_keys(range(1, 7)) == list("123456")
    assert value_keys(range(-4, 5)) == list("123456789")
    assert "u" not in value_keys(range(30)) and "q" not in value_keys(range(30))
    with pytest.raises(StatsError, match="keys"):
        value_keys(range(100))


def test_tally_state_machine_counts_undo_and_resume():
    tally = Tally(FOUR_DF.values, FOUR_DF.probabilities, 0.05, rolls=[0, 0, 1])
    assert tally.counts.tolist() == [0, 0, 0, 0, 2, 1, 0, 0, 0]
    kinds = [tally.press(k).kind for k in ["9", "1", "backspace", "x", "u", "q"]]
    assert kinds == ["roll", "roll", "undo", "ignored", "undo", "quit"]
    assert tally.rolls == [0, 0, 1]
    for _ in range(3):
        tally.press("u")
    assert tally.n == 0 and tally.press("u").kind == "ignored"
    with pytest.raises(StatsError, match="not a value"):
        Tally(FOUR_DF.values, FOUR_DF.probabilities, 0.05, rolls=[7])


def test_tally_reaches_the_verdict_of_a_loaded_die():
    tally = Tally([1, 2], [0.5, 0.5], 0.2)
    for _ in range(40):
        tally.press("2")
    res = tally.result()
    assert res.decision == "off" and res.tvd_low >= 0.2


def test_log_round_trip_torn_line_and_undo(tmp_path):
    path = tmp_path / "die.rolls.csv"
    append_roll(path, Roll.now(-3))
    append_roll(path, Roll("2026-05-01T18:03:11.250Z", 2, "f3", 0.998, 1412))
    assert path.read_text().splitlines()[0] == ",".join(HEADER)
    log = read_log(path)
    assert log.values.tolist() == [-3, 2] and log.rolls[1].face == "f3" and log.rolls[1].frame == 1412
    with open(path, "a") as f:
        f.write("2026-05-01T18:03:12Z,1")  # a crash mid-line: never a roll
    assert read_log(path).values.tolist() == [-3, 2] and read_log(path).torn
    assert repair_log(path) > 0 and not read_log(path).torn
    assert remove_last_roll(path).value == 2 and read_log(path).values.tolist() == [-3]


def test_bad_log_cells_name_line_and_token(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text(",".join(HEADER) + "\n2026-05-01T00:00:00Z,1,,,\n2026-05-01T00:00:01Z,two,,,\n")
    with pytest.raises(StatsError, match=r"bad.csv:3: 'two' is not a whole-number roll"):
        read_log(path)
    path.write_text(",".join(HEADER) + "\n2026-05-01T00:00:00Z,1,f1,1.5,\n")
    with pytest.raises(StatsError, match=r":2: confidence '1.5' is outside"):
        read_log(path)


def test_spreadsheet_prefers_a_named_column_and_names_bad_tokens(tmp_path):
    sheet = tmp_path / "sheet.csv"
    sheet.write_text("Roll #,Die A,Die B,Result\n1,3,4,7\n2,1,x,3\n3,2,2,4\n")
    values, column = read_roll_column(sheet)
    assert values.tolist() == [7, 3, 4] and column == "Result"
    sheet.write_text("Roll #,Die A,Die B,Total\n1,3,4,7\n2,1,2,three\n")
    with pytest.raises(StatsError, match=r"sheet.csv:3, column 'Total': 'three'"):
        read_roll_column(sheet)
    plain = tmp_path / "plain.txt"
    plain.write_text("1 2 3  # first session\n4,5\n")
    assert read_roll_column(plain) == (pytest.approx(np.array([1, 2, 3, 4, 5])), None)


def test_stats_reads_a_roll_log_and_gives_the_sequential_verdict(run, tmp_path):
    path = tmp_path / "gem.rolls.csv"
    rng = np.random.default_rng(5)
    for v in rng.choice(FOUR_DF.values, size=300, p=FOUR_DF.probabilities):
        append_roll(path, Roll.now(int(v)))
    code, out, _ = run("stats", "--rolls", path, "--target", "4df", "--sequential", "--delta", "0.03", "--json")
    data = json.loads(out)
    assert code == 0 and data["n"] == 300 and data["decision"] == "undecided" and data["more_rolls"] > 0
    code, out, err = run("stats", "--rolls", path, "--target", "4df")
    assert code == 0 and "read column 'value'" in err and "verdict: indistinguishable from 4dF at 300 rolls" in out


def test_stats_bad_token_is_one_line(bad, tmp_path):
    sheet = tmp_path / "sheet.csv"
    sheet.write_text("Roll #,Result\n1,7\n2,seven\n")
    assert "sheet.csv:3, column 'Result': 'seven' is not a whole-number roll" in bad(
        "stats", "--rolls", sheet, "--target", "2d6"
    )


def test_roll_refuses_a_second_process_and_needs_a_terminal(bad, tmp_path):
    pytest.importorskip("textual")
    from diefab.core.files import ExclusiveLock

    with ExclusiveLock(tmp_path / "d6-rolls.csv", "a roll log"):
        assert f"is in use by process {os.getpid()}" in bad("roll", "d6", "--out", tmp_path)
    assert "needs a terminal" in bad("roll", "d6", "--out", tmp_path)
    assert not list(tmp_path.glob(".*.lock"))  # the lock file goes with the lock


def test_read_and_roll_share_one_log_name_and_resume_an_old_one(tmp_path):
    from diefab.stats.rolllog import log_path

    assert log_path(tmp_path, "d6") == tmp_path / "d6-rolls.csv"
    old = tmp_path / "d6.rolls.csv"
    append_roll(old, Roll.now(3))
    assert log_path(tmp_path, "d6") == old  # a log saved under the former name is resumed
    append_roll(tmp_path / "d6-rolls.csv", Roll.now(4))
    assert log_path(tmp_path, "d6") == tmp_path / "d6-rolls.csv"


def test_tally_add_counts_a_value_and_refuses_a_foreign_one():
    tally = Tally([1, 2, 3], [0.2, 0.3, 0.5], 0.1)
    tally.add(3)
    tally.add(3)
    assert tally.counts.tolist() == [0, 0, 2] and tally.result().n == 2
    with pytest.raises(StatsError, match="not a value of the die"):
        tally.add(7)


def _roll_in_a_terminal(folder, keys: bytes, close: bool, end: bytes = b"q") -> int:
    """Run ``diefab roll d6`` in a pseudo-terminal, type `keys`, then `end` or close the terminal; its exit status."""
    import pty
    import select
    import sys
    import time
    from pathlib import Path

    root = str(Path(__file__).resolve().parent.parent)
    pid, fd = pty.fork()
    if pid == 0:  # the child: the command, at the terminal
        os.environ["PYTHONPATH"] = root
        signal.signal(signal.SIGHUP, signal.SIG_DFL)  # as in a terminal (under nohup it arrives ignored)
        os.execv(sys.executable, [sys.executable, "-m", "diefab", "roll", "d6", "--out", str(folder)])
    shown, deadline = b"", time.monotonic() + 120
    try:
        while b"quit:" not in shown and time.monotonic() < deadline:  # the app is drawn
            if select.select([fd], [], [], 0.1)[0]:
                shown += os.read(fd, 65536)
        for key in keys + (b"" if close else end):
            os.write(fd, bytes([key]))
            time.sleep(0.3)
            try:
                while select.select([fd], [], [], 0)[0]:
                    shown += os.read(fd, 65536)
            except OSError:  # the command had ended (after the last key) and closed its end: EIO on Linux
                break
        if not close:  # read until the command has ended (a terminal that nobody reads would block it)
            while select.select([fd], [], [], 30)[0]:
                try:
                    if not os.read(fd, 65536):
                        break
                except OSError:  # the other end closed
                    break
    finally:
        os.close(fd)  # the terminal window goes: a hang-up for the command if it still runs
    return os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])


@pytest.mark.skipif(not hasattr(os, "fork"), reason="pseudo-terminals")
@pytest.mark.parametrize(
    ("close", "end", "code"), [(False, b"q", 0), (False, b"\x03", 130), (True, b"", 130)],
    ids=["quit", "ctrl-c", "terminal-closed"],
)  # fmt: skip
def test_roll_in_a_terminal_keeps_every_roll_and_leaves_no_lock_file(tmp_path, close, end, code):
    pytest.importorskip("textual")
    status = _roll_in_a_terminal(tmp_path, b"6613", close, end)
    assert status == code
    assert read_log(tmp_path / "d6-rolls.csv").values.tolist() == [6, 6, 1, 3]
    assert [p.name for p in tmp_path.iterdir()] == ["d6-rolls.csv"]  # the lock file went with the lock


def _drive_roll_app(path, title: str, keys: tuple[str, ...], shown: str, width: int = 110):
    """Press `keys` in ``diefab roll``'s window on a fair d6's tally logged at `path`; the tally and widget `shown`."""
    pytest.importorskip("textual")
    from diefab.cli.roll import roll_app

    repair_log(path)
    t = parse_target("uniform:6")
    tally = Tally(t.values, t.probabilities, 0.05)

    async def drive():
        app = roll_app(tally, path, title, "a fair d6")
        async with app.run_test(size=(width, 30)) as pilot:
            await pilot.press(*keys)
            await pilot.pause()
            text = str(app.query_one(shown).render())
            await pilot.press("q")
        return text

    return tally, asyncio.run(drive())


def test_roll_app_records_every_key_in_the_log(tmp_path):
    path = tmp_path / "d6.rolls.csv"
    tally, verdict = _drive_roll_app(path, "d6 against uniform:6", ("6", "6", "1", "backspace", "3"), "#verdict")
    assert read_log(path).values.tolist() == [6, 6, 3]
    assert tally.counts.tolist() == [0, 0, 1, 0, 0, 2]
    assert "3 rolls" in verdict and "fair d6" in verdict
    resumed = Tally(tally.values, tally.target, 0.05, rolls=read_log(path).values)
    assert resumed.counts.tolist() == tally.counts.tolist()


def test_a_roll_the_log_cannot_take_is_not_counted(tmp_path):
    path = tmp_path / "d6-rolls.csv"
    repair_log(path)
    t = parse_target("uniform:6")
    tally = Tally(t.values, t.probabilities, 0.05)

    async def drive():
        from diefab.cli.roll import roll_app

        app = roll_app(tally, path, "d6", "a fair d6")
        async with app.run_test(size=(110, 30)) as pilot:
            await pilot.press("2")
            path.unlink()
            path.mkdir()  # the log is now a folder: nothing can be appended
            await pilot.press("3", "backspace")
            await pilot.pause()
            text = str(app.query_one("#status").render())
            await pilot.press("q")
        return text

    status = asyncio.run(drive())
    assert status.startswith("not recorded:")
    assert tally.counts.tolist() == [0, 1, 0, 0, 0, 0]


def test_roll_with_its_input_closed_is_one_line(tmp_path):
    import subprocess
    import sys

    pytest.importorskip("textual")
    done = subprocess.run(
        [sys.executable, "-m", "diefab", "roll", "d6", "--out", str(tmp_path)],
        capture_output=True, text=True, preexec_fn=lambda: os.close(0), timeout=120,
    )  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "terminal" in done.stderr


def test_roll_app_shows_names_and_paths_as_they_are(tmp_path):
    """Brackets in a design's name or the log's folder are text, not markup (an unmatched tag would crash)."""
    path = tmp_path / "run[b]" / "d6[i]-rolls.csv"
    path.parent.mkdir()
    _, title = _drive_roll_app(path, "d6[/bold] against uniform:6", ("2",), "#title", width=200)
    assert title == f"d6[/bold] against uniform:6   log: {path}"
    assert read_log(path).values.tolist() == [2]


def test_calibrate_reads_a_roll_log(tmp_path):
    from diefab.dice.design import load_design
    from diefab.search.calibrate import real_die

    design = load_design("fudge-gem-paper")
    path = tmp_path / "gem.rolls.csv"
    for v in [-1, 0, 0, 2, -4]:
        append_roll(path, Roll.now(v))
    die = real_die(design.name, design, str(path))
    assert die.n == 5 and die.counts.tolist() == [1, 0, 0, 1, 2, 0, 1, 0, 0]


def test_stats_json_is_strict_json_before_any_roll(run):
    def refuse(constant):
        raise ValueError(f"{constant} is not JSON")

    code, out, _ = run("stats", "--counts", "0,0,0", "--target", "1:1,2:1,3:1", "--sequential", "--json")
    data = json.loads(out, parse_constant=refuse)
    assert code == 0 and data["n"] == 0 and data["tvd"] is None and data["tvd_high"] == pytest.approx(2 / 3)
