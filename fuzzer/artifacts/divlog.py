"""Campaign logs in the artifacts folder, for triage and reports.

Two append-only JSON Lines files, written by every campaign process (``-fork``
and ``-jobs`` workers included):

``divergences.jsonl``
    One line per divergent execution (not only the first of its signature), so
    triage can count and the report can reproduce the paper's Tables III and IV
    and Figs. 6 and 8.
``stats.jsonl``
    A cumulative snapshot of each process's counters every few seconds and at
    exit: executions over time and Fig. 7 (joints near zero per test case).

Each line is one ``write`` to a file opened with O_APPEND, so lines from
concurrent processes do not interleave and ``kill -9`` cannot tear one. A reader
skips a line it cannot parse.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import math
import os
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fuzzer.input import untrusted_json

if TYPE_CHECKING:
    from fuzzer.execution.evaluate import Evaluation

DIVERGENCES = "divergences.jsonl"
STATS = "stats.jsonl"
NEAR_ZERO = 0.05
"""A joint value counts as "close to zero" (the paper's Fig. 7) below this (rad or m)."""


def append_line(path: Path, record: dict[str, Any]) -> None:
    """Append ``record`` as one line, in one ``O_APPEND`` write (concurrent writers never
    interleave within a line).

    Raises
    ------
    OSError
        It could not be written whole: a full disk writes part of it (``ENOSPC``; the line is
        torn, and :func:`end_torn_line` ends it before the next campaign appends).
    """
    data = (json.dumps(record, separators=(",", ":")) + "\n").encode()
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        written = os.write(fd, data)
        if written != len(data):  # a full disk, or a file size limit (which said "No space left")
            raise OSError(
                errno.ENOSPC,
                f"only {written} of a line's {len(data)} bytes written (a full disk?)",
                str(path),
            )
    finally:
        os.close(fd)


def end_torn_line(path: Path) -> None:
    """End a last line cut short (a write on a full disk) with a newline, so that the next record
    starts a line of its own instead of joining it (readers skip the torn line alone)."""
    with contextlib.suppress(OSError):
        with open(path, "rb") as handle:
            handle.seek(-1, os.SEEK_END)
            if handle.read(1) == b"\n":
                return
        fd = os.open(path, os.O_WRONLY | os.O_APPEND)
        try:
            os.write(fd, b"\n")
        finally:
            os.close(fd)


def read_lines(path: Path) -> Iterator[dict[str, Any]]:
    """Records of a JSON Lines file; unparsable lines are skipped."""
    for record in untrusted_json.jsonl_records(path):
        if isinstance(record, dict):
            yield record


def near_zero_count(values: Sequence[float]) -> int:
    """How many joint values of a test case are close to zero."""
    return sum(1 for v in values if math.isfinite(v) and abs(v) < NEAR_ZERO)


def closer_to_command(command: Sequence[float] | None, a: Sequence[float], b: Sequence[float]) -> str:
    """The paper's Table IV: which final state is nearer the commanded joint values.

    'a', 'b' or 'tie' (equal to 1e-12); 'n/a' without a full command.
    """
    if command is None or len(command) != len(a) or len(a) != len(b):
        return "n/a"
    da = math.fsum(abs(x - c) for x, c in zip(a, command, strict=True))
    db = math.fsum(abs(x - c) for x, c in zip(b, command, strict=True))
    if not (math.isfinite(da) and math.isfinite(db)) or abs(da - db) <= 1e-12:
        return "tie"
    return "a" if da < db else "b"


def divergence_record(
    ev: Evaluation,
    strategy: str,
    data: bytes,
    values: Sequence[float],
    joint_names: Sequence[str],
    command: Sequence[float] | None,
) -> dict[str, Any]:
    """The ``divergences.jsonl`` line of a divergent evaluation of the input ``data``.

    Parameters
    ----------
    ev : Evaluation
        A divergent evaluation (its ``signature`` set).
    strategy : str
        The lineage name that made the input.
    data : bytes
        The input's bytes (their SHA-1 names the crash file).
    values : sequence of float, shape (n_joints,)
        The joint values of a ``move`` or ``fk`` call (rad or m), empty otherwise.
    joint_names : sequence of str
        The robot's joint names, in the order of the comparison's joint indices.
    command : sequence of float or None, shape (n_joints,)
        The commanded joint values of a ``move`` naming every joint in order (rad or m), for
        ``closer`` (the paper's Table IV); None otherwise.
    """
    a, b = ev.outcomes
    finals = a.values.get("joint_values", ()), b.values.get("joint_values", ())
    cmp = ev.comparison
    assert ev.signature is not None
    return {
        "sig": ev.signature.key,
        "kind": str(cmp.kind),
        "field": cmp.field,
        "bucket": cmp.bucket,
        "sign_flip": cmp.sign_flip,
        "difference": cmp.difference,
        "unit": cmp.unit,
        "raw": cmp.raw,
        "joints": list(cmp.joints),
        "joint_names": [joint_names[j] for j in cmp.joints if j < len(joint_names)],
        "target": cmp.target,
        "step": cmp.step,
        "step_kind": cmp.step_kind,
        "unchecked": cmp.unchecked,
        "outcome_a": a.label,
        "outcome_b": b.label,
        "strategy": strategy,
        "near_zero": near_zero_count(values) if values else None,
        "closer": closer_to_command(command, *finals),
        "sha1": hashlib.sha1(data).hexdigest(),
    }


class CampaignLog:
    """The two logs of one campaign folder."""

    def __init__(self, directory: Path) -> None:
        self.divergences = directory / DIVERGENCES
        self.stats = directory / STATS
        for path in (self.divergences, self.stats):
            end_torn_line(path)

    @property
    def pid(self) -> int:
        """The writing process's: read at each record, so that a log made before a fork (the
        dry run's, ``fuzzer.dry_run``) names the child in the child's records."""
        return os.getpid()

    def divergence(self, record: dict[str, Any]) -> None:
        append_line(self.divergences, {"t": time.time(), "pid": self.pid, **record})

    def snapshot(self, record: dict[str, Any]) -> None:
        append_line(self.stats, {"t": time.time(), "pid": self.pid, **record})


def worker_totals(
    directory: Path, since: float, exclude_pid: int | None = None, pids: Sequence[int] | None = None
) -> dict[str, Any]:
    """Counters summed over the processes that logged to ``directory`` since ``since``
    (``-fork``/``-jobs`` workers; ``pids``: those processes only, e.g. the dry run's children):
    the last ``stats.jsonl`` snapshot of each process, and the distinct signatures of
    ``divergences.jsonl``.

    Returns ``processes``, ``execs``, ``filtered``, ``malformed``, ``interrupted`` (processes
    ended by a signal), ``divergent`` (kind -> count), ``divergences``, ``signatures`` and
    ``max_difference``.
    """
    last: dict[Any, dict[str, Any]] = {}
    for record in read_lines(directory / STATS):
        t, pid = record.get("t"), record.get("pid")
        if not isinstance(t, int | float) or t < since or not isinstance(pid, int) or pid == exclude_pid:
            continue  # a pid that is no int (a damaged line) could not even be a key
        if pids is not None and pid not in pids:
            continue
        last[pid] = record
    totals: dict[str, Any] = {"processes": len(last), "execs": 0, "filtered": 0, "malformed": 0}
    totals["interrupted"] = sum(r.get("interrupted") is True for r in last.values())
    divergent: dict[str, int] = {}
    biggest = 0.0
    for record in last.values():
        for name in ("execs", "filtered", "malformed"):
            value = record.get(name)
            totals[name] += value if isinstance(value, int) else 0
        kinds = record.get("divergent")
        for kind, n in kinds.items() if isinstance(kinds, dict) else ():
            divergent[str(kind)] = divergent.get(str(kind), 0) + (n if isinstance(n, int) else 0)
        value = record.get("max_difference")
        if isinstance(value, int | float) and math.isfinite(value):
            biggest = max(biggest, float(value))
    signatures = {
        str(r.get("sig"))
        for r in read_lines(directory / DIVERGENCES)
        if isinstance(r.get("t"), int | float)
        and r["t"] >= since
        and r.get("pid") != exclude_pid
        and (pids is None or r.get("pid") in pids)
    }
    totals.update(
        divergent=divergent,
        divergences=sum(divergent.values()),
        signatures=len(signatures),
        max_difference=biggest,
    )
    return totals
