"""Shared vocabulary of the two implementations: records, errors, constants, robots.

This package holds no kinematics. It plays the role ROS message definitions
play between MoveIt's C++ and Python interfaces: both sides speak it.
"""

from robot_api import constants
from robot_api.errors import (
    ErrorCode,
    InvalidInputError,
    OutOfBoundsError,
    PlanningError,
    RobotAPIError,
    UnknownNameError,
    URDFError,
    error_class,
    make_error,
)
from robot_api.records import (
    IKResult,
    IKStatus,
    JointLimit,
    JointState,
    JointType,
    MimicJoint,
    MoveItErrorCode,
    PlanResult,
    Pose,
    RobotState,
    RobotTrajectory,
)

__all__ = [
    "ErrorCode",
    "IKResult",
    "IKStatus",
    "InvalidInputError",
    "JointLimit",
    "JointState",
    "JointType",
    "MimicJoint",
    "MoveItErrorCode",
    "OutOfBoundsError",
    "PlanResult",
    "PlanningError",
    "Pose",
    "RobotAPIError",
    "RobotState",
    "RobotTrajectory",
    "URDFError",
    "UnknownNameError",
    "constants",
    "error_class",
    "make_error",
]
