"""The campaign logs as typed records: ``divergences.jsonl`` lines (:class:`Divergence`),
``stats.jsonl`` snapshots (:class:`Snapshot`) and the processes they come from.

Both logs (``fuzzer.artifacts.divlog``) are read leniently: a line that is not JSON, or lacks
the fields a record needs, is skipped and counted, never fatal.

``stats.jsonl`` holds cumulative snapshots per process id. A process is one pid whose counters
never go backwards; a recycled pid (counters restart, or the start time moves) is a new
process. The totals of the page sum the *last* snapshot of each process.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from fuzzer.input import untrusted_json

T = TypeVar("T")

# -- reading ----------------------------------------------------------------------------------------


def read_records(path: Path) -> tuple[list[dict[str, Any]], int]:
    """The JSON objects of a JSON Lines file and how many non-blank lines were not one.

    Parameters
    ----------
    path : Path
        A JSON Lines file; a missing file has no records.

    Returns
    -------
    records : list of dict
    skipped : int
    """
    return parsed_records(path, dict)


def parsed_records(path: Path, parse: Callable[[Mapping[str, Any]], T | None]) -> tuple[list[T], int]:
    """``parse`` of each JSON object of a JSON Lines file, and how many non-blank lines were not
    one or did not parse. Each line is parsed as it is read: a four-day scenario campaign's
    ``divergences.jsonl`` (1-2 GB, mostly explained divergences) held as dicts took about 6.6 MB of
    memory per MB of log."""
    parsed: list[T] = []
    skipped = 0
    for record in untrusted_json.jsonl_records(path):
        item = parse(record) if isinstance(record, dict) else None
        if item is None:
            skipped += 1
        else:
            parsed.append(item)
    return parsed, skipped


def _name(value: Any, default: str = "") -> str:
    """A string field, interned: a log repeats a few signatures, kinds and strategies."""
    return sys.intern(value) if isinstance(value, str) else default


LATEST = 253402300799.0
"""The last second of the year 9999 (s since the epoch): the latest time the page can print."""
COUNT_LIMIT = 2**63
"""A counter at or past this (a 64-bit counter's range) is not one a campaign wrote."""


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    try:
        return float(value)
    except OverflowError:  # an integer past a float's range (untrusted_json refuses most)
        return None


def _time(value: Any) -> float | None:
    """A time in seconds (since the epoch, or elapsed): a finite number from 0 to :data:`LATEST`,
    else None (a line with ``"t": 1e308`` or ``NaN`` made the page's clock and plots fail)."""
    number = _number(value)
    return number if number is not None and 0.0 <= number <= LATEST else None


def _int(value: Any, default: int = 0) -> int:
    counter = isinstance(value, int) and not isinstance(value, bool) and abs(value) < COUNT_LIMIT
    return value if counter else default


def _counter(value: Any) -> dict[str, int]:
    if not isinstance(value, dict):
        return {}
    return {str(k): v for k, v in value.items() if _int(v, -1) == v}


@dataclass(frozen=True, slots=True)
class Divergence:
    """One line of ``divergences.jsonl`` (one divergent execution)."""

    sig: str
    kind: str
    field: str = ""
    difference: float = 0.0
    sign_flip: bool = False
    strategy: str = "unknown"
    near_zero: int | None = None
    closer: str = "n/a"
    t: float | None = None
    pid: int | None = None
    sha1: str = ""
    unit: str = ""
    """The difference's unit (m, rad, s, ...; empty in logs from before it was recorded)."""

    @classmethod
    def parse(cls, record: Mapping[str, Any]) -> Divergence | None:
        """The divergence a record describes, or None when it lacks ``sig`` or ``kind``."""
        sig, kind = record.get("sig"), record.get("kind")
        if not isinstance(sig, str) or not isinstance(kind, str):
            return None
        difference = _number(record.get("difference"))
        if kind == "representation" and "raw" in record:
            # Fig. 8 shows the paper's difference information: the gap as numbers (the
            # headline "difference" of a representation divergence is modulo equivalence)
            difference = _number(record.get("raw"))
        near_zero = record.get("near_zero")
        strategy, closer, field_ = record.get("strategy"), record.get("closer"), record.get("field")
        pid, sha1 = record.get("pid"), record.get("sha1")
        return cls(
            sig=_name(sig),
            kind=_name(kind),
            field=_name(field_),
            difference=0.0 if difference is None else difference,
            sign_flip=record.get("sign_flip") is True,
            strategy=_name(strategy, "unknown"),
            near_zero=near_zero if isinstance(near_zero, int) and not isinstance(near_zero, bool) else None,
            closer=closer if closer in ("a", "b", "tie", "n/a") else "n/a",
            t=_time(record.get("t")),
            pid=pid if isinstance(pid, int) and not isinstance(pid, bool) else None,
            sha1=sha1 if isinstance(sha1, str) else "",
            unit=_name(record.get("unit")),
        )


@dataclass(frozen=True, slots=True)
class Snapshot:
    """One line of ``stats.jsonl``: a process's cumulative counters at time ``t``."""

    t: float
    pid: int
    elapsed: float
    execs: int
    filtered: int = 0
    malformed: int = 0
    divergent: Mapping[str, int] = field(default_factory=dict)
    by_strategy: Mapping[str, int] = field(default_factory=dict)
    executed_by_strategy: Mapping[str, int] = field(default_factory=dict)
    near_zero: Mapping[str, int] = field(default_factory=dict)

    @property
    def start(self) -> float:
        """Wall-clock time at which this process's counters were zero."""
        return self.t - self.elapsed

    @property
    def divergences(self) -> int:
        return sum(self.divergent.values())

    @classmethod
    def parse(cls, record: Mapping[str, Any]) -> Snapshot | None:
        """The snapshot a record describes, or None without numeric ``t``, ``pid``, ``execs``."""
        t, pid, execs = _time(record.get("t")), record.get("pid"), _int(record.get("execs"), -1)
        if t is None or not isinstance(pid, int) or isinstance(pid, bool) or execs < 0:
            return None
        elapsed = _time(record.get("elapsed"))
        return cls(
            t=t,
            pid=pid,
            elapsed=max(0.0, elapsed or 0.0),
            execs=execs,
            filtered=_int(record.get("filtered")),
            malformed=_int(record.get("malformed")),
            divergent=_counter(record.get("divergent")),
            by_strategy=_counter(record.get("by_strategy")),
            executed_by_strategy=_counter(record.get("executed_by_strategy")),
            near_zero=_counter(record.get("near_zero")),
        )


@dataclass(frozen=True)
class Process:
    """The snapshots of one campaign process, oldest first."""

    pid: int
    snapshots: tuple[Snapshot, ...]

    @property
    def start(self) -> float:
        return self.snapshots[0].start

    @property
    def end(self) -> float:
        return self.snapshots[-1].t

    @property
    def last(self) -> Snapshot:
        return self.snapshots[-1]


def processes(snapshots: Iterable[Snapshot]) -> list[Process]:
    """Group snapshots into processes (a pid may be recycled), ordered by start time.

    A pid's sequence is cut wherever its executions go backwards or its start time
    moves by more than a second: that is a new process with the same pid.
    """
    by_pid: dict[int, list[Snapshot]] = {}
    for snap in snapshots:
        by_pid.setdefault(snap.pid, []).append(snap)
    out: list[Process] = []
    for pid, snaps in by_pid.items():
        current: list[Snapshot] = []
        for snap in sorted(snaps, key=lambda s: s.t):
            if current and (snap.execs < current[-1].execs or abs(snap.start - current[-1].start) > 1.0):
                out.append(Process(pid, tuple(current)))
                current = []
            current.append(snap)
        out.append(Process(pid, tuple(current)))
    return sorted(out, key=lambda p: (p.start, p.pid))
