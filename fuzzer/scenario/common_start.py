"""A divergence at a step the two arms began apart: the step re-run from one common state.

An earlier step the oracle does not count can leave the two arms apart as numbers: two IK
answers of one pose (``known_limitation``), such as joint_6 of PROBOT Anno at -pi on one
target and +pi on the other, which the oracle compares modulo 2pi and calls one state. Every
later step then starts from two different states, and what a step computes from its start
may differ for that reason alone: the room each joint has to its limits along a Cartesian
path (from -pi a joint with limits +-3.1416 can turn 6.28 rad one way, from +pi 7e-6 rad),
the way a plan turns. The oracle cannot tell that from a fault by looking at the step.

So the evaluator re-runs the scenario up to that step twice on fresh targets, each time with
both arms moved, just before the step, to one target's state (``Nudge(step, 0.0, Moved.TO,
state=...)``: the first target's state, then the second's). If at that step both re-runs agree,
or differ only as a documented limitation explains (``oracle_ik.classify``, with the common
state as the start), the split start is the whole difference: ``known_limitation``. If either
re-run still diverges there, the divergence stands and goes on to the usual checks.

Found by the controls on 0586935 (``control@scenario/probot_anno``, seed 1;
``benchmarks/results/control-fp-0586935/``): a ``/cartesian_path`` to home turned half a turn
about z left joint_6 at -pi on native and +pi on the twin; the next path then got 0% of the way
on one and 7.1% on the other.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import replace

from fuzzer.execution.records import Comparison, Kind, Outcome
from fuzzer.execution.tolerance import Tolerance
from fuzzer.scenario.execute import NUDGE_FAILED
from fuzzer.scenario.nudge import Moved, Nudge
from fuzzer.scenario.oracle import compare_step
from fuzzer.scenario.oracle_facts import ScenarioFacts, contexts
from fuzzer.scenario.oracle_ik import classify
from fuzzer.scenario.steps import ScenarioCall

State = tuple[float, ...]
Rerun = Callable[[ScenarioCall, Nudge], Sequence[Outcome]]
"""Runs a scenario on both (fresh) targets with a nudge."""


def split_states(
    call: ScenarioCall, outcomes: Sequence[Outcome], step: int, facts: ScenarioFacts, tol: Tolerance
) -> tuple[State, State] | None:
    """The two targets' states before ``step`` when they differ as numbers by more than the
    tolerance on some joint (rad, or m for a prismatic one); else None."""
    if step < 1 or len(outcomes) < 2:
        return None
    before = [contexts(call, o, facts) for o in outcomes[:2]]
    if any(step >= len(b) for b in before):
        return None
    x, y = before[0][step].state, before[1][step].state
    if not x or not y or len(x) != len(y) or len(x) != len(facts.joints):
        return None
    limits = [tol.metres if p else tol.radians for p in facts.prismatic]
    if all(abs(p - q) <= lim for p, q, lim in zip(x, y, limits, strict=True)):
        return None
    return tuple(x), tuple(y)


def agrees_from(
    call: ScenarioCall,
    again: Sequence[Outcome],
    step: int,
    state: State,
    facts: ScenarioFacts,
    tol: Tolerance,
) -> bool:
    """Whether two runs started at ``step`` from ``state`` agree there, or differ only as a
    documented limitation explains (``classify`` with ``state`` as both starts)."""
    if len(again) != 2 or any(NUDGE_FAILED in o.values or step >= len(o.steps) for o in again):
        return False  # a target refused the move, or ended earlier: no evidence
    a, b = again[0].steps[step], again[1].steps[step]
    kind = call.steps[step].kind
    c = compare_step(kind, a, b, tol, facts)
    if not c.divergent:
        return True
    before = tuple(replace(contexts(call, o, facts)[step], state=state) for o in again)
    return classify(call, step, a, b, c, (before[0], before[1]), facts, tol).kind is Kind.KNOWN_LIMITATION


def judge(
    call: ScenarioCall,
    outcomes: Sequence[Outcome],
    comparison: Comparison,
    facts: ScenarioFacts,
    tol: Tolerance,
    rerun: Rerun,
    out_of_time: Callable[[float], bool],
) -> Comparison:
    """``comparison`` as ``known_limitation`` when its step began from states split beyond the
    tolerance and, started from either target's state, the two targets agree there (module
    docstring); otherwise ``comparison`` unchanged (also when ``out_of_time(longest re-run)``
    says a re-run would not fit the input's time budget: the usual checks then note that)."""
    step = comparison.step
    if comparison.kind not in (Kind.STATUS, Kind.VALUE) or step is None:
        return comparison
    states = split_states(call, outcomes, step, facts, tol)
    if states is None:
        return comparison
    prefix = replace(call, steps=call.steps[: step + 1])
    longest = 0.0
    for state in states:
        if out_of_time(longest):
            return comparison
        began = time.monotonic()
        again = rerun(prefix, Nudge(step, 0.0, Moved.TO, state=state))
        longest = max(longest, time.monotonic() - began)
        if not agrees_from(prefix, again, step, state, facts, tol):
            return comparison
    return replace(comparison, kind=Kind.KNOWN_LIMITATION)
