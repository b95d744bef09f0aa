"""Building the report of an artifacts folder (``fuzz_diff.py report DIR``).

The page reproduces the paper's evaluation (Tables III and IV, Figs. 6, 7 and 8),
shows executions and divergences over time, and gives one section per bucket with
a 3D view of where each target left the arm (the role RVIZ played in the paper).

Modules: :mod:`~fuzzer.report.records` reads the logs, :mod:`~fuzzer.report.tables` makes
the paper's tables and figures of them, :mod:`~fuzzer.report.buckets` the buckets' views, and
:mod:`~fuzzer.report.data` gathers it all and adds the runs over time (all pure),
:mod:`~fuzzer.report.figures` and :mod:`~fuzzer.report.arm` draw,
:mod:`~fuzzer.report.page` renders the HTML.
"""

from __future__ import annotations

import contextlib
import re
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import matplotlib

from fuzzer.artifacts.store import atomic_write
from fuzzer.report import figures, scenario
from fuzzer.report.arm import ArmView, Sessions, render
from fuzzer.report.data import ReportData, gather
from fuzzer.report.page import render as render_page

__all__ = ["build_figures", "write_report"]


def build_figures(data: ReportData) -> dict[str, bytes]:
    """The page's figures that have data to show, as PNG bytes by name."""
    out: dict[str, bytes] = {}
    if data.strategies:
        out["fig6"] = figures.strategies(data.strategies)
    if not data.near_zero.empty:
        out["fig7"] = figures.near_zero(data.near_zero)
    if not data.differences.empty:
        out["fig8"] = figures.differences(data.differences)
    if data.runs:
        out["timeline"] = figures.timeline(data.runs)
    return out


FILE_NAMES = {
    "fig6": "fig6-strategies.png",
    "fig7": "fig7-near-zero.png",
    "fig8": "fig8-differences.png",
    "timeline": "over-time.png",
}


OWN_FIGURE = re.compile(
    "|".join(re.escape(name) for name in FILE_NAMES.values()) + r"|(?:arm|trajectory)-[A-Za-z0-9_-]+\.png"
)
"""The names of the figures a report writes: those of an earlier report on the same folder that
the new page no longer shows are removed (they stayed, beside a page saying "Nothing to show")."""


PLAIN_TEXT: dict[Any, Any] = {"text.parse_math": False, "text.usetex": False}
"""Strings from inputs (strategy names, robot names, targets) are drawn as they are:
no mathtext, so ``$...$`` in a lineage cannot break (or style) a figure."""


def write_report(
    directory: Path, out: Path | None = None, trust: bool = False, robots: Mapping[str, str] | None = None
) -> Path:
    """Write ``out/report.html`` and every figure as a PNG file in ``out``.

    Parameters
    ----------
    directory : Path
        An artifacts folder (crash files, sidecars, divergences.jsonl, stats.jsonl);
        an empty or missing folder gives a page saying there is nothing to show.
    out : Path, optional
        The output folder, ``directory / "report"`` by default.
    trust : bool
        Re-run buckets whose sidecar names targets other than the builtins
        (``--trust-sidecar``); without it they get a note instead of a 3D view.
    robots : mapping, optional
        ``--robot`` files by their SHA-256: the robot of every sidecar that records that
        digest, for paths relative to another working folder.

    Returns
    -------
    Path
        The HTML page. It is self-contained: images are data: URIs, CSS is inline,
        there is no script and no network access. Nothing outside ``directory`` is
        read: symlinks leading out of it are ignored (with a warning and a note).
    """
    directory = Path(directory)
    out = Path(out) if out is not None else directory / "report"
    out.mkdir(parents=True, exist_ok=True)
    data = gather(directory)
    with matplotlib.rc_context(PLAIN_TEXT):
        pictures = build_figures(data)
        sessions = Sessions(trust=trust, robots=robots)
        arms: dict[str, ArmView] = {b.key: render(b, sessions) for b in data.buckets if b.sidecar is not None}
        views = {b.key: scenario.view_of(b.sidecar) for b in data.buckets}
        scenarios = {
            key: (view, scenario.figures(key, view)) for key, view in views.items() if view is not None
        }
    # each file whole or not at all (a full disk cut the page and the figures of the report before)
    written = {FILE_NAMES[name]: png for name, png in pictures.items()}
    for _, trajectories in scenarios.values():
        written.update(trajectories)
    for key, view in arms.items():
        if view.png is not None:
            written[f"arm-{re.sub(r'[^A-Za-z0-9_-]', '_', key)}.png"] = view.png
    for name, png in written.items():
        atomic_write(out / name, png, durable=False)
    for stale in out.iterdir():  # a figure of an earlier report that this page no longer shows
        if OWN_FIGURE.fullmatch(stale.name) and stale.name not in written and stale.is_file():
            with contextlib.suppress(OSError):
                stale.unlink()
    generated = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
    page = out / "report.html"
    sections = {key: scenario.section(key, view, pngs) for key, (view, pngs) in scenarios.items()}
    atomic_write(page, render_page(data, pictures, arms, generated, sections).encode("utf-8"), durable=False)
    return page
