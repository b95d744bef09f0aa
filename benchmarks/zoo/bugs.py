"""Fault-injected variants of the Python twin: the bug zoo.

Each variant is ``python_impl`` with exactly one behaviour changed, exposed as
an object with ``RobotModel`` and ``MoveGroup`` (``--targets
native,benchmarks.zoo.bugs:NAME``). ``benchmarks/zoo/__init__.py`` lists them
with a one-line description, the public source of their bug class, and the
campaign (op, robot) in which they can show.
"""

from __future__ import annotations

import dataclasses
import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from types import SimpleNamespace
from typing import Any
from unittest import mock

import defusedxml.ElementTree as SafeET
import numpy as np

import python_impl
from python_impl import chain as chain_module
from python_impl import convert, kinematics
from python_impl.angles import normalize_angle
from python_impl.transforms import homogeneous
from robot_api.errors import OutOfBoundsError
from robot_api.records import IKResult, IKStatus, JointType, Pose, RobotTrajectory

TWO_PI = 2 * math.pi
Model = python_impl.RobotModel
Group = python_impl.MoveGroup


def _impl(model: type = Model, group: type = Group) -> SimpleNamespace:
    return SimpleNamespace(RobotModel=model, MoveGroup=group)


def _rewritten(urdf: Any, edit: Any) -> str:
    """The URDF text after ``edit(root)`` changed its element tree."""
    path = os.fspath(urdf)
    text = path if path.lstrip().startswith("<") else Path(path).read_text(encoding="utf-8")
    root = SafeET.fromstring(text.encode())
    edit(root)
    return ET.tostring(root, encoding="unicode")


# -- 1. continuous joints reported in [0, 2pi) instead of (-pi, pi] ------------------------------


class _WrapPositive(Group):
    def get_current_joint_values(self) -> list[float]:
        return [
            v % TWO_PI if lim.type == JointType.CONTINUOUS else v
            for v, lim in zip(super().get_current_joint_values(), self._limits, strict=True)
        ]


wrap_positive = _impl(group=_WrapPositive)


# -- 2. the +-pi boundary: [-pi, pi) instead of (-pi, pi] -----------------------------------------


class _HalfOpenLow(Group):
    def get_current_joint_values(self) -> list[float]:
        return [
            -math.pi if lim.type == JointType.CONTINUOUS and v == math.pi else v
            for v, lim in zip(super().get_current_joint_values(), self._limits, strict=True)
        ]


pi_boundary = _impl(group=_HalfOpenLow)


# -- 3. out-of-bounds targets clamped silently instead of rejected -------------------------------


class _SilentClamp(Group):
    def _accept(self, i: int, value: float) -> float:
        lim = self._limits[i]
        if lim.type == JointType.CONTINUOUS:
            return normalize_angle(value)
        return min(max(value, lim.lower), lim.upper)


silent_clamp = _impl(group=_SilentClamp)


# -- 4. the error is a return value nobody checks, and the target is set anyway -----------------


class _TargetDespiteError(Group):
    def _accept(self, i: int, value: float) -> float:
        try:
            return super()._accept(i, value)
        except OutOfBoundsError:
            return value  # MoveIt's setJointValueTarget returns false, but has set the state

    def _execute(self, names: list[str], times: Sequence[float] | np.ndarray, positions: np.ndarray) -> None:
        self._current = positions[-1].tolist()  # and execution does not check bounds either


target_despite_error = _impl(group=_TargetDespiteError)


# -- 5. a missing lower limit read as "no limit" instead of 0 ---------------------------------


class _MissingLowerUnlimited(Model):
    def __init__(self, urdf: Any, tip_link: str | None = None) -> None:
        def edit(root: ET.Element) -> None:
            for limit in root.iter("limit"):
                if limit.get("lower") is None and limit.get("upper") is not None:
                    limit.set("lower", "-1e9")

        super().__init__(_rewritten(urdf, edit), tip_link)


missing_lower_unlimited = _impl(model=_MissingLowerUnlimited)


# -- 6. the joint axis used without normalizing ---------------------------------------------


class _RawAxis(Model):
    def __init__(self, urdf: Any, tip_link: str | None = None) -> None:
        with mock.patch.object(chain_module, "unit", lambda v: np.asarray(v, dtype=np.float64)):
            super().__init__(urdf, tip_link)


axis_not_normalized = _impl(model=_RawAxis)


# -- 7. a missing <axis> defaulting to z instead of x -----------------------------------------


class _MissingAxisZ(Model):
    def __init__(self, urdf: Any, tip_link: str | None = None) -> None:
        def edit(root: ET.Element) -> None:
            for joint in root.iter("joint"):
                if joint.get("type") not in ("fixed", "floating") and joint.find("axis") is None:
                    ET.SubElement(joint, "axis", {"xyz": "0 0 1"})

        super().__init__(_rewritten(urdf, edit), tip_link)


missing_axis_z = _impl(model=_MissingAxisZ)


# -- 8. the IK target quaternion used without normalizing ------------------------------------


class _RawQuaternion(Model):
    def inverse_kinematics(self, pose: Pose, seed: Any = None, link: str | None = None) -> IKResult:
        position, _ = convert.to_pose(pose)  # the checks, but then the raw quaternion:
        x, y, z, w = (float(c) for c in pose[1])
        rot = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        q = list(self.home_values) if seed is None else convert.to_vector(seed, "seed")
        index = self.link_index(link)
        nvars = self._ik_variables(index)
        target = homogeneous(rot, (position[0], position[1], position[2]))
        ok, values, perr, oerr = kinematics.ik(self.chain, target, q, index, nvars)
        return IKResult(IKStatus.SUCCESS if ok else IKStatus.NO_SOLUTION, tuple(values), perr, oerr)


quaternion_not_normalized = _impl(model=_RawQuaternion)


# -- 9. orientation through roll-pitch-yaw, with a gimbal-lock branch taken too early ----------

GIMBAL_BAND = 1e-6


def _via_rpy(r: np.ndarray) -> tuple[float, float, float, float]:
    if abs(r[2, 0]) > 1.0 - GIMBAL_BAND:  # "at gimbal lock": roll set to 0
        pitch = -math.copysign(math.pi / 2, r[2, 0])
        roll, yaw = 0.0, math.atan2(-r[0, 1], r[1, 1])
    else:
        roll, pitch, yaw = math.atan2(r[2, 1], r[2, 2]), math.asin(-r[2, 0]), math.atan2(r[1, 0], r[0, 0])
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    q = (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )
    return q if q[3] >= 0 else (-q[0], -q[1], -q[2], -q[3])


class _GimbalModel(Model):
    def pose_of(self, values: list[float], link: int) -> Pose:
        t = kinematics.fk(self.chain, np.array(values, dtype=np.float64), link)
        x, y, z = t[:3, 3].tolist()
        return Pose((x, y, z), _via_rpy(t[:3, :3]))


rpy_gimbal_band = _impl(model=_GimbalModel)


# -- 10. execution integrates velocities in float32 ------------------------------------------


class _Float32Integration(Group):
    def _plan(self) -> RobotTrajectory:
        self._last_plan: RobotTrajectory | None = super()._plan()
        return self._last_plan

    def go(self, joints: Any = None, wait: bool = True) -> bool:
        self._last_plan = None
        moved = super().go(joints, wait)  # every check, then the state is re-integrated:
        traj = self._last_plan
        if moved and traj is not None and len(traj) > 1:
            state = traj.positions[0].astype(np.float32)
            dt = np.diff(traj.time_from_start).astype(np.float32)
            for i in range(1, len(traj)):
                state = state + traj.velocities[i - 1].astype(np.float32) * dt[i - 1]
            self._current = [
                normalize_angle(float(v)) if lim.type == JointType.CONTINUOUS else float(v)
                for v, lim in zip(state, self._limits, strict=True)
            ]
        return moved


float32_integration = _impl(group=_Float32Integration)


# -- 11. mimic joints ignored (they stay at 0) ---------------------------------------------


class _MimicIgnored(Model):
    def __init__(self, urdf: Any, tip_link: str | None = None) -> None:
        super().__init__(urdf, tip_link)
        c = self._chain
        ignored = np.where(c.mimic, 0.0, c.multiplier)
        offsets = np.where(c.mimic, 0.0, c.offset)
        self._chain = dataclasses.replace(c, multiplier=ignored, offset=offsets)


mimic_ignored = _impl(model=_MimicIgnored)


# -- 12. the trajectory's last sample dropped (ends at the last multiple of dt) ------------


class _LastSampleDropped(Group):
    def _plan(self) -> RobotTrajectory:
        t = super()._plan()
        if len(t) < 3:
            return t
        return RobotTrajectory(
            t.joint_names, t.time_from_start[:-1], t.positions[:-1], t.velocities[:-1], t.accelerations[:-1]
        )


last_sample_dropped = _impl(group=_LastSampleDropped)


# -- 13. an IK status misread: "did not converge" reported as success ---------------------


class _StatusMisread(Model):
    def inverse_kinematics(self, pose: Pose, seed: Any = None, link: str | None = None) -> IKResult:
        result = super().inverse_kinematics(pose, seed, link)
        return result._replace(status=IKStatus.SUCCESS)


ik_status_misread = _impl(model=_StatusMisread)


# -- 14. off by tolerance: a goal tolerance ten times tighter than MoveIt's ----------------


class _TightTolerance(Group):
    def __init__(self, model: Model) -> None:
        super().__init__(model)
        self._tolerance = 1e-5


off_by_tolerance = _impl(group=_TightTolerance)


# -- control: the twin itself (no fault) -------------------------------------------------

control = _impl()

__all__ = [
    "axis_not_normalized",
    "control",
    "float32_integration",
    "ik_status_misread",
    "last_sample_dropped",
    "mimic_ignored",
    "missing_axis_z",
    "missing_lower_unlimited",
    "off_by_tolerance",
    "pi_boundary",
    "quaternion_not_normalized",
    "rpy_gimbal_band",
    "silent_clamp",
    "target_despite_error",
    "wrap_positive",
]
