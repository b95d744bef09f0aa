"""Twins with planted faults for the oracle-precision tests (issue 15).

Each is the Python twin with one behaviour changed, exposed as an object with
``RobotModel`` and ``MoveGroup``: ``--targets native,tests.plugins.stateful_faults:NAME``.

* ``fk_cache``: forward kinematics remembers its last answer and returns it again for
  any configuration within 0.05 rad of the last one on every joint. Right on a fresh
  model, wrong after a nearby call: a *state-dependent* divergence.
* ``ik_out_of_limits``: an IK success whose first joint is moved by 2pi when that
  leaves the limits (``-0.503`` becomes ``5.78`` against an upper limit of pi): the same
  pose, a joint vector outside the limits.
* ``ik_zero_seed``: IK's default seed is 0.3 on every joint instead of ``home_values``.
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import python_impl
from robot_api.records import IKResult, IKStatus

CACHE_RADIUS = 0.05


class _CachingModel(python_impl.RobotModel):
    """FK with a one-entry cache keyed loosely (the fault)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._last: tuple[tuple[float, ...], str | None, Any] | None = None

    def forward_kinematics(self, joint_values: Any, link: str | None = None) -> Any:
        q = tuple(float(x) for x in joint_values)
        last = self._last
        if (
            last is not None
            and last[1] == link
            and len(last[0]) == len(q)
            and all(abs(x - y) <= CACHE_RADIUS for x, y in zip(last[0], q, strict=True))
        ):
            return last[2]
        pose = super().forward_kinematics(joint_values, link)
        self._last = (q, link, pose)
        return pose


class _OutOfLimitsIk(python_impl.RobotModel):
    """IK successes with joint 1 wrapped by 2pi out of its limits (same pose)."""

    def inverse_kinematics(self, pose: Any, seed: Any = None, link: str | None = None) -> IKResult:
        result = super().inverse_kinematics(pose, seed, link)
        if result.status != IKStatus.SUCCESS:
            return result
        values = list(result.joint_values)
        upper = self.joint_limits[0].upper
        if values[0] + 2 * math.pi > upper:
            values[0] += 2 * math.pi
        return IKResult(result.status, tuple(values), result.position_error, result.orientation_error)


class _OtherDefaultSeed(python_impl.RobotModel):
    """IK from 0.3 rad on every joint when no seed is given (the contract: ``home_values``)."""

    def inverse_kinematics(self, pose: Any, seed: Any = None, link: str | None = None) -> IKResult:
        if seed is None:
            seed = [0.3] * self.dof
        return super().inverse_kinematics(pose, seed, link)


fk_cache = SimpleNamespace(RobotModel=_CachingModel, MoveGroup=python_impl.MoveGroup)
ik_out_of_limits = SimpleNamespace(RobotModel=_OutOfLimitsIk, MoveGroup=python_impl.MoveGroup)
ik_other_default_seed = SimpleNamespace(RobotModel=_OtherDefaultSeed, MoveGroup=python_impl.MoveGroup)
