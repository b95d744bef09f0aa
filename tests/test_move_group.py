"""MoveGroup semantics (moveit_commander) and trajectories, on both implementations."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import native
import python_impl
from robot_api import ErrorCode, InvalidInputError, MoveItErrorCode, OutOfBoundsError, UnknownNameError
from robot_api.constants import ACCELERATION_LIMIT, GOAL_JOINT_TOLERANCE, TRAJECTORY_DT
from robot_api.records import JointType, RobotTrajectory
from tests.support import outcome, robot_path, sample_configurations

TRAJECTORY_ROBOTS = ["probot_anno", "kinova", "panda", "ur5"]


def group(impl, robot: str = "probot_anno", tip: str | None = None):  # type: ignore[no-untyped-def]
    return impl.MoveGroup(impl.RobotModel(robot_path(robot), tip))


def check_trajectory(
    g, traj: RobotTrajectory, start: list[float], goal: list[float], vscale: float = 1.0, ascale: float = 1.0
) -> None:  # type: ignore[no-untyped-def]
    limits = g._model.joint_limits
    t = traj.time_from_start
    assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    assert np.allclose(np.diff(t)[:-1], TRAJECTORY_DT, rtol=0, atol=1e-12)
    assert traj.positions[-1].tolist() == goal  # exactly the goal
    assert np.max(np.abs(traj.positions[0] - np.array(start))) <= 1e-12
    for j, lim in enumerate(limits):
        column = traj.positions[:, j]
        if lim.type == JointType.CONTINUOUS:
            assert np.all((column > -math.pi) & (column <= math.pi))
        else:
            assert np.all((column >= lim.lower) & (column <= lim.upper))
        assert np.max(np.abs(traj.velocities[:, j])) <= lim.velocity * vscale * (1 + 1e-12)
        assert np.max(np.abs(traj.accelerations[:, j])) <= ACCELERATION_LIMIT * ascale * (1 + 1e-12)
    assert np.all(traj.velocities[-1] == 0.0)


@pytest.mark.parametrize("robot", TRAJECTORY_ROBOTS)
def test_trajectories_respect_limits_and_end_at_the_goal(impl, robot: str) -> None:
    g = group(impl, robot)
    model = impl.RobotModel(robot_path(robot))
    for target in sample_configurations(model, 40, seed=20):
        start = g.get_current_joint_values()
        g.set_joint_value_target(target.tolist())
        goal = g.get_joint_value_target()
        check_trajectory(g, g.plan().trajectory, start, goal)
        assert g.go() is True
        assert g.get_current_joint_values() == goal
        assert g.get_current_pose() == model.forward_kinematics(goal)


@pytest.mark.parametrize("robot", TRAJECTORY_ROBOTS)
def test_native_and_twin_plan_the_same_trajectory(robot: str) -> None:
    a, b = group(native, robot), group(python_impl, robot)
    model = native.RobotModel(robot_path(robot))
    for i, target in enumerate(sample_configurations(model, 40, seed=21)):
        scale = 1.0 if i % 2 else 0.37
        for g in (a, b):
            g.set_max_velocity_scaling_factor(scale)
            g.set_max_acceleration_scaling_factor(1.0 - scale / 2)
            g.set_joint_value_target(target.tolist())
        ta, tb = a.plan().trajectory, b.plan().trajectory
        assert ta.joint_names == tb.joint_names
        assert ta.positions.shape == tb.positions.shape
        for name in ("time_from_start", "positions", "velocities", "accelerations"):
            assert np.max(np.abs(getattr(ta, name) - getattr(tb, name))) <= 1e-9, name
        a.go()
        b.go()
        assert (
            np.max(np.abs(np.subtract(a.get_current_joint_values(), b.get_current_joint_values()))) <= 1e-12
        )


def test_scaled_trajectory_respects_scaled_limits(impl) -> None:
    g = group(impl)
    g.set_max_velocity_scaling_factor(0.25)
    g.set_max_acceleration_scaling_factor(0.5)
    start = g.get_current_joint_values()
    g.set_joint_value_target([1.0, -1.0, 2.0, 0.5, 3.0, -2.0])
    check_trajectory(g, g.plan().trajectory, start, g.get_joint_value_target(), 0.25, 0.5)


def test_continuous_joint_targets_are_normalized(impl) -> None:
    g = group(impl, "kinova")  # joints 1, 4 and 6 are continuous
    g.set_joint_value_target("j2s6s200_joint_1", 4.0)
    assert g.get_joint_value_target()[0] == pytest.approx(4.0 - 2 * math.pi, abs=1e-15)
    g.set_joint_value_target("j2s6s200_joint_1", -math.pi)
    assert g.get_joint_value_target()[0] == math.pi  # (-pi, pi]: -pi becomes pi
    g.set_joint_value_target("j2s6s200_joint_1", math.pi)
    assert g.get_joint_value_target()[0] == math.pi
    g.set_joint_value_target("j2s6s200_joint_1", 1e12)
    assert -math.pi < g.get_joint_value_target()[0] <= math.pi


def test_continuous_joints_take_the_short_way_round(impl) -> None:
    g = group(impl, "kinova")
    g.go({"j2s6s200_joint_1": 3.0})
    traj = g.plan({"j2s6s200_joint_1": -3.0}).trajectory
    column = traj.positions[:, 0]
    # 3.0 -> -3.0 the short way passes through pi (0.283 rad), not through 0 (6 rad).
    assert np.all(np.abs(column) >= 3.0 - 1e-12)
    assert traj.positions[-1, 0] == -3.0


def test_tolerance_beyond_limits(impl) -> None:
    g = group(impl)
    upper = 3.8397  # joint_3
    g.set_joint_value_target("joint_3", upper + GOAL_JOINT_TOLERANCE / 2)
    assert g.get_joint_value_target()[2] == upper  # accepted and clamped onto the limit
    before = g.get_joint_value_target()
    with pytest.raises(OutOfBoundsError) as err:
        g.set_joint_value_target("joint_3", upper + 2 * GOAL_JOINT_TOLERANCE)
    assert err.value.code == ErrorCode.OUT_OF_BOUNDS
    assert g.get_joint_value_target() == before  # unchanged on error
    g.set_goal_joint_tolerance(0.1)
    g.set_joint_value_target("joint_3", upper + 0.05)
    assert g.get_joint_value_target()[2] == upper


def test_joint_3_beyond_pi_is_a_valid_revolute_target(impl) -> None:
    """The paper's arm: joint_3 goes to 3.8397, beyond pi; it must not be wrapped."""
    g = group(impl)
    g.go([0.0, 0.0, 3.8, 0.0, 3.9, 0.0])
    assert g.get_current_joint_values() == [0.0, 0.0, 3.8, 0.0, 3.9, 0.0]


def test_partial_targets_keep_the_other_joints(impl) -> None:
    g = group(impl)
    g.set_joint_value_target([0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    g.set_joint_value_target({"joint_2": -0.5, "joint_6": 1.0})
    assert g.get_joint_value_target() == [0.1, -0.5, 0.3, 0.4, 0.5, 1.0]
    g.set_joint_value_target(["joint_1", "joint_4"], [0.7, -0.7])
    assert g.get_joint_value_target() == [0.7, -0.5, 0.3, -0.7, 0.5, 1.0]
    g.set_joint_value_target([], [])  # an empty JointState: nothing changes
    assert g.get_joint_value_target() == [0.7, -0.5, 0.3, -0.7, 0.5, 1.0]


def test_named_targets(impl) -> None:
    g = group(impl, "panda")
    assert g.get_named_targets() == ["home"]
    home = g.get_named_target_values("home")
    assert home["panda_joint4"] == -0.0698  # 0 clamped into [-3.0718, -0.0698]
    g.go([0.1] * 3 + [-1.0] + [0.1] * 3)
    g.remember_joint_values("ready")
    g.remember_joint_values("other", [0.0, 0.0, 0.0, -2.0, 0.0, 2.0, 0.0])
    assert g.get_named_targets() == ["home", "other", "ready"]
    g.set_named_target("home")
    g.go()
    assert g.get_current_joint_values() == list(home.values())
    g.set_named_target("ready")
    assert g.get_joint_value_target() == [0.1] * 3 + [-1.0] + [0.1] * 3
    with pytest.raises(UnknownNameError) as err:
        g.set_named_target("nope")
    assert err.value.code == ErrorCode.UNKNOWN_NAMED_TARGET


def assert_planning_failed(result) -> None:  # type: ignore[no-untyped-def]
    """plan() reports the failure as moveit_commander does: (False, empty plan, 0.0, PLANNING_FAILED)."""
    success, trajectory, planning_time, error_code = result
    assert success is False and planning_time == 0.0
    assert error_code == MoveItErrorCode.PLANNING_FAILED
    assert len(trajectory) == 0 and trajectory.positions.shape[0] == 0


def test_tiny_scaling_fails_planning(impl) -> None:
    g = group(impl)
    g.set_max_velocity_scaling_factor(1e-9)
    g.set_joint_value_target([1.0] * 6)
    assert_planning_failed(g.plan())
    before = g.get_current_joint_values()
    assert g.go() is False
    assert g.get_current_joint_values() == before


@pytest.mark.parametrize("setter", ["set_max_velocity_scaling_factor", "set_max_acceleration_scaling_factor"])
def test_scaling_that_underflows_fails_planning_cleanly(impl, setter: str) -> None:
    """Found by the fuzzer: 5e-324 / distance underflows to 0; the twin divided by it."""
    g = group(impl)
    getattr(g, setter)(5e-324)  # the smallest subnormal: a valid factor in (0, 1]
    g.set_joint_value_target([0.5, 0.0, 0.7, 0.0, 0.0, -1.0])
    assert_planning_failed(g.plan())
    assert g.go() is False


def test_a_subnormal_move_is_still_a_move(impl) -> None:
    """Found by the fuzzer: 3.0 / 5e-319 overflows to inf; the twin took inf for 'nothing moves'."""
    g = group(impl)
    g.set_max_acceleration_scaling_factor(5e-324)
    g.set_joint_value_target([0.0, 0.0, 0.0, 0.0, 0.0, 5e-319])
    assert_planning_failed(g.plan())  # 636 s at the scaled acceleration: more than 600 s
    g.set_max_acceleration_scaling_factor(1.0)
    traj = g.plan().trajectory  # both bounds overflow to inf: a zero-length profile, one sample, at the goal
    assert traj.time_from_start[0] == 0.0 and traj.positions[-1][5] == 5e-319
    assert g.go() is True and g.get_current_joint_values()[5] == 5e-319


def test_execute_rejects_foreign_trajectories(impl) -> None:
    g = group(impl)
    traj = g.plan([0.5, 0.5, 0.5, 0.5, 0.5, 0.5]).trajectory
    g.go([1.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # the state moved: traj no longer starts here
    with pytest.raises(InvalidInputError) as err:
        g.execute(traj)
    assert err.value.code == ErrorCode.INVALID_TRAJECTORY
    bad_times = RobotTrajectory(
        traj.joint_names,
        traj.time_from_start[::-1].copy(),
        traj.positions,
        traj.velocities,
        traj.accelerations,
    )
    with pytest.raises(InvalidInputError):
        g.execute(bad_times)
    with pytest.raises(InvalidInputError) as err:
        g.execute("not a plan")  # type: ignore[arg-type]
    assert err.value.code == ErrorCode.INVALID_ARGUMENT
    fresh = g.plan([0.2, 0.2, 0.2, 0.2, 0.2, 0.2]).trajectory
    assert g.execute(fresh) is True
    assert g.get_current_joint_values() == [0.2] * 6


# -- property: for any target the two implementations do the same thing -------------------------

_values = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=-5, max_value=5),
    st.sampled_from([math.pi, -math.pi, 2 * math.pi, 3.8397, 3.8398, 3.9270, -0.6981, -0.7854, 0.0, -0.0]),
    st.integers(min_value=-10, max_value=10),
)
_names = st.sampled_from(["joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6", "joint_7", ""])
_targets = st.one_of(
    st.lists(_values, min_size=0, max_size=8),
    st.dictionaries(_names, _values, max_size=7),
    st.tuples(st.lists(_names, max_size=7), st.lists(_values, max_size=7)),
)


@settings(max_examples=300, deadline=None)
@given(targets=st.lists(_targets, min_size=1, max_size=4))
def test_same_outcome_for_any_target_sequence(targets) -> None:  # type: ignore[no-untyped-def]
    a, b = group(native), group(python_impl)
    for target in targets:
        args = target if isinstance(target, tuple) else (target,)
        ra = outcome(lambda args=args: (a.set_joint_value_target(*args), a.go()))
        rb = outcome(lambda args=args: (b.set_joint_value_target(*args), b.go()))
        assert ra == rb
        ca, cb = a.get_current_joint_values(), b.get_current_joint_values()
        assert np.max(np.abs(np.subtract(ca, cb))) <= 1e-12
