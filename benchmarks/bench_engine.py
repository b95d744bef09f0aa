"""Speed of the fuzzing engine (issue: fuzz_diff.py engine).

    taskset -c 0 .venv/bin/python -m benchmarks.bench_engine [--seconds 20] [--seeds 1 2 3]

For each op, runs ``fuzz_diff.py`` (default targets native vs python, default
robot, python_impl and the oracle instrumented by Atheris) for ``--seconds``
per seed on a fresh corpus, and reads the engine's own summary (executions
and fuzzing time, startup excluded). Then runs the paper's experiment size,
15,246 executions of ``move`` (``-runs=15246``), and reports the wall time of
the whole command, startup included. Medians over the seeds.
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SUMMARY = re.compile(r"executions: (\d+) in ([0-9.]+) s")
PAPER_RUNS = 15246


def run(args: list[str]) -> tuple[int, float, float]:
    """(executions, fuzzing seconds, wall seconds) of one fuzz_diff.py run."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [
            sys.executable,
            str(ROOT / "fuzz_diff.py"),
            f"{tmp}/corpus",
            f"--artifacts={tmp}/artifacts",
            "--no-progress",
            *args,
        ]
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
    found = SUMMARY.findall(done.stderr)
    if done.returncode != 0 or not found:
        raise SystemExit(f"run failed ({done.returncode}): {' '.join(cmd)}\n{done.stderr[-2000:]}")
    execs, seconds = found[-1]
    return int(execs), float(seconds), wall


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seconds", type=int, default=20)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--ops", nargs="+", default=["fk", "move", "ik"])
    args = parser.parse_args()
    cpus = len(os.sched_getaffinity(0))
    print(f"# {cpus} CPU(s) available; {args.seconds} s per run; seeds {args.seeds}; medians")
    print("| op | exec/s (median) | runs (exec/s) |")
    print("|---|---|---|")
    for op in args.ops:
        rates = []
        for seed in args.seeds:
            execs, seconds, _ = run([f"--op={op}", f"-max_total_time={args.seconds}", f"-seed={seed}"])
            rates.append(execs / seconds)
        cells = ", ".join(f"{r:,.0f}" for r in rates)
        print(f"| {op} | {statistics.median(rates):,.0f} | {cells} |")
    walls = []
    for seed in args.seeds:
        execs, _, wall = run(["--op=move", f"-runs={PAPER_RUNS}", f"-seed={seed}"])
        # libFuzzer's first input is the empty one, which is not a test case and not counted
        assert execs >= PAPER_RUNS - 1, f"{execs} executions for -runs={PAPER_RUNS}"
        walls.append(wall)
    print()
    print(
        f"Paper's experiment size, {PAPER_RUNS:,} executions of move (whole command, startup included): "
        f"median {statistics.median(walls):.1f} s (runs: {', '.join(f'{w:.1f}' for w in walls)})"
    )


if __name__ == "__main__":
    main()
