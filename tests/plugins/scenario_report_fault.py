"""Twins with stateful or trajectory faults, for the scenario report tests (issue 10).

Each is the Python twin with one behaviour changed, exposed as an object with
``RobotModel`` and ``MoveGroup``: ``--targets native,tests.plugins.scenario_report_fault:NAME``.

* ``stale_second_go``: from the second ``go()`` of a group on, the move is planned and
  reported (``go`` returns True) but the current state is left where it was: right on
  one call, wrong on the second call of a live group.
* ``fast_plan``: ``plan()`` returns velocities twice the true ones (positions and times
  unchanged): the right end point, the wrong timing.
"""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace
from typing import Any

import python_impl
from robot_api.records import PlanResult


class _StaleSecondGo(python_impl.MoveGroup):
    """``go()`` stops updating the state after the first call (the fault)."""

    def __init__(self, model: python_impl.RobotModel) -> None:
        super().__init__(model)
        self._gos = 0

    def go(self, joints: Any = None, wait: bool = True) -> bool:
        self._gos += 1
        before = self.get_current_joint_values()
        moved = super().go(joints, wait)
        if self._gos >= 2:
            self._current = before
        return moved


class _FastPlan(python_impl.MoveGroup):
    """``plan()`` with doubled velocities (the fault)."""

    def plan(self, joints: Any = None) -> PlanResult:
        result = super().plan(joints)
        trajectory = replace(result.trajectory, velocities=2.0 * result.trajectory.velocities)
        return result._replace(trajectory=trajectory)


stale_second_go = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_StaleSecondGo)
fast_plan = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_FastPlan)
