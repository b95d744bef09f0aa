"""The report's figures: one function per figure, data in, PNG bytes out.

Figures are drawn on :class:`matplotlib.figure.Figure` with the Agg canvas, never
through pyplot, so importing this module changes no global backend.
"""

from __future__ import annotations

import io
import math
import time
from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from fuzzer.report.data import Run
from fuzzer.report.tables import Differences, NearZero, StrategyRow

PAPER_COLOR = "#1f5fbf"
OTHER_COLOR = "#9aa5b1"
DIVERGENT_COLOR = "#e8710a"
BAND_COLORS = ("#1f5fbf", "#e8710a", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#7f7f7f")
MAX_RUNS = 8
"""At most this many runs (the latest) are drawn over time."""
DPI = 100


def _new(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _png(fig: Figure) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", metadata={"Software": None})
    return buffer.getvalue()


def _style(ax: Axes) -> None:
    ax.grid(True, axis="both", color="#dddddd", lw=0.8)
    ax.set_axisbelow(True)
    ax.tick_params(labelsize=10)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)


def rate_label(rate: float | None, executions: int | None) -> str:
    """Fig. 6's label of a strategy's divergence rate: ``100% of 1,818`` (``.2g`` printed
    "1e+02% of 1,818"), ``n/a`` where no execution of it was recorded (it read "0% of 0")."""
    if not executions or rate is None:
        return "n/a (no executions recorded)"
    percent = 100 * rate
    shown = f"{percent:.3g}" if percent >= 10 else f"{percent:.2g}"
    return f"{shown}% of {executions:,}"


def strategies(rows: Sequence[StrategyRow]) -> bytes:
    """Fig. 6: divergences per mutation strategy, and the rate per strategy when known."""
    rows = list(rows)
    with_rate = any(r.executions for r in rows)
    fig = _new(11.0, 1.6 + 0.34 * len(rows))
    axes = fig.subplots(1, 2 if with_rate else 1, sharey=True, squeeze=False)[0]
    y = np.arange(len(rows))
    colors = [PAPER_COLOR if r.paper else OTHER_COLOR for r in rows]
    ax = axes[0]
    ax.barh(y, [r.divergences for r in rows], color=colors)
    for yi, r in zip(y, rows, strict=True):
        ax.annotate(f" {r.divergences}", (r.divergences, yi), va="center", fontsize=9)
    ax.set_yticks(y, [r.name for r in rows], fontsize=10)
    ax.invert_yaxis()
    ax.set_xlabel("divergent executions (count)", fontsize=11)
    ax.set_title("Divergences found by each mutation strategy", fontsize=12)
    ax.margins(x=0.15)
    _style(ax)
    if with_rate:
        ax = axes[1]
        rates = [100 * (r.rate or 0.0) for r in rows]
        ax.barh(y, rates, color=colors)
        for yi, r, rate in zip(y, rows, rates, strict=True):
            ax.annotate(f" {rate_label(r.rate, r.executions)}", (rate, yi), va="center", fontsize=9)
        ax.set_xlabel("divergence rate (% of the test cases it produced)", fontsize=11)
        ax.set_title("Divergences per execution", fontsize=12)
        ax.margins(x=0.35)
        _style(ax)
    fig.legend(
        handles=[
            Patch(color=PAPER_COLOR, label="paper's strategies (Table II)"),
            Patch(color=OTHER_COLOR, label="other mutators of RROSFuzz"),
        ],
        loc="outside lower center",
        ncols=2,
        fontsize=10,
        frameon=False,
    )
    return _png(fig)


def near_zero(data: NearZero) -> bytes:
    """Fig. 7: share of test cases by number of joint values close to zero."""
    keys = sorted(set(data.evaluated) | set(data.divergent))
    x = np.arange(len(keys))
    fig = _new(10.0, 4.6)
    ax = fig.subplots()
    series = [
        (data.evaluated, PAPER_COLOR, "all evaluated test cases"),
        (data.divergent, DIVERGENT_COLOR, "divergent test cases"),
    ]
    shown = [s for s in series if s[0]]
    width = 0.8 / len(shown)
    for i, (counts, color, label) in enumerate(shown):
        total = sum(counts.values())
        shares = [100 * counts.get(k, 0) / total for k in keys]
        offset = (i - (len(shown) - 1) / 2) * width
        ax.bar(x + offset, shares, width, color=color, label=f"{label} (n = {total})")
        for xi, share, k in zip(x, shares, keys, strict=True):
            if counts.get(k):
                ax.annotate(f"{share:.0f}%", (xi + offset, share), ha="center", va="bottom", fontsize=8)
    ax.set_xticks(x, [str(k) for k in keys])
    ax.set_xlabel(f"joint values with |value| < {data.threshold} (rad or m) in the test case", fontsize=11)
    ax.set_ylabel("share of test cases (%)", fontsize=11)
    ax.set_title("Distribution of test cases by joints close to zero", fontsize=12)
    ax.legend(fontsize=10, frameon=False)
    _style(ax)
    return _png(fig)


def differences(data: Differences) -> bytes:
    """Fig. 8: histogram of log10(difference), and the divergences that have no size."""
    fig = _new(11.0, 4.6)
    left, right = fig.subplots(1, 2, width_ratios=(3, 1))
    logs = [math.log10(v) for v in data.values + data.representations]
    if logs:
        # always show Table III's limits (1e-2, 1e-1) and a difference of 1
        lo, hi = min(math.floor(min(logs)), -3), max(math.ceil(max(logs)), 1)
        bins = np.arange(lo, hi + 0.25, 0.25)
        left.hist(
            [[math.log10(v) for v in data.values], [math.log10(v) for v in data.representations]],
            bins=bins,
            stacked=True,
            color=[PAPER_COLOR, DIVERGENT_COLOR],
            label=[f"value (n = {len(data.values)})", f"representation (n = {len(data.representations)})"],
        )
        for edge in (-2, -1):
            left.axvline(edge, color="#444444", ls="--", lw=1)
            left.annotate(
                f"Table III limit 1e{edge}",
                (edge, 0),
                xycoords=("data", "axes fraction"),
                ha="right",
                va="bottom",
                rotation=90,
                fontsize=9,
                xytext=(-2, 4),
                textcoords="offset points",
                color="#444444",
            )
        fig.legend(loc="outside lower center", ncols=2, fontsize=10, frameon=False)
    else:
        left.text(
            0.5,
            0.5,
            "no value or representation divergence",
            ha="center",
            va="center",
            transform=left.transAxes,
            fontsize=11,
        )
    left.set_xlabel("log10(difference), difference in m or rad", fontsize=11)
    left.set_ylabel("divergent executions", fontsize=11)
    left.set_title("Size of value differences", fontsize=12)
    _style(left)
    labels = ["status", "crash", "other", "other\nunits", "zero or\nnot finite"]
    counts = [data.status, data.crash, data.other, data.other_units, data.zero + data.nonfinite]
    right.bar(labels, counts, color=["#6a51a3", "#c00000", OTHER_COLOR, OTHER_COLOR, OTHER_COLOR])
    for i, n in enumerate(counts):
        right.annotate(str(n), (i, n), ha="center", va="bottom", fontsize=9)
    right.set_ylabel("divergent executions", fontsize=11)
    right.set_title("Without a size in m or rad", fontsize=12)
    right.tick_params(axis="x", labelsize=9)
    right.margins(y=0.12)
    _style(right)
    return _png(fig)


def timeline(runs: Sequence[Run]) -> bytes:
    """Cumulative executions and divergences over time, one row per run, one band per
    configuration (stacked, so the top edge is the sum over processes)."""
    shown = list(runs)[-MAX_RUNS:]
    labels = list(dict.fromkeys(b.label for r in shown for b in r.bands))
    color = {label: BAND_COLORS[i % len(BAND_COLORS)] for i, label in enumerate(labels)}
    fig = _new(11.0, 1.0 + 3.2 * len(shown))
    subfigs = fig.subfigures(len(shown), 1, squeeze=False)[:, 0]
    for number, (sub, run) in enumerate(zip(subfigs, shown, strict=True), len(runs) - len(shown) + 1):
        started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(run.start))
        sub.suptitle(f"Run {number}: started {started}, {run.processes} process(es)", fontsize=12)
        row = sub.subplots(1, 2)
        for ax, what, unit in (
            (row[0], "execs", "executions"),
            (row[1], "divergences", "divergent executions"),
        ):
            stacks = [getattr(b, what) for b in run.bands]
            ax.stackplot(run.times, stacks, colors=[color[b.label] for b in run.bands], alpha=0.85)
            ax.set_xlabel("time since the run started (s)", fontsize=10)
            ax.set_ylabel(f"{unit} (cumulative)", fontsize=10)
            ax.set_xlim(0, max(run.times[-1], 1e-3))
            ax.set_ylim(bottom=0)
            _style(ax)
    fig.legend(
        handles=[Patch(color=color[label], label=label) for label in labels],
        loc="outside lower center",
        ncols=1,
        fontsize=10,
        frameon=False,
    )
    return _png(fig)
