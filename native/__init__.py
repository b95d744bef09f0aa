"""The native target: Orocos KDL kinematics and a simulated MoveGroup, in C++.

A thin facade over the private compiled module ``native._native``: these
classes give the API its Python signatures and documentation and delegate every
call; argument conversion and all semantics live in C++ (``native/src``).
The contract is ``docs/api.md``; errors are :mod:`robot_api.errors` classes.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import os
import sys
from typing import Any

import numpy as np
from numpy.typing import NDArray

if os.environ.get("RROSFUZZ_NATIVE_MODULE"):
    # The fuzzing build (clang -fsanitize=fuzzer-no-link,address; `make fuzz-native`)
    # replaces the regular module. It needs Atheris' asan_with_fuzzer.so preloaded.
    _path = os.environ["RROSFUZZ_NATIVE_MODULE"]
    _loader = importlib.machinery.ExtensionFileLoader("native._native", _path)
    _spec = importlib.util.spec_from_file_location("native._native", _path, loader=_loader)
    if _spec is None:
        raise ImportError(f"RROSFUZZ_NATIVE_MODULE={_path} is not an extension module")
    _native = importlib.util.module_from_spec(_spec)
    sys.modules["native._native"] = _native
    _loader.exec_module(_native)
else:
    import native._native as _native
from collections.abc import Sequence

from robot_api.errors import ErrorCode, InvalidInputError
from robot_api.protocol import JointTarget, JointValues, PoseLike
from robot_api.records import IKResult, JointLimit, MimicJoint, PlanResult, Pose, RobotState, RobotTrajectory

__all__ = ["MoveGroup", "RobotModel", "constants"]

constants: dict[str, float] = dict(_native.constants)


def _source(urdf: Any) -> tuple[Any, bool]:
    if isinstance(urdf, os.PathLike):
        return os.fspath(urdf), True
    if isinstance(urdf, str):
        return urdf, not urdf.lstrip().startswith("<")
    return urdf, False  # C++ rejects the type with INVALID_ARGUMENT


class RobotModel:
    """A kinematic chain loaded from URDF (urdfdom), solved with Orocos KDL.

    Parameters
    ----------
    urdf : str or os.PathLike
        A URDF file path, or URDF XML text (a string starting with ``<``).
    tip_link : str, optional
        Last link of the chain; by default the contract's tip rule picks it.

    Raises
    ------
    URDFError
        The URDF is unreadable, malformed or unsupported.
    UnknownNameError
        ``tip_link`` is not a link of the URDF.
    """

    __slots__ = ("_m",)

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None:
        source, is_path = _source(urdf)
        self._m = _native.Model(source, is_path, tip_link)

    @property
    def name(self) -> str:
        """Robot name from the URDF."""
        return str(self._m.name)

    @property
    def root_link(self) -> str:
        """First link of the chain (the planning frame)."""
        return str(self._m.root_link)

    @property
    def tip_link(self) -> str:
        """Last link of the chain (the end effector)."""
        return str(self._m.tip_link)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Joint variables in order, length ``dof``."""
        return tuple(self._m.joint_names)

    @property
    def link_names(self) -> tuple[str, ...]:
        """Links of the chain from root to tip."""
        return tuple(self._m.link_names)

    @property
    def dof(self) -> int:
        """Number of joint variables."""
        return int(self._m.dof)

    @property
    def joint_limits(self) -> tuple[JointLimit, ...]:
        """Limits of each variable, length ``dof``."""
        return tuple(self._m.joint_limits)

    @property
    def mimic_joints(self) -> tuple[MimicJoint, ...]:
        """Mimic joints on the chain."""
        return tuple(self._m.mimic_joints)

    @property
    def home_values(self) -> tuple[float, ...]:
        """The "home" configuration: 0 clamped into each joint's limits."""
        return tuple(self._m.home_values)

    def forward_kinematics(self, joint_values: JointValues, link: str | None = None) -> Pose:
        """Pose of a link for one configuration.

        Parameters
        ----------
        joint_values : sequence of float or ndarray, shape (dof,)
            Joint values (rad, m). Limits are not enforced.
        link : str, optional
            A link of the chain; the tip by default.

        Returns
        -------
        Pose
            Position (m) and unit quaternion (x, y, z, w), ``w >= 0``, in the root frame.
        """
        return self._m.forward_kinematics(joint_values, link)  # type: ignore[no-any-return]

    def forward_kinematics_batch(
        self, joint_values: NDArray[np.float64], link: str | None = None
    ) -> NDArray[np.float64]:
        """Poses of a link for many configurations.

        Parameters
        ----------
        joint_values : ndarray, shape (N, dof), or list of N rows
            Joint values (rad, m).
        link : str, optional
            A link of the chain; the tip by default.

        Returns
        -------
        ndarray, shape (N, 4, 4)
            Homogeneous transforms in the root frame.
        """
        return self._m.forward_kinematics_batch(joint_values, link)  # type: ignore[no-any-return]

    def inverse_kinematics(
        self, pose: Pose, seed: JointValues | None = None, link: str | None = None
    ) -> IKResult:
        """Joint values that put ``link`` at ``pose`` (KDL ChainIkSolverPos_NR_JL).

        Parameters
        ----------
        pose : Pose or (position, orientation)
            Target; the quaternion (x, y, z, w) is normalized.
        seed : sequence of float, shape (dof,), optional
            Start of the search, clamped into the limits; ``home_values`` by default.
        link : str, optional
            A link of the chain; the tip by default.

        Returns
        -------
        IKResult
            Status, joint values (within limits), position (m) and orientation (rad) errors.
        """
        return self._m.inverse_kinematics(pose, seed, link)  # type: ignore[no-any-return]


class MoveGroup:
    """moveit_commander's ``MoveGroupCommander`` over a simulated arm.

    The arm starts at "home". ``go()`` plans a straight joint-space move with a
    trapezoidal profile and executes it: the state follows the trajectory.

    Parameters
    ----------
    model : RobotModel
        A model of this package.
    """

    __slots__ = ("_g", "_model")

    def __init__(self, model: RobotModel) -> None:
        if not isinstance(model, RobotModel):
            raise InvalidInputError(
                f"model: expected a native.RobotModel, got {type(model).__name__}",
                ErrorCode.INVALID_ARGUMENT,
            )
        self._model = model
        self._g = _native.MoveGroup(model._m)

    def get_active_joints(self) -> list[str]:
        """Names of the joint variables."""
        return self._g.get_active_joints()  # type: ignore[no-any-return]

    def get_end_effector_link(self) -> str:
        """The model's tip link."""
        return self._g.get_end_effector_link()  # type: ignore[no-any-return]

    def get_planning_frame(self) -> str:
        """The model's root link."""
        return self._g.get_planning_frame()  # type: ignore[no-any-return]

    def get_current_joint_values(self) -> list[float]:
        """Current joint values (rad, m), length dof."""
        return self._g.get_current_joint_values()  # type: ignore[no-any-return]

    def get_current_pose(self, link: str | None = None) -> Pose:
        """Pose of ``link`` (the end effector by default) in the current state."""
        return self._g.get_current_pose(link)  # type: ignore[no-any-return]

    def get_joint_value_target(self) -> list[float]:
        """The joint value target, length dof."""
        return self._g.get_joint_value_target()  # type: ignore[no-any-return]

    def get_current_state(self) -> RobotState:
        """The current state as ``moveit_msgs/RobotState``: ``joint_state.name`` and ``.position``."""
        return self._g.get_current_state()  # type: ignore[no-any-return]

    def set_joint_value_target(self, arg1: JointTarget, arg2: Any = None) -> None:
        """Set the joint value target (moveit_commander's forms).

        Parameters
        ----------
        arg1 : sequence of float, dict of str to float, str, or sequence of str
            All values in order; some values by name; one joint's name (with
            ``arg2`` its value); or names (with ``arg2`` their values).
        arg2 : float or sequence of float, optional
            Value(s) for the name(s) in ``arg1``.

        Raises
        ------
        InvalidInputError, UnknownNameError, OutOfBoundsError
            See docs/api.md; on error the target is unchanged.
        """
        self._g.set_joint_value_target(arg1, arg2)

    def set_named_target(self, name: str) -> None:
        """Set the target to a named state ("home" or a remembered one)."""
        self._g.set_named_target(name)

    def get_named_targets(self) -> list[str]:
        """Names of the named states, sorted."""
        return self._g.get_named_targets()  # type: ignore[no-any-return]

    def get_named_target_values(self, name: str) -> dict[str, float]:
        """Joint values of a named state, by joint name."""
        return self._g.get_named_target_values(name)  # type: ignore[no-any-return]

    def remember_joint_values(self, name: str, values: JointValues | None = None) -> None:
        """Store ``values`` (the current state by default) as a named state."""
        self._g.remember_joint_values(name, values)

    def set_goal_joint_tolerance(self, value: float) -> None:
        """Set how far beyond a limit (rad, m) a target may lie and still be accepted."""
        self._g.set_goal_joint_tolerance(value)

    def get_goal_joint_tolerance(self) -> float:
        """The goal joint tolerance (rad, m)."""
        return self._g.get_goal_joint_tolerance()  # type: ignore[no-any-return]

    def set_max_velocity_scaling_factor(self, value: float) -> None:
        """Scale every velocity limit by ``value`` in (0, 1]."""
        self._g.set_max_velocity_scaling_factor(value)

    def set_max_acceleration_scaling_factor(self, value: float) -> None:
        """Scale the acceleration limit by ``value`` in (0, 1]."""
        self._g.set_max_acceleration_scaling_factor(value)

    def set_pose_target(self, pose: PoseLike, end_effector_link: str | None = None) -> None:
        """Make ``pose`` of ``end_effector_link`` (the tip by default) the goal of plan() and go().

        The joint goal is found at planning time by IK (KDL) seeded with the current state;
        ``set_joint_value_target``, ``set_named_target`` and ``clear_pose_targets`` end it.
        """
        self._g.set_pose_target(pose, end_effector_link)

    def set_position_target(self, xyz: JointValues, end_effector_link: str | None = None) -> None:
        """Like set_pose_target, with the link's orientation in the state planning starts from."""
        self._g.set_position_target(xyz, end_effector_link)

    def clear_pose_targets(self) -> None:
        """Forget the pose or position target: plan() and go() aim at the joint value target again."""
        self._g.clear_pose_targets()

    def plan(self, joints: JointTarget | None = None) -> PlanResult:
        """Plan from the current state to the goal (the joint target is set first from ``joints``).

        Returns
        -------
        PlanResult
            ``(success, trajectory, planning_time, error_code)`` as moveit_commander Noetic;
            on failure the trajectory has no points and the state is unchanged.
        """
        return self._g.plan(joints)  # type: ignore[no-any-return]

    def execute(self, plan: RobotTrajectory, wait: bool = True) -> bool:
        """Execute a trajectory; the state ends at its last point. Returns True."""
        return self._g.execute(plan, wait)  # type: ignore[no-any-return]

    def go(self, joints: JointTarget | None = None, wait: bool = True) -> bool:
        """Plan and execute a move to the target (set first from ``joints`` if given)."""
        return self._g.go(joints, wait)  # type: ignore[no-any-return]

    def stop(self) -> None:
        """Do nothing: execution is synchronous, so no motion is ever under way."""
        self._g.stop()

    def compute_cartesian_path(
        self, waypoints: Sequence[PoseLike], eef_step: float, jump_threshold: float = 0.0
    ) -> tuple[RobotTrajectory, float]:
        """Straight lines in Cartesian space from the current pose through ``waypoints`` (KDL IK).

        Parameters
        ----------
        waypoints : sequence of Pose or (position, orientation)
            Poses of the end effector (the tip), at least one.
        eef_step : float
            Largest distance (m) between interpolated positions, finite and > 0.
        jump_threshold : float, optional
            MoveIt's relative jump factor, finite and >= 0; 0 disables the test.

        Returns
        -------
        (RobotTrajectory, float)
            The timed path (first point: the current state) and the fraction achieved.
            The state does not change.
        """
        return self._g.compute_cartesian_path(waypoints, eef_step, jump_threshold)  # type: ignore[no-any-return]
