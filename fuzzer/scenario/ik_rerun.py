"""The ill-conditioning re-runs of a scenario divergence at a step that solves IK.

A status or value divergence at a step that solves IK (``go``/``plan`` with a pose or position
target, ``cartesian_path``) is re-run on fresh targets with the state moved by 1e-9 (both
ways) and 1e-7 just before that step, then with the goal's positions moved, then its
orientations turned, by ``ik_check.GOAL_NUDGES`` (m, rad): the pose or position target in effect, or the
path's waypoints (``run_scenario``'s ``nudge``). A target whose own
answer at that step changes (status, a failed step's error code, fraction, point count, or
the IK answer - the state after ``go``, the last point of a plan, any point of a path - beyond
the campaign tolerance)
makes it ``ill_conditioned``. The goal nudge is needed where Newton-Raphson's first step
clamps joints at their limits: that erases a move of the state, while the iterates that
follow still depend on every rounding, so two correct solvers can end differently from one
seed (docs/engine.md, "Ill-conditioning").

``IkRerun`` is the part of ``fuzzer.execution.evaluate.Evaluator`` that runs them (mixed into it;
the fields and methods it uses are the evaluator's, described there).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from fuzzer.execution import ik_check
from fuzzer.execution.dead_zone import twin_with_kdl_dead_zone
from fuzzer.execution.records import UNCOUNTED, Comparison, Kind, Outcome
from fuzzer.execution.targets import Runner
from fuzzer.execution.tolerance import Tolerance
from fuzzer.scenario.execute import NUDGE_FAILED, scenario_outcome
from fuzzer.scenario.nudge import Explainers, Moved, Nudge, Retry
from fuzzer.scenario.oracle import ik_answer_changed
from fuzzer.scenario.oracle_ik import EXTENT_FIELDS, extent_changed, split_on_ik, state_gap
from fuzzer.scenario.steps import ScenarioCall

if TYPE_CHECKING:
    from fuzzer.execution.history import AnyCall
    from fuzzer.scenario.oracle_facts import ScenarioFacts


class IkRerun:
    """The nudged re-runs of a scenario's IK step (``_scenario_ik``) and their time budget."""

    tolerance: Tolerance
    check_seconds: float | None
    _explainers: Explainers
    _started: float

    if TYPE_CHECKING:

        @property
        def scenario_facts(self) -> ScenarioFacts: ...

        @property
        def replay(self) -> Any | None: ...

        def run_both(
            self,
            call: AnyCall,
            seeds: tuple[tuple[float, ...] | None, ...] = (None, None),
            runners: Sequence[Runner] | None = None,
            nudge: Nudge | None = None,
        ) -> tuple[Outcome, ...]: ...

        def judge(self, outcomes: tuple[Outcome, ...], call: AnyCall | None = None) -> Comparison: ...

    def _scenario_ik(
        self,
        call: ScenarioCall,
        outcomes: tuple[Outcome, ...],
        comparison: Comparison,
        runners: Sequence[Runner],
    ) -> Comparison:
        """A divergence at a step that solves IK, re-run with the state, then the goal, nudged
        before it (the state also by the campaign tolerance, a move the oracle itself calls no
        difference, and by twice the gap between the two arms before the step, ``state_gap``):
        ``ill_conditioned`` if a target's answer at that step moves under a nudge
        (``ik_answer_changed``), or, for a divergence of how far a path got (``EXTENT_FIELDS``:
        its fraction or point count), if a target's path ends elsewhere (``extent_changed``):
        points that move under a nudge near a singularity do not explain a path that stops at
        10% on one target and completes on the other whatever the nudge. Last, the scenario is
        run once more with KDL's rotation dead zone in the twin (``dead_zone``): if the two
        targets then agree at that step (their answers, and the scenario oracle finds no counted
        divergence: a path timed differently from the same answers is not the dead zone's), the
        documented dead zone is the whole difference, ``known_limitation``; before that, an
        ok-vs-failed step, or a plan failed on both with ``NO_IK_SOLUTION`` on one only
        (``oracle_ik.split_on_ik``), whose one IK call meets KDL's half turn on the twin's replayed
        iterates is ``known_limitation`` too (``ik_check.step_meets_half_turn``). Every re-run stops
        after that step: only its answer is judged, and each scenario runs on a new
        ``MoveGroup``, so the steps after it cannot change it. The nudges that explained earlier
        divergences go first (``Explainers``): the verdict is the same, from fewer re-runs."""
        step = comparison.step
        facts = self.scenario_facts
        assert step is not None
        kind = call.steps[step].kind
        call = replace(call, steps=call.steps[: step + 1])
        extent = comparison.field in EXTENT_FIELDS  # how far a path got: does that move?

        def changed(first: Outcome, second: Outcome, slack: float = 0.0) -> bool:
            if extent:
                return extent_changed(kind, first, second)
            tol = self.tolerance
            if slack:
                tol = replace(tol, metres=tol.metres + slack, radians=tol.radians + slack)
            return ik_answer_changed(kind, first, second, tol, facts)

        tries = self._explainers.ordered(self._tries(outcomes, step))
        longest = 0.0
        for done, attempt in enumerate(tries):
            if self._out_of_time(longest):
                return replace(comparison, unchecked=self._cut_short(done, len(tries) + 1))
            began = time.monotonic()
            nudged = self.run_both(call, runners=runners, nudge=attempt.nudge)
            longest = max(longest, time.monotonic() - began)
            if any(NUDGE_FAILED in o.values for o in nudged):
                continue  # a target refused the nudge itself: no evidence either way
            for first, second in zip(outcomes, nudged, strict=True):
                if step >= len(first.steps):
                    continue
                if step >= len(second.steps) or changed(first.steps[step], second.steps[step], attempt.slack):
                    self._explainers.explained(attempt.label)
                    return replace(comparison, kind=Kind.ILL_CONDITIONED)
        if self._out_of_time(longest):
            return replace(comparison, unchecked=self._cut_short(len(tries), len(tries) + 1))
        steps = [o.steps[step] for o in outcomes[:2] if step < len(o.steps)]
        split = comparison.kind is Kind.STATUS or (len(steps) == 2 and split_on_ik(comparison, *steps))
        if split and ik_check.step_meets_half_turn(runners, self.replay, call, step, scenario_outcome):
            return replace(comparison, kind=Kind.KNOWN_LIMITATION)  # KDL's half turn, met on the way
        with twin_with_kdl_dead_zone() as swapped:  # KDL's documented dead zone in the twin
            again = self.run_both(call, runners=runners) if swapped else ()
        explained = len(again) == 2 and all(step < len(o.steps) for o in again)
        if explained and not changed(again[0].steps[step], again[1].steps[step]):
            still = self.judge(again, call)  # the dead zone explains only what it takes away
            if not (still.divergent and still.kind not in UNCOUNTED):
                return replace(comparison, kind=Kind.KNOWN_LIMITATION)
        return comparison

    def _tries(self, outcomes: tuple[Outcome, ...], step: int) -> list[Retry]:
        """The nudged re-runs of ``_scenario_ik``, in their documented order."""
        perturbations = enumerate(ik_check.IK_PERTURBATIONS)
        tries = [Retry(f"state{i}", Nudge(step, s)) for i, s in perturbations]
        equal = min(self.tolerance.radians, self.tolerance.metres)  # states the oracle calls equal
        # moved by the tolerance, an answer that follows the state (the IK seed) as far as the
        # state moved is continuous in it, not ill-conditioned: an IK that answers with its seed
        # wherever the goal is would otherwise always pass for ill-conditioned (docs/engine.md)
        tries += [Retry(f"equal{s:+g}", Nudge(step, s * equal), slack=equal) for s in (1, -1)]
        gap = state_gap(outcomes, step)  # arms an earlier step left apart: as far as that too
        tries += [Retry(f"gap{s:+g}", Nudge(step, 2.0 * s * gap)) for s in (1, -1) if gap]
        for moved in (Moved.POSITION, Moved.ORIENTATION):
            tries += [
                Retry(f"{moved.value}{i}", Nudge(step, shift, moved, axis))
                for i, (shift, axis) in enumerate(ik_check.GOAL_NUDGES)
            ]
        return tries

    def _out_of_time(self, longest: float) -> bool:
        """A re-run as long as ``longest`` (s) would end past ``check_seconds``."""
        budget = self.check_seconds
        return budget is not None and time.monotonic() - self._started + longest > budget

    def _cut_short(self, done: int, total: int) -> str:
        return (
            f"{total - done} of {total} ill-conditioning re-runs not run: the input's time budget "
            f"({self.check_seconds:g} s, half of -timeout) ran out; replaying the file runs them"
        )
