"""What the report shows, as plain data: logs and buckets in, dataclasses out.

Everything here is pure (no plotting, no HTML) except :func:`gather`, which reads
an artifacts folder. The two campaign logs (``fuzzer.artifacts.divlog``) are read leniently:
a line that is not JSON, or lacks the fields a record needs, is skipped and
counted, never fatal.

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
import math
import shlex
from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from fuzzer.artifacts.divlog import DIVERGENCES, NEAR_ZERO, STATS
from fuzzer.triage.pipeline import Bucket, collect

PAPER_STRATEGIES = ("bit_flip", "arithmetic", "interesting", "comb1", "comb2", "comb3", "comb4")
"""The paper's basic and combination mutation strategies (Table II), in its order."""

RUN_GAP_SECONDS = 60.0
"""Processes more than this far apart in time belong to different runs."""

UNKNOWN_CONFIG = "configuration not recorded"

# Table III rows (labels as shown on the page).
ROW_BELOW_1E2 = "range < 1e-2"
ROW_1E2_1E1 = "1e-2 .. 1e-1"
ROW_ABOVE_1E1 = ">= 1e-1"
ROW_COORDINATES = "coordinate values"
ROW_ROTATIONS = "rotation values"
ROW_STATUS = "different status or error"
ROW_CRASH = "crash of a target"
ROW_OTHER = "ill-conditioned, flaky or other"

GROUP_RANGE = "value difference"
GROUP_SIGN = "positive and negative"
GROUP_STATUS = "status and crash"

TABLE_III_RULES = (
    "Each divergent execution (one line of divergences.jsonl) falls in exactly one row; "
    "the first rule that matches decides.",
    "Crash: kind 'crash' (a target raised a non-API exception). "
    "Status: kind 'status' (different statuses, error classes or codes).",
    "Positive and negative: kind 'representation' (equal modulo 2pi or q/-q, different as "
    "numbers) or a value divergence whose differing numbers have opposite signs. "
    "Field joint_values or position: coordinate values; field orientation: rotation values.",
    "Value difference: the remaining 'value' divergences, by their difference d (metres or "
    "radians, after canonicalization): d < 1e-2, 1e-2 <= d < 1e-1, d >= 1e-1 (or not finite).",
    "Ill-conditioned (an IK status flip caused by a singular seed), flaky (non-deterministic) "
    "and anything else: the last row.",
    "Numbers: divergent executions. Proportion: of all executions, as in the paper "
    "(which also divides by every executed test case). Share: of divergent executions.",
)


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
    records: list[dict[str, Any]] = []
    skipped = 0
    if not path.is_file():
        return records, skipped
    with open(path, encoding="utf-8", errors="replace") as handle:
        for line in handle:
            if not line.strip():
                continue
            try:
                record = json.loads(line)
            except (json.JSONDecodeError, RecursionError):
                skipped += 1
                continue
            if isinstance(record, dict):
                records.append(record)
            else:
                skipped += 1
    return records, skipped


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value)


def _int(value: Any, default: int = 0) -> int:
    return value if isinstance(value, int) and not isinstance(value, bool) else default


def _counter(value: Any) -> dict[str, int]:
    if not isinstance(value, dict):
        return {}
    return {str(k): v for k, v in value.items() if isinstance(v, int) and not isinstance(v, bool)}


@dataclass(frozen=True)
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
            sig=sig,
            kind=kind,
            field=field_ if isinstance(field_, str) else "",
            difference=0.0 if difference is None else difference,
            sign_flip=record.get("sign_flip") is True,
            strategy=strategy if isinstance(strategy, str) else "unknown",
            near_zero=near_zero if isinstance(near_zero, int) and not isinstance(near_zero, bool) else None,
            closer=closer if closer in ("a", "b", "tie", "n/a") else "n/a",
            t=_number(record.get("t")),
            pid=pid if isinstance(pid, int) and not isinstance(pid, bool) else None,
            sha1=sha1 if isinstance(sha1, str) else "",
        )


@dataclass(frozen=True)
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
        t, pid, execs = _number(record.get("t")), record.get("pid"), record.get("execs")
        if t is None or not isinstance(pid, int) or not isinstance(execs, int) or isinstance(execs, bool):
            return None
        elapsed = _number(record.get("elapsed"))
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

    def for_pid(self, pid: int | None) -> Mapping[str, Any] | None:
        return self.by_pid.get(pid) if pid is not None else None

    def for_line(self, line: Divergence) -> Mapping[str, Any] | None:
        return self.for_pid(line.pid) or self.by_sig.get(line.sig)


def config_index(sidecars: Iterable[Mapping[str, Any]], lines: Sequence[Divergence]) -> ConfigIndex:
    """Map processes and signatures to the configurations recorded in sidecars."""
    by_sha: dict[tuple[str, str], Mapping[str, Any]] = {}
    by_sig: dict[str, Mapping[str, Any]] = {}
    for sidecar in sidecars:
        config, signature = sidecar.get("config"), sidecar.get("signature")
        if not isinstance(config, dict) or not isinstance(signature, dict):
            continue
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
    return ConfigIndex({p: c for p, c in by_pid.items() if p not in conflicts}, by_sig)


# -- Table III ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TableRow:
    """One row of Table III."""

    group: str
    label: str
    count: int
    proportion: float | None
    """Of all executions (None without executions)."""
    share: float | None
    """Of divergent executions (None without divergences)."""


def classify(line: Divergence) -> str:
    """The Table III row of one divergence (rules in :data:`TABLE_III_RULES`)."""
    if line.kind == "crash":
        return ROW_CRASH
    if line.kind == "status":
        return ROW_STATUS
    if line.kind in ("representation", "value") and (line.kind == "representation" or line.sign_flip):
        field_ = line.field.split(".", 1)[-1]  # a scenario's field is "<step kind>.<quantity>"
        if field_ == "orientation":
            return ROW_ROTATIONS
        if field_ in ("joint_values", "position"):
            return ROW_COORDINATES
        return ROW_OTHER
    if line.kind == "value":
        d = line.difference
        if not math.isfinite(d) or d >= 1e-1:
            return ROW_ABOVE_1E1
        return ROW_BELOW_1E2 if d < 1e-2 else ROW_1E2_1E1
    return ROW_OTHER


TABLE_III_LAYOUT = (
    (GROUP_RANGE, ROW_BELOW_1E2),
    (GROUP_RANGE, ROW_1E2_1E1),
    (GROUP_RANGE, ROW_ABOVE_1E1),
    (GROUP_SIGN, ROW_COORDINATES),
    (GROUP_SIGN, ROW_ROTATIONS),
    (GROUP_STATUS, ROW_STATUS),
    (GROUP_STATUS, ROW_CRASH),
    ("", ROW_OTHER),
)


def table_iii(lines: Sequence[Divergence], executions: int) -> list[TableRow]:
    """Table III: divergent executions per row, then a total row (group ``total``).

    The last row (ill-conditioned, flaky, other) is left out when empty.
    """
    counts = Counter(classify(line) for line in lines)
    total = len(lines)

    def row(group: str, label: str, n: int) -> TableRow:
        return TableRow(group, label, n, n / executions if executions else None, n / total if total else None)

    rows = [
        row(g, label, counts[label]) for g, label in TABLE_III_LAYOUT if label != ROW_OTHER or counts[label]
    ]
    rows.append(row("total", "all divergent executions", total))
    return rows


# -- Table IV -----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CloserRow:
    """Table IV for one pair of targets: whose final state is nearer the command."""

    target_a: str
    target_b: str
    a: int
    b: int
    tie: int
    excluded: int
    """Lines with closer 'n/a' (no full joint command, e.g. status divergences, fk, ik)."""

    @property
    def compared(self) -> int:
        return self.a + self.b + self.tie


def table_iv(
    lines: Sequence[Divergence], configs: Callable[[Divergence], Mapping[str, Any] | None]
) -> list[CloserRow]:
    """Table IV, one row per target pair seen (unknown pairs are named 'target a'/'target b')."""
    tallies: dict[tuple[str, str], Counter[str]] = {}
    for line in lines:
        config = configs(line)
        targets = config.get("targets") if config else None
        pair = ("target a", "target b")
        if isinstance(targets, list) and len(targets) == 2:
            pair = (str(targets[0]), str(targets[1]))
        tallies.setdefault(pair, Counter())[line.closer] += 1
    return [CloserRow(a, b, c["a"], c["b"], c["tie"], c["n/a"]) for (a, b), c in sorted(tallies.items())]


# -- Fig. 6: strategies --------------------------------------------------------------------------------


@dataclass(frozen=True)
class StrategyRow:
    """Divergences and executions of one mutation strategy."""

    name: str
    divergences: int
    executions: int | None
    """Evaluated test cases it produced (None when stats.jsonl does not say)."""

    @property
    def paper(self) -> bool:
        return self.name in PAPER_STRATEGIES

    @property
    def rate(self) -> float | None:
        return self.divergences / self.executions if self.executions else None


def strategies(lines: Sequence[Divergence], procs: Sequence[Process]) -> list[StrategyRow]:
    """Per strategy: divergences (from divergences.jsonl, which every divergence reaches)
    and executions (``executed_by_strategy`` of each process's last snapshot).

    The paper's strategies come first in the paper's order, then the others by
    divergences (most first) and name.
    """
    divergent = Counter(line.strategy for line in lines)
    executed: Counter[str] = Counter()
    for proc in procs:
        executed.update(proc.last.executed_by_strategy)
    known = bool(procs)
    names = set(divergent) | set(executed)
    rows = [StrategyRow(n, divergent[n], executed[n] if known else None) for n in names]
    return sorted(
        rows,
        key=lambda r: (
            not r.paper,
            PAPER_STRATEGIES.index(r.name) if r.paper else 0,
            -r.divergences,
            -(r.executions or 0),
            r.name,
        ),
    )


# -- Fig. 7: joints near zero --------------------------------------------------------------------------


@dataclass(frozen=True)
class NearZero:
    """Test cases by how many joint values are within ``threshold`` of zero (move and fk)."""

    evaluated: dict[int, int]
    """All evaluated test cases (stats.jsonl, last snapshot of each process, summed)."""
    divergent: dict[int, int]
    """Divergent ones (divergences.jsonl)."""
    threshold: float = NEAR_ZERO

    @property
    def empty(self) -> bool:
        return not self.evaluated and not self.divergent


def near_zero(lines: Sequence[Divergence], procs: Sequence[Process]) -> NearZero:
    evaluated: Counter[int] = Counter()
    for proc in procs:
        for key, n in proc.last.near_zero.items():
            if key.lstrip("-").isdigit():
                evaluated[int(key)] += n
    divergent = Counter(line.near_zero for line in lines if line.near_zero is not None)
    return NearZero(dict(sorted(evaluated.items())), {k: divergent[k] for k in sorted(divergent)})


# -- Fig. 8: differences -------------------------------------------------------------------------------


@dataclass(frozen=True)
class Differences:
    """The paper's difference information."""

    values: tuple[float, ...]
    """Positive finite differences of value divergences (m or rad), sorted."""
    representations: tuple[float, ...]
    """Positive finite differences of representation divergences, sorted."""
    zero: int
    """Value or representation divergences with a zero difference."""
    nonfinite: int
    status: int
    crash: int
    other: int

    @property
    def empty(self) -> bool:
        return not (
            self.values
            or self.representations
            or self.zero
            or self.nonfinite
            or self.status
            or self.crash
            or self.other
        )


def differences(lines: Sequence[Divergence]) -> Differences:
    found: dict[str, list[float]] = {"value": [], "representation": []}
    zero = nonfinite = 0
    kinds: Counter[str] = Counter()
    for line in lines:
        if line.kind in found:
            if not math.isfinite(line.difference):
                nonfinite += 1
            elif line.difference > 0:
                found[line.kind].append(line.difference)
            else:
                zero += 1
        else:
            kinds[line.kind if line.kind in ("status", "crash") else "other"] += 1
    return Differences(
        tuple(sorted(found["value"])),
        tuple(sorted(found["representation"])),
        zero,
        nonfinite,
        kinds["status"],
        kinds["crash"],
        kinds["other"],
    )


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


# -- buckets ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class OutcomeView:
    """One target's recorded answer."""

    target: str
    status: str
    error: str
    code: int | None
    message: str
    values: dict[str, tuple[float, ...]]

    @property
    def label(self) -> str:
        if self.error or self.status in ("rejected", "crashed"):
            return f"{self.status}: {self.error} (code {self.code})"
        return self.status

    @classmethod
    def parse(cls, data: Any) -> OutcomeView | None:
        if not isinstance(data, dict):
            return None
        values: dict[str, tuple[float, ...]] = {}
        raw = data.get("values")
        if isinstance(raw, dict):
            for name, vector in raw.items():
                if isinstance(vector, list):
                    values[str(name)] = tuple(float(x) for x in vector if _number(x) is not None)
        code = data.get("code")
        return cls(
            str(data.get("target", "?")),
            str(data.get("status", "?")),
            str(data.get("error") or ""),
            code if isinstance(code, int) else None,
            str(data.get("message") or ""),
            values,
        )


@dataclass(frozen=True)
class BucketView:
    """What the page shows of one bucket."""

    key: str
    kind: str
    description: str
    count: int
    path: str
    """The file to look at (minimized when there is one)."""
    representative: str
    minimized: str | None
    replay: str
    size: int
    signature: dict[str, Any] | None = None
    config: dict[str, Any] | None = None
    outcomes: tuple[OutcomeView, ...] = ()
    joint_names: tuple[str, ...] = ()
    message: str = ""
    msg_type: str = ""
    lineage: tuple[str, ...] = ()
    lineage_length: int = 0
    sequence: int | None = None
    origin: str = ""
    difference: float | None = None
    unit: str = ""
    written: str = ""
    call: dict[str, Any] | None = None
    """The call the sidecar recorded (``kind``: MoveCall, FkCall or IkCall)."""
    preview: str = ""
    """First bytes of a file without sidecar."""

    @property
    def has_sidecar(self) -> bool:
        return self.signature is not None


MESSAGE_CHARS = 1500


def compact_json(value: Any, limit: int = MESSAGE_CHARS) -> str:
    """One-line JSON, cut at ``limit`` characters."""
    text = json.dumps(value, separators=(", ", ": "), ensure_ascii=False, allow_nan=True)
    return text if len(text) <= limit else text[:limit] + f" ... ({len(text) - limit} more characters)"


def bucket_view(bucket: Bucket) -> BucketView:
    path = bucket.best
    try:
        size = path.stat().st_size
    except OSError:
        size = -1
    common = BucketView(
        key=bucket.key,
        kind=bucket.kind,
        description=bucket.describe(),
        count=bucket.count,
        path=str(path),
        representative=str(bucket.representative),
        minimized=str(bucket.minimized) if bucket.minimized else None,
        replay=f"python fuzz_diff.py {shlex.quote(str(path.resolve()))}",
        size=size,
    )
    sidecar = bucket.sidecar
    if sidecar is None or bucket.signature is None:
        try:
            head = path.read_bytes()[:240]
        except OSError:
            head = b""
        return replace(common, preview=head.decode("utf-8", errors="replace"))
    testcase = sidecar.get("testcase") if isinstance(sidecar.get("testcase"), dict) else {}
    assert isinstance(testcase, dict)
    outcomes = tuple(o for o in map(OutcomeView.parse, sidecar.get("outcomes") or []) if o is not None)
    lineage = sidecar.get("lineage") or testcase.get("lineage") or []
    difference = _number(sidecar.get("difference"))
    sequence = testcase.get("sequence")
    config, call = sidecar.get("config"), sidecar.get("call")
    return replace(
        common,
        signature=bucket.signature.to_json(),
        config=config if isinstance(config, dict) else None,
        outcomes=outcomes,
        joint_names=tuple(str(n) for n in sidecar.get("joint_names") or []),
        message=compact_json(testcase.get("message", {})),
        msg_type=str(testcase.get("msg_type", "")),
        lineage=tuple(str(s) for s in lineage),
        lineage_length=_int(testcase.get("lineage_length"), len(lineage)),
        sequence=sequence if isinstance(sequence, int) else None,
        origin=str(testcase.get("origin", "")),
        difference=difference,
        unit=bucket.difference[1] if bucket.difference[1] != "status" else "",
        written=str(sidecar.get("written", "")),
        call=call if isinstance(call, dict) else None,
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
    from fuzzer.input.paths import contained

    out = []
    for path in sorted(directory.glob("*.json")) if directory.is_dir() else []:
        if not contained(directory, path):
            continue
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError):
            continue
        if isinstance(data, dict) and "signature" in data:
            out.append(data)
    return out


def gather(directory: Path) -> ReportData:
    """Read an artifacts folder: both logs, sidecars and triage's buckets."""
    notes: list[str] = []
    outside = outside_links(directory)
    if outside:
        names = ", ".join(p.name for p in outside[:10]) + (" ..." if len(outside) > 10 else "")
        notes.append(
            f"{len(outside)} symbolic link(s) in the folder lead outside it and were ignored: {names}."
        )
    div_records, div_skipped = (
        read_records(directory / DIVERGENCES) if directory / DIVERGENCES not in outside else ([], 0)
    )
    stat_records, stat_skipped = (
        read_records(directory / STATS) if directory / STATS not in outside else ([], 0)
    )
    lines = [d for d in map(Divergence.parse, div_records) if d is not None]
    snaps = [s for s in map(Snapshot.parse, stat_records) if s is not None]
    div_skipped += len(div_records) - len(lines)
    stat_skipped += len(stat_records) - len(snaps)
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
