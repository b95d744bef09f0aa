"""KDL's half-turn dead zone met by a scenario's IK (``ik_check.step_meets_half_turn``): the
rule single IK calls had (step 5 of ``ik_check.judge_status``), for a ``go``/``plan`` toward a
pose goal, where the twin solves IK from the current state."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from fuzzer.execution import ik_check
from fuzzer.execution.records import Comparison, Kind, Outcome, Status
from fuzzer.execution.session import RunConfig
from fuzzer.scenario.oracle_ik import split_on_ik
from fuzzer.triage.replay import Result, replay_file
from python_impl import RobotModel
from robot_api.records import Pose

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "robot_api" / "robots" / "probot_anno.urdf"

# `make run` on a fresh clone of f760b8d (2026-12-04, fiftieth session): a scenario whose step 6,
# a go() toward a pose goal that only joint_1 near -pi reaches, has KDL succeed and the twin fail.
# From the current state (joint_1 at its -3.1416 limit) the twin's Newton-Raphson meets a rotation
# error 2.7e-7 rad short of pi, where KDL's diff and the twin's logarithm pick opposite axes; it
# stalls 0.14 m and 2.6 rad away, KDL converges. No nudge of state or goal changes either answer.
FALSE_POSITIVE = (
    ROOT / "benchmarks" / "results" / "run-fp-f760b8d" / "crash-93c00644873848ec3392099a386d9f3498a94b35"
)
SEED = (
    -3.1416,
    1.940775882534124,
    2.214931450844742,
    1.7606415851309891,
    -0.7686094428297132,
    2.453286937505007,
)
POSE = Pose(
    (-0.27807702971138154, 6.884592204749716e-07, 0.4002266581729376),
    (6.673065952899016e-06, 0.7402646377910462, 1.3595700337341615e-06, 0.6723155999898506),
)


# A 25-minute scenario campaign on 0967709 (sixty-seventh session, -seed=4, the default robot): a
# plan toward a pose goal after acceleration scaling 4.1e-10 failed on both targets, native (KDL)
# with NO_IK_SOLUTION and the twin with PLANNING_FAILED: its IK answered, and the plan would have
# lasted past MAX_TRAJECTORY_DURATION. A status split of the IK inside the step, reported as a value
# divergence of plan.error_code, which the half-turn rule did not look at. From the state (joint_2
# and joint_4 at their lower limits) the twin's Newton-Raphson meets a rotation error 3.1e-7 rad
# short of pi; KDL stalls there, a half turn from the goal.
ERROR_CODE_SPLIT = (
    ROOT / "benchmarks" / "results" / "run-fp-0967709" / "crash-e51923dff155af4fc4b8930563d2a7e2baf79387"
)
SPLIT_SEED = (math.pi, -2.0071, math.pi, -3.1416, math.pi, -math.pi)
SPLIT_POSE = Pose(
    (-0.11517939850804439, -1.6303928313124317e-06, 0.47536111087385835),
    (1.286474139745248e-07, 0.9975437541522285, 1.8320837680046208e-06, 0.07004611729785952),
)


def _replay(monkeypatch: pytest.MonkeyPatch, path: Path) -> tuple[Result, str]:
    monkeypatch.chdir(ROOT)
    done = replay_file(path, RunConfig(), {}, trust=True)  # the project's own file
    kind = done.evaluation.comparison.kind.value if done.evaluation is not None else ""
    return done.result, kind


@pytest.mark.parametrize(
    ("path", "seed", "pose", "without_rule"),
    [(FALSE_POSITIVE, SEED, POSE, "status"), (ERROR_CODE_SPLIT, SPLIT_SEED, SPLIT_POSE, "value")],
    ids=["make-run-go-status", "plan-error-code"],
)
def test_a_scenario_ik_split_at_kdls_half_turn_is_explained(
    path: Path, seed: tuple[float, ...], pose: Pose, without_rule: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert ik_check.pose_meets_half_turn(RobotModel(str(URDF)), pose, seed, None)
    result, kind = _replay(monkeypatch, path)
    if result is Result.AGREES:  # as the other IK splits' tests: rounding is the CPU's
        pytest.skip("the scenario does not split the targets on this CPU")
    assert (result, kind) == (Result.EXPLAINED, "known_limitation")
    monkeypatch.setattr(ik_check, "step_meets_half_turn", lambda *args: False)
    result, kind = _replay(monkeypatch, path)
    assert (result, kind) == (Result.SAME, without_rule), "only the half-turn rule explains it"


def _failed(code: float) -> Outcome:
    return Outcome(Status.FAILED, values={"error_code": (code,), "success": (0.0,)})


def test_split_on_ik_is_a_failed_plan_with_no_ik_solution_on_one_target_only() -> None:
    codes = Comparison(Kind.VALUE, "plan.error_code", difference=30.0)
    assert split_on_ik(codes, _failed(-31.0), _failed(-1.0))
    assert split_on_ik(codes, _failed(-1.0), _failed(-31.0))
    assert not split_on_ik(codes, _failed(-1.0), _failed(-2.0))  # neither failed in IK
    assert not split_on_ik(codes, _failed(-31.0), _failed(-31.0))
    ok = Outcome(Status.OK, values={"error_code": (1.0,), "success": (1.0,)})
    assert not split_on_ik(codes, _failed(-31.0), ok)  # a status divergence: its own rule
    other = Comparison(Kind.VALUE, "plan.joint_values", difference=1.0, unit="rad")
    assert not split_on_ik(other, _failed(-31.0), _failed(-1.0))


def test_recorded_ik_sees_the_twins_calls_and_leaves_its_class_as_it_was() -> None:
    model = RobotModel(str(URDF))
    before = RobotModel.__dict__["inverse_kinematics"]
    with ik_check.recorded_ik(model) as requests:
        assert requests is not None
        answer = model.inverse_kinematics(POSE, list(SEED))
        model.forward_kinematics(list(SEED))
    assert requests == [(POSE, SEED, None)]
    assert RobotModel.__dict__["inverse_kinematics"] is before
    assert model.inverse_kinematics(POSE, list(SEED)) == answer and len(requests) == 1

    class Variant(RobotModel):  # a target built on the twin, as the zoo's are
        __slots__ = ()

    variant = Variant(str(URDF))
    with ik_check.recorded_ik(variant) as requests:
        variant.inverse_kinematics(POSE)
    assert requests == [(POSE, None, None)] and "inverse_kinematics" not in Variant.__dict__
    with ik_check.recorded_ik(object()) as requests:
        assert requests is None  # not the twin: nothing to look into


def test_a_pose_away_from_the_half_turn_does_not_meet_it() -> None:
    model = RobotModel(str(URDF))
    home = tuple(model.home_values)
    reachable = model.forward_kinematics([0.3, 0.2, 0.4, 0.1, 0.5, 0.2])
    assert not ik_check.pose_meets_half_turn(model, reachable, home, None)
