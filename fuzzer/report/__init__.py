"""A self-contained HTML report of an artifacts folder (``fuzz_diff.py report DIR``).

The page reproduces the paper's evaluation (Tables III and IV, Figs. 6, 7 and 8),
shows executions and divergences over time, and gives one section per bucket with
a 3D view of where each target left the arm (the role RVIZ played in the paper);
a scenario bucket also gets its step list and trajectory plots.

Modules: :mod:`~fuzzer.report.records` reads the logs, :mod:`~fuzzer.report.tables` makes
the paper's tables and figures of them, :mod:`~fuzzer.report.buckets` the buckets' views, and
:mod:`~fuzzer.report.data` gathers it all and adds the runs over time (all pure),
:mod:`~fuzzer.report.steps` and :mod:`~fuzzer.report.scenario` read scenarios,
:mod:`~fuzzer.report.figures` and :mod:`~fuzzer.report.arm` draw,
:mod:`~fuzzer.report.page` renders the HTML (the buckets in
:mod:`~fuzzer.report.bucket_section`, small helpers in :mod:`~fuzzer.report.markup`),
:mod:`~fuzzer.report.build` writes it all.
This package imports nothing heavy itself: :mod:`fuzzer.triage.pipeline` uses
:mod:`~fuzzer.report.steps` without loading matplotlib.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

__all__ = ["write_report"]


def write_report(
    directory: Path, out: Path | None = None, trust: bool = False, robots: Mapping[str, str] | None = None
) -> Path:
    """Write ``out/report.html`` and every figure as a PNG file in ``out``
    (:func:`fuzzer.report.build.write_report`, which documents the parameters)."""
    from fuzzer.report.build import write_report as write

    return write(directory, out, trust, robots)
