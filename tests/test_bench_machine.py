"""The machine reference printed beside throughput figures (``benchmarks.machine``)."""

from __future__ import annotations

import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks import bench_evaluate, machine


def test_the_reference_is_a_time_in_milliseconds() -> None:
    ms = machine.reference_ms(repeat=2)
    assert math.isfinite(ms) and ms > 0.0
    line = machine.reference_line("before")
    assert line.startswith("# machine reference before: ")
    assert re.search(r": \d+\.\d ms \(fastest of 7: sum\(i \* i", line)


def test_a_repeat_below_one_is_refused_by_name() -> None:
    with pytest.raises(ValueError, match="repeat must be at least 1, not 0"):
        machine.reference_ms(repeat=0)


def test_bench_evaluate_prints_the_reference_around_its_figures(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["bench_evaluate", "--plain", "--ops", "fk", "--rounds", "1", "--seconds", "0.05"]
    monkeypatch.setattr(sys, "argv", argv)
    bench_evaluate.main()
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(":")[0] for line in lines] == [
        "# machine reference before",
        "fk plain",
        "# machine reference after",
    ]


def test_bench_evaluate_decompose_counts_and_rates_each_setting() -> None:
    """``--decompose`` (in a process of its own: it instruments the twin and the oracle in place)
    counts an ``fk`` evaluation's edges and float comparisons and gives each setting a rate."""
    root = Path(__file__).resolve().parents[1]
    argv = ["--decompose", "--ops", "fk", "--rounds", "1", "--seconds", "0.05"]
    run = subprocess.run(
        [sys.executable, "-m", "benchmarks.bench_evaluate", *argv],
        cwd=root, capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr[-2000:]
    lines = run.stdout.splitlines()
    counts = re.fullmatch(r"fk: per evaluation, (\d+) edge callbacks and (\d+) float comparisons.*", lines[1])
    assert counts is not None and int(counts[1]) > 0 and int(counts[2]) > 0, lines
    rates = [re.fullmatch(r"fk (.+): median ([\d,]+) evaluations/s .*", line) for line in lines[2:-1]]
    assert [m[1] for m in rates if m] == list(bench_evaluate.SETTINGS)
    assert all(int(m[2].replace(",", "")) > 0 for m in rates if m)
