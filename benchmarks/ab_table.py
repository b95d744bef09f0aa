"""The file and the table of ``benchmarks.bench_ab``: reading a pairs file, pooling several, and
the paired statistics per bug (the Wilcoxon signed-rank test on the pairs' differences, beside
the unpaired Mann-Whitney U and A12 of the tables)."""

from __future__ import annotations

import json
import statistics
from pathlib import Path
from typing import Any

from scipy.stats import rankdata, wilcoxon

from benchmarks import journal
from benchmarks.bench_zoo import Run
from benchmarks.deep_stats import ALPHA, compare

FORMAT = "rrosfuzz-bench-ab"
"""The first line's ``format`` of a pairs file."""


def read(path: Path) -> tuple[dict[str, Any], list[tuple[str, Run]]]:
    """A pairs file's header and its trials as (arm side "a"/"b", run); a last line cut short is
    left out.

    Raises
    ------
    ValueError
        The file cannot be read, or a line is not what this tool writes (named).
    """
    try:
        lines = path.read_text(encoding="utf-8").split("\n")
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: cannot be read ({exc})") from exc
    complete = lines[:-1]  # every line written ends with a newline
    try:
        header = json.loads(complete[0]) if complete else None
        if not isinstance(header, dict) or header.get("format") != FORMAT:
            raise ValueError("its first line is not a bench_ab header")
        _check_header(header)
        names = [arm["name"] for arm in header["arms"]]
        runs = []
        for number, line in enumerate(complete[1:], 2):
            try:
                row = json.loads(line)
                if not isinstance(row, dict) or row.get("arm") not in names:
                    raise ValueError("not a trial of one of the arms")
                runs.append(("a" if row["arm"] == names[0] else "b", journal.run_of(row)))
            except (ValueError, TypeError, KeyError, RecursionError) as exc:
                raise ValueError(f"line {number}: {exc}") from exc
    except (ValueError, TypeError, KeyError, RecursionError) as exc:
        raise ValueError(f"{path}: not a bench_ab file ({exc})") from exc
    return header, runs


def _check_header(header: dict[str, Any]) -> None:
    """Raise ValueError naming the first field of a bench_ab header that is not as this tool
    writes it (two arms with a name, root, commit and env; two engines; a budget; a machine)."""
    arms = header.get("arms")
    if not isinstance(arms, list) or len(arms) != 2 or not all(isinstance(arm, dict) for arm in arms):
        raise ValueError("its header does not name two arms")
    for arm in arms:
        for key in ("name", "root", "commit"):
            if not isinstance(arm.get(key), str):
                raise ValueError(f"its header's arm {key} is not a string")
        env = arm.get("env")
        if not isinstance(env, list) or not all(isinstance(item, str) for item in env):
            raise ValueError("its header's arm env is not a list of strings")
    engines = header.get("engines")
    if not isinstance(engines, list) or len(engines) != 2 or not all(isinstance(e, str) for e in engines):
        raise ValueError("its header does not name two engines")
    budget = header.get("budget")
    if (
        isinstance(budget, bool)
        or not isinstance(budget, (int, float))
        or not journal.seconds_ok(budget, "> 0")
    ):
        raise ValueError(f"its header's budget {budget!r} is not a finite number of seconds above 0")
    if not isinstance(header.get("machine"), str):
        raise ValueError("its header does not name the machine")


POOLED = ("engines", "budget")
"""What the files of one pooled table must agree on, besides their arms' names."""


def pool(paths: list[Path]) -> tuple[list[dict[str, Any]], list[tuple[str, Run]], list[int]]:
    """The headers of the files ``paths``, their trials in order, and each trial's file (its
    index in ``paths``).

    Raises
    ------
    ValueError
        A file that ``read`` refuses, or whose arms' names, engines or budget differ from the
        first file's (named).
    """
    headers: list[dict[str, Any]] = []
    runs: list[tuple[str, Run]] = []
    batches: list[int] = []
    for index, path in enumerate(paths):
        header, held = read(path)
        if headers:
            first = headers[0]
            names = [arm["name"] for arm in header["arms"]]
            if names != [arm["name"] for arm in first["arms"]]:
                raise ValueError(f"{path}: arms {names} are not those of {paths[0]}")
            for key in POOLED:
                if header.get(key) != first.get(key):
                    raise ValueError(
                        f"{path}: {key} {header.get(key)!r} is not that of {paths[0]} ({first.get(key)!r})"
                    )
        headers.append(header)
        runs += held
        batches += [index] * len(held)
    return headers, runs, batches


def _censored(value: float | None, budget: float) -> float:
    """A time, a miss or a detection past the budget counted as the budget (as ``deep_stats``)."""
    return budget if value is None else min(value, budget)


def paired(a: list[float], b: list[float]) -> tuple[float, float, float, str]:
    """(Wilcoxon p, median of b - a, share of pairs where b is lower (ties half), verdict for b)."""
    diffs = [y - x for x, y in zip(a, b, strict=True)]
    sooner = sum((d < 0) + 0.5 * (d == 0) for d in diffs) / len(diffs)
    if not any(diffs):
        return 1.0, 0.0, sooner, "tie"
    p = float(wilcoxon(a, b, zero_method="zsplit").pvalue)
    # the direction the test found: the larger signed-rank sum (zeros split, so they cancel), not
    # the share of pairs b wins, which a few large losses can outweigh (21 pairs 1 ms sooner and 19
    # pairs seconds later: "faster" by the share, b later by W+ = 589 against W- = 231)
    ranks = rankdata([abs(d) for d in diffs])
    later = sum(r for r, d in zip(ranks, diffs, strict=True) if d > 0)
    earlier = sum(r for r, d in zip(ranks, diffs, strict=True) if d < 0)
    verdict = "tie" if p >= ALPHA else ("faster" if earlier > later else "slower")
    return p, statistics.median(diffs), sooner, verdict


def report(
    header: dict[str, Any],
    runs: list[tuple[str, Run]],
    batches: list[int] | None = None,
    pooled: list[dict[str, Any]] | tuple[dict[str, Any], ...] = (),
) -> dict[str, list[tuple[Run, Run]]]:
    """Print the table: per bug, the second arm against the first. Returns the pairs by bug.

    ``batches``: each run's file when files are pooled (a pair is a file's bug and seed);
    ``pooled``: the headers of the files after the first."""
    names = [arm["name"] for arm in header["arms"]]
    budget = float(header["budget"])
    sides: dict[tuple[str, int, int], dict[str, Run]] = {}
    for index, (side, run) in enumerate(runs):
        batch = batches[index] if batches is not None else 0
        sides.setdefault((run.bug, batch, run.seed), {})[side] = run
    by_bug: dict[str, list[tuple[Run, Run]]] = {}
    for (bug, _, _), both in sorted(sides.items()):
        if len(both) == 2:
            by_bug.setdefault(bug, []).append((both["a"], both["b"]))
    if pooled:
        print(f"{1 + len(pooled)} files pooled (a seed in two files counts twice: p is a little optimistic)")
    for each in (header, *pooled):
        for arm in each["arms"]:
            print(
                f"{arm['name']}: {arm['root']} at {arm['commit']}"
                + (f", {' '.join(arm['env'])}" if arm["env"] else "")
            )
    engines = header["engines"]
    print(
        f"engines {engines[0]} and {engines[1]}, {budget:g} s per trial, {header['machine']}; "
        f"'{names[1]}' against '{names[0]}'"
    )
    print()
    print(
        "| bug | pairs (found) | what | "
        + f"{names[0]} median (s) | {names[1]} median (s) | median paired difference (ms) | "
        + f"pairs {names[1]} sooner | Wilcoxon p | {names[1]} is | Mann-Whitney p, A12 |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for bug, pairs in by_bug.items():
        found = [
            sum(r.detected_at is not None and r.detected_at <= budget for r in side)
            for side in zip(*pairs, strict=True)
        ]
        for what in ("launch", "search", "start-up"):
            a, b = ([_value(r, what, budget) for r in side] for side in zip(*pairs, strict=True))
            p, diff, sooner, verdict = paired(a, b)
            mw, effect, _ = compare(b, a)
            share = f" ({found[0]}/{len(pairs)}, {found[1]}/{len(pairs)} found)" if what == "launch" else ""
            print(
                f"| {bug} | {len(pairs)}{share} | {what} | "
                f"{statistics.median(a):.4f} | {statistics.median(b):.4f} | {1000 * diff:+.1f} | "
                f"{sooner:.2f} | {p:.3g} | {verdict} | {mw:.3g}, {effect:.2f} |"
            )
    return by_bug


def _value(run: Run, what: str, budget: float) -> float:
    if what == "launch":
        return _censored(run.detected_at, budget)
    if what == "search":
        return _censored(run.search_time, budget)
    return _censored(run.first_input, budget)
