"""KDL's half-turn dead zone met by a scenario's IK (``ik_check.step_meets_half_turn``): the
rule single IK calls had (step 5 of ``ik_check.judge_status``), for a ``go``/``plan`` toward a
pose goal, where the twin solves IK from the current state."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzer.execution import ik_check
from fuzzer.execution.session import RunConfig
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


def _replay(monkeypatch: pytest.MonkeyPatch) -> tuple[Result, str]:
    monkeypatch.chdir(ROOT)
    done = replay_file(FALSE_POSITIVE, RunConfig(), {}, trust=True)  # the project's own file
    kind = done.evaluation.comparison.kind.value if done.evaluation is not None else ""
    return done.result, kind


def test_the_make_run_false_positive_is_kdls_half_turn(monkeypatch: pytest.MonkeyPatch) -> None:
    assert ik_check.pose_meets_half_turn(RobotModel(str(URDF)), POSE, SEED, None)
    result, kind = _replay(monkeypatch)
    if result is Result.AGREES:  # as the other IK splits' tests: rounding is the CPU's
        pytest.skip("the scenario does not split the targets on this CPU")
    assert (result, kind) == (Result.EXPLAINED, "known_limitation")
    monkeypatch.setattr(ik_check, "step_meets_half_turn", lambda *args: False)
    result, kind = _replay(monkeypatch)
    assert (result, kind) == (Result.SAME, "status"), "only the half-turn rule explains it"


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
