"""Speed of ``--op scenario`` on the default arm: steps and executions per second, one core.

    .venv/bin/python -m benchmarks.bench_scenario              # 5 runs, 20 s campaigns
    .venv/bin/python -m benchmarks.bench_scenario --write-md   # and the section of BENCHMARKS.md

Two measurements, each repeated ``--runs`` times (run ``i`` uses seed ``i``), medians reported:

(a) the executor alone: ``run_scenario`` (through ``Runner.run``) over the scenarios the
    campaign generates from that seed (``fuzzer.generation.corpus.make_seeds``, as many as a fresh
    campaign writes), on each target separately; steps are the step outcomes returned. The
    twin's IK memory (``python_impl.kinematics.IK_MEMO``) is emptied before each pass, so a
    pass solves every IK problem it poses the first time, as a campaign would;
(b) a whole campaign: ``fuzz_diff.py --op scenario`` for ``--seconds``, execs and elapsed
    time from its ``stats.jsonl``; steps per second estimated as execs/s x the mean number
    of steps of the corpus it kept (the campaign does not count executed steps).

The process (and the campaign it starts) is pinned to one CPU. Where the time goes: the
time per step kind on each target (an instrumented extra pass of (a)), and the top entries
of a cProfile of the whole evaluation (both targets and the oracle) over the seeds.
The load average is recorded with the figures: other work on the machine slows them.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import os
import pstats
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any
from unittest import mock

from benchmarks import cli
from benchmarks.zoo_tables import ROOT, replace_section
from fuzzer.artifacts.divlog import STATS, read_lines
from fuzzer.execution.session import RunConfig, Session
from fuzzer.generation.corpus import make_seeds
from fuzzer.input.testcase import TestCase, decode
from fuzzer.scenario import execute
from fuzzer.scenario.steps import ScenarioCall, to_call
from python_impl.kinematics import IK_MEMO

RESULTS = ROOT / "benchmarks" / "results"
MARKS = ("<!-- bench_scenario:begin -->", "<!-- bench_scenario:end -->")
TITLE = "## Scenario speed (`--op scenario`)"
GOAL = 2000.0
"""Steps per second asked for by issue 10."""
CAMPAIGN_SEEDS = 32
"""Seeds a fresh campaign generates (fuzzer.campaign: ``wanted`` with an empty corpus)."""


def pin_one_core() -> int:
    """Pin this process (and its children) to one CPU, the last it may run on; returns it."""
    cpu = max(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpu})
    return cpu


def load() -> str:
    """The 1, 5 and 15 minute load averages."""
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def scenarios(session: Session, seed: int, n: int = CAMPAIGN_SEEDS) -> list[TestCase]:
    """The scenarios a fresh campaign with ``-seed=seed`` starts from."""
    return make_seeds(session, n, seed)


def time_executor(session: Session, calls: list[ScenarioCall]) -> dict[str, dict[str, float]]:
    """Run every scenario on each target alone.

    Returns
    -------
    dict
        Per target name: ``seconds`` (wall time, s), ``steps`` (step outcomes), ``execs``.
    """
    out = {}
    for runner in session.runners:
        IK_MEMO.clear()
        steps = 0
        started = time.perf_counter()
        for call in calls:
            steps += len(runner.run(call).steps)
        out[runner.name] = {
            "seconds": time.perf_counter() - started,
            "steps": float(steps),
            "execs": float(len(calls)),
        }
    return out


@contextmanager
def _timed_steps(sink: dict[str, list[float]]) -> Iterator[None]:
    """Record the duration (s) of every ``_Run.step`` call by step kind while active."""
    original = execute._Run.step

    def step(self: Any, scenario_step: Any) -> Any:
        started = time.perf_counter()
        try:
            return original(self, scenario_step)
        finally:
            sink[scenario_step.kind].append(time.perf_counter() - started)

    with mock.patch.object(execute._Run, "step", step):
        yield


def step_costs(session: Session, calls: list[ScenarioCall]) -> dict[str, dict[str, dict[str, float]]]:
    """Per target and step kind: count, total seconds, mean microseconds, mean trajectory points."""
    out: dict[str, dict[str, dict[str, float]]] = {}
    for runner in session.runners:
        IK_MEMO.clear()
        durations: dict[str, list[float]] = defaultdict(list)
        points: dict[str, list[int]] = defaultdict(list)
        with _timed_steps(durations):
            for call in calls:
                outcome = runner.run(call)
                for step, result in zip(call.steps, outcome.steps, strict=False):
                    points[step.kind].append(len(result.values.get("trajectory.time_from_start", ())))
        out[runner.name] = {
            kind: {
                "count": float(len(d)),
                "seconds": sum(d),
                "mean_us": 1e6 * statistics.fmean(d),
                "mean_points": statistics.fmean(points[kind]) if points[kind] else 0.0,
            }
            for kind, d in durations.items()
        }
    return out


def profile_evaluation(session: Session, cases: list[TestCase], top: int = 12) -> list[str]:
    """cProfile of the evaluation (both targets and the oracle) of ``cases``: top entries by
    own time, as ``own s | cumulative s | calls | function``."""
    evaluator = session.evaluator()
    IK_MEMO.clear()
    profiler = cProfile.Profile()
    profiler.enable()
    for case in cases:
        evaluator.evaluate(case)
    profiler.disable()
    stream = io.StringIO()
    stats = pstats.Stats(profiler, stream=stream)
    rows = []
    entries: dict[Any, Any] = stats.stats  # type: ignore[attr-defined]
    ranked = sorted(entries.items(), key=lambda kv: kv[1][2], reverse=True)[:top]
    for (filename, line, name), (_, calls, own, cumulative, _) in ranked:
        where = Path(filename).name if filename != "~" else "builtin"
        rows.append(f"{own:.3f} | {cumulative:.3f} | {calls} | `{name}` ({where}:{line})")
    return rows


def run_campaign(seed: int, seconds: float) -> dict[str, float]:
    """One ``fuzz_diff.py --op scenario`` campaign (default arm, native vs python)."""
    with tempfile.TemporaryDirectory(prefix="rrosfuzz-bench-scenario-") as tmp:
        corpus, artifacts = Path(tmp) / "corpus", Path(tmp) / "artifacts"
        cmd = [
            sys.executable,
            str(ROOT / "fuzz_diff.py"),
            str(corpus),
            f"-max_total_time={int(seconds)}",
            f"-seed={seed}",
            f"--artifacts={artifacts}",
            "--no-progress",
            "--op=scenario",
        ]
        done = subprocess.run(
            cmd,
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=seconds + 300,
            check=False,
            env=dict(os.environ, PYTHONPATH=str(ROOT)),
        )
        last: dict[Any, dict[str, Any]] = {}
        for record in read_lines(artifacts / STATS):
            last[record.get("pid")] = record
        if not last:
            raise RuntimeError(
                f"campaign (seed {seed}) wrote no stats; exit {done.returncode}: {done.stderr.strip()[-400:]}"
            )
        execs = sum(int(r.get("execs", 0)) for r in last.values())
        elapsed = max(float(r.get("elapsed", 0.0)) for r in last.values())
        lengths = []
        for path in corpus.iterdir():
            if not path.is_file() or path.name.startswith("."):
                continue  # the campaign's own bookkeeping
            try:
                lengths.append(len(decode(path.read_bytes()).message["steps"]))
            except (ValueError, KeyError, TypeError):
                continue  # not a scenario test case (none expected)
    mean_steps = statistics.fmean(lengths) if lengths else 0.0
    return {
        "execs": float(execs),
        "elapsed": elapsed,
        "exec_per_s": execs / elapsed if elapsed else 0.0,
        "corpus_mean_steps": mean_steps,
        "steps_per_s": mean_steps * execs / elapsed if elapsed else 0.0,
        "returncode": float(done.returncode),
    }


def measure(runs: int, seconds: float, campaigns: bool = True) -> dict[str, Any]:
    """All figures (see the module docstring)."""
    cpu = pin_one_core()
    loads = [load()]
    session = Session.open(RunConfig(op="scenario"))
    executor: list[dict[str, dict[str, float]]] = []
    for seed in range(1, runs + 1):
        calls = [to_call(case.message) for case in scenarios(session, seed)]
        executor.append(time_executor(session, calls))
    first = scenarios(session, 1)
    calls = [to_call(case.message) for case in first]
    result: dict[str, Any] = {
        "cpu": cpu,
        "runs": runs,
        "robot": session.config.robot,
        "scenarios_per_run": CAMPAIGN_SEEDS,
        "executor": executor,
        "step_costs": step_costs(session, calls),
        "profile": profile_evaluation(session, first),
    }
    loads.append(load())
    result["campaigns"] = [run_campaign(seed, seconds) for seed in range(1, runs + 1)] if campaigns else []
    result["campaign_seconds"] = seconds
    loads.append(load())
    result["load"] = loads
    result["uptime"] = subprocess.run(["uptime"], capture_output=True, text=True, check=False).stdout.strip()
    return result


def _median(values: list[float]) -> float:
    return statistics.median(values) if values else 0.0


def markdown(result: dict[str, Any]) -> str:
    """The section of BENCHMARKS.md."""
    runs, names = result["runs"], list(result["executor"][0])
    lines = [
        f"`--op scenario` on `{result['robot']}` (native vs python), one core (CPU {result['cpu']} pinned), "
        f"medians over {runs} runs (run i: seed i). Load average (1, 5, 15 min) before / after the executor "
        f"runs / after the campaigns: {' / '.join(result['load'])}; `uptime` at the end: "
        f"`{result['uptime']}`. Command: `python -m benchmarks.bench_scenario`.",
        "",
        "| measurement | steps/s | executions/s |",
        "|---|---|---|",
    ]
    executor = result["executor"]
    rows: list[tuple[str, float, float]] = []  # (measurement, steps/s, executions/s)
    for name in names:
        steps = [r[name]["steps"] / r[name]["seconds"] for r in executor]
        execs = [r[name]["execs"] / r[name]["seconds"] for r in executor]
        rows.append((f"(a) executor alone, {name}", _median(steps), _median(execs)))
    both_time = [sum(r[n]["seconds"] for n in names) for r in executor]
    steps_both = [r[names[0]]["steps"] / t for r, t in zip(executor, both_time, strict=True)]
    execs_both = [r[names[0]]["execs"] / t for r, t in zip(executor, both_time, strict=True)]
    rows.append(("(a) executor, both targets in turn", _median(steps_both), _median(execs_both)))
    campaigns = result["campaigns"]
    if campaigns:
        rows.append(
            (
                f"(b) whole campaign, {result['campaign_seconds']:.0f} s (steps: estimate)",
                _median([c["steps_per_s"] for c in campaigns]),
                _median([c["exec_per_s"] for c in campaigns]),
            )
        )
    lines += [f"| {m} | {st:,.0f} | {ex:,.1f} |" for m, st, ex in rows]
    met = ", ".join(m for m, st, _ in rows if st >= GOAL) or "none"
    missed = ", ".join(m for m, st, _ in rows if st < GOAL) or "none"
    scenario_steps = _median([r[names[0]]["steps"] / r[names[0]]["execs"] for r in result["executor"]])
    lines += [
        "",
        f"(a) runs the {result['scenarios_per_run']} scenarios a fresh campaign generates "
        f"(mean {scenario_steps:.1f} steps each); in (b) one execution runs the scenario on both targets and "
        "compares them; its steps/s is execs/s x the mean steps of the corpus the campaign kept. "
        f"Goal: {GOAL:,.0f} steps/s; met by: {met}; missed by: {missed}.",
        "",
        "Where the time goes, per step kind (seeds of run 1; mean time per step, its share of the target's "
        "step time, and mean trajectory points for steps that return one):",
        "",
        "| step kind | " + " | ".join(f"{n}: mean µs (share)" for n in names) + " | mean points |",
        "|---|" + "---|" * len(names) + "---|",
    ]
    costs = result["step_costs"]
    totals = {n: sum(c["seconds"] for c in costs[n].values()) for n in names}

    def spent(kind: str) -> float:
        return float(sum(costs[n].get(kind, {}).get("seconds", 0.0) for n in names))

    kinds = sorted(costs[names[0]], key=lambda k: -spent(k))
    for kind in kinds:
        cells = []
        for n in names:
            c = costs[n].get(kind)
            share = c["seconds"] / totals[n] if c and totals[n] else 0.0
            cells.append(f"{c['mean_us']:,.0f} ({share:.0%})" if c else "")
        points = costs[names[0]][kind]["mean_points"]
        shown = f"{points:,.0f}" if points else "-"
        lines.append(f"| {kind} | " + " | ".join(cells) + f" | {shown} |")
    lines += [
        "",
        "cProfile of the evaluation of the same seeds (both targets and the oracle), "
        "top entries by own time:",
        "",
        "| own s | cumulative s | calls | function |",
        "|---|---|---|---|",
        *[f"| {row} |" for row in result["profile"]],
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--runs", type=int, default=5, help="repetitions (default 5)")
    parser.add_argument("--seconds", type=float, default=20.0, help="campaign length (default 20 s)")
    parser.add_argument("--no-campaign", action="store_true", help="measure the executor only")
    parser.add_argument("--out", type=Path, default=RESULTS / "scenario-speed.json")
    parser.add_argument("--write-md", action="store_true", help="update BENCHMARKS.md")
    parser.add_argument("--render", type=Path, default=None, help="only render a saved result (JSON)")
    args = parser.parse_args(argv)
    cli.check_sizes(parser, runs=args.runs)
    cli.check_campaign_seconds(parser, seconds=args.seconds)
    if args.render is not None:
        try:
            result: dict[str, Any] = json.loads(args.render.read_text(encoding="utf-8"))
            text = markdown(result)
        except (
            OSError,
            UnicodeDecodeError,
            RecursionError,
            ValueError,
            TypeError,
            LookupError,
            ArithmeticError,
        ) as exc:
            # a saved result is data from anywhere: any shape it does not have is named, not a traceback
            parser.error(f"{args.render}: not a bench_scenario result ({type(exc).__name__}: {exc})")
    else:
        cli.check_out_file(parser, args.out)
        result = measure(args.runs, args.seconds, not args.no_campaign)
        args.out.write_text(json.dumps(result, indent=1), encoding="utf-8")
        text = markdown(result)
    print(text)
    if args.write_md:
        replace_section(text, MARKS, TITLE)
    return result


if __name__ == "__main__":
    main()
