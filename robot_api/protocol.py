"""The API both implementations expose, as typing protocols.

``docs/api.md`` is the prose contract; these protocols pin names and
signatures, and ``tests/test_parity.py`` checks that ``native`` and
``python_impl`` (and any plugged-in target) match them exactly.

An *implementation* is any object with two attributes, ``RobotModel`` and
``MoveGroup``, that construct objects following :class:`RobotModelAPI` and
:class:`MoveGroupAPI`: a module such as ``native`` or ``python_impl``, or a
``types.SimpleNamespace`` built by a plugin.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from robot_api.records import (
    IKResult,
    JointLimit,
    MimicJoint,
    PlanResult,
    Pose,
    RobotState,
    RobotTrajectory,
)

JointValues = Sequence[float] | NDArray[np.float64]
JointTarget = JointValues | Mapping[str, float] | str | Sequence[str]
PoseLike = Pose | tuple[Sequence[float], Sequence[float]]


@runtime_checkable
class RobotModelAPI(Protocol):
    """A kinematic chain loaded from URDF."""

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None: ...

    @property
    def name(self) -> str: ...
    @property
    def root_link(self) -> str: ...
    @property
    def tip_link(self) -> str: ...
    @property
    def joint_names(self) -> tuple[str, ...]: ...
    @property
    def link_names(self) -> tuple[str, ...]: ...
    @property
    def dof(self) -> int: ...
    @property
    def joint_limits(self) -> tuple[JointLimit, ...]: ...
    @property
    def mimic_joints(self) -> tuple[MimicJoint, ...]: ...
    @property
    def home_values(self) -> tuple[float, ...]: ...

    def forward_kinematics(self, joint_values: JointValues, link: str | None = None) -> Pose: ...

    def forward_kinematics_batch(
        self, joint_values: NDArray[np.float64], link: str | None = None
    ) -> NDArray[np.float64]: ...

    def inverse_kinematics(
        self, pose: Pose, seed: JointValues | None = None, link: str | None = None
    ) -> IKResult: ...


@runtime_checkable
class MoveGroupAPI(Protocol):
    """moveit_commander's MoveGroupCommander semantics over a simulated arm."""

    def __init__(self, model: Any) -> None: ...

    def get_active_joints(self) -> list[str]: ...
    def get_end_effector_link(self) -> str: ...
    def get_planning_frame(self) -> str: ...
    def get_current_joint_values(self) -> list[float]: ...
    def get_current_pose(self, link: str | None = None) -> Pose: ...
    def get_joint_value_target(self) -> list[float]: ...
    def get_current_state(self) -> RobotState: ...

    def set_joint_value_target(self, arg1: JointTarget, arg2: Any = None) -> None: ...
    def set_named_target(self, name: str) -> None: ...
    def get_named_targets(self) -> list[str]: ...
    def get_named_target_values(self, name: str) -> dict[str, float]: ...
    def remember_joint_values(self, name: str, values: JointValues | None = None) -> None: ...

    def set_goal_joint_tolerance(self, value: float) -> None: ...
    def get_goal_joint_tolerance(self) -> float: ...
    def set_max_velocity_scaling_factor(self, value: float) -> None: ...
    def set_max_acceleration_scaling_factor(self, value: float) -> None: ...

    def set_pose_target(self, pose: PoseLike, end_effector_link: str | None = None) -> None: ...
    def set_position_target(self, xyz: JointValues, end_effector_link: str | None = None) -> None: ...
    def clear_pose_targets(self) -> None: ...

    def plan(self, joints: JointTarget | None = None) -> PlanResult: ...
    def execute(self, plan: RobotTrajectory, wait: bool = True) -> bool: ...
    def go(self, joints: JointTarget | None = None, wait: bool = True) -> bool: ...
    def stop(self) -> None: ...
    def compute_cartesian_path(
        self, waypoints: Sequence[PoseLike], eef_step: float, jump_threshold: float = 0.0
    ) -> tuple[RobotTrajectory, float]: ...


class Implementation(Protocol):
    """What ``--targets module:attribute`` must name."""

    RobotModel: type[RobotModelAPI]
    MoveGroup: type[MoveGroupAPI]


MODEL_METHODS = (
    "forward_kinematics",
    "forward_kinematics_batch",
    "inverse_kinematics",
)
MODEL_PROPERTIES = (
    "name",
    "root_link",
    "tip_link",
    "joint_names",
    "link_names",
    "dof",
    "joint_limits",
    "mimic_joints",
    "home_values",
)
GROUP_METHODS = (
    "get_active_joints",
    "get_end_effector_link",
    "get_planning_frame",
    "get_current_joint_values",
    "get_current_pose",
    "get_joint_value_target",
    "get_current_state",
    "set_joint_value_target",
    "set_named_target",
    "get_named_targets",
    "get_named_target_values",
    "remember_joint_values",
    "set_goal_joint_tolerance",
    "get_goal_joint_tolerance",
    "set_max_velocity_scaling_factor",
    "set_max_acceleration_scaling_factor",
    "set_pose_target",
    "set_position_target",
    "clear_pose_targets",
    "plan",
    "execute",
    "go",
    "stop",
    "compute_cartesian_path",
)
