"""The tables, statistics and survival plot of ``benchmarks.bench_deep`` (FuzzBench/Magma style).

Per (bug, engine): detection rate and median time to first detection; per bug, the full engine
against each baseline: the two-sided Mann-Whitney U test on the times to detection (a trial
that never detects counts as the budget: censored) and the Vargha-Delaney A12; the same test
with the start-up taken out; the share of trials that have found the bug over time. Under the
table, how many of its verdicts stand once corrected for the number of comparisons it makes
(``corrected``).
"""

from __future__ import annotations

import math
import os
import platform
import signal
import statistics
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from scipy.stats import mannwhitneyu

from benchmarks import journal
from benchmarks.bench_zoo import Run

ALPHA = 0.05


@dataclass(frozen=True)
class Mode:
    bugs: tuple[str, ...]
    trials: int
    budget: float
    engines: tuple[str, ...] = ("full", "weights", "libfuzzer", "paper", "hypothesis", "uniform")


def a12(xs: list[float], ys: list[float]) -> float:
    """Vargha-Delaney A12 for times (lower is better): P(x < y) + 0.5 P(x == y)."""
    wins = sum((x < y) + 0.5 * (x == y) for x in xs for y in ys)
    return wins / (len(xs) * len(ys))


def censored(runs: list[Run], budget: float) -> list[float]:
    """Times to first detection, a trial without one counted as the budget."""
    return [budget if r.detected_at is None else min(r.detected_at, budget) for r in runs]


def censored_search(runs: list[Run], budget: float) -> list[float]:
    """Times from the first evaluated input to the first detection (start-up excluded), a trial
    without one (or without a logged first input) counted as the budget."""
    return [budget if r.search_time is None else min(r.search_time, budget) for r in runs]


def _median(values: list[float]) -> float | None:
    return statistics.median(values) if values else None


def compare(mine: list[float], other: list[float]) -> tuple[float, float, str]:
    """(p, A12, verdict): 'faster' / 'slower' when p < ALPHA, else 'tie'."""
    if len(set(mine) | set(other)) <= 1:
        return 1.0, 0.5, "tie"
    p = float(mannwhitneyu(mine, other, alternative="two-sided").pvalue)
    effect = a12(mine, other)
    if p >= ALPHA:
        return p, effect, "tie"
    return p, effect, "faster" if effect > 0.5 else "slower"


def survival(runs: list[Run], budget: float, points: int = 200) -> tuple[list[float], list[float]]:
    """(times, share of trials that have detected by each time)."""
    times = [budget * i / (points - 1) for i in range(points)]
    found = [r.detected_at for r in runs if r.detected_at is not None]
    share = [sum(t <= x for t in found) / max(1, len(runs)) for x in times]
    return times, share


def _head(mode: Mode, engine: str, baseline: str) -> list[str]:
    """A table's header rows: a cell per engine, then one per baseline."""
    cells = [f"{engine}{e}" for e in mode.engines] + [f"{baseline}{e}" for e in mode.engines[1:]]
    return ["| bug | " + " | ".join(cells) + " |", "|---|" + "---|" * len(cells)]


def _by_engine(runs: list[Run], bug: str, mode: Mode) -> dict[str, list[Run]]:
    return {e: [r for r in runs if r.bug == bug and r.engine == e] for e in mode.engines}


def markdown(runs: list[Run], mode: Mode, cmd: str, jobs: int | None = None) -> str:
    """The tables; ``jobs``: runs at a time (None: tabulated from a results file, whose runs
    the text around the table must describe)."""
    at_once = f"{jobs} run{'s' if jobs != 1 else ''} at a time" if jobs else "tabulated from a results file"
    where = f", {journal.cpu_model()}" if jobs else ""  # the machine that ran them (a results file has none)
    lines = [
        f"{mode.trials} trials x {mode.budget:.0f} s per (bug, engine), {at_once} on "
        f"{os.cpu_count()} CPUs ({platform.machine()}{where}, Python {platform.python_version()}). Command: "
        f"`{cmd}`. "
        + (
            "A trial stops at its first detection, which does not change its time to first "
            "detection (the engine's own timestamp in its log). "
            if any(r.returncode == -signal.SIGKILL for r in runs)
            else ""
        )
        + f"Cells: median time to first detection in s over all the trials, a trial without "
        f"detection later than any (when more than half detect; else '>budget', or '-' for none), "
        f"then detected within the budget/trials ('n/a (no trials)': none of that engine on "
        f"that bug in these results: a sweep in progress, or results from before the baselines had "
        f"a scenario op). "
        f"p: Mann-Whitney U (two-sided) of the full engine's times against the baseline's, a trial "
        f"without detection counted as the budget; A12: Vargha-Delaney (full engine sooner; 0.5 = "
        f"no difference); verdict at p < {ALPHA}.",
        "",
        *_head(mode, "", "vs "),
    ]
    tests: list[tuple[float, str]] = []
    for bug in mode.bugs:
        by_engine = _by_engine(runs, bug, mode)
        cells = []
        for engine in mode.engines:
            mine = by_engine[engine]
            if not mine:  # a journal so far, or results from before the baselines ran scenarios
                cells.append("n/a (no trials)")
                continue
            # a detection counts within the budget only: a run overruns it by up to one input
            # (a long scenario: seconds), and what it finds then is not a detection in budget
            hits = sorted(
                r.detected_at for r in mine if r.detected_at is not None and r.detected_at <= mode.budget
            )
            # the median of all the trials, a miss later than any detection: a detection time
            # when more than half detect (it was the upper middle of the detections alone until
            # the fifty-ninth session: 4.0 for 1..7 s and three misses, where it is 5.5)
            censored_hits = hits + [math.inf] * (len(mine) - len(hits))
            median = f"{statistics.median(censored_hits):.1f}" if len(hits) * 2 > len(mine) else "-"
            if hits and median == "-":
                median = f">{mode.budget:.0f}"
            cells.append(f"{median} ({len(hits)}/{len(mine)})")
        found = comparisons(by_engine, mode, censored)
        tests += [(test[0], test[2]) for test in found if test is not None]
        cells += [_cell(test) for test in found]
        lines.append(f"| {bug} | " + " | ".join(cells) + " |")
    return "\n".join([*lines, "", corrected(tests), "", *search_table(runs, mode)])


def corrected(tests: list[tuple[float, str]]) -> str:
    """How many of a table's verdicts (``(p, verdict)`` per comparison) stand at Bonferroni's
    threshold, ``ALPHA`` over their number: the chance that any of the verdicts standing is a
    chance result stays below ``ALPHA`` (each verdict of the table is at p < ``ALPHA`` alone, and
    with 60-88 comparisons a few of those are chance). Not Benjamini-Hochberg
    (``scipy.stats.false_discovery_control``): it bounds the share of chance verdicts among
    those kept, and a table's many strong "faster" verdicts would then keep a weak "slower"
    one, where the question is whether any "slower" verdict is real."""
    if not tests:
        return "No comparisons to correct."
    threshold = ALPHA / len(tests)
    kept = {
        v: (sum(t == v for _, t in tests), sum(t == v and p < threshold for p, t in tests))
        for v in ("faster", "slower")
    }
    (faster, faster_kept), (slower, slower_kept) = kept["faster"], kept["slower"]
    return (
        f"Corrected for the table's {len(tests)} comparisons (Bonferroni: p < {ALPHA}/{len(tests)} = "
        f'{threshold:.2g}): {faster_kept} of its {faster} "faster" and {slower_kept} of its {slower} '
        f'"slower" verdicts stand.'
    )


def comparisons(
    by_engine: dict[str, list[Run]], mode: Mode, times: Callable[[list[Run], float], list[float]]
) -> list[tuple[float, float, str] | None]:
    """Per baseline, the full engine's ``times`` against the baseline's: ``compare``'s (p, A12,
    verdict), or None without trials of either."""
    full = times(by_engine[mode.engines[0]], mode.budget)
    return [
        compare(full, times(by_engine[engine], mode.budget)) if by_engine[engine] and full else None
        for engine in mode.engines[1:]
    ]


def _cell(test: tuple[float, float, str] | None) -> str:
    if test is None:
        return "n/a"
    p, effect, verdict = test
    return f"{verdict} (p={p:.3g}, A12={effect:.2f})"


def verdicts(
    by_engine: dict[str, list[Run]], mode: Mode, times: Callable[[list[Run], float], list[float]]
) -> list[str]:
    """One cell per baseline: the full engine's ``times`` against the baseline's (MWU, A12)."""
    return [_cell(test) for test in comparisons(by_engine, mode, times)]


def search_table(runs: list[Run], mode: Mode) -> list[str]:
    """The same comparison with the start-up taken out: per bug, each engine's median start-up
    (process start to its first evaluated input) and the verdicts on the time from there to the
    first detection (the search alone)."""
    lines = [
        "Start-up excluded: median seconds from the process start to each engine's first evaluated "
        "input (imports, seeds, instrumentation), then the same test on the time from that first "
        "input to the first detection (a trial without detection counted as the budget).",
        "",
        *_head(mode, "start-up ", "search vs "),
    ]
    for bug in mode.bugs:
        by_engine = _by_engine(runs, bug, mode)
        cells = []
        for engine in mode.engines:
            start = _median([r.first_input for r in by_engine[engine] if r.first_input is not None])
            cells.append("n/a" if start is None else f"{start:.2f}")
        cells += verdicts(by_engine, mode, censored_search)
        lines.append(f"| {bug} | " + " | ".join(cells) + " |")
    return lines


def plot(runs: list[Run], mode: Mode, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    cols = min(4, len(mode.bugs))
    rows = (len(mode.bugs) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.6 * rows), squeeze=False, sharey=True)
    lines: dict[str, Line2D] = {}
    for ax, bug in zip(axes.flat, mode.bugs, strict=False):
        for i, engine in enumerate(mode.engines):
            mine = [r for r in runs if r.bug == bug and r.engine == engine]
            if not mine:  # no trials: no curve (not a curve at zero)
                continue
            times, share = survival(mine, mode.budget)
            (lines[engine],) = ax.step(times, share, where="post", color=f"C{i}", label=engine)
        ax.set_title(bug, fontsize=9)
        ax.set_xlabel("s", fontsize=8)
        ax.set_ylim(-0.02, 1.02)
    for ax in list(axes.flat)[len(mode.bugs) :]:
        ax.axis("off")
    axes[0][0].set_ylabel("share of trials that found it")
    shown = [e for e in mode.engines if e in lines]
    axes[0][0].legend([lines[e] for e in shown], shown, fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
