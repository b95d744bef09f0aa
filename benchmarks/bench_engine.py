"""Speed of the fuzzing engine (issue: fuzz_diff.py engine).

    taskset -c 0 .venv/bin/python -m benchmarks.bench_engine [--seconds 20] [--seeds 1 2 3]
    taskset -c 0 .venv/bin/python -m benchmarks.bench_engine --sweep [--seconds 5]

For each op, runs ``fuzz_diff.py`` (default targets native vs python, default
robot, python_impl and the oracle instrumented by Atheris) for ``--seconds``
per seed on a fresh corpus, and reads the engine's own summary (executions
and fuzzing time, startup excluded) and, for ``fk`` and ``move``, the batched sweeps'
rows compared (``stats.jsonl``; half of an ``fk`` campaign's time goes to them, about a
tenth of a ``move`` one's). Then
runs the paper's experiment size, 15,246 executions of ``move``
(``-runs=15246``), and reports the wall time of the whole command, startup
included. Medians over the seeds. Before and after, the machine's speed at that moment
(``benchmarks.machine``: a fixed Python workload's time), to set figures of different days
side by side.

``--sweep`` measures the batched path alone, in this process: ``Sweep.run`` on the
default robot, native against the twin, 1,024 rows a sweep, for ``--seconds`` per seed
(differential FK comparisons per second).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks import cli, machine
from fuzzer.cli_options import MUTATORS

ROOT = Path(__file__).resolve().parents[1]
SUMMARY = re.compile(r"executions: (\d+) in ([0-9.]+) s")
PAPER_RUNS = 15246


def campaign_command(tmp: str, args: list[str]) -> list[str]:
    """``fuzz_diff.py`` with a fresh corpus and artifacts folder in ``tmp``, no progress bar, and ``args``."""
    return [
        sys.executable,
        str(ROOT / "fuzz_diff.py"),
        f"{tmp}/corpus",
        f"--artifacts={tmp}/artifacts",
        "--no-progress",
        *args,
    ]


def run(args: list[str]) -> tuple[int, float, float, int]:
    """(executions, fuzzing seconds, wall seconds, sweep rows compared) of one fuzz_diff.py run."""
    compared = 0
    with tempfile.TemporaryDirectory() as tmp:
        cmd = campaign_command(tmp, args)
        start = time.monotonic()
        done = subprocess.run(
            cmd,
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=False,
            env=dict(os.environ, PYTHONPATH=str(ROOT)),
        )
        wall = time.monotonic() - start
        stats = Path(tmp) / "artifacts" / "stats.jsonl"
        if stats.is_file():
            lines = stats.read_text().splitlines()
            compared = int(json.loads(lines[-1]).get("sweep", {}).get("compared", 0)) if lines else 0
    found = SUMMARY.findall(done.stderr)
    if done.returncode != 0 or not found:
        raise SystemExit(f"run failed ({done.returncode}): {' '.join(cmd)}\n{done.stderr[-2000:]}")
    execs, seconds = found[-1]
    return int(execs), float(seconds), wall, compared


def sweep_rate(seconds: float, seed: int) -> float:
    """Differential FK comparisons per second of ``Sweep.run`` (native vs twin, default robot)."""
    import native
    import python_impl
    from fuzzer.execution.tolerance import Tolerance
    from fuzzer.generation.sweep import Sweep
    from robot_api.robots import default_robot_path

    reference = native.RobotModel(default_robot_path())
    models = [reference, python_impl.RobotModel(default_robot_path())]
    limits = reference.joint_limits
    sweep = Sweep([lim.lower for lim in limits], [lim.upper for lim in limits], Tolerance(), seed=seed)
    sweep.run(models, [])  # warm up
    sweep.compared = 0
    start = time.perf_counter()
    while time.perf_counter() - start < seconds:
        sweep.run(models, [])
    return sweep.compared / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seconds", type=int, default=20)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument(
        "--ops", nargs="+", default=["fk", "move", "ik"], choices=("fk", "move", "ik", "scenario")
    )
    parser.add_argument(
        "--mutator", default=None, choices=MUTATORS, help="pass --mutator to fuzz_diff.py (e.g. weights)"
    )
    parser.add_argument("--sweep", action="store_true", help="measure the batched FK path alone")
    args = parser.parse_args()
    cli.check_sizes(parser, seconds=args.seconds)
    if min(args.seeds) < 1:
        parser.error(
            f"--seeds must be 1 or more (libFuzzer takes -seed=0 as the clock's seed), not {min(args.seeds)}"
        )
    cpus = len(os.sched_getaffinity(0))
    print(machine.reference_line("before"))
    if args.sweep:
        rates = [sweep_rate(args.seconds, seed) for seed in args.seeds]
        print(f"# {cpus} CPU(s); {args.seconds} s per seed; seeds {args.seeds}")
        print(
            f"batched sweeps: median {statistics.median(rates):,.0f} differential FK comparisons/s "
            f"(runs: {', '.join(f'{r:,.0f}' for r in rates)})"
        )
        print(machine.reference_line("after"))
        return
    extra = [f"--mutator={args.mutator}"] if args.mutator else []
    print(f"# {cpus} CPU(s) available; {args.seconds} s per run; seeds {args.seeds}; medians")
    print("| op | exec/s (median) | runs (exec/s) | sweep comparisons/s (median) |")
    print("|---|---|---|---|")
    for op in args.ops:
        rates, swept = [], []
        for seed in args.seeds:
            execs, seconds, _, compared = run(
                [f"--op={op}", f"-max_total_time={args.seconds}", f"-seed={seed}", *extra]
            )
            rates.append(execs / seconds)
            swept.append(compared / seconds)
        cells = ", ".join(f"{r:,.0f}" for r in rates)
        sweep = f"{statistics.median(swept):,.0f}" if any(swept) else "-"
        print(f"| {op} | {statistics.median(rates):,.0f} | {cells} | {sweep} |")
    walls = []
    for seed in args.seeds:
        execs, _, wall, _ = run(["--op=move", f"-runs={PAPER_RUNS}", f"-seed={seed}", *extra])
        # libFuzzer's first input is the empty one, which is not a test case and not counted
        assert execs >= PAPER_RUNS - 1, f"{execs} executions for -runs={PAPER_RUNS}"
        walls.append(wall)
    print()
    print(
        f"Paper's experiment size, {PAPER_RUNS:,} executions of move (whole command, startup included): "
        f"median {statistics.median(walls):.1f} s (runs: {', '.join(f'{w:.1f}' for w in walls)})"
    )
    print(machine.reference_line("after"))


if __name__ == "__main__":
    main()
