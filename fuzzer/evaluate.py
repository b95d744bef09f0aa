"""Unified execution and difference computation (paper III.D) for one test case.

``Evaluator.evaluate`` filters the input (III.E), maps the message onto a call,
runs it on both targets, asks the oracle, and confirms a divergence before it
counts: the input is run a second time (nondeterminism gives ``flaky``), and
an IK status divergence is re-run from seeds moved by 1e-9 (both ways) and 1e-7,
where a target that changes its own answer makes it ``ill_conditioned``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from typing import Any

from fuzzer import oracle
from fuzzer.mapping import Call, IkCall
from fuzzer.records import Comparison, Kind, Outcome, Signature, Status, signature_of
from fuzzer.targets import Runner
from fuzzer.testcase import TestCase
from fuzzer.tolerance import Tolerance

ABSURD = 1e6
"""Early input filtering drops floats larger than this in magnitude (and NaN/inf)."""

IK_PERTURBATIONS = (1e-9, -1e-9, 1e-7)
"""Seed shifts tried when checking an IK status divergence for ill-conditioning (every joint
moves by the shift, alternating in sign for the last one)."""


class Verdict:
    FILTERED = "filtered"
    MALFORMED = "malformed"
    EVALUATED = "evaluated"


@dataclass(frozen=True)
class Evaluation:
    """Everything known about one executed test case."""

    verdict: str
    call: Call | None = None
    outcomes: tuple[Outcome, ...] = ()
    comparison: Comparison = field(default_factory=lambda: Comparison(Kind.AGREE))
    signature: Signature | None = None
    difference: float = 0.0
    reason: str = ""

    @property
    def divergent(self) -> bool:
        return self.verdict == Verdict.EVALUATED and self.comparison.divergent


def floats_of(value: Any) -> Iterator[float]:
    """Every float leaf of a message."""
    if isinstance(value, float):
        yield value
    elif isinstance(value, dict):
        for item in value.values():
            yield from floats_of(item)
    elif isinstance(value, list):
        for item in value:
            yield from floats_of(item)


def is_reasonable(message: dict[str, Any]) -> bool:
    """Early input filtering: finite floats of sane magnitude only."""
    return all(math.isfinite(x) and abs(x) <= ABSURD for x in floats_of(message))


@dataclass
class Evaluator:
    """Runs test cases on two targets and judges them."""

    op: str
    runners: tuple[Runner, Runner]
    mapping: Callable[[dict[str, Any]], Call]
    tolerance: Tolerance
    validate: Callable[[dict[str, Any]], None]
    filtering: bool = True
    prismatic: tuple[bool, ...] = ()

    def run_both(
        self, call: Call, seeds: tuple[tuple[float, ...] | None, ...] = (None, None)
    ) -> tuple[Outcome, ...]:
        return tuple(r.run(call, s) for r, s in zip(self.runners, seeds, strict=True))

    def judge(self, outcomes: tuple[Outcome, ...]) -> Comparison:
        return oracle.compare(outcomes[0], outcomes[1], self.tolerance, self.prismatic, self.op)

    def evaluate(self, case: TestCase, validated: bool = False) -> Evaluation:
        message = case.message
        if not validated:
            try:
                self.validate(message)
            except ValueError as exc:
                return Evaluation(Verdict.MALFORMED, reason=str(exc))
        if self.filtering and not is_reasonable(message):
            return Evaluation(Verdict.FILTERED, reason="non-finite or absurd value")
        call = self.mapping(message)
        outcomes = self.run_both(call)
        comparison = self.judge(outcomes)
        if comparison.divergent:
            comparison, outcomes = self._confirm(call, outcomes, comparison)
        a, b = outcomes
        signature = signature_of(self.op, a, b, comparison) if comparison.divergent else None
        return Evaluation(Verdict.EVALUATED, call, outcomes, comparison, signature, comparison.largest)

    def _confirm(
        self, call: Call, outcomes: tuple[Outcome, ...], comparison: Comparison
    ) -> tuple[Comparison, tuple[Outcome, ...]]:
        again = self.run_both(call)
        if self.judge(again) != comparison:
            return replace(comparison, kind=Kind.FLAKY), outcomes
        if (
            isinstance(call, IkCall)
            and comparison.kind is Kind.STATUS
            and {o.status for o in outcomes} <= {Status.OK, Status.FAILED}
        ):
            for i, shift in enumerate(IK_PERTURBATIONS):
                moved = tuple(
                    tuple(v + (shift if i < 2 or j % 2 == 0 else -shift) for j, v in enumerate(r.home))
                    for r in self.runners
                )
                for first, second in zip(outcomes, self.run_both(call, moved), strict=True):
                    if first.status is not second.status:
                        return replace(comparison, kind=Kind.ILL_CONDITIONED), outcomes
        return comparison, outcomes
