"""Twins with planted stateful faults for the scenario oracle's tests (issue 10).

Each is the Python twin with one behaviour changed, exposed as an object with
``RobotModel`` and ``MoveGroup``: ``--targets native,tests.plugins.scenario_faults:NAME``.

* ``stale_second_go``: ``go()`` after the group's first one plans and reports success but
  leaves the current state where it was. Invisible to ``--op move`` (one ``go`` per group).
* ``seed_parity_ik``: IK fails when round(seed[0] * 1e9) is even, so a 1e-9 change of the
  state a pose target is planned from flips its own answer (an ill-conditioned divergence).
* ``no_pose_goal``: pose and position targets never find an IK solution (a status
  divergence that no nudge of the state changes).
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import python_impl
from robot_api.records import IKResult, IKStatus


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


stale_second_go = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_StaleGroup)
seed_parity_ik = SimpleNamespace(RobotModel=_ParityModel, MoveGroup=python_impl.MoveGroup)
no_pose_goal = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_NoPoseGoalGroup)
