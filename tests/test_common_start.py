"""A divergence at a step the two arms began apart is re-run from one common state
(``fuzzer.scenario.common_start``)."""

from __future__ import annotations

import math
import shutil
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import pytest

from fuzzer.execution.records import Comparison, Kind, Outcome, Status
from fuzzer.execution.session import RunConfig
from fuzzer.execution.targets import Runner
from fuzzer.execution.tolerance import Tolerance
from fuzzer.input.testcase import TestCase
from fuzzer.scenario import common_start
from fuzzer.scenario.execute import NUDGE_FAILED, run_scenario
from fuzzer.scenario.nudge import Moved, Nudge
from fuzzer.scenario.oracle import compare_scenario
from fuzzer.scenario.oracle_facts import JointSpec, ScenarioFacts
from fuzzer.scenario.steps import ScenarioCall, Step, to_call
from fuzzer.triage.regressions import PromoteError, promote
from fuzzer.triage.replay import Result, replay_file
from robot_api import robots
from tests.test_scenario_oracle import evaluator

TOL = Tolerance(1e-6, 1e-6)
FACTS = ScenarioFacts((JointSpec("revolute", -3.2, 3.2, 1.0),) * 2, ("a", "b"), (0.0, 0.0))

# control@scenario/probot_anno, seed 1, on 0586935 (benchmarks/results/control-fp-0586935/),
# steps 13 to 15 of its crash file: from home, a path to home's position turned half a turn about
# z, its execution, and a path through two waypoints.
HALF_TURN_PATH = {
    "header": {"frame_id": "", "seq": 1220, "stamp": {"nsecs": 1, "secs": 5840}},
    "poses": [
        {
            "orientation": {
                "w": 0.0,
                "x": 6.746245984389591e-12,
                "y": 1.8365999999401066e-06,
                "z": -0.9999999999915673,
            },
            "position": {"x": 0.22885535000000004, "y": -1.471118577552194e-06, "z": 0.4319999999972982},
        }
    ],
}
NEXT_PATH = {
    "header": {"frame_id": "", "seq": 11945587, "stamp": {"nsecs": 383, "secs": 120}},
    "poses": [
        {
            "orientation": {
                "w": -0.0,
                "x": 0.042515707917727165,
                "y": -0.030144294460042333,
                "z": 0.04519099184741245,
            },
            "position": {"x": 0.35282549448042566, "y": 0.004810997175440881, "z": 0.48552507529101885},
        },
        {
            "orientation": {
                "w": 0.7925001616232176,
                "x": -0.20947158007155842,
                "y": 0.5715882087371108,
                "z": -0.03677051267251813,
            },
            "position": {"x": 0.08734105419904357, "y": 0.02748710008358792, "z": 0.37373942181693676},
        },
    ],
}
SPLIT = TestCase(
    "rrosfuzz/Scenario",
    {
        "steps": [
            {"topic": "/cartesian_path", "msg": HALF_TURN_PATH},
            {"topic": "/execute", "msg": {}},
            {"topic": "/cartesian_path", "msg": NEXT_PATH},
        ]
    },
)


def test_a_path_after_a_half_turn_split_is_a_known_limitation() -> None:
    """The controls' false positive on 0586935: the half-turn path leaves joint_6 at -pi on
    native and +pi on the twin (one state modulo 2pi, so the oracle compares the next step);
    the next path then gets 0% of the way on native and 7.1% on the twin. Started from either
    target's state, both get as far: the split is the whole difference."""
    found = evaluator("scenario", "python").evaluate(SPLIT, validated=True)
    a, b = found.outcomes
    assert a.steps[1].values["joint_values"][5] == pytest.approx(-math.pi)
    assert b.steps[1].values["joint_values"][5] == pytest.approx(math.pi)
    assert [o.steps[2].values["fraction"] for o in (a, b)] == [(0.0,), (pytest.approx(1 / 14),)]
    ev = evaluator("scenario", "python")
    alone = compare_scenario(to_call(SPLIT.message), a, b, ev.tolerance, ev.scenario_facts)
    assert (alone.kind, alone.step, alone.field) == (
        Kind.VALUE,
        2,
        "cartesian_path.fraction",
    )  # the oracle alone
    c = found.comparison
    assert (c.kind, c.step, c.field) == (Kind.KNOWN_LIMITATION, 2, "cartesian_path.fraction")


def test_a_fault_that_shows_from_a_common_state_still_counts() -> None:
    """A twin whose path from a joint beyond 3 rad reports half its fraction: from native's
    state (-pi) both get 0% (half of 0), from the twin's (+pi) native gets 7.1% and the twin
    half that. One common state that agrees is not enough; the divergence stands."""
    found = evaluator("scenario", "tests.plugins.scenario_faults:short_path_from_far_joints").evaluate(
        SPLIT, validated=True
    )
    c = found.comparison
    assert (c.kind, c.step, c.field) == (Kind.VALUE, 2, "cartesian_path.fraction")
    assert [o.steps[2].values["fraction"] for o in found.outcomes] == [(0.0,), (pytest.approx(1 / 28),)]


@pytest.mark.parametrize("impl", ["native", "python"])
def test_moved_to_puts_the_state_where_it_is_told(impl: str) -> None:
    runner = Runner.create(impl, robots.resolve("probot_anno"), None)
    far = (0.1, -0.2, 0.3, -0.4, 0.5, math.pi)
    call = ScenarioCall((Step("stop", {}), Step("stop", {})))
    out = run_scenario(runner, call, Nudge(1, 0.0, Moved.TO, state=far))
    assert out.steps[0].values["joint_values"] == (0.0,) * 6
    assert out.steps[1].values["joint_values"] == far
    refused = run_scenario(runner, call, Nudge(1, 0.0, Moved.TO, state=(0.0,) * 5))  # one value short
    assert NUDGE_FAILED in refused.values
    beyond = run_scenario(runner, call, Nudge(1, 0.0, Moved.TO, state=(0.0,) * 5 + (4.0,)))  # past the limit
    assert NUDGE_FAILED in beyond.values


# the oracle's side, with a fake re-run: two joints, a path step after a step that split them
CALL = ScenarioCall((Step("stop", {}), Step("cartesian_path", {"poses": []})))
DIVERGENCE = Comparison(Kind.VALUE, "cartesian_path.fraction", 0.5, step=1, step_kind="cartesian_path")


def outcome(state: tuple[float, float], fraction: float, **extra: tuple[float, ...]) -> Outcome:
    steps = (
        Outcome(Status.OK, values={"joint_values": state}),
        Outcome(Status.OK, values={"joint_values": state, "fraction": (fraction,)}),
    )
    return Outcome(Status.OK, values={**extra}, steps=steps)


class Reruns:
    """A fake ``rerun``: the fraction each target gets from a common state (by its joint 1)."""

    def __init__(self, fractions: dict[float, tuple[float, float]], refuse: bool = False) -> None:
        self.fractions, self.refuse = fractions, refuse
        self.calls: list[Nudge] = []

    def __call__(self, call: ScenarioCall, nudge: Nudge) -> Sequence[Outcome]:
        assert nudge.moved is Moved.TO and nudge.index == 1 and len(call.steps) == 2
        self.calls.append(nudge)
        extra = {NUDGE_FAILED: (1.0,)} if self.refuse else {}
        state = (nudge.state[0], nudge.state[1])
        return tuple(outcome(state, f, **extra) for f in self.fractions[nudge.state[1]])


def judged(a: Outcome, b: Outcome, rerun: Reruns, late: bool = False, c: Comparison = DIVERGENCE) -> Kind:
    out = common_start.judge(CALL, (a, b), c, FACTS, TOL, rerun, lambda longest: late)
    assert out in (c, replace(c, kind=Kind.KNOWN_LIMITATION))
    return out.kind


SPLIT_PAIR = (outcome((0.0, -3.0), 0.0), outcome((0.0, 3.0), 0.5))


def test_a_split_start_explained_from_both_states_is_a_known_limitation() -> None:
    rerun = Reruns({-3.0: (0.0, 0.0), 3.0: (0.5, 0.5)})
    assert judged(*SPLIT_PAIR, rerun) is Kind.KNOWN_LIMITATION
    assert [n.state for n in rerun.calls] == [(0.0, -3.0), (0.0, 3.0)]


@pytest.mark.parametrize(
    "fractions", [{-3.0: (0.0, 0.1), 3.0: (0.5, 0.5)}, {-3.0: (0.0, 0.0), 3.0: (0.5, 0.2)}]
)
def test_a_divergence_from_either_common_state_stands(fractions: dict[float, tuple[float, float]]) -> None:
    assert judged(*SPLIT_PAIR, Reruns(fractions)) is Kind.VALUE


def test_no_evidence_leaves_the_divergence_as_it_is() -> None:
    agreeing = {-3.0: (0.0, 0.0), 3.0: (0.5, 0.5)}
    assert judged(*SPLIT_PAIR, Reruns(agreeing, refuse=True)) is Kind.VALUE  # a target refused the move
    late = Reruns(agreeing)
    assert judged(*SPLIT_PAIR, late, late=True) is Kind.VALUE and not late.calls  # out of time
    crash = Comparison(Kind.CRASH, "cartesian_path.status", step=1, step_kind="cartesian_path")
    assert judged(*SPLIT_PAIR, Reruns(agreeing), c=crash) is Kind.CRASH


def test_states_within_the_tolerance_are_not_re_run() -> None:
    rerun = Reruns({})
    near = (outcome((0.0, 3.0), 0.0), outcome((0.0, 3.0 + 0.9e-6), 0.5))
    assert judged(*near, rerun) is Kind.VALUE and not rerun.calls
    assert common_start.split_states(CALL, near, 1, FACTS, TOL) is None
    assert common_start.split_states(CALL, SPLIT_PAIR, 1, FACTS, TOL) == ((0.0, -3.0), (0.0, 3.0))
    assert common_start.split_states(CALL, SPLIT_PAIR, 0, FACTS, TOL) is None  # home: one state


KEPT = Path(__file__).resolve().parents[1] / "benchmarks" / "results" / "control-fp-0586935"
CRASH = "crash-a57f012a7ad5de16dd146ec3744e2a82b0ff32f6"


def test_the_controls_crash_file_now_replays_as_no_finding(tmp_path: Path) -> None:
    """The file the controls wrote on 0586935 (16 steps; a value divergence then) replays as
    known_limitation: "now explained (not a finding)", exit 0, and the suite will not take it
    either way."""
    for name in (CRASH, CRASH + ".json"):
        shutil.copyfile(KEPT / name, tmp_path / name)
    result = replay_file(tmp_path / CRASH, RunConfig(), {}, trust=True)  # the zoo's control: ours
    assert result.result is Result.EXPLAINED and not result.diverges
    assert result.evaluation is not None
    c = result.evaluation.comparison
    assert (c.kind, c.step, c.field) == (Kind.KNOWN_LIMITATION, 15, "cartesian_path.fraction")
    for fixed in (True, False):
        with pytest.raises(PromoteError, match="now explained"):
            promote(tmp_path / CRASH, fixed=fixed, suite=tmp_path / "suite", trust=True)
