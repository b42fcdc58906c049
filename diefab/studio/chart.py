"""What the page's charts and tables show: ECharts options and table rows from an evaluation or a job's result.

Pure functions of plain data (no web page here), so that they are tested without a browser.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from diefab.dice.design import Design

#: Bar color of the model's prediction, and of a provisional one (the solid body's, while the made body's runs).
PREDICTED = "#fd8d3c"
PROVISIONAL = "#c6c6c6"


def distribution_options(values, probs, target, *, name: str = "fast model", provisional: bool = False) -> dict:
    """A bar chart of `probs` over `values` against the dashed `target` line.

    Parameters
    ----------
    values : (k,) str
        The die's values, as printed.
    probs, target : (k,) float
        Predicted and target probability of each value.
    name : str
        The bars' legend entry.
    provisional : bool
        The bars are a stand-in (drawn gray) until the real prediction arrives.
    """
    return {
        "animation": False,
        "legend": {"data": [name, "target"]},
        "tooltip": {"trigger": "axis"},
        "xAxis": {"type": "category", "data": list(values), "name": "value"},
        "yAxis": {"type": "value", "name": "probability"},
        "series": [
            {"name": name, "type": "bar", "data": [round(float(p), 6) for p in probs],
             "itemStyle": {"color": PROVISIONAL if provisional else PREDICTED}},
            {"name": "target", "type": "line", "data": [round(float(p), 6) for p in target], "symbolSize": 8,
             "lineStyle": {"type": "dashed"}, "itemStyle": {"color": "#333"}},
        ],
    }  # fmt: skip


def validation_options(values, result: dict) -> dict:
    """The simulated shares of a validation (:func:`diefab.studio.jobs.validate_job`) with their 95 % intervals."""
    opts = distribution_options(values, result["observed"], result["target"], name="simulated")
    low = {"name": "interval low", "type": "scatter", "symbol": "triangle",
           "data": [lo for lo, _ in result["intervals"]], "itemStyle": {"color": "#555"}}  # fmt: skip
    high = {"name": "interval high", "type": "scatter", "symbol": "triangle", "symbolRotate": 180,
            "data": [hi for _, hi in result["intervals"]], "itemStyle": {"color": "#555"}}  # fmt: skip
    opts["series"][1:1] = [low, high]
    return opts


def counts_options(values, counts, target) -> dict:
    """Shares of rolls read by the camera against the target."""
    n = max(1, int(sum(counts)))
    return distribution_options(values, [c / n for c in counts], target, name="rolls read")


def margin_rows(ev: dict) -> list[dict]:
    """One row per face for the margins table: value, probability, stability margin, reading, state."""
    return [
        {"face": f["name"], "value": f["value"] or "-", "probability": f"{f['probability']:.4f}",
         "margin": f"{f['margin']:.4f}", "read from": f["read_from"] or ("-" if f["transitional"] else "vertex"),
         "state": "transitional" if f["transitional"] else ("stable" if f["margin"] > 0 else "unstable")}
        for f in ev["faces"]
    ]  # fmt: skip


def status_line(ev: dict) -> str:
    """Stable or not (and why), and the distance to the target."""
    if ev["stable"]:
        head = f"stable: every valued face has a positive margin (smallest {ev['min_margin']:.4f})"
    else:
        head = f"UNSTABLE: {ev['message']}"
    return f"{head}   TVD to target {ev['tvd']:.4f}"


def validation_line(result: dict) -> str:
    """The verdict of a validation, one line."""
    r = result
    ok = r["p_value"] >= 0.05
    head = (f"consistent with the target (p = {r['p_value']:.3g} >= 0.05)" if ok
            else f"differs from the target (p = {r['p_value']:.3g} < 0.05)")  # fmt: skip
    return (f"{head}; TVD {r['tvd']:.4f} (expected from noise {r['expected_tvd']:.4f}); {r['landed']} of {r['n']} "
            f"drops on a face, {r['cocked']} cocked, {r['unsettled']} unsettled, {r['seconds']:.1f} s")  # fmt: skip


def live_verdict(design: Design, values: list[int], delta: float) -> tuple[list[int], str, str]:
    """Counts of each of `design`'s values among the rolls `values`, the anytime-valid line and the plain verdict.

    Returns
    -------
    counts : (k,) int, aligned on ``design.support``
    sequential : str
        :func:`~diefab.stats.verdict.sequential_line` of the rolls in order.
    plain : str
        :func:`~diefab.stats.verdict.verdict`'s text ("" before the first roll).
    """
    from diefab.stats.goodness import goodness_of_fit
    from diefab.stats.tally import Tally
    from diefab.stats.verdict import sequential_line, target_label, verdict

    goal = design.target_distribution.aligned(design.support)
    tally = Tally(design.support, goal, delta, [v for v in values if v in design.support])
    counts = [int(c) for c in tally.counts]
    label = target_label(design.target)
    seq = tally.result()
    if tally.n == 0:
        return counts, sequential_line(seq, label), ""
    fit = goodness_of_fit(counts, goal, mc_samples=10_000)
    return counts, sequential_line(seq, label), verdict(counts, goal, label, p_value=fit.p_value, sequential=seq).text
