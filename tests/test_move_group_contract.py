"""The grown MoveGroup contract: pose targets, plan()'s 4-tuple, Cartesian paths, state, stop.

Both implementations, and their agreement (docs/api.md, "MoveGroup").
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import native
import python_impl
from python_impl import kinematics
from python_impl.trajectory import time_parameterize
from python_impl.transforms import rotation_angle
from robot_api import ErrorCode as E
from robot_api import MoveItErrorCode, PlanResult, RobotState
from robot_api.constants import ACCELERATION_LIMIT, CARTESIAN_MAX_POINTS, IK_EPS
from robot_api.records import JointType, Pose, RobotTrajectory
from tests.support import outcome, robot_path, sample_configurations

AGREEMENT_ROBOTS = ["probot_anno", "ur5", "panda"]
POSITION_TOL = 1e-6
"""Joint positions (rad, m) of the two targets' Cartesian paths agree within this."""
REACHED_TOL = 2 * math.sqrt(3) * IK_EPS
"""A converged IK leaves every twist component within IK_EPS: position (m) and angle (rad)."""
TIMING_TOL = 1e-9
"""Times (s), velocities and accelerations of the same points agree within this."""
TIMED = ("time_from_start", "velocities", "accelerations")
DEAD_ZONE_ROBOTS = {"ur5"}
"""Robots whose paths meet KDL's rotation dead zone (docs/api.md, "Known divergences")."""


def group(impl: Any, robot: str = "probot_anno") -> Any:
    return impl.MoveGroup(impl.RobotModel(robot_path(robot)))


def limits_of(g: Any) -> tuple[np.ndarray, np.ndarray]:
    limits = g._model.joint_limits
    return np.array([lim.lower for lim in limits]), np.array([lim.upper for lim in limits])


def near_poses(g: Any, rng: np.random.Generator, count: int, spread: float) -> list[Pose]:
    """FK of random configurations near the current state: reachable waypoints."""
    lower, upper = limits_of(g)
    current = np.array(g.get_current_joint_values())
    return [
        g._model.forward_kinematics(np.clip(current + rng.normal(0.0, spread, current.size), lower, upper))
        for _ in range(count)
    ]


def pose_gap(model: Any, a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Distance (m) and angle (rad) between the tip poses of two configurations (twin FK)."""
    tip = len(model.link_names) - 1
    ta, tb = kinematics.fk(model.chain, a, tip), kinematics.fk(model.chain, b, tip)
    return float(np.linalg.norm(ta[:3, 3] - tb[:3, 3])), rotation_angle(ta[:3, :3].T @ tb[:3, :3])


def check_path(g: Any, traj: RobotTrajectory, start: list[float], vscale: float, ascale: float) -> None:
    """Properties every timed path has, on one target alone."""
    t = traj.time_from_start
    assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    assert traj.positions[0].tolist() == start
    assert np.all(traj.velocities[0] == 0.0) and np.all(traj.velocities[-1] == 0.0)
    for j, lim in enumerate(g._model.joint_limits):
        column = traj.positions[:, j]
        if lim.type == JointType.CONTINUOUS:
            assert np.all((column > -math.pi) & (column <= math.pi))
        else:
            assert np.all((column >= lim.lower) & (column <= lim.upper))
        assert np.max(np.abs(traj.velocities[:, j])) <= lim.velocity * vscale * (1 + 1e-12)
        assert np.max(np.abs(traj.accelerations[:, j])) <= ACCELERATION_LIMIT * ascale * (1 + 1e-12)


# -- Cartesian paths: the two targets agree --------------------------------------------------------


@pytest.mark.parametrize("robot", AGREEMENT_ROBOTS)
def test_cartesian_paths_agree(robot: str) -> None:
    a, b = group(native, robot), group(python_impl, robot)
    rng = np.random.default_rng(7)
    starts = sample_configurations(a._model, 30, seed=5, margin=-0.3)
    fractions, lengths, explained = [], [], 0
    for case, start in enumerate(starts):
        a.go(start.tolist())
        b.go(start.tolist())
        assert a.get_current_joint_values() == b.get_current_joint_values()
        waypoints = near_poses(a, rng, int(rng.integers(1, 4)), 0.2)
        step, jump = (0.005, 0.01, 0.02)[case % 3], (0.0, 1.5, 4.0)[(case // 3) % 3]
        vscale = (1.0, 0.5)[case % 2]
        for g in (a, b):
            g.set_max_velocity_scaling_factor(vscale)
        before = a.get_current_joint_values()
        ta, fa = a.compute_cartesian_path(waypoints, step, jump)
        tb, fb = b.compute_cartesian_path(waypoints, step, jump)
        assert a.get_current_joint_values() == before == b.get_current_joint_values()  # nothing moved
        fractions.append(fa)
        lengths.append(len(ta))
        if fa != fb:
            # KDL's rotation dead zone again: the points differ by ~1e-6 rad, and near an IK branch
            # point the next solve from the two seeds lands on different branches, so one path
            # jumps (and is cut) a step before the other. Both cut, at consecutive points; the
            # shared prefix reaches the same poses.
            assert robot in DEAD_ZONE_ROBOTS and jump > 0.0, (case, fa, fb)
            assert max(fa, fb) < 1.0 and abs(len(ta) - len(tb)) == 1, (case, fa, fb, len(ta), len(tb))
            for qa, qb in zip(ta.positions, tb.positions, strict=False):
                distance, angle = pose_gap(b._model, qa, qb)
                assert distance <= REACHED_TOL and angle <= REACHED_TOL, (case, distance, angle)
            explained += 1
            continue
        assert len(ta) == len(tb), case
        assert ta.joint_names == tb.joint_names
        for traj, g in ((ta, a), (tb, b)):
            check_path(g, traj, before, vscale, 1.0)
        gap = np.max(np.abs(ta.positions - tb.positions), axis=1)
        for k in np.flatnonzero(gap > POSITION_TOL):
            # Only KDL's rotation dead zone may separate the two: both points then reach
            # the same interpolated pose within the IK tolerance.
            assert robot in DEAD_ZONE_ROBOTS, (case, int(k), float(gap[k]))
            distance, angle = pose_gap(b._model, ta.positions[k], tb.positions[k])
            assert distance <= REACHED_TOL and angle <= REACHED_TOL, (case, int(k), distance, angle)
            explained += 1
        # the timing rule agrees on the same points: the twin's, applied to the native points
        retimed = time_parameterize(b._model.joint_limits, ta.positions.tolist(), vscale, 1.0)
        assert np.array_equal(retimed.positions, ta.positions)
        for name in TIMED:
            assert np.max(np.abs(getattr(ta, name) - getattr(retimed, name))) <= TIMING_TOL, (case, name)
        if robot not in DEAD_ZONE_ROBOTS:  # elsewhere IK agrees to ~1e-13: so do the timings
            for name in TIMED:
                assert np.max(np.abs(getattr(ta, name) - getattr(tb, name))) <= TIMING_TOL, (case, name)
    # the sample is not trivial: whole paths, cut paths and long paths
    assert sum(f == 1.0 for f in fractions) >= 10 and sum(0.0 < f < 1.0 for f in fractions) >= 3
    assert max(lengths) >= 50
    assert explained <= 10


def test_cartesian_path_semantics(impl: Any) -> None:
    g = group(impl)
    g.go([0.2, 0.3, 0.4, 0.1, 0.5, 0.2])
    here = g.get_current_pose()
    x, y, z = here.position
    # 5.5 cm along x at 1 cm: floor(5.5) + 1 = 6 steps (the last one lands exactly on the waypoint)
    goal = Pose((x + 0.055, y, z), here.orientation)
    traj, fraction = g.compute_cartesian_path([goal], 0.01)
    assert fraction == 1.0 and len(traj) == 7
    reached = g._model.forward_kinematics(traj.positions[-1])
    assert np.linalg.norm(np.subtract(reached.position, goal.position)) <= REACHED_TOL
    assert g.execute(traj) is True
    assert g.get_current_joint_values() == traj.positions[-1].tolist()
    # the current pose as the only waypoint: IK returns the seed, an exact repeat, dropped
    traj, fraction = g.compute_cartesian_path([g.get_current_pose()], 0.01)
    assert fraction == 1.0 and len(traj) == 1 and traj.positions[0].tolist() == g.get_current_joint_values()


def test_unreachable_waypoint_cuts_the_path(impl: Any) -> None:
    g = group(impl)
    g.go([0.2, 0.3, 0.4, 0.1, 0.5, 0.2])
    here = g.get_current_pose()
    x, y, z = here.position
    near = Pose((x + 0.025, y, z), here.orientation)
    far = Pose((x + 3.0, y, z), here.orientation)  # 3 m away: beyond the arm's reach
    traj, fraction = g.compute_cartesian_path([near, far], 0.01)
    # MoveIt's fraction: the first waypoint whole (1/2), then the share of the second one's steps
    steps = math.floor(math.dist(near.position, far.position) / 0.01) + 1
    reached = len(traj) - 1 - 3  # 3 points for the first waypoint
    assert 0 <= reached < steps
    assert fraction == 0.5 + (reached / steps) / 2


def test_jump_threshold_truncates_at_the_jump(impl: Any) -> None:
    g = group(impl)
    g.go([0.2, 0.3, 0.4, 0.1, 0.5, 0.2])
    here = g.get_current_pose()
    x, y, z = here.position
    moved = Pose((x + 0.105, y, z), here.orientation)  # 11 steps of about 1 cm
    # then a quarter turn of the tool about its own z axis, in one step: q * (0, 0, sin 45, cos 45)
    qx, qy, qz, qw = here.orientation
    c = s = math.sqrt(0.5)
    turned = Pose(moved.position, (qx * c + qy * s, qy * c - qx * s, qz * c + qw * s, qw * c - qz * s))
    full, whole = g.compute_cartesian_path([moved, turned], 0.01, 0.0)
    cut, fraction = g.compute_cartesian_path([moved, turned], 0.01, 3.0)
    assert whole == 1.0 and len(full) == 1 + 11 + 1
    steps = [float(np.sum(np.abs(np.diff(full.positions[i - 1 : i + 1], axis=0)))) for i in range(1, 13)]
    assert steps[-1] > 3.0 * sum(steps) / len(steps) > max(steps[:-1])  # only the turn is a jump
    assert len(cut) == 12 and fraction == 12 / 13  # MoveIt keeps the points before the jump: (i + 1) / 13
    assert np.array_equal(cut.positions, full.positions[:12])


def test_too_many_points_fail_before_any_ik(impl: Any) -> None:
    g = group(impl)
    far = Pose((0.2, 0.0, 0.4), (0.0, 0.0, 0.0, 1.0))
    for step in (1e-9, 5e-324):
        assert outcome(lambda step=step: g.compute_cartesian_path([far], step)) == (
            "PlanningError",
            E.PLANNING_FAILED,
        )
    here = g.get_current_pose()
    ok = [here] * (CARTESIAN_MAX_POINTS - 1)  # one step each, plus the start: exactly the maximum
    traj, fraction = g.compute_cartesian_path(ok, 0.01)
    assert fraction == 1.0 and len(traj) == 1
    assert outcome(lambda: g.compute_cartesian_path([*ok, here], 0.01)) == (
        "PlanningError",
        E.PLANNING_FAILED,
    )


# -- pose and position targets ---------------------------------------------------------------------


@pytest.mark.parametrize("robot", AGREEMENT_ROBOTS)
def test_pose_target_go_reaches_the_pose(robot: str) -> None:
    a, b = group(native, robot), group(python_impl, robot)
    rng = np.random.default_rng(11)
    starts = sample_configurations(a._model, 12, seed=12, margin=-0.3)
    reached_both = 0
    for start in starts:
        a.go(start.tolist())
        b.go(start.tolist())
        (pose,) = near_poses(a, rng, 1, 0.3)
        results = []
        for g in (a, b):
            target_before = g.get_joint_value_target()
            g.set_pose_target(pose)
            moved = g.go()
            results.append(moved)
            assert g.get_joint_value_target() == target_before  # the joint target is not touched
            if moved:
                here = g.get_current_pose()
                assert math.dist(here.position, pose.position) <= REACHED_TOL
                rotation = g._model.forward_kinematics(g.get_current_joint_values()).matrix[:3, :3]
                assert rotation_angle(rotation.T @ pose.matrix[:3, :3]) <= REACHED_TOL
        assert results[0] == results[1]
        reached_both += results[0]
        gap = np.max(np.abs(np.subtract(a.get_current_joint_values(), b.get_current_joint_values())))
        if robot not in DEAD_ZONE_ROBOTS:
            assert gap <= POSITION_TOL
        else:
            distance, angle = pose_gap(
                b._model, np.array(a.get_current_joint_values()), np.array(b.get_current_joint_values())
            )
            assert distance <= REACHED_TOL and angle <= REACHED_TOL
    assert reached_both >= 8


def test_plan_with_a_pose_target(impl: Any) -> None:
    g = group(impl)
    g.go([0.2, 0.3, 0.4, 0.1, 0.5, 0.2])
    start = g.get_current_joint_values()
    pose = g._model.forward_kinematics([0.3, 0.2, 0.5, 0.0, 0.4, 0.3])
    g.set_pose_target(pose)
    success, traj, planning_time, code = g.plan()
    assert success is True and code == MoveItErrorCode.SUCCESS and planning_time == 0.0
    assert traj.positions[0].tolist() == start and g.get_current_joint_values() == start
    assert g.execute(traj) is True
    assert math.dist(g.get_current_pose().position, pose.position) <= REACHED_TOL
    # the pose target stays: planning again from the pose is a plan that does not move
    success, traj, _, _ = g.plan()
    assert success and len(traj) <= 2
    assert np.max(np.abs(traj.positions[-1] - traj.positions[0])) <= 1e-5


def test_unreachable_pose_target(impl: Any) -> None:
    g = group(impl)
    start = g.get_current_joint_values()
    g.set_pose_target(Pose((3.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)))
    result = g.plan()
    assert isinstance(result, PlanResult)
    assert result == (False, result.trajectory, 0.0, MoveItErrorCode.NO_IK_SOLUTION)
    assert result.trajectory.positions.shape == (0, 6) and len(result.trajectory) == 0
    assert g.go() is False
    assert g.get_current_joint_values() == start


def test_joint_targets_end_pose_targets(impl: Any) -> None:
    g = group(impl)
    unreachable = Pose((3.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    g.set_pose_target(unreachable)
    g.clear_pose_targets()
    assert g.plan().success is True  # the joint target (home): a one-point plan
    g.set_pose_target(unreachable)
    g.set_joint_value_target([0.1] * 6)
    assert g.go() is True and g.get_current_joint_values() == [0.1] * 6
    g.set_pose_target(unreachable)
    g.set_named_target("home")
    assert g.go() is True and g.get_current_joint_values() == list(g._model.home_values)
    g.set_pose_target(unreachable)
    with pytest.raises(Exception):  # noqa: B017 - a rejected joint target leaves the pose target
        g.set_joint_value_target([9.0] * 6)
    assert g.plan().error_code == MoveItErrorCode.NO_IK_SOLUTION


@pytest.mark.parametrize("robot", ["probot_anno", "panda"])
def test_position_target_keeps_the_orientation(impl: Any, robot: str) -> None:
    g = group(impl, robot)
    start = sample_configurations(g._model, 1, seed=3, margin=-0.4)[0]
    g.go(start.tolist())
    here = g.get_current_pose()
    goal = np.add(here.position, (0.03, -0.02, 0.02))
    g.set_position_target(goal.tolist())
    assert g.go() is True
    after = g.get_current_pose()
    assert math.dist(after.position, goal) <= REACHED_TOL
    assert rotation_angle(here.matrix[:3, :3].T @ after.matrix[:3, :3]) <= REACHED_TOL


# -- state, stop, plan()'s tuple -------------------------------------------------------------------


def test_current_state_and_stop(impl: Any) -> None:
    g = group(impl)
    g.go([0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    state = g.get_current_state()
    assert isinstance(state, RobotState)
    assert state.joint_state.name == tuple(g.get_active_joints())
    assert list(state.joint_state.position) == g.get_current_joint_values()
    target = g.get_joint_value_target()
    assert g.stop() is None
    assert g.get_current_state() == state and g.get_joint_value_target() == target


def test_plan_is_moveit_commanders_tuple(impl: Any) -> None:
    g = group(impl)
    success, traj, planning_time, code = g.plan([0.3] * 6)
    assert (success, planning_time, code) == (True, 0.0, MoveItErrorCode.SUCCESS)
    assert isinstance(traj, RobotTrajectory) and traj.positions[-1].tolist() == [0.3] * 6
    assert g.get_current_joint_values() == list(g._model.home_values)  # plan() does not move
