"""Numbers of the contract that both implementations must use.

Units: radians for revolute/continuous joints, metres for prismatic joints,
seconds for time. The C++ implementation defines the same numbers in
``native/src/constants.hpp``; a parity test checks they are equal.
"""

from __future__ import annotations

GOAL_JOINT_TOLERANCE = 1e-4
"""Default goal joint tolerance (MoveIt's default): a target up to this far
beyond a limit is accepted and clamped onto the limit."""

DEFAULT_VELOCITY_LIMIT = 1.0
"""Velocity limit (rad/s or m/s) used when the URDF gives none or a value <= 0
(MoveIt's time parameterization does the same)."""

ACCELERATION_LIMIT = 1.0
"""Acceleration limit (rad/s^2 or m/s^2) of every joint before scaling; URDF has
no acceleration limits and MoveIt's default is 1.0."""

TRAJECTORY_DT = 0.01
"""Sampling period (s) of planned trajectories."""

MAX_TRAJECTORY_DURATION = 600.0
"""A plan that would last longer (s) fails with PLANNING_FAILED (tiny scaling
factors would otherwise ask for billions of samples)."""

IK_MAX_ITERATIONS = 100
"""Newton-Raphson iterations of the IK solver (KDL's default)."""

IK_EPS = 1e-6
"""IK convergence threshold on every component of the error twist (m, rad)."""

IK_PINV_EPS = 1e-5
"""Singular values of the Jacobian below this are treated as zero (truncated SVD)."""

EXECUTE_START_TOLERANCE = 0.01
"""Largest deviation between a trajectory's first point and the current state
that ``execute`` accepts (MoveIt's ``allowed_start_tolerance``)."""

QUATERNION_NORM_EPS = 1e-9
"""A pose orientation with a norm below this cannot be normalized: rejected."""

CARTESIAN_MAX_POINTS = 1000
"""``compute_cartesian_path`` fails with PLANNING_FAILED, before any IK, when its
interpolation would need more points than this (a tiny ``eef_step``)."""
