"""The time the oracle's ill-conditioning re-runs take: their budget (``Evaluator.check_seconds``:
a slow target's divergence is reported, not turned into a libFuzzer timeout), and a signature
they kept is not re-run for later inputs (``Evaluator._checked``)."""

from __future__ import annotations

import itertools
import re
from typing import Any

import pytest

from fuzzer.campaign import check_seconds
from fuzzer.execution import evaluate
from fuzzer.execution.evaluate import SEEN_BEFORE
from fuzzer.execution.records import Kind
from fuzzer.input.testcase import TestCase
from fuzzer.scenario.nudge import Explainers, Nudge, Retry
from tests.test_scenario_oracle import FAR_WAYPOINT, HEADER, evaluator, live, seed_band_go

CUT = re.compile(r"^(\d+) of (\d+) ill-conditioning re-runs not run: the input's time budget")


def far_path() -> TestCase:
    """``ik_seed_band``'s path of tests/test_scenario_oracle.py: a ``value`` divergence of the
    fraction at a step that solves IK, which the nudge check re-runs."""
    steps = [live("cartesian_path", header={**HEADER, "frame_id": "link_4"}, poses=[FAR_WAYPOINT])]
    return TestCase("rrosfuzz/Scenario", {"steps": steps})


def judged(budget: float | None):  # type: ignore[no-untyped-def]
    ev = evaluator("scenario", "benchmarks.zoo.deep:ik_seed_band")
    ev.check_seconds = budget
    return ev.evaluate(far_path(), validated=True).comparison


def test_a_spent_budget_keeps_the_divergence_and_says_no_re_run_ran() -> None:
    c = judged(0.0)
    assert (c.kind, c.field) == (Kind.VALUE, "cartesian_path.fraction")
    match = CUT.match(c.unchecked)
    assert match is not None, c.unchecked
    assert match.group(1) == match.group(2)  # none ran
    assert int(match.group(2)) >= 17  # the nudges of docs/engine.md and the dead-zone run


def test_the_budget_stops_before_a_re_run_that_would_end_past_it(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """A clock that advances one second per reading: each re-run lasts one second, so with
    a budget of 5 s the checks stop after two re-runs, before the one that would pass 5 s."""
    clock = itertools.count()
    monkeypatch.setattr(evaluate.time, "monotonic", lambda: float(next(clock)))
    c = judged(5.0)
    match = CUT.match(c.unchecked)
    assert match is not None, c.unchecked
    not_run, total = int(match.group(1)), int(match.group(2))
    assert total - not_run == 2
    assert c.kind is Kind.VALUE


@pytest.mark.parametrize(("timeout", "budget"), [(20, 10.0), (3, 1.5), (0, None)])
def test_a_campaign_gives_half_of_libfuzzers_timeout(timeout: int, budget: float | None) -> None:
    assert check_seconds(timeout) == budget


def test_a_signature_that_passed_every_re_run_is_not_re_run_for_a_later_input() -> None:
    ev = evaluator("scenario", "benchmarks.zoo.deep:ik_seed_band")
    first = ev.evaluate(seed_band_go(0.305), validated=True)
    later = ev.evaluate(seed_band_go(0.306), validated=True)
    assert (first.comparison.kind, first.comparison.unchecked) == (Kind.VALUE, "")
    assert first.signature is not None and later.signature is not None
    assert later.signature.key == first.signature.key
    assert later.comparison.kind is Kind.VALUE
    assert later.comparison.unchecked.startswith(SEEN_BEFORE)
    alone = evaluator("scenario", "benchmarks.zoo.deep:ik_seed_band").evaluate(
        seed_band_go(0.306), validated=True
    )
    assert (alone.comparison.kind, alone.comparison.unchecked) == (Kind.VALUE, "")  # a new evaluator re-runs


def test_a_signature_the_budget_cut_short_is_not_re_run_for_a_later_input() -> None:
    ev = evaluator("scenario", "benchmarks.zoo.deep:ik_seed_band")
    ev.check_seconds = 0.0
    first = ev.evaluate(seed_band_go(0.305), validated=True).comparison
    later = ev.evaluate(seed_band_go(0.306), validated=True).comparison
    assert CUT.match(first.unchecked) is not None
    assert later.kind is Kind.VALUE and later.unchecked.startswith(SEEN_BEFORE)


def nudges_of(ev: evaluate.Evaluator) -> list[Any]:
    """The nudges of ``ev``'s nudged re-runs from now on, in order (a spy on ``run_both``)."""
    nudged: list[Any] = []
    run_both = ev.run_both

    def spy(call, seeds=(None, None), runners=None, nudge=None):  # type: ignore[no-untyped-def]
        if nudge is not None:
            nudged.append(nudge)
        return run_both(call, seeds, runners, nudge)

    ev.run_both = spy  # type: ignore[method-assign]
    return nudged


def test_a_divergence_the_re_runs_explain_is_re_run_every_time() -> None:
    """At the band's edge a 1e-9 nudge moves the answer: the difference is ill-conditioned, never
    a finding whose later inputs could skip the re-runs. (The verdict is the faulty twin's own
    ``go.pose_goal`` violation since the sixty-third session: it reports the goal reached at its
    start, and a violation wins over an explained difference; the re-runs still run each time.)"""
    ev = evaluator("scenario", "benchmarks.zoo.deep:ik_seed_band")
    nudged = nudges_of(ev)
    for _ in range(2):
        before = len(nudged)
        c = ev.evaluate(seed_band_go(0.3), validated=True).comparison
        assert (c.kind, c.field, c.unchecked) == (Kind.PROPERTY, "go.pose_goal", "")
        assert len(nudged) > before  # re-run again, not skipped as seen before


def test_the_re_runs_stop_after_the_divergent_step() -> None:
    """The nudged and dead-zone re-runs judge only the divergent step's answer, and each
    scenario runs on a new MoveGroup: the steps after it are not run again, and the verdict
    is the one without them."""
    steps = seed_band_go(0.305).message["steps"]  # diverges at step 3, a go to a pose goal
    tail = [live("joint_target", position=[0.5, 0.5]), live("go"), live("plan")]
    longer = TestCase("rrosfuzz/Scenario", {"steps": [*steps, *tail]})
    ev = evaluator("scenario", "benchmarks.zoo.deep:ik_seed_band")
    lengths: list[int] = []
    run_both = ev.run_both

    def spy(call, seeds=(None, None), runners=None, nudge=None):  # type: ignore[no-untyped-def]
        lengths.append(len(call.steps))
        return run_both(call, seeds, runners, nudge)

    ev.run_both = spy  # type: ignore[method-assign]
    found = ev.evaluate(longer, validated=True).comparison
    alone = evaluator("scenario", "benchmarks.zoo.deep:ik_seed_band").evaluate(
        seed_band_go(0.305), validated=True
    )
    assert (found.kind, found.step, found.unchecked) == (Kind.VALUE, 3, "")
    assert found == alone.comparison
    assert lengths[:2] == [7, 7]  # the input, then the flakiness re-run on new targets: whole
    assert len(lengths) >= 19 and set(lengths[2:]) == {4}  # every nudge and the dead-zone run: to step 3


def test_the_re_run_that_explained_last_goes_first() -> None:
    """Move to front: the re-run that explained a divergence is tried first for the next one, the
    others keep their documented order."""
    tries = [Retry(label, Nudge(0, 1e-9)) for label in ("a", "b", "c", "d")]
    explainers = Explainers()
    assert [t.label for t in explainers.ordered(tries)] == ["a", "b", "c", "d"]
    explainers.explained("c")
    explainers.explained("d")
    explainers.explained("c")
    assert [t.label for t in explainers.ordered(tries)] == ["c", "d", "a", "b"]


def test_a_divergence_explained_again_takes_fewer_re_runs_and_the_same_verdict() -> None:
    """The second input an ill-conditioning re-run explains starts with that re-run: one nudged
    run, where the first input took more; the verdict is the one a new evaluator gives."""
    ev = evaluator("scenario", "benchmarks.zoo.deep:ik_seed_band")
    nudged = nudges_of(ev)
    first = ev.evaluate(seed_band_go(0.3), validated=True).comparison
    runs_first = len(nudged)
    later = ev.evaluate(seed_band_go(0.3), validated=True).comparison
    alone = evaluator("scenario", "benchmarks.zoo.deep:ik_seed_band").evaluate(
        seed_band_go(0.3), validated=True
    )
    # the difference is explained (ill-conditioned); the verdict is the twin's pose-goal violation
    assert first.kind is Kind.PROPERTY and later == first == alone.comparison
    assert runs_first > 1, "the case must need more than the first re-run to show the point"
    assert len(nudged) - runs_first == 1
    assert nudged[-1] == nudged[runs_first - 1]  # the one that explained the first
