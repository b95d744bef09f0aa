"""Deep zoo bugs (issue 11): faults confined to narrow regions of the input space.

Each variant is ``python_impl`` with one behaviour changed only inside a region a campaign
must *find*: a band about 0.1% wide of one joint's range away from round values, a relation
between two joints, a branch on a computed float (a position of the tool, an ``atan2``
angle), a calibration-table entry, a near-singular wrist, a revolute joint past pi, an IK
that goes wrong only from certain seeds. ``benchmarks/zoo/__init__.py`` lists them with the
public source of each class. Outside its region every variant is the twin itself.
"""

from __future__ import annotations

import math
from typing import Any

import python_impl
from python_impl.angles import normalize_angle
from robot_api.records import IKResult, IKStatus, JointType, Pose

Model = python_impl.RobotModel
Group = python_impl.MoveGroup
SHIFT = 1e-3
"""How wrong a faulty answer is (m or rad): far above the oracle's 1e-6."""


def _impl(model: type = Model, group: type = Group) -> Any:
    from types import SimpleNamespace

    return SimpleNamespace(RobotModel=model, MoveGroup=group)


def _shifted(pose: Pose, dz: float = SHIFT) -> Pose:
    x, y, z = pose.position
    return Pose((x, y, z + dz), pose.orientation)


# -- 1. a band 0.1% wide of joint 2's range, at 61.73% of the range -------------------------


class _NarrowBand(Model):
    def pose_of(self, values: list[float], link: int) -> Pose:
        pose = super().pose_of(values, link)
        lim = self.joint_limits[1]
        start = lim.lower + 0.6173 * (lim.upper - lim.lower)
        if len(values) > 1 and start <= values[1] < start + 0.001 * (lim.upper - lim.lower):
            return _shifted(pose)
        return pose


narrow_band = _impl(model=_NarrowBand)


# -- 2. two joints in a relation: joint_1 - joint_3 within 1e-3 of sqrt(2) - 1 ---------------


class _JointRelation(Model):
    def pose_of(self, values: list[float], link: int) -> Pose:
        pose = super().pose_of(values, link)
        if len(values) > 2 and abs(values[0] - values[2] - (math.sqrt(2.0) - 1.0)) < 1e-3:
            return _shifted(pose)
        return pose


joint_relation = _impl(model=_JointRelation)


# -- 3. a branch on a computed float: the tool's x position in [0.1234, 0.1244) m ------------


class _ComputedBranch(Model):
    def pose_of(self, values: list[float], link: int) -> Pose:
        pose = super().pose_of(values, link)
        if 0.1234 <= pose.position[0] < 0.1244:
            return _shifted(pose)
        return pose


computed_branch = _impl(model=_ComputedBranch)


# -- 4. atan2 quadrant: the tool's azimuth in (2.0, 2.01) rad mirrored -----------------------


class _Atan2Quadrant(Model):
    def pose_of(self, values: list[float], link: int) -> Pose:
        pose = super().pose_of(values, link)
        x, y, z = pose.position
        if 2.0 < math.atan2(y, x) < 2.01:
            return Pose((-x, y, z), pose.orientation)
        return pose


atan2_quadrant = _impl(model=_Atan2Quadrant)


# -- 5. a calibration table with one wrong entry: joint_3 at round(100 q) == 137 -------------


class _CalibrationEntry(Model):
    def pose_of(self, values: list[float], link: int) -> Pose:
        if len(values) > 2 and round(values[2] * 100) == 137:
            values = [*values[:2], values[2] + SHIFT, *values[3:]]
        return super().pose_of(values, link)


calibration_entry = _impl(model=_CalibrationEntry)


# -- 6. near-singular wrist: joint_5 within 2e-3 of 0 (but not 0) treated as 0 --------------


class _SmallAngleWrist(Model):
    def pose_of(self, values: list[float], link: int) -> Pose:
        if len(values) > 4 and 0.0 < abs(values[4]) < 2e-3:
            values = [*values[:4], 0.0, *values[5:]]
        return super().pose_of(values, link)


small_angle_wrist = _impl(model=_SmallAngleWrist)


# -- 7. a revolute joint past pi: targets in [4.0, 4.05) rad wrapped into (-pi, pi] ----------


class _WrapPastPi(Group):
    def set_joint_value_target(self, arg1: Any, arg2: Any = None) -> None:
        super().set_joint_value_target(arg1, arg2)
        self._target = [
            normalize_angle(v) if lim.type == JointType.REVOLUTE and 4.0 <= v < 4.05 else v
            for v, lim in zip(self._target, self._limits, strict=True)
        ]


wrap_past_pi = _impl(group=_WrapPastPi)


# -- 8. IK from certain seeds: a seed with joint_1 in [0.3, 0.31) rad reports its seed -------


class _SeedBandIk(Model):
    def inverse_kinematics(self, pose: Pose, seed: Any = None, link: str | None = None) -> IKResult:
        result = super().inverse_kinematics(pose, seed, link)
        if seed is not None and len(seed) and 0.3 <= float(seed[0]) < 0.31:
            return IKResult(IKStatus.SUCCESS, tuple(float(v) for v in seed), 0.0, 0.0)
        return result


ik_seed_band = _impl(model=_SeedBandIk)

__all__ = [
    "atan2_quadrant",
    "calibration_entry",
    "computed_branch",
    "ik_seed_band",
    "joint_relation",
    "narrow_band",
    "small_angle_wrist",
    "wrap_past_pi",
]
