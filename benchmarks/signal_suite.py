"""Signal suite: SIGINT, SIGTERM and SIGHUP at random moments in every long command; count the outcomes.

Each trial starts one command in its own process group, waits a random time
(from the first instant, inside the imports, to well into the work), sends
one stop signal to the process or to its whole group (as a closed terminal
does), and classifies the end:

* clean    -- exit 130, one line on stderr, no traceback, no temporary file,
              no process of the group left;
* finished -- the command had finished before the signal: it had ended, or
              it had reported and was in the interpreter's teardown, where
              the stop signals are ignored and its exit status 0 stands
              (not counted);
* early    -- the signal came before diefab's first line had run (the
              interpreter's own start-up, which no Python program can
              handle) and ended the process; not counted, listed;
* lost     -- the command went on and exited 0 after the signal;
* traceback, orphan, unclean -- what must never happen.

The moments are read from the kernel (``/proc/PID/status`` on Linux): diefab's
handlers are in place once the process catches SIGTERM and SIGHUP, which the
interpreter alone leaves at their defaults; a finished command ignores them.
Where /proc is missing no trial is classified early or finished-in-teardown.

Run:  python benchmarks/signal_suite.py [TRIALS] [SEED] [--commands stl,net] [--between EARLIEST LATEST]
      (default 120 trials, seed 0, every command, signals at 0 to 6 s)
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
    "checkpoint": ["validate", "fudge-gem", "--sims", "40000", "--workers", "2", "--checkpoint", "OUT/drops.npz"],
    "optimize": ["optimize", "fudge-gem", "--model", "simulation", "--start", "design", "--sims-per-eval", "400",
                 "--max-evals", "200", "--workers", "2", "--out", "OUT"],
    "calibrate": ["calibrate", *DIE, "--free", "restitution", "--sims-per-eval", "400", "--max-evals", "200",
                  "--workers", "2", "--name", "c", "--out", "OUT"],
    "design": ["design", "1,2,3,4,5,6", "--workers", "2", "--out", "OUT"],
    "design-checkpoint": ["design", "1,2,3,4,5,6", "--workers", "2", "--out", "OUT", "--checkpoint", "OUT/drops"],
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


def _masks(pid: int) -> tuple[int, int] | None:
    """The signals process `pid` catches and those it ignores, as bit masks (bit ``s - 1`` for signal s), or None."""
    try:
        lines = Path(f"/proc/{pid}/status").read_text().splitlines()
    except OSError:
        return None
    fields = dict(line.split(":", 1) for line in lines if ":" in line)
    try:
        return int(fields["SigCgt"], 16), int(fields["SigIgn"], 16)
    except (KeyError, ValueError):
        return None


def _bit(mask: int, signum: int) -> bool:
    return bool(mask >> (signum - 1) & 1)


def _handlers_in_place(pid: int) -> bool:
    """True once diefab's stop handlers are installed: SIGTERM and SIGHUP are caught (or ignored, as under nohup).

    Also True where the kernel does not say (no /proc): no trial is then put down to the start-up.
    """
    masks = _masks(pid)
    if masks is None:
        return not Path("/proc/self/status").exists()
    caught, ignored = masks
    late = [s for s in SIGNALS if s != signal.SIGINT]  # the interpreter itself catches only SIGINT
    return all(_bit(caught | ignored, s) for s in late) and any(_bit(caught, s) for s in late)


def _ignores(pid: int, signum: int) -> bool:
    masks = _masks(pid)
    return masks is not None and _bit(masks[1], signum)


def _wait(proc: subprocess.Popen, delay: float) -> bool:
    """Sleep `delay` seconds from now; return whether diefab's handlers were seen in place by then."""
    end = time.monotonic() + delay
    in_place = False
    while not in_place and time.monotonic() < end and proc.poll() is None:
        in_place = _handlers_in_place(proc.pid)
        time.sleep(min(0.005, max(end - time.monotonic(), 0)))
    time.sleep(max(end - time.monotonic(), 0))
    return in_place or _handlers_in_place(proc.pid)


def _as_from_a_terminal() -> None:
    """In the child: the stop signals at their defaults, as a terminal starts a command (not as nohup or ``&``)."""
    for signum in SIGNALS:
        signal.signal(signum, signal.SIG_DFL)


def trial(command: str, signum: int, to_group: bool, delay: float) -> str:
    """One trial's outcome: clean, finished, early, lost, traceback, orphan or unclean."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        args = [a.replace("OUT", str(out)) for a in COMMANDS[command]]
        proc = subprocess.Popen([sys.executable, "-m", "diefab", *args], cwd=ROOT, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True, start_new_session=True,
                                preexec_fn=_as_from_a_terminal)  # fmt: skip
        try:
            in_place = _wait(proc, delay)
            if proc.poll() is not None:
                proc.communicate()
                return "finished"
            done = in_place and _ignores(proc.pid, signum)  # reported and tearing down
            (os.killpg if to_group else os.kill)(proc.pid, signum)
            done = done or (in_place and _ignores(proc.pid, signum))  # the signal met the ignoring teardown
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
        if not in_place and proc.returncode not in (0, 130):  # before diefab's first line: the interpreter's start-up
            return f"early (exit {proc.returncode}: {' | '.join(lines[-2:])[-200:]})"
        if done and proc.returncode == 0:
            return "finished (it had reported; the signal met its teardown)"
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
        counts["teardown"] += "teardown" in outcome
        if outcome.startswith(("unclean", "traceback", "early")):
            counts[outcome] += 0  # keep the first words of each unclean end for the report
            print(f"  {command} {signal.Signals(signum).name} at {delay:.2f} s: {outcome}", file=sys.stderr)
    return counts


def main() -> None:
    import argparse

    parser = argparse.ArgumentParser(description="Stop signals at random moments in the long commands.")
    parser.add_argument("trials", type=int, nargs="?", default=120)
    parser.add_argument("seed", type=int, nargs="?", default=0)
    parser.add_argument("--commands", default=",".join(COMMANDS), help="comma-separated, of: " + ", ".join(COMMANDS))
    parser.add_argument("--between", type=float, nargs=2, default=(0.0, LATEST), metavar=("EARLIEST", "LATEST"),
                        help="seconds after the start within which each signal is sent")  # fmt: skip
    args = parser.parse_args()
    commands = tuple(args.commands.split(","))
    unknown = set(commands) - set(COMMANDS)
    if unknown:
        parser.error(f"unknown command(s) {', '.join(sorted(unknown))}")
    earliest, latest = args.between
    started = time.perf_counter()
    counts = run_trials(args.trials, args.seed, commands, earliest, latest)
    signalled = args.trials - counts["finished"] - counts["early"]
    print(f"signal suite: {args.trials} trials (seed {args.seed}), {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f}, commands {', '.join(commands)}; signals SIGINT/SIGTERM/SIGHUP to the process "
          f"or its group at {earliest:g}-{latest:g} s")  # fmt: skip
    for outcome in ("clean", "finished", "early", "lost", "traceback", "orphan", "unclean"):
        print(f"  {outcome:10s} {counts[outcome]}")
    if counts["teardown"]:
        print(f"  ({counts['teardown']} of the finished had reported and met the signal in their teardown)")
    if signalled:
        print(f"clean: {counts['clean']} of {signalled} signalled runs ({100 * counts['clean'] / signalled:.1f} %); "
              f"{time.perf_counter() - started:.0f} s")  # fmt: skip


if __name__ == "__main__":
    main()
