"""Test case files and the message-to-call mapping."""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fuzzer.generation.strategies import strategy_for
from fuzzer.input.mapping import FkCall, IkCall, MappingError, MoveCall, RobotFacts, mapping_for, seed_hints
from fuzzer.input.msgdef import MessageRegistry
from fuzzer.input.testcase import LINEAGE_KEEP, TestCase, TestCaseError, decode
from robot_api.robots import default_robot_path
from tests.support import IMPLEMENTATIONS

JOINT_STATE = {
    "header": {"seq": 1, "stamp": {"secs": 2, "nsecs": 3}, "frame_id": ""},
    "name": ["joint_1", "joint_2"],
    "position": [0.5, -0.0],
    "velocity": [],
    "effort": [],
}


def test_round_trip_keeps_every_float() -> None:
    message = dict(JOINT_STATE, position=[math.nan, math.inf, -math.inf, -0.0, 5e-324, 0.1 + 0.2])
    case = TestCase("sensor_msgs/JointState", message, 7, "hypothesis", ("comb3",), 1)
    back = decode(case.encode())
    assert back.msg_type == case.msg_type and back.sequence == 7 and back.lineage == ("comb3",)
    got = back.message["position"]
    assert math.isnan(got[0]) and got[1:3] == [math.inf, -math.inf]
    assert math.copysign(1.0, got[3]) == -1.0 and got[4] == 5e-324 and got[5] == 0.1 + 0.2


@pytest.mark.parametrize(
    "data",
    [
        b"",
        b"not json",
        b"\xff\xfe",
        b"[]",
        b'{"rrosfuzz": 2, "msg_type": "x", "message": {}}',
        b'{"rrosfuzz": 1, "msg_type": 3, "message": {}}',
        b'{"rrosfuzz": 1, "msg_type": "x", "message": []}',
        b'{"rrosfuzz": 1, "msg_type": "x", "message": {}, "lineage": [1]}',
        b'{"rrosfuzz": 1, "msg_type": "x", "message": {}, "sequence": 1.5}',
        b'{"rrosfuzz": 1, "msg_type": "x", "message": {}, "sequence": true}',
        b"[" * 100000,
    ],
)
def test_malformed_test_cases_are_rejected_with_a_reason(data: bytes) -> None:
    with pytest.raises(TestCaseError):
        decode(data)


def test_lineage_is_recorded_and_capped() -> None:
    case = TestCase("sensor_msgs/JointState", JOINT_STATE)
    assert case.strategy == "seed"
    for i in range(LINEAGE_KEEP + 10):
        case = case.child(JOINT_STATE, f"m{i}")
    assert case.origin == "mutation" and case.lineage_length == LINEAGE_KEEP + 10
    assert len(case.lineage) == LINEAGE_KEEP and case.strategy == f"m{LINEAGE_KEEP + 9}"
    assert json.loads(case.encode())["lineage"][-1] == case.strategy


def test_joint_state_maps_onto_moveit_calls() -> None:
    move = mapping_for("move", "sensor_msgs/JointState")
    assert move(JOINT_STATE) == MoveCall(("joint_1", "joint_2"), (0.5, -0.0))
    by_position = dict(JOINT_STATE, name=[], velocity=[0.5], effort=[0.25, 9.0])
    assert move(by_position) == MoveCall(None, (0.5, -0.0), 0.5, 0.25)
    fk = mapping_for("fk", "sensor_msgs/JointState")
    assert fk(dict(JOINT_STATE, header={**JOINT_STATE["header"], "frame_id": "link_3"})) == FkCall(
        (0.5, -0.0), "link_3"
    )
    assert fk(JOINT_STATE) == FkCall((0.5, -0.0), None)


def test_poses_map_onto_ik() -> None:
    pose = {
        "position": {"x": 1.0, "y": 2.0, "z": 3.0},
        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
    }
    stamped = {"header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": "tool0"}, "pose": pose}
    assert mapping_for("ik", "geometry_msgs/Pose")(pose) == IkCall((1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0))
    assert mapping_for("ik", "geometry_msgs/PoseStamped")(stamped).link == "tool0"


def test_unsupported_combinations_name_the_alternatives() -> None:
    with pytest.raises(MappingError, match="supported: geometry_msgs/PoseStamped"):
        mapping_for("ik", "sensor_msgs/JointState")


@pytest.fixture(scope="module")
def facts() -> RobotFacts:
    model = IMPLEMENTATIONS["python"].RobotModel(default_robot_path())

    def reachable(q):  # type: ignore[no-untyped-def]
        pose = model.forward_kinematics(list(q))
        return tuple(pose.position), tuple(pose.orientation)

    limits = model.joint_limits
    return RobotFacts(
        tuple(model.joint_names),
        tuple(lim.lower for lim in limits),
        tuple(lim.upper for lim in limits),
        tuple(model.link_names),
        reachable,
    )


@pytest.mark.parametrize(
    "msg_type",
    [
        "sensor_msgs/JointState",
        "geometry_msgs/PoseStamped",
        "std_msgs/Float64MultiArray",
        "geometry_msgs/Pose",
    ],
)
def test_seed_hints_make_valid_robot_aware_messages(facts: RobotFacts, msg_type: str) -> None:
    registry = MessageRegistry()
    strategy = strategy_for(registry, msg_type, hints=seed_hints(msg_type, facts))

    @settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
    @given(strategy)
    def check(message):  # type: ignore[no-untyped-def]
        registry.validate(msg_type, message)
        if msg_type == "sensor_msgs/JointState":
            assert message["name"] in ([], list(facts.joint_names))
            assert len(message["position"]) == len(facts.joint_names)
            for v, lo, hi in zip(message["position"], facts.lower, facts.upper, strict=True):
                assert lo <= v <= hi
        if msg_type == "geometry_msgs/PoseStamped":
            q = message["pose"]["orientation"]
            assert math.isclose(math.hypot(q["x"], q["y"], q["z"], q["w"]), 1.0, rel_tol=1e-9)

    check()


@given(st.lists(st.floats(allow_nan=False), max_size=6))
def test_float_array_maps_positionally(values: list[float]) -> None:
    message = {"layout": {"dim": [], "data_offset": 0}, "data": values}
    assert mapping_for("move", "std_msgs/Float64MultiArray")(message) == MoveCall(None, tuple(values))
