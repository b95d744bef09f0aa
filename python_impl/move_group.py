"""The twin's MoveGroup: moveit_commander's MoveGroupCommander over a simulated arm."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from python_impl import cartesian, convert
from python_impl.angles import normalize_angle
from python_impl.model import RobotModel
from python_impl.trajectory import check_execution, plan_trajectory, time_parameterize
from robot_api.constants import GOAL_JOINT_TOLERANCE
from robot_api.errors import (
    ErrorCode,
    InvalidInputError,
    OutOfBoundsError,
    PlanningError,
    UnknownNameError,
)
from robot_api.protocol import JointTarget, JointValues, PoseLike
from robot_api.records import (
    IKStatus,
    JointState,
    JointType,
    MoveItErrorCode,
    PlanResult,
    Pose,
    RobotState,
    RobotTrajectory,
)

_WHAT = "joint value target"


class _NoIKSolution(PlanningError):
    """The pose target has no IK solution from the current state (plan() reports NO_IK_SOLUTION)."""


class MoveGroup:
    """moveit_commander's ``MoveGroupCommander`` over a simulated arm.

    The arm starts at "home". ``go()`` plans a straight joint-space move with a
    trapezoidal profile and executes it: the state follows the trajectory.

    Parameters
    ----------
    model : RobotModel
        A model of this package.
    """

    def __init__(self, model: RobotModel) -> None:
        if not isinstance(model, RobotModel):
            raise InvalidInputError(
                f"model: expected a python_impl.RobotModel, got {type(model).__name__}",
                ErrorCode.INVALID_ARGUMENT,
            )
        self._model = model
        self._limits = model.joint_limits
        self._index = {lim.name: i for i, lim in enumerate(self._limits)}
        self._current = list(model.home_values)
        self._target = list(self._current)
        self._named: dict[str, list[float]] = {"home": list(self._current)}
        self._tolerance = GOAL_JOINT_TOLERANCE
        self._velocity_scaling = 1.0
        self._acceleration_scaling = 1.0
        # (position, orientation or None for a position target, link index) or None
        self._pose_goal: tuple[list[float], list[float] | None, int] | None = None

    # -- state -------------------------------------------------------------------------------

    def get_active_joints(self) -> list[str]:
        """Names of the joint variables."""
        return list(self._model.joint_names)

    def get_end_effector_link(self) -> str:
        """The model's tip link."""
        return self._model.tip_link

    def get_planning_frame(self) -> str:
        """The model's root link."""
        return self._model.root_link

    def get_current_joint_values(self) -> list[float]:
        """Current joint values (rad, m), length dof."""
        return list(self._current)

    def get_current_pose(self, link: str | None = None) -> Pose:
        """Pose of ``link`` (the end effector by default) in the current state."""
        return self._model.pose_of(self._current, self._model.link_index(link))

    def get_joint_value_target(self) -> list[float]:
        """The joint value target, length dof."""
        return list(self._target)

    def get_current_state(self) -> RobotState:
        """The current state as ``moveit_msgs/RobotState``: ``joint_state.name`` and ``.position``."""
        return RobotState(JointState(tuple(self._model.joint_names), tuple(self._current)))

    # -- targets -----------------------------------------------------------------------------

    def _accept(self, i: int, value: float) -> float:
        lim = self._limits[i]
        if lim.type == JointType.CONTINUOUS:
            return normalize_angle(value)
        if value < lim.lower - self._tolerance or value > lim.upper + self._tolerance:
            raise OutOfBoundsError(
                f"target {value!r} of joint '{lim.name}' is outside its limits [{lim.lower!r}, {lim.upper!r}]"
            )
        return min(max(value, lim.lower), lim.upper)

    def _set_values(self, values: list[float]) -> None:
        self._model.check_vector(values, _WHAT)
        self._target = [self._accept(i, v) for i, v in enumerate(values)]
        self._pose_goal = None

    def _set_named(self, names: list[str], values: list[float]) -> None:
        if len(names) != len(values):
            raise InvalidInputError(
                f"{_WHAT}: {len(names)} names but {len(values)} values", ErrorCode.WRONG_LENGTH
            )
        index = []
        for name in names:
            if name not in self._index:
                raise UnknownNameError(
                    f"joint '{name}' is not an active joint of the group", ErrorCode.UNKNOWN_JOINT
                )
            index.append(self._index[name])
        seen: set[int] = set()
        for name, i in zip(names, index, strict=True):
            if i in seen:
                raise InvalidInputError(f"joint '{name}' is given twice", ErrorCode.DUPLICATE_NAME)
            seen.add(i)
        for name, v in zip(names, values, strict=True):
            if not math.isfinite(v):
                raise InvalidInputError(f"value of joint '{name}' is not finite", ErrorCode.NON_FINITE)
        target = list(self._target)
        for i, v in zip(index, values, strict=True):
            target[i] = self._accept(i, v)
        self._target = target
        self._pose_goal = None

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
        if arg2 is None:
            if isinstance(arg1, dict):
                names, values = [], []
                for key, value in list(dict.items(arg1)):  # read once, as native reads a dict
                    names.append(convert.to_string(key, _WHAT))
                    values.append(convert.to_real(value, _WHAT))
                self._set_named(names, values)
            elif convert.is_sequence(arg1):
                self._set_values(convert.to_vector(arg1, _WHAT))
            elif isinstance(arg1, str):
                raise convert.bad(
                    _WHAT, f"joint name '{convert.to_string(arg1, _WHAT)}' given without a value"
                )
            else:
                raise convert.bad(_WHAT, f"unsupported argument of type {type(arg1).__name__}")
        elif isinstance(arg1, str):
            name = convert.to_string(arg1, _WHAT)
            self._set_named([name], [convert.to_real(arg2, _WHAT)])
        elif isinstance(arg1, list | tuple):
            names = convert.to_strings(arg1, _WHAT)
            self._set_named(names, convert.to_vector(arg2, _WHAT))
        else:
            raise convert.bad(_WHAT, f"unsupported argument of type {type(arg1).__name__}")

    def set_named_target(self, name: str) -> None:
        """Set the target to a named state ("home" or a remembered one)."""
        self._set_values(list(self._named_values(convert.to_string(name, "named target"))))

    def _named_values(self, name: str) -> list[float]:
        if name not in self._named:
            raise UnknownNameError(f"no named target '{name}'", ErrorCode.UNKNOWN_NAMED_TARGET)
        return self._named[name]

    def get_named_targets(self) -> list[str]:
        """Names of the named states, sorted."""
        return sorted(self._named, key=lambda s: s.encode("utf-8"))

    def get_named_target_values(self, name: str) -> dict[str, float]:
        """Joint values of a named state, by joint name."""
        values = self._named_values(convert.to_string(name, "named target"))
        return dict(zip(self._model.joint_names, values, strict=True))

    def remember_joint_values(self, name: str, values: JointValues | None = None) -> None:
        """Store ``values`` (the current state by default) as a named state."""
        key = convert.to_string(name, "named target")
        if values is None:
            self._named[key] = list(self._current)
            return
        vector = convert.to_vector(values, "remembered joint values")
        self._model.check_vector(vector, "remembered joint values")
        self._named[key] = vector

    # -- settings ----------------------------------------------------------------------------

    def set_goal_joint_tolerance(self, value: float) -> None:
        """Set how far beyond a limit (rad, m) a target may lie and still be accepted."""
        v = convert.to_real(value, "goal joint tolerance")
        if not (math.isfinite(v) and v >= 0.0):
            raise convert.bad("goal joint tolerance", f"must be finite and >= 0, got {v!r}")
        self._tolerance = v

    def get_goal_joint_tolerance(self) -> float:
        """The goal joint tolerance (rad, m)."""
        return self._tolerance

    @staticmethod
    def _scaling(value: Any, what: str) -> float:
        v = convert.to_real(value, what)
        if not (math.isfinite(v) and 0.0 < v <= 1.0):
            raise convert.bad(what, f"must be in (0, 1], got {v!r}")
        return v

    def set_max_velocity_scaling_factor(self, value: float) -> None:
        """Scale every velocity limit by ``value`` in (0, 1]."""
        self._velocity_scaling = self._scaling(value, "max velocity scaling factor")

    def set_max_acceleration_scaling_factor(self, value: float) -> None:
        """Scale the acceleration limit by ``value`` in (0, 1]."""
        self._acceleration_scaling = self._scaling(value, "max acceleration scaling factor")

    # -- pose targets ------------------------------------------------------------------------

    def set_pose_target(self, pose: PoseLike, end_effector_link: str | None = None) -> None:
        """Make ``pose`` of ``end_effector_link`` (the tip by default) the goal of plan() and go().

        The joint goal is found at planning time by IK seeded with the current state;
        ``set_joint_value_target``, ``set_named_target`` and ``clear_pose_targets`` end it.
        """
        position, orientation = convert.to_pose(pose)
        self._pose_goal = (position, orientation, self._model.link_index(end_effector_link))

    def set_position_target(self, xyz: JointValues, end_effector_link: str | None = None) -> None:
        """Like set_pose_target, with the link's orientation in the state planning starts from."""
        what = "position target"
        position = convert.to_vector(xyz, what)
        if len(position) != 3:
            raise InvalidInputError(f"{what}: expected 3 values, got {len(position)}", ErrorCode.WRONG_LENGTH)
        if not all(math.isfinite(v) for v in position):
            raise InvalidInputError(f"{what} is not finite", ErrorCode.NON_FINITE)
        self._pose_goal = (position, None, self._model.link_index(end_effector_link))

    def clear_pose_targets(self) -> None:
        """Forget the pose or position target: plan() and go() aim at the joint value target again."""
        self._pose_goal = None

    # -- motion ------------------------------------------------------------------------------

    def _goal(self) -> list[float]:
        if self._pose_goal is None:
            return self._target
        position, orientation, link = self._pose_goal
        if orientation is None:
            orientation = list(self._model.pose_of(self._current, link).orientation)
        answer = self._model.inverse_kinematics(
            Pose(
                (position[0], position[1], position[2]),
                (orientation[0], orientation[1], orientation[2], orientation[3]),
            ),
            self._current,
            self._model.link_names[link],
        )
        if answer.status != IKStatus.SUCCESS:
            raise _NoIKSolution("no IK solution for the pose target from the current state")
        return list(answer.joint_values)

    def _plan(self) -> RobotTrajectory:
        return plan_trajectory(
            self._limits, self._current, self._goal(), self._velocity_scaling, self._acceleration_scaling
        )

    def _empty(self) -> RobotTrajectory:
        n = self._model.dof
        return RobotTrajectory(
            tuple(self._model.joint_names), np.zeros(0), np.zeros((0, n)), np.zeros((0, n)), np.zeros((0, n))
        )

    def plan(self, joints: JointTarget | None = None) -> PlanResult:
        """Plan from the current state to the goal (the joint target is set first from ``joints``).

        Returns
        -------
        PlanResult
            ``(success, trajectory, planning_time, error_code)`` as moveit_commander Noetic;
            on failure the trajectory has no points and the state is unchanged.
        """
        if joints is not None:
            self.set_joint_value_target(joints)
        try:
            trajectory = self._plan()
        except _NoIKSolution:
            return PlanResult(False, self._empty(), 0.0, MoveItErrorCode.NO_IK_SOLUTION)
        except PlanningError:
            return PlanResult(False, self._empty(), 0.0, MoveItErrorCode.PLANNING_FAILED)
        return PlanResult(True, trajectory, 0.0, MoveItErrorCode.SUCCESS)

    def execute(self, plan: RobotTrajectory, wait: bool = True) -> bool:
        """Execute a trajectory; the state ends at its last point. Returns True."""
        if not isinstance(plan, RobotTrajectory):
            raise convert.bad("plan", f"expected a robot_api.RobotTrajectory, got {type(plan).__name__}")
        try:
            names = convert.to_strings(plan.joint_names, "trajectory joint names")
            times = convert.to_vector(plan.time_from_start, "trajectory times")
        except InvalidInputError as exc:
            raise InvalidInputError(str(exc), ErrorCode.INVALID_TRAJECTORY) from None
        positions = plan.positions
        if (
            not isinstance(positions, np.ndarray)
            or positions.ndim != 2
            or positions.shape != (len(times), self._model.dof)
            or positions.dtype.kind not in ("f", "i", "u")
        ):
            raise InvalidInputError(
                "trajectory positions: expected a real array of shape (M, dof) matching the times",
                ErrorCode.INVALID_TRAJECTORY,
            )
        convert.refuse_masked(positions, "trajectory positions", ErrorCode.INVALID_TRAJECTORY)
        values = convert.as_float64(positions, "trajectory positions", ErrorCode.INVALID_TRAJECTORY)
        if not isinstance(wait, bool):
            raise convert.bad("wait", "expected a bool")
        self._execute(names, times, values)
        return True

    def _execute(self, names: list[str], times: Sequence[float] | np.ndarray, positions: np.ndarray) -> None:
        check_execution(
            self._limits, self._model.joint_names, self._current, self._tolerance, names, times, positions
        )
        last = positions[-1].tolist()
        self._current = [
            normalize_angle(v) if lim.type == JointType.CONTINUOUS else min(max(v, lim.lower), lim.upper)
            for v, lim in zip(last, self._limits, strict=True)
        ]

    def go(self, joints: JointTarget | None = None, wait: bool = True) -> bool:
        """Plan and execute a move to the target (set first from ``joints`` if given; ``wait`` is
        checked before that, so a refused call changes nothing)."""
        if not isinstance(wait, bool):
            raise convert.bad("wait", "expected a bool")
        if joints is not None:
            self.set_joint_value_target(joints)
        try:
            trajectory = self._plan()
        except PlanningError:
            return False  # moveit_commander's go() returns False when planning fails
        self._execute(list(trajectory.joint_names), trajectory.time_from_start, trajectory.positions)
        return True

    def stop(self) -> None:
        """Do nothing: execution is synchronous, so no motion is ever under way."""

    def compute_cartesian_path(
        self, waypoints: Sequence[PoseLike], eef_step: float, jump_threshold: float = 0.0
    ) -> tuple[RobotTrajectory, float]:
        """Straight lines in Cartesian space from the current pose through ``waypoints``.

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
        poses, step, jump = cartesian.check_arguments(waypoints, eef_step, jump_threshold)

        def solve(pose: Pose, seed: list[float]) -> tuple[IKStatus, list[float]]:
            answer = self._model.inverse_kinematics(pose, seed)
            return answer.status, list(answer.joint_values)

        tip = len(self._model.link_names) - 1
        start = self._model.pose_of(self._current, tip)
        points, fraction = cartesian.cartesian_points(start, self._current, poses, step, solve)
        if jump > 0.0:
            fraction *= cartesian.jump_test(self._limits, points, jump)
        trajectory = time_parameterize(
            self._limits, points, self._velocity_scaling, self._acceleration_scaling
        )
        return trajectory, fraction
