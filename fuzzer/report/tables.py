"""The paper's tables and figures as data: Table III (divergences by kind and size), Table IV
(which target was closer to the command), Fig. 6 (strategies), Fig. 7 (joints near zero) and
Fig. 8 (differences). Pure: records in, frozen dataclasses out."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from fuzzer.artifacts.divlog import NEAR_ZERO
from fuzzer.mutation.base import PAPER_STRATEGIES  # the paper's Table II, in its order
from fuzzer.report.records import Divergence, Process

# Table III rows (labels as shown on the page).
ROW_BELOW_1E2 = "range < 1e-2"
ROW_1E2_1E1 = "1e-2 .. 1e-1"
ROW_ABOVE_1E1 = ">= 1e-1"
ROW_OTHER_UNITS = "in other units (s, rad/s, ...)"
ROW_COORDINATES = "coordinate values"
ROW_ROTATIONS = "rotation values"
ROW_STATUS = "different status or error"
ROW_CRASH = "crash of a target"
ROW_PROPERTY = "a target breaks the contract"
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
    "Field joint_values or position: coordinate values; field orientation: rotation values; "
    "a value divergence of another field with opposite signs is sized as the others.",
    "Value difference: the remaining 'value' divergences, by their difference d (metres or "
    "radians, after canonicalization): d < 1e-2, 1e-2 <= d < 1e-1, d >= 1e-1 (or not finite); "
    "a scenario's differences in other units (a duration in s, a velocity, a count of points) "
    "have a row of their own, shown when not empty.",
    "Property: kind 'property' (one target's answer breaks the contract whatever the other says, "
    "e.g. accelerations above the limits), shown when not empty.",
    "Ill-conditioned (an IK status flip caused by a singular seed), flaky (non-deterministic) "
    "and anything else: the last row.",
    "Numbers: divergent executions. Proportion: of all executions, as in the paper "
    "(which also divides by every executed test case). Share: of divergent executions.",
)


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
    if line.kind == "property":
        return ROW_PROPERTY
    if line.kind in ("representation", "value") and (line.kind == "representation" or line.sign_flip):
        field_ = line.field.split(".", 1)[-1]  # a scenario's field is "<step kind>.<quantity>"
        if field_ == "orientation":
            return ROW_ROTATIONS
        if field_ in ("joint_values", "position"):
            return ROW_COORDINATES
        if line.kind == "representation":
            return ROW_OTHER
        # a value of another field (a named target, a trajectory's points) with opposite signs
        # is sized as the others: all of them went to the last row
    if line.kind == "value":
        if line.unit not in ("", "m", "rad"):
            return ROW_OTHER_UNITS
        d = line.difference
        if not math.isfinite(d) or d >= 1e-1:
            return ROW_ABOVE_1E1
        return ROW_BELOW_1E2 if d < 1e-2 else ROW_1E2_1E1
    return ROW_OTHER


TABLE_III_LAYOUT = (
    (GROUP_RANGE, ROW_BELOW_1E2),
    (GROUP_RANGE, ROW_1E2_1E1),
    (GROUP_RANGE, ROW_ABOVE_1E1),
    (GROUP_RANGE, ROW_OTHER_UNITS),
    (GROUP_SIGN, ROW_COORDINATES),
    (GROUP_SIGN, ROW_ROTATIONS),
    (GROUP_STATUS, ROW_STATUS),
    (GROUP_STATUS, ROW_CRASH),
    (GROUP_STATUS, ROW_PROPERTY),
    ("", ROW_OTHER),
)


OPTIONAL = (ROW_OTHER_UNITS, ROW_PROPERTY, ROW_OTHER)
"""Rows the paper's Table III has not: shown only when a divergence falls in them."""


def table_iii(lines: Sequence[Divergence], executions: int) -> list[TableRow]:
    """Table III: divergent executions per row, then a total row (group ``total``).

    The rows that are not the paper's (other units, property, and the last: ill-conditioned,
    flaky, other) are left out when empty.
    """
    counts = Counter(classify(line) for line in lines)
    total = len(lines)

    def row(group: str, label: str, n: int) -> TableRow:
        return TableRow(group, label, n, n / executions if executions else None, n / total if total else None)

    rows = [
        row(g, label, counts[label])
        for g, label in TABLE_III_LAYOUT
        if label not in OPTIONAL or counts[label]
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
    other_units: int = 0
    """Value divergences in units other than m and rad (a duration, a velocity, a count):
    Table III's row of their own, not on Fig. 8's axis of metres and radians."""

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
            or self.other_units
        )


def differences(lines: Sequence[Divergence]) -> Differences:
    found: dict[str, list[float]] = {"value": [], "representation": []}
    zero = nonfinite = other_units = 0
    kinds: Counter[str] = Counter()
    for line in lines:
        if line.kind == "value" and line.unit not in ("", "m", "rad"):
            other_units += 1  # drawn on an axis of "m or rad": 40.8 s among them
        elif line.kind in found:
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
        other_units,
    )
