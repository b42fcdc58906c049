"""The live view of a tally shared by ``diefab roll`` and ``diefab read``: counts beside the target, and the verdict."""

from __future__ import annotations

#: Width of the longest bar, in characters.
BAR_WIDTH = 36


def bars(tally, width: int = BAR_WIDTH, *, keys: bool = True):
    """A rich table: (key,) value, count, observed and target frequency as bars.

    Parameters
    ----------
    tally : diefab.stats.tally.Tally
    keys : bool
        Show the key of each value (a hand tally).
    """
    from rich.table import Table
    from rich.text import Text

    from diefab.dice.design import format_value

    n = tally.n
    observed = tally.counts / n if n else tally.counts * 0.0
    top = max(float(tally.target.max()), float(observed.max()), 1e-12)
    signed = min(tally.values) < 0
    head = ("key",) if keys else ()
    table = Table(*head, "value", "count", "observed", "target", "observed \u2588 target \u2502", box=None)
    for key, value, count, o, t in zip(tally.keys, tally.values, tally.counts, observed, tally.target):
        bar = [" "] * (width + 1)
        filled = int(round(o / top * width))
        for i in range(filled):
            bar[i] = "\u2588"
        bar[int(round(t / top * width))] = "\u2502"
        cells = (Text(str(key), style="bold"),) if keys else ()
        table.add_row(
            *cells, format_value(value, signed), str(int(count)), f"{o:.3f}", f"{t:.3f}",
            Text("".join(bar), style="cyan"),
        )  # fmt: skip
    return table


def tally_view(tally, label: str, title: str, *, keys: bool = False, verdict: bool = True):
    """A rich renderable: `title`, the bars of :func:`bars` and (with `verdict`) the verdict line against `label`."""
    from rich.console import Group
    from rich.text import Text

    from diefab.stats.verdict import sequential_line

    if not verdict:
        return Group(Text(title), bars(tally, keys=keys))
    return Group(Text(title), bars(tally, keys=keys), Text(sequential_line(tally.result(), label), style="bold"))
