"""Signal suite: SIGINT, SIGTERM and SIGHUP at random moments in every long command; count the outcomes.

Each trial starts one command in its own process group, waits a random time
(from the first instant, inside the imports, to well into the work), sends
one stop signal to the process or to its whole group (as a closed terminal
does), and classifies the end:

* clean    -- exit 130, one line on stderr, no traceback, no temporary file,
              no process of the group left;
* finished -- the command ended before the signal was sent (not counted);
* lost     -- the command went on and exited 0 after the signal;
* traceback, orphan, unclean -- what must never happen.

Run:  python benchmarks/signal_suite.py [TRIALS] [SEED]   (default 120 trials, seed 0)
The test suite runs the same trials, fewer of them (tests/test_signal_suite.py).
"""

from __future__ import annotations

import collections
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DIE = ["--die", "d6", "10,11,9,10,12,8"]
#: The long commands, each run in a fresh output folder OUT.
COMMANDS = {
    "validate": ["validate", "fudge-gem", "--sims", "40000", "--workers", "2"],
    "optimize": ["optimize", "fudge-gem", "--model", "simulation", "--start", "design", "--sims-per-eval", "400",
                 "--max-evals", "200", "--workers", "2", "--out", "OUT"],
    "calibrate": ["calibrate", *DIE, "--free", "restitution", "--sims-per-eval", "400", "--max-evals", "200",
                  "--workers", "2", "--name", "c", "--out", "OUT"],
    "stl": ["stl", "fudge-gem", "--out", "OUT"],
    "net": ["net", "fudge-gem", "--out", "OUT"],
}  # fmt: skip
SIGNALS = [signal.SIGINT, signal.SIGTERM, signal.SIGHUP]
#: Latest moment a signal is sent, seconds after the start (startup takes 1 to 3 s on a loaded machine).
LATEST = 6.0
#: Seconds a command has to end after its signal before it counts as lost.
GRACE = 60.0


def _group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def trial(command: str, signum: int, to_group: bool, delay: float) -> str:
    """One trial's outcome: clean, finished, lost, traceback, orphan or unclean."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        args = [a.replace("OUT", str(out)) for a in COMMANDS[command]]
        proc = subprocess.Popen([sys.executable, "-m", "diefab", *args], cwd=ROOT, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True, start_new_session=True)  # fmt: skip
        try:
            time.sleep(delay)
            if proc.poll() is not None:
                proc.communicate()
                return "finished"
            (os.killpg if to_group else os.kill)(proc.pid, signum)
            try:
                _, err = proc.communicate(timeout=GRACE)
            except subprocess.TimeoutExpired:
                return "lost"
            time.sleep(0.3)
            orphaned = _group_alive(proc.pid)
        finally:
            if _group_alive(proc.pid):
                os.killpg(proc.pid, signal.SIGKILL)
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
        lines = [line for line in err.splitlines() if line.strip()]
        if "Traceback" in err:
            return f"traceback ({' | '.join(lines[-3:])[-300:]})"
        if orphaned:
            return "orphan"
        if proc.returncode == 0:
            return "lost"
        temporary = list(Path(tmp).rglob("*.tmp")) + list(Path(tmp).rglob(".*.lock"))
        stop_lines = [line for line in lines if line.startswith("diefab: interrupted")]
        one_line = len(stop_lines) == 1 and lines[-1] == stop_lines[0] and not any("error" in x for x in lines)
        if proc.returncode == 130 and one_line and not temporary:
            return "clean"
        return f"unclean (exit {proc.returncode}: {' | '.join(lines)[-200:]})"


def run_trials(n: int, seed: int = 0, commands=tuple(COMMANDS), earliest: float = 0.0,
               latest: float = LATEST) -> collections.Counter:  # fmt: skip
    """`n` trials, round-robin over the commands and signals, random targets and delays (seeded)."""
    rng = random.Random(seed)
    counts: collections.Counter = collections.Counter()
    for i in range(n):
        command = commands[i % len(commands)]
        signum = SIGNALS[(i // len(commands)) % len(SIGNALS)]
        to_group, delay = rng.random() < 0.5, rng.uniform(earliest, latest)
        outcome = trial(command, signum, to_group, delay)
        counts[outcome.split(" (")[0]] += 1
        if outcome.startswith(("unclean", "traceback")):
            counts[outcome] += 0  # keep the first words of each unclean end for the report
            print(f"  {command} {signal.Signals(signum).name} at {delay:.2f} s: {outcome}", file=sys.stderr)
    return counts


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 120
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    started = time.perf_counter()
    counts = run_trials(n, seed)
    signalled = n - counts["finished"]
    print(f"signal suite: {n} trials (seed {seed}), {os.cpu_count()} cores, commands {', '.join(COMMANDS)}; "
          f"signals SIGINT/SIGTERM/SIGHUP to the process or its group at 0-{LATEST:g} s")  # fmt: skip
    for outcome in ("clean", "finished", "lost", "traceback", "orphan", "unclean"):
        print(f"  {outcome:10s} {counts[outcome]}")
    if signalled:
        print(f"clean: {counts['clean']} of {signalled} signalled runs ({100 * counts['clean'] / signalled:.1f} %); "
              f"{time.perf_counter() - started:.0f} s")  # fmt: skip


if __name__ == "__main__":
    main()
