"""Typed records returned by both implementations.

Poses, IK results, states and plan results are named tuples (immutable and
cheap to build on the hot path); a trajectory is a frozen dataclass of numpy
arrays.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray


class JointType(enum.StrEnum):
    """Kinds of joints that carry a variable."""

    REVOLUTE = "revolute"
    CONTINUOUS = "continuous"
    PRISMATIC = "prismatic"


class JointLimit(NamedTuple):
    """Limits of one joint variable.

    Attributes
    ----------
    name : str
        Joint name.
    type : JointType
        Kind of joint.
    lower, upper : float
        Position limits (rad or m); ``-inf``/``inf`` for continuous joints.
    velocity : float
        Velocity limit used for planning (rad/s or m/s), before scaling.
    """

    name: str
    type: JointType
    lower: float
    upper: float
    velocity: float


class MimicJoint(NamedTuple):
    """A joint on the chain whose value follows another joint.

    ``value = multiplier * value(master) + offset``.
    """

    name: str
    master: str
    multiplier: float
    offset: float


class Pose(NamedTuple):
    """A rigid transform of a link in the model's root frame.

    Attributes
    ----------
    position : tuple of 3 float
        Translation (x, y, z) in metres.
    orientation : tuple of 4 float
        Unit quaternion (x, y, z, w), ROS order, with ``w >= 0``.
    """

    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]

    @property
    def matrix(self) -> NDArray[np.float64]:
        """Homogeneous transform, shape (4, 4)."""
        x, y, z, w = self.orientation
        m = np.eye(4)
        m[:3, :3] = (
            (1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)),
            (2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)),
            (2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)),
        )
        m[:3, 3] = self.position
        return m


class IKStatus(enum.StrEnum):
    """Outcome of an inverse kinematics query."""

    SUCCESS = "success"
    """Converged: every component of the error twist is below ``IK_EPS``."""
    NO_SOLUTION = "no_solution"
    """Did not converge within ``IK_MAX_ITERATIONS``."""


class IKResult(NamedTuple):
    """Answer of an inverse kinematics query.

    Attributes
    ----------
    status : IKStatus
        Whether the solver converged.
    joint_values : tuple of float, length dof
        The last iterate (within limits; continuous joints in (-pi, pi]).
    position_error : float
        Distance (m) between the reached and the requested position.
    orientation_error : float
        Angle (rad) of the rotation between reached and requested orientation.
    """

    status: IKStatus
    joint_values: tuple[float, ...]
    position_error: float
    orientation_error: float


@dataclass(frozen=True, eq=False)
class RobotTrajectory:
    """A time-parameterized joint trajectory (what ``plan()`` returns).

    Attributes
    ----------
    joint_names : tuple of str, length dof
        Variables, in the model's order.
    time_from_start : ndarray, shape (M,)
        Sample times in seconds, strictly increasing, starting at 0.
    positions, velocities, accelerations : ndarray, shape (M, dof)
        Joint states at each sample (rad or m, per second, per second squared).
    """

    joint_names: tuple[str, ...]
    time_from_start: NDArray[np.float64]
    positions: NDArray[np.float64]
    velocities: NDArray[np.float64]
    accelerations: NDArray[np.float64]

    def __len__(self) -> int:
        return int(self.time_from_start.shape[0])

    @property
    def duration(self) -> float:
        """Time (s) of the last sample."""
        return float(self.time_from_start[-1]) if len(self) else 0.0


class MoveItErrorCode(enum.IntEnum):
    """Outcome of ``plan()``: the values of ``moveit_msgs/MoveItErrorCodes`` it can take."""

    SUCCESS = 1
    PLANNING_FAILED = -1
    """No acceptable trajectory (it would last longer than ``MAX_TRAJECTORY_DURATION``)."""
    NO_IK_SOLUTION = -31
    """The pose or position target has no IK solution from the current state."""


class PlanResult(NamedTuple):
    """What ``plan()`` returns: moveit_commander Noetic's 4-tuple.

    Attributes
    ----------
    success : bool
        Whether a trajectory was found.
    trajectory : RobotTrajectory
        The plan; no points (shape ``(0, dof)``) when ``success`` is False.
    planning_time : float
        Always 0.0: planning is simulated (MoveIt reports wall time, which no
        two runs share).
    error_code : MoveItErrorCode
        ``SUCCESS``, ``PLANNING_FAILED`` or ``NO_IK_SOLUTION``.
    """

    success: bool
    trajectory: RobotTrajectory
    planning_time: float
    error_code: MoveItErrorCode


class JointState(NamedTuple):
    """``sensor_msgs/JointState`` restricted to what a simulated arm has.

    Attributes
    ----------
    name : tuple of str, length dof
        Joint variables, in the model's order.
    position : tuple of float, length dof
        Their values (rad, m).
    """

    name: tuple[str, ...]
    position: tuple[float, ...]


class RobotState(NamedTuple):
    """``moveit_msgs/RobotState`` as ``get_current_state()`` returns it.

    Attributes
    ----------
    joint_state : JointState
        The group's variables and their current values.
    """

    joint_state: JointState
