"""The machine reference printed beside throughput figures (``benchmarks.machine``)."""

from __future__ import annotations

import math
import re
import sys

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
