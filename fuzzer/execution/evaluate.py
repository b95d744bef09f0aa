"""Unified execution and difference computation (paper III.D) for one test case.

``Evaluator.evaluate`` filters the input (III.E), maps the message onto a call,
runs it on both targets, asks the oracle (and, for IK, checks each target's
success on its own: ``oracle.ik_property``), and confirms a divergence before
it counts:

* on fresh targets: the input is run on newly constructed targets (new model,
  new group, same process). If they show the same verdict, the divergence
  stands. If not, the campaign's targets are asked again: the same verdict there
  makes it ``state_dependent`` (the answer depends on earlier calls; the last
  ``HISTORY`` calls go with it, and ``evaluate(case, history=...)`` replays them
  on fresh targets first), a different one ``flaky``;
* an IK status divergence is judged by ``ik_check.judge_status``: a different default
  seed makes it stand; the seed's or any Newton-Raphson iterate's rotation error within
  ``DEAD_ZONE`` of a half turn (KDL's dead zone) makes it ``known_limitation``; a target
  whose own status changes under a 1e-9..1e-7 move of the seed or of the goal makes it
  ``ill_conditioned``; the targets agreeing once the twin has KDL's small-rotation dead
  zone (``dead_zone``) makes it ``known_limitation``. Either way a target that claims
  success without reaching the pose
  still breaks its own property (``oracle.ik_property``), which is then the verdict, as a
  scenario's property violation wins over a ``known_limitation``.

A scenario (``--op scenario``) is one call: the whole scenario is run again on fresh
targets, and its ``state_dependent`` history is earlier scenarios. Its oracle is
``fuzzer.scenario.oracle.compare_scenario``; its signature is built from the divergent
step's outcomes (the field names the step kind, the step index is not in the key). A status
or value divergence at a step the two arms began apart beyond the tolerance (an uncounted
earlier step left them so) is re-run from each target's state in turn
(``fuzzer.scenario.common_start``): ``known_limitation`` if the step agrees from both. A status
or value divergence at a step that solves IK (``go``/``plan`` with a pose or position target,
``cartesian_path``) is re-run with the state, then the goal, nudged just before that step:
``ill_conditioned`` if a target's own answer there moves (``fuzzer.scenario.ik_rerun``, whose
``IkRerun`` is mixed into the ``Evaluator``; docs/engine.md, "Ill-conditioning").
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from fuzzer.execution import ik_check, oracle
from fuzzer.execution.history import HISTORY, AnyCall, stored_call
from fuzzer.execution.records import UNCOUNTED, Comparison, Kind, Outcome, Signature, Status, signature_of
from fuzzer.execution.targets import Runner
from fuzzer.execution.tolerance import Tolerance
from fuzzer.input.filtering import is_reasonable
from fuzzer.input.mapping import IkCall
from fuzzer.input.testcase import TestCase
from fuzzer.scenario import common_start
from fuzzer.scenario.execute import scenario_outcome
from fuzzer.scenario.ik_rerun import IkRerun
from fuzzer.scenario.nudge import Explainers, Nudge
from fuzzer.scenario.oracle import compare_scenario, prefer, solves_ik
from fuzzer.scenario.oracle_facts import ScenarioFacts, contexts
from fuzzer.scenario.oracle_properties import violation_at
from fuzzer.scenario.steps import ScenarioCall
from robot_api.records import JointType

Seeds = tuple[tuple[float, ...] | None, ...]
SEEN_BEFORE = "ill-conditioning re-runs not run: an earlier input of this signature kept the divergence"


class Verdict:
    FILTERED = "filtered"
    MALFORMED = "malformed"
    EVALUATED = "evaluated"


@dataclass(frozen=True)
class Evaluation:
    """Everything known about one executed test case."""

    verdict: str
    call: AnyCall | None = None
    outcomes: tuple[Outcome, ...] = ()
    comparison: Comparison = field(default_factory=lambda: Comparison(Kind.AGREE))
    signature: Signature | None = None
    difference: float = 0.0
    """The comparison's headline difference (in ``comparison.unit``)."""
    reason: str = ""
    history: tuple[dict[str, Any], ...] = ()
    """For ``state_dependent``: the calls made on the targets before this one, oldest first."""

    @property
    def divergent(self) -> bool:
        return self.verdict == Verdict.EVALUATED and self.comparison.divergent


@dataclass
class Evaluator(IkRerun):
    """Runs test cases on two targets and judges them."""

    op: str
    runners: tuple[Runner, Runner]
    mapping: Callable[[dict[str, Any]], AnyCall]
    tolerance: Tolerance
    validate: Callable[[dict[str, Any]], None]
    filtering: bool = True
    prismatic: tuple[bool, ...] = ()
    _history: deque[tuple[AnyCall, Seeds]] = field(default_factory=lambda: deque(maxlen=HISTORY))
    _stateless: set[str] = field(default_factory=set)
    """Live signatures already confirmed on fresh targets (later ones skip the construction)."""
    _checked: set[str] = field(default_factory=set)
    """Live signatures whose ill-conditioning re-runs kept the divergence (all of them, or as
    many as ``check_seconds`` allowed): a later input with one is not re-run again (its bucket
    is reported already; a replay re-runs)."""
    _explainers: Explainers = field(default_factory=Explainers)
    """The ill-conditioning re-runs that explained divergences lately: tried first."""
    _facts: ScenarioFacts | None = None
    _replay: Any = None
    check_seconds: float | None = None
    """Time budget (s) of one input's evaluation for the ill-conditioning re-runs of a scenario
    divergence (``_scenario_ik``), None for no budget: a campaign sets half of libFuzzer's
    ``-timeout``, so that checking a divergence of a slow target never makes it a timeout. A
    re-run that would end past it (by the longest re-run so far) is not started; the divergence
    stands, with ``Comparison.unchecked`` saying how many were not run."""
    _started: float = 0.0

    def __post_init__(self) -> None:
        limits = list(getattr(self.runners[0].model, "joint_limits", []))
        self.joint_types = tuple(str(lim.type) for lim in limits)
        self.continuous = tuple(lim.type == JointType.CONTINUOUS for lim in limits)
        self.joint_facts = tuple(
            oracle.JointFacts(lim.type == JointType.CONTINUOUS, lim.lower, lim.upper) for lim in limits
        )

    @property
    def scenario_facts(self) -> ScenarioFacts:
        """What the scenario oracle knows of the robot (the first target's model)."""
        if self._facts is None:
            names = (self.runners[0].name, self.runners[1].name)
            self._facts = ScenarioFacts.of(self.runners[0].model, names)
        return self._facts

    def run_both(
        self,
        call: AnyCall,
        seeds: Seeds = (None, None),
        runners: Sequence[Runner] | None = None,
        nudge: Nudge | None = None,
    ) -> tuple[Outcome, ...]:
        """Run ``call`` on both targets (the campaign's unless ``runners`` is given); ``nudge``
        is passed to ``run_scenario`` for a scenario."""
        if runners is None:
            runners = self.runners
            self._history.append((call, seeds))
        if isinstance(call, ScenarioCall):
            return tuple(scenario_outcome(r, call, nudge) for r in runners)
        return tuple(r.run(call, s) for r, s in zip(runners, seeds, strict=True))

    def judge(self, outcomes: tuple[Outcome, ...], call: AnyCall | None = None) -> Comparison:
        if isinstance(call, ScenarioCall):
            return compare_scenario(call, outcomes[0], outcomes[1], self.tolerance, self.scenario_facts)
        comparison = oracle.compare(
            outcomes[0], outcomes[1], self.tolerance, self.prismatic, self.op, self.continuous
        )
        if comparison.divergent or not isinstance(call, IkCall):
            return comparison
        return self._ik_violation(call, outcomes) or comparison

    def _ik_violation(self, call: IkCall, outcomes: tuple[Outcome, ...]) -> Comparison | None:
        """The first target's IK property violation (``oracle.ik_property``), or None."""
        for runner, outcome in zip(self.runners, outcomes, strict=True):
            violation = oracle.ik_property(
                outcome, runner.name, (call.position, call.orientation), self.joint_facts
            )
            if violation is not None:
                return violation
        return None

    def fresh(self) -> tuple[Runner, Runner]:
        """Newly constructed targets (no state from earlier calls). A target whose constructor
        fails the second time (a finding of its own, not this input's) is kept as it is."""
        out = []
        for runner in self.runners:
            try:
                out.append(runner.fresh())
            except Exception:  # noqa: BLE001 - the target's failure, never the campaign's
                out.append(runner)
        return (out[0], out[1])

    def evaluate(
        self,
        case: TestCase,
        validated: bool = False,
        history: Sequence[tuple[AnyCall, tuple[float, ...] | None]] | None = None,
    ) -> Evaluation:
        """Judge one test case.

        Parameters
        ----------
        case : TestCase
        validated : bool
            The message is known valid (skip validation).
        history : sequence of (call, IK seed), optional
            Replay: start from fresh targets and make these calls on them first (a
            ``state_dependent`` sidecar's history; ``[]`` for fresh targets only).
        """
        self._started = time.monotonic()
        message = case.message
        if not validated:
            try:
                self.validate(message)
            except ValueError as exc:
                return Evaluation(Verdict.MALFORMED, reason=str(exc))
        if self.filtering and not is_reasonable(message):
            return Evaluation(Verdict.FILTERED, reason="non-finite or absurd value")
        call = self.mapping(message)
        if history is not None:
            self.runners = self.fresh()
            for past, seed in history:
                self.run_both(past, (seed, seed))
        before = tuple(self._history)
        outcomes = self.run_both(call)
        comparison = self.judge(outcomes, call)
        recorded: tuple[dict[str, Any], ...] = ()
        if comparison.divergent:
            comparison, outcomes = self._confirm(call, outcomes, comparison)
            if comparison.kind is Kind.STATE_DEPENDENT:
                recorded = tuple(stored_call(c, s[0]) for c, s in before)
        a, b = outcomes
        signature = self.signature(a, b, comparison) if comparison.divergent else None
        return Evaluation(
            Verdict.EVALUATED, call, outcomes, comparison, signature, comparison.difference, history=recorded
        )

    def signature(self, a: Outcome, b: Outcome, comparison: Comparison) -> Signature:
        """A divergence's signature; for a scenario from the divergent step's outcomes."""
        if comparison.step is None:
            return signature_of(self.op, a, b, comparison, self.joint_types)
        step = comparison.step
        sa = a.steps[step] if step < len(a.steps) else a
        sb = b.steps[step] if step < len(b.steps) else b
        # a "<kind>.status" field coarsens the outcome pair as a single call's status does
        return signature_of(self.op, sa, sb, comparison, self.joint_types)

    def _confirm(
        self, call: AnyCall, outcomes: tuple[Outcome, ...], comparison: Comparison
    ) -> tuple[Comparison, tuple[Outcome, ...]]:
        if comparison.kind in UNCOUNTED:
            # the oracle already explained it (a scenario step's known limitation): re-running
            # could only relabel it flaky or state-dependent, never make it a finding (a scenario
            # at a step in KDL's dead zone: a quarter of a scenario campaign's runs on the
            # default robot once went to confirming them)
            return comparison, outcomes
        live_key = self.signature(outcomes[0], outcomes[1], comparison).key
        fresh: tuple[Runner, Runner] | None = None
        if live_key in self._stateless:
            if self.judge(self.run_both(call), call) != comparison:
                return replace(comparison, kind=Kind.FLAKY), outcomes
        else:
            fresh = self.fresh()
            if self.judge(self.run_both(call, runners=fresh), call) != comparison:
                same = self.judge(self.run_both(call), call) == comparison
                return replace(comparison, kind=Kind.STATE_DEPENDENT if same else Kind.FLAKY), outcomes
            self._stateless.add(live_key)
        if isinstance(call, ScenarioCall):
            facts, pair = self.scenario_facts, (outcomes[0], outcomes[1])
            rerun = lambda c, n: self.run_both(c, runners=fresh or self.fresh(), nudge=n)  # noqa: E731
            split = common_start.judge(
                call, pair, comparison, facts, self.tolerance, rerun, self._out_of_time
            )
            if split.kind is Kind.KNOWN_LIMITATION:  # the arms began the step apart: that explains it
                return prefer(split, violation_at(call, pair, split, facts, self.tolerance)), outcomes
            if self._at_ik_step(call, outcomes, comparison):
                if live_key in self._checked:
                    return replace(comparison, unchecked=f"{SEEN_BEFORE} ({live_key})"), outcomes
                judged = self._scenario_ik(call, outcomes, comparison, fresh or self.fresh())
                if judged.kind is comparison.kind:  # the divergence stands (all re-runs, or the budget's)
                    self._checked.add(live_key)
                if judged.kind in (Kind.ILL_CONDITIONED, Kind.KNOWN_LIMITATION):
                    pair = (outcomes[0], outcomes[1])
                    judged = prefer(
                        judged, violation_at(call, pair, judged, self.scenario_facts, self.tolerance)
                    )
                return judged, outcomes
            return comparison, outcomes
        if (
            isinstance(call, IkCall)
            and comparison.kind is Kind.STATUS
            and {o.status for o in outcomes} <= {Status.OK, Status.FAILED}
        ):
            runners = fresh or self.fresh()
            judge = lambda pair: self.judge(pair, call)  # noqa: E731
            judged = ik_check.judge_status(
                call, outcomes, comparison, runners, self.run_both, self.replay, judge
            )
            if judged.kind in (Kind.ILL_CONDITIONED, Kind.KNOWN_LIMITATION):
                # a status split that is no finding leaves each target's own claim to check
                judged = self._ik_violation(call, outcomes) or judged
            return judged, outcomes
        return comparison, outcomes

    @property
    def replay(self) -> Any | None:
        """A fresh twin model of the robot that replays Newton-Raphson iterates for the IK
        status check (``ik_check.meets_half_turn``); None when the twin cannot load it."""
        if self._replay is None:
            first = self.runners[0]
            try:
                from python_impl import RobotModel

                self._replay = RobotModel(first.urdf, first.tip_link) if first.urdf is not None else False
            except Exception:  # noqa: BLE001 - no replay is no evidence: the divergence stands
                self._replay = False
        return self._replay or None

    def _at_ik_step(self, call: ScenarioCall, outcomes: tuple[Outcome, ...], comparison: Comparison) -> bool:
        """A status or value divergence at a step that solves IK (what the nudge check is for)."""
        step = comparison.step
        if comparison.kind not in (Kind.STATUS, Kind.VALUE) or step is None:
            return False
        before = contexts(call, outcomes[0], self.scenario_facts)
        return step < len(before) and solves_ik(call, step, before[step])
