"""One self-contained HTML page about a die: its picture, its net, its distribution and the verdict.

The page has no external reference (images are ``data:`` URIs, the style is
inline), so it opens offline and can be mailed as one file.  The renderer
returns ``str``; the command line writes it.
"""

from __future__ import annotations

import base64
import html
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from diefab.dice.design import Design, format_value

__all__ = ["DieReport", "design_report", "die_pictures", "render_report"]


@dataclass(frozen=True)
class DieReport:
    """What a report shows.

    Attributes
    ----------
    design : Design
    title : str
        The page's heading, e.g. ``"validate fudge-gem-print"``.
    verdict : str
        The one plain verdict line of the command.
    probabilities : (k,) float
        Measured or predicted probability of each value of ``design.support``.
    intervals : (k, 2) float or None
        Simultaneous confidence intervals of `probabilities` (None: a prediction).
    source : str
        What `probabilities` are, e.g. ``"10000 pybullet drops"``.
    lines : sequence of str
        Further facts, one per line (counts, seeds, settings).
    pictures : dict of str to (bytes, str)
        Caption -> (image bytes, MIME type): the die, its net.
    """

    design: Design
    title: str
    verdict: str
    probabilities: np.ndarray
    intervals: np.ndarray | None
    source: str
    lines: Sequence[str] = ()
    pictures: dict[str, tuple[bytes, str]] = field(default_factory=dict)


def die_pictures(design: Design) -> dict[str, tuple[bytes, str]]:
    """The die as printed (preview PNG) and its paper net (SVG), for :class:`DieReport`."""
    from diefab.fabricate.net import design_net, render_net
    from diefab.fabricate.preview import render_preview
    from diefab.fabricate.stl import build_solid

    solid = build_solid(design)
    net = design_net(design)
    svg = render_net(design, net, ["svg"])["svg"]
    svg = svg.encode() if isinstance(svg, str) else svg
    return {
        "the die, printed (diefab stl --preview)": (render_preview(solid, dpi=70), "image/png"),
        "the die, in paper (diefab net)": (svg, "image/svg+xml"),
    }


def design_report(design: Design, predicted: np.ndarray, model: str, validated: dict | None) -> DieReport:
    """The report of a designed die: its predicted distribution under `model` and its check by simulation.

    Parameters
    ----------
    design : Design
    predicted : (k,) float
        Probability of each value of ``design.support`` under `model`.
    model : str
        The model the design was optimized under.
    validated : dict or None
        The check by simulation: ``n``, ``seed``, ``tvd``, ``p_value`` (None: not checked).
    """
    if validated:
        verdict = (f"checked by {validated['n']:,} pybullet drops on a fresh seed ({validated['seed']}): TVD "
                   f"{validated['tvd']:.4f} to {design.target}, p = {validated['p_value']:.3g}")  # fmt: skip
    else:
        verdict = f"not checked by simulation; predicted under the {model} model only"
    return DieReport(design=design, title=f"diefab design {design.target}: {design.name}", verdict=verdict,
                     probabilities=np.asarray(predicted, dtype=float), intervals=None, source=f"{model} model",
                     pictures=die_pictures(design))  # fmt: skip


def _distribution_png(report: DieReport) -> bytes:
    import io

    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    d = report.design
    values = d.support
    target = d.target_distribution.aligned(values)
    p = np.asarray(report.probabilities, dtype=float)
    x = np.arange(len(values))
    fig = Figure(figsize=(7.0, 3.8), dpi=100)
    ax = fig.add_subplot()
    err = None if report.intervals is None else [p - report.intervals[:, 0], report.intervals[:, 1] - p]
    ax.bar(x - 0.2, p, 0.4, yerr=err, capsize=3, color="#3b75af", label=report.source)
    ax.bar(x + 0.2, target, 0.4, color="#9e9e9e", label=f"target {d.target}")
    ax.set_xticks(x, [format_value(int(v), min(values) < 0) for v in values])
    ax.set_xlabel("value")
    ax.set_ylabel("probability")
    ax.legend(fontsize=8, frameon=False)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def _img(data: bytes, mime: str, alt: str) -> str:
    uri = f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"
    return f'<img src="{uri}" alt="{html.escape(alt)}">'


def render_report(report: DieReport) -> str:
    """The report as one HTML document (UTF-8 text, no external references)."""
    d = report.design
    e = html.escape
    signed = min(d.support) < 0
    target = d.target_distribution.aligned(d.support)
    rows = []
    for k, v in enumerate(d.support):
        ci = "" if report.intervals is None else f"{report.intervals[k, 0]:.4f} – {report.intervals[k, 1]:.4f}"
        rows.append(f"<tr><td>{e(format_value(int(v), signed))}</td><td>{report.probabilities[k]:.4f}</td>"
                    f"<td>{ci}</td><td>{target[k]:.4f}</td></tr>")  # fmt: skip
    figures = "".join(f"<figure>{_img(data, mime, caption)}<figcaption>{e(caption)}</figcaption></figure>"
                      for caption, (data, mime) in report.pictures.items())  # fmt: skip
    params = " ".join(f"{k}={v:g}" for k, v in d.params.items())
    facts = "".join(f"<li>{e(line)}</li>" for line in report.lines)
    interval = "95% simultaneous CI" if report.intervals is not None else ""
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{e(report.title)}</title>
<style>
body {{ font-family: system-ui, sans-serif; max-width: 60rem; margin: 2rem auto; padding: 0 1rem; color: #222; }}
.verdict {{ font-size: 1.25rem; padding: .8rem 1rem; background: #eef4fb; border-left: .3rem solid #3b75af; }}
figure {{ display: inline-block; margin: .5rem; vertical-align: top; max-width: 28rem; }}
figure img {{ max-width: 100%; border: 1px solid #ddd; background: #fff; }}
table {{ border-collapse: collapse; }}
td, th {{ padding: .2rem .8rem; border-bottom: 1px solid #ddd; text-align: right; }}
</style></head><body>
<h1>{e(report.title)}</h1>
<p>{e(d.name)}: {e(d.family)} {e(params)}, target {e(d.target)}, fill {e(d.fill.kind)}</p>
<p class="verdict">{e(report.verdict)}</p>
<h2>Distribution against the target</h2>
{_img(_distribution_png(report), "image/png", "distribution against the target")}
<table><tr><th>value</th><th>{e(report.source)}</th><th>{interval}</th><th>target</th></tr>{"".join(rows)}</table>
<ul>{facts}</ul>
<h2>The die</h2>
{figures}
</body></html>
"""
