"""Twins with planted stateful faults for the scenario oracle's tests (issue 10).

Each is the Python twin with one behaviour changed, exposed as an object with
``RobotModel`` and ``MoveGroup``: ``--targets native,tests.plugins.scenario_faults:NAME``.

* ``stale_second_go``: ``go()`` after the group's first one plans and reports success but
  leaves the current state where it was. Invisible to ``--op move`` (one ``go`` per group).
* ``seed_parity_ik``: IK fails when round(seed[0] * 1e9) is even, so a 1e-9 change of the
  state a pose target is planned from flips its own answer (an ill-conditioned divergence).
* ``no_pose_goal``: pose and position targets never find an IK solution (a status
  divergence that no nudge of the state changes).
* ``left_side_at_switch``: *not* a fault. A plan's sample that falls exactly on a switch of the
  trapezoid (``t == ta`` or ``t == total - ta``) reports the acceleration of the phase before
  it, where the twin reports the phase after it (``t < ta``); both are right.
* ``early_switch``: each phase's acceleration is reported one sample early (the fault).
* ``short_path_from_far_joints``: a Cartesian path from a state with a joint beyond 3 rad
  reports half the fraction it achieved (a fault a state split by 2pi would otherwise hide:
  ``fuzzer.scenario.common_start``).
* ``path_points_off``: every point of a Cartesian path after its start is 1 mrad off in the
  first joint (a fault that round waypoints, on the knife edge of a step count, once hid).
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace
from typing import Any

import numpy as np

import python_impl
from robot_api.constants import ACCELERATION_LIMIT
from robot_api.records import IKResult, IKStatus, RobotTrajectory


class _StaleGroup(python_impl.MoveGroup):
    """The current state is not updated by ``go()`` after the first one (the fault)."""

    def __init__(self, model: Any) -> None:
        super().__init__(model)
        self._moves = 0

    def go(self, joints: Any = None, wait: bool = True) -> bool:
        self._moves += 1
        if self._moves == 1:
            return super().go(joints, wait)
        state = list(self.get_current_joint_values())
        moved = super().go(joints, wait)
        self._current = state
        return moved


class _ParityModel(python_impl.RobotModel):
    """IK that fails for every other nanoradian of the seed's first joint."""

    def inverse_kinematics(self, pose: Any, seed: Any = None, link: str | None = None) -> IKResult:
        result = super().inverse_kinematics(pose, seed, link)
        start = list(seed) if seed is not None else list(self.home_values)
        if round(start[0] * 1e9) % 2 == 0:
            return IKResult(IKStatus.NO_SOLUTION, tuple(start), 1.0, 1.0)
        return result


class _NoPoseGoalGroup(python_impl.MoveGroup):
    """Pose goals never solve (the fault): plan() fails with NO_IK_SOLUTION, go() is False."""

    def _goal(self) -> list[float]:
        if self._pose_goal is not None:
            from python_impl.move_group import _NoIKSolution

            raise _NoIKSolution("no IK solution (planted fault)")
        return super()._goal()


class _LeftSideGroup(python_impl.MoveGroup):
    """At a sample exactly on a switch, the acceleration of the phase before it."""

    def _plan(self) -> RobotTrajectory:
        trajectory = super()._plan()
        t, acc = trajectory.time_from_start, trajectory.accelerations.copy()
        delta = trajectory.positions[-1] - trajectory.positions[0]
        moving = np.abs(delta) > 0.0
        if len(t) < 3 or not moving.any():
            return trajectory
        velocity = np.array([lim.velocity for lim in self._limits])[moving] * self._velocity_scaling
        vs = float(np.min(velocity / np.abs(delta[moving])))
        accel = float(np.min(ACCELERATION_LIMIT * self._acceleration_scaling / np.abs(delta[moving])))
        ta = vs / accel if vs * vs < accel else float(np.sqrt(1.0 / accel))
        total = 1.0 / vs + ta if vs * vs < accel else 2.0 * ta
        for i in range(1, len(t) - 1):
            if t[i] == ta or t[i] == total - ta:
                acc[i] = acc[i - 1]
        return dataclasses.replace(trajectory, accelerations=acc)


class _EarlySwitchGroup(python_impl.MoveGroup):
    """Each phase's acceleration one sample early (the fault)."""

    def _plan(self) -> RobotTrajectory:
        trajectory = super()._plan()
        acc = trajectory.accelerations.copy()
        for i in range(len(acc) - 2):  # the last row is the goal, at rest
            if not np.array_equal(acc[i + 1], acc[i]):
                acc[i] = acc[i + 1]
        return dataclasses.replace(trajectory, accelerations=acc)


class _ShortPathGroup(python_impl.MoveGroup):
    """A path from a state with a joint beyond 3 rad reports half its fraction (the fault)."""

    def compute_cartesian_path(
        self, waypoints: Any, eef_step: float, jump_threshold: float = 0.0
    ) -> tuple[RobotTrajectory, float]:
        trajectory, fraction = super().compute_cartesian_path(waypoints, eef_step, jump_threshold)
        far = any(abs(q) > 3.0 for q in self.get_current_joint_values())
        return trajectory, fraction / 2.0 if far else fraction


class _PathPointsOffGroup(python_impl.MoveGroup):
    """Every Cartesian path point after the start 1e-3 rad off in the first joint (the fault)."""

    def compute_cartesian_path(
        self, waypoints: Any, eef_step: float, jump_threshold: float = 0.0
    ) -> tuple[RobotTrajectory, float]:
        trajectory, fraction = super().compute_cartesian_path(waypoints, eef_step, jump_threshold)
        positions = np.array(trajectory.positions, dtype=float)
        positions[1:, 0] += 1e-3
        return dataclasses.replace(trajectory, positions=positions), fraction


stale_second_go = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_StaleGroup)
seed_parity_ik = SimpleNamespace(RobotModel=_ParityModel, MoveGroup=python_impl.MoveGroup)
no_pose_goal = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_NoPoseGoalGroup)
left_side_at_switch = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_LeftSideGroup)
early_switch = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_EarlySwitchGroup)
short_path_from_far_joints = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_ShortPathGroup)
path_points_off = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_PathPointsOffGroup)
