"""What the report shows, as plain data: logs and buckets in, dataclasses out.

Everything here is pure (no plotting, no HTML) except :func:`gather`, which reads
an artifacts folder. The campaign logs are read as records by ``fuzzer.report.records``; the
paper's tables and figures come from ``fuzzer.report.tables``, the buckets' views from
``fuzzer.report.buckets``.

Processes and campaigns
-----------------------
``stats.jsonl`` holds cumulative snapshots per process id. A process is one pid
whose counters never go backwards; a recycled pid (counters restart, or the start
time moves) is a new process. The totals of the page sum the *last* snapshot of
each process. Processes whose activity overlaps or follows within
:data:`RUN_GAP_SECONDS` form one *run* (one campaign, or several launched back to
back, or the workers of ``-fork``/``-jobs``), plotted on its own time axis.
"""

from __future__ import annotations

import json
import stat
from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from fuzzer.artifacts.divlog import DIVERGENCES, STATS
from fuzzer.artifacts.travel import CONFIGURATION
from fuzzer.input import untrusted_json
from fuzzer.report.buckets import BucketView, bucket_view
from fuzzer.report.records import Divergence, Process, Snapshot, parsed_records, processes
from fuzzer.report.tables import (
    CloserRow,
    Differences,
    NearZero,
    StrategyRow,
    TableRow,
    differences,
    near_zero,
    strategies,
    table_iii,
    table_iv,
)
from fuzzer.triage.pipeline import Bucket, collect

RUN_GAP_SECONDS = 60.0
"""Processes more than this far apart in time belong to different runs."""

UNKNOWN_CONFIG = "configuration not recorded"


# -- configurations -----------------------------------------------------------------------------------


def config_label(config: Mapping[str, Any] | None) -> str:
    """A short human name of a run configuration: robot, op and the two targets."""
    if not config:
        return UNKNOWN_CONFIG
    robot = Path(str(config.get("robot", "?"))).name
    targets = config.get("targets") or ["?", "?"]
    pair = " vs ".join(str(t) for t in targets)
    return f"{robot} · {config.get('op', '?')} · {pair}"


def tolerance_label(config: Mapping[str, Any]) -> str:
    tol = config.get("tolerance")
    if not isinstance(tol, dict):
        return "?"
    return f"{tol.get('m', '?')} m, {tol.get('rad', '?')} rad"


@dataclass(frozen=True)
class ConfigIndex:
    """Which configuration a process or a divergence belongs to.

    The logs do not record it: a process is known when one of its divergence lines
    is the input of a crash file (same sha1 and signature), whose sidecar has the
    configuration; otherwise a line falls back to the configuration of its signature.
    """

    by_pid: Mapping[int, Mapping[str, Any]]
    by_sig: Mapping[str, Mapping[str, Any]]
    only: Mapping[str, Any] | None = None
    """The one configuration every sidecar records, if they agree: that of every process (most
    processes write no crash file, the dry run's children write the first ones, and 31,343 of a
    campaign's 31,540 executions were drawn as "configuration not recorded")."""

    def for_pid(self, pid: int | None) -> Mapping[str, Any] | None:
        found = self.by_pid.get(pid) if pid is not None else None
        return found if found is not None else self.only

    def for_line(self, line: Divergence) -> Mapping[str, Any] | None:
        return self.for_pid(line.pid) or self.by_sig.get(line.sig)


def config_index(sidecars: Iterable[Mapping[str, Any]], lines: Sequence[Divergence]) -> ConfigIndex:
    """Map processes and signatures to the configurations recorded in sidecars."""
    by_sha: dict[tuple[str, str], Mapping[str, Any]] = {}
    by_sig: dict[str, Mapping[str, Any]] = {}
    distinct: dict[str, Mapping[str, Any]] = {}
    for sidecar in sidecars:
        config, signature = sidecar.get("config"), sidecar.get("signature")
        if not isinstance(config, dict) or not isinstance(signature, dict):
            continue
        distinct.setdefault(json.dumps(config, sort_keys=True, default=str), config)
        key = str(signature.get("key", ""))
        by_sig.setdefault(key, config)
        by_sha[(str(sidecar.get("sha1", "")), key)] = config
    by_pid: dict[int, Mapping[str, Any]] = {}
    conflicts: set[int] = set()
    for line in lines:
        config = by_sha.get((line.sha1, line.sig))
        if config is None or line.pid is None:
            continue
        if line.pid in by_pid and by_pid[line.pid] != config:
            conflicts.add(line.pid)  # a recycled pid ran two configurations: trust neither
        by_pid.setdefault(line.pid, config)
    only = next(iter(distinct.values())) if len(distinct) == 1 else None
    return ConfigIndex({p: c for p, c in by_pid.items() if p not in conflicts}, by_sig, only)


# -- over time -------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Band:
    """Cumulative counters of the processes of one configuration within a run."""

    label: str
    execs: tuple[float, ...]
    divergences: tuple[float, ...]


@dataclass(frozen=True)
class Run:
    """Processes close together in time, on one time axis (seconds since ``start``)."""

    start: float
    end: float
    processes: int
    times: tuple[float, ...]
    bands: tuple[Band, ...]

    @property
    def execs(self) -> tuple[float, ...]:
        return tuple(float(x) for x in np.sum([b.execs for b in self.bands], axis=0))

    @property
    def divergences(self) -> tuple[float, ...]:
        return tuple(float(x) for x in np.sum([b.divergences for b in self.bands], axis=0))


def _series(proc: Process, grid: np.ndarray, counter: Callable[[Snapshot], int]) -> np.ndarray:
    """A process's cumulative counter on ``grid``: 0 before it starts, linear between
    snapshots, held at its last value after it ends."""
    ts = [proc.start] + [s.t for s in proc.snapshots]
    ys = [0.0] + [float(counter(s)) for s in proc.snapshots]
    return np.asarray(np.interp(grid, ts, ys, left=0.0, right=ys[-1]), dtype=float)


def _total(
    members: Sequence[Process], grid: np.ndarray, counter: Callable[[Snapshot], int]
) -> tuple[float, ...]:
    total = np.zeros_like(grid)
    for proc in members:
        total += _series(proc, grid, counter)
    return tuple(float(x) for x in total)


def _execs(snapshot: Snapshot) -> int:
    return snapshot.execs


def _divergences(snapshot: Snapshot) -> int:
    return snapshot.divergences


def runs(procs: Sequence[Process], label_of: Callable[[int], str], gap: float = RUN_GAP_SECONDS) -> list[Run]:
    """Executions and divergences over time, summed over processes, one :class:`Run`
    per group of processes less than ``gap`` seconds apart; within a run, one band
    per configuration (in order of first appearance)."""
    groups: list[list[Process]] = []
    for proc in sorted(procs, key=lambda p: p.start):
        if groups and proc.start <= max(p.end for p in groups[-1]) + gap:
            groups[-1].append(proc)
        else:
            groups.append([proc])
    out = []
    for group in groups:
        start, end = min(p.start for p in group), max(p.end for p in group)
        grid = np.array(
            sorted({start, end} | {p.start for p in group} | {s.t for p in group for s in p.snapshots})
        )
        labels: dict[str, list[Process]] = {}
        for proc in group:
            labels.setdefault(label_of(proc.pid), []).append(proc)
        bands = tuple(
            Band(label, _total(members, grid, _execs), _total(members, grid, _divergences))
            for label, members in labels.items()
        )
        out.append(Run(start, end, len(group), tuple(float(x) for x in grid - start), bands))
    return out


# -- summary ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Summary:
    """The header of the page."""

    executions: int
    filtered: int
    malformed: int
    divergent: int
    """Divergent executions: lines of divergences.jsonl."""
    divergent_in_stats: int
    """The same count from the last snapshots (lower if a process died before its last one)."""
    by_kind: dict[str, int]
    signatures: int
    buckets: int
    processes: int
    robots: tuple[str, ...]
    ops: tuple[str, ...]
    targets: tuple[str, ...]
    tolerances: tuple[str, ...]
    first: float | None
    last: float | None

    @property
    def rate(self) -> float | None:
        return self.divergent / self.executions if self.executions else None


def summarize(
    lines: Sequence[Divergence],
    procs: Sequence[Process],
    buckets: Sequence[Bucket],
    configs: Iterable[Mapping[str, Any]],
) -> Summary:
    configs = list(configs)
    times = [line.t for line in lines if line.t is not None]
    times += [p.start for p in procs] + [p.end for p in procs]
    return Summary(
        executions=sum(p.last.execs for p in procs),
        filtered=sum(p.last.filtered for p in procs),
        malformed=sum(p.last.malformed for p in procs),
        divergent=len(lines),
        divergent_in_stats=sum(p.last.divergences for p in procs),
        by_kind=dict(sorted(Counter(line.kind for line in lines).items())),
        signatures=len({line.sig for line in lines} | {b.key for b in buckets if b.signature is not None}),
        buckets=len(buckets),
        processes=len(procs),
        robots=tuple(sorted({str(c.get("robot", "?")) for c in configs})),
        ops=tuple(sorted({str(c.get("op", "?")) for c in configs})),
        targets=tuple(sorted({" vs ".join(map(str, c.get("targets") or [])) for c in configs})),
        tolerances=tuple(sorted({tolerance_label(c) for c in configs})),
        first=min(times) if times else None,
        last=max(times) if times else None,
    )


# -- everything ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ReportData:
    """Everything the page shows, read from one artifacts folder."""

    directory: Path
    summary: Summary
    table_iii: list[TableRow]
    table_iv: list[CloserRow]
    strategies: list[StrategyRow]
    near_zero: NearZero
    differences: Differences
    runs: list[Run]
    buckets: list[Bucket]
    views: list[BucketView]
    notes: list[str]
    """Data problems worth knowing (skipped lines, counts that disagree, triage errors)."""

    @property
    def empty(self) -> bool:
        return not self.summary.executions and not self.summary.divergent and not self.buckets


def outside_links(directory: Path) -> list[Path]:
    """Entries of the folder that are symlinks leading outside it (never read by the report)."""
    from fuzzer.input.paths import contained

    if not directory.is_dir():
        return []
    return sorted(p for p in directory.iterdir() if p.is_symlink() and not contained(directory, p))


def _sidecars(directory: Path) -> list[dict[str, Any]]:
    """Every readable sidecar of the folder (all crash files, not only representatives)."""
    from fuzzer.artifacts.sidecar import SidecarError, validate
    from fuzzer.artifacts.store import oversized
    from fuzzer.input.paths import contained

    out = []
    for path in sorted(directory.glob("*.json")) if directory.is_dir() else []:
        # never open a FIFO or a device planted under a sidecar's name (reading one never returns)
        if not contained(directory, path) or not path.is_file() or oversized(path):
            continue
        try:
            data = untrusted_json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError, RecursionError):  # not UTF-8, bad JSON, an int past a float's range
            continue
        if not (isinstance(data, dict) and "signature" in data):
            continue
        try:  # a damaged one (config.targets a number) ended the report with a traceback
            validate(data, path)
        except SidecarError:
            continue  # triage's bucket of the file says "damaged sidecar"
        out.append(data)
    return out


def first_configuration(directory: Path) -> str | None:
    """The line ``travel.note_configuration`` wrote for the folder's first campaign (robot, tip
    link, targets), or None (no such file, or not one of ours)."""
    path = directory / CONFIGURATION
    try:
        info = path.lstat()
        if not stat.S_ISREG(info.st_mode) or info.st_size > 4096:
            return None
        text = path.read_bytes().decode("utf-8", "backslashreplace").strip()
    except OSError:
        return None
    return text if text.startswith("robot ") and "\n" not in text else None


def _agrees(first: str, config: Mapping[str, Any]) -> bool:
    """Whether the first campaign's line names ``config``'s robot and targets."""
    targets = config.get("targets")
    pair = ",".join(map(str, targets)) if isinstance(targets, list) else ""
    return first.startswith(f"robot {config.get('robot')} (") and first.endswith(f", targets {pair}")


def gather(directory: Path) -> ReportData:
    """Read an artifacts folder: both logs, sidecars and triage's buckets."""
    notes: list[str] = []
    outside = outside_links(directory)
    if outside:
        names = ", ".join(p.name for p in outside[:10]) + (" ..." if len(outside) > 10 else "")
        notes.append(
            f"{len(outside)} symbolic link(s) in the folder lead outside it and were ignored: {names}."
        )
    lines, div_skipped = (
        parsed_records(directory / DIVERGENCES, Divergence.parse)
        if directory / DIVERGENCES not in outside
        else ([], 0)
    )
    snaps, stat_skipped = (
        parsed_records(directory / STATS, Snapshot.parse) if directory / STATS not in outside else ([], 0)
    )
    for name, n in ((DIVERGENCES, div_skipped), (STATS, stat_skipped)):
        if n:
            notes.append(f"{n} malformed line(s) of {name} were skipped.")
    try:
        buckets = collect(directory) if directory.is_dir() else []
    except (OSError, ValueError, KeyError, TypeError) as exc:
        buckets = []
        notes.append(
            f"Triage could not read the crash files ({type(exc).__name__}: {exc}); no buckets shown."
        )
    procs = processes(snaps)
    sidecars = _sidecars(directory)
    index = config_index(sidecars, lines)
    configs = [c for c in (s.get("config") for s in sidecars) if isinstance(c, dict)]
    first = first_configuration(directory) if directory / CONFIGURATION not in outside else None
    if index.only is not None and first is not None and not _agrees(first, index.only):
        index = replace(index, only=None)  # the folder's first campaign ran on another configuration
    if not configs and first is not None and (lines or procs):
        notes.append(
            "No crash file here records the configuration of the campaigns; the folder's first "
            f"campaign ran on: {first} ({CONFIGURATION})."
        )
    summary = summarize(lines, procs, buckets, configs)
    if procs and summary.divergent_in_stats != summary.divergent:
        notes.append(
            f"stats.jsonl counts {summary.divergent_in_stats} divergent execution(s), divergences.jsonl "
            f"{summary.divergent}: a process stopped before its last snapshot, or a log was edited. "
            "Divergence counts come from divergences.jsonl, execution counts from stats.jsonl."
        )
    if lines and not procs:
        notes.append("stats.jsonl is missing or empty: executions are unknown, proportions are not shown.")
    return ReportData(
        directory=directory,
        summary=summary,
        table_iii=table_iii(lines, summary.executions),
        table_iv=table_iv(lines, index.for_line),
        strategies=strategies(lines, procs),
        near_zero=near_zero(lines, procs),
        differences=differences(lines),
        runs=runs(procs, lambda pid: config_label(index.for_pid(pid))),
        buckets=buckets,
        views=[bucket_view(b) for b in buckets],
        notes=notes,
    )
