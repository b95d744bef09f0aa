"""Cartesian paths of the twin: moveit_commander's ``compute_cartesian_path`` (numpy only).

The path runs from the end effector's current pose through each waypoint in
straight lines: positions interpolated linearly, orientations by slerp (the
formula of Eigen's ``Quaternion::slerp``), one IK per interpolated pose seeded by
the previous solution, then MoveIt's relative joint-space jump test
(docs/api.md, "compute_cartesian_path").
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

from python_impl import convert
from python_impl.angles import normalize_angle
from robot_api.constants import CARTESIAN_MAX_POINTS
from robot_api.errors import PlanningError
from robot_api.records import IKStatus, JointLimit, JointType, Pose

_SLERP_ONE = 1.0 - 2.220446049250313e-16  # Eigen: 1 - NumTraits<double>::epsilon()

Waypoint = tuple[list[float], list[float]]  # position (3,), unit quaternion (x, y, z, w)
Solver = Callable[[Pose, list[float]], tuple[IKStatus, list[float]]]


def check_arguments(
    waypoints: Any, eef_step: Any, jump_threshold: Any
) -> tuple[list[Waypoint], float, float]:
    """The checks of ``compute_cartesian_path``, in signature order (INVALID_ARGUMENT unless noted).

    ``waypoints`` is a non-empty list or tuple of poses (the pose rule, NON_FINITE included),
    ``eef_step`` a finite real > 0, ``jump_threshold`` a finite real >= 0.
    """
    if not isinstance(waypoints, list | tuple):
        raise convert.bad("waypoints", f"expected a list or tuple of poses, got {type(waypoints).__name__}")
    if not waypoints:
        raise convert.bad("waypoints", "no waypoints")
    poses = [convert.to_pose(w) for w in waypoints]
    step = convert.to_real(eef_step, "eef_step")
    if not (math.isfinite(step) and step > 0.0):
        raise convert.bad("eef_step", f"must be finite and > 0, got {step!r}")
    jump = convert.to_real(jump_threshold, "jump_threshold")
    if not (math.isfinite(jump) and jump >= 0.0):
        raise convert.bad("jump_threshold", f"must be finite and >= 0, got {jump!r}")
    return poses, step, jump


def slerp(a: list[float], b: list[float], t: float) -> list[float]:
    """Eigen's ``a.slerp(t, b)`` on (x, y, z, w) quaternions (not renormalized)."""
    d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
    abs_d = abs(d)
    if abs_d >= _SLERP_ONE:
        scale0 = 1.0 - t
        scale1 = t
    else:
        theta = math.acos(abs_d)
        sin_theta = math.sin(theta)
        scale0 = math.sin((1.0 - t) * theta) / sin_theta
        scale1 = math.sin(t * theta) / sin_theta
    if d < 0.0:
        scale1 = -scale1
    return [scale0 * x + scale1 * y for x, y in zip(a, b, strict=True)]


def step_counts(start: list[float], waypoints: Sequence[Waypoint], eef_step: float) -> list[int]:
    """Interpolation steps per segment: ``floor(distance / eef_step) + 1``.

    Raises PlanningError when the path would have more than CARTESIAN_MAX_POINTS points.
    """
    counts = []
    total = 1  # the start point
    prev = start
    for position, _ in waypoints:
        dx, dy, dz = position[0] - prev[0], position[1] - prev[1], position[2] - prev[2]
        ratio = math.sqrt(dx * dx + dy * dy + dz * dz) / eef_step
        if not ratio < CARTESIAN_MAX_POINTS:
            raise PlanningError(f"the path needs more than {CARTESIAN_MAX_POINTS} points at this eef_step")
        steps = math.floor(ratio) + 1
        total += steps
        if total > CARTESIAN_MAX_POINTS:
            raise PlanningError(f"the path needs more than {CARTESIAN_MAX_POINTS} points at this eef_step")
        counts.append(steps)
        prev = position
    return counts


def distance(limits: tuple[JointLimit, ...], a: list[float], b: list[float]) -> float:
    """MoveIt's ``RobotState::distance``: sum of per-joint distances (short way for continuous)."""
    total = 0.0
    for lim, x, y in zip(limits, a, b, strict=True):
        d = x - y
        total += abs(normalize_angle(d)) if lim.type == JointType.CONTINUOUS else abs(d)
    return total


def jump_test(limits: tuple[JointLimit, ...], points: list[list[float]], factor: float) -> float:
    """MoveIt's relative jump test; truncates ``points`` in place and returns the kept share."""
    if len(points) < 2:
        return 1.0
    steps = [distance(limits, points[i], points[i - 1]) for i in range(1, len(points))]
    total = 0.0
    for d in steps:
        total += d
    threshold = factor * (total / len(steps))
    for i, d in enumerate(steps):
        if d > threshold:
            share = (i + 1) / len(points)
            del points[i + 1 :]
            return share
    return 1.0


def cartesian_points(
    start_pose: Pose,
    start_values: list[float],
    waypoints: Sequence[Waypoint],
    eef_step: float,
    solve: Solver,
) -> tuple[list[list[float]], float]:
    """Joint points of the path (start first) and the fraction before the jump test."""
    start_position = list(start_pose.position)
    counts = step_counts(start_position, waypoints, eef_step)
    points = [list(start_values)]
    q = list(start_values)
    fraction = 0.0
    prev_p, prev_q = start_position, list(start_pose.orientation)
    for i, ((position, orientation), steps) in enumerate(zip(waypoints, counts, strict=True)):
        reached = 0
        for k in range(1, steps + 1):
            t = k / steps
            p = [t * b + (1.0 - t) * a for a, b in zip(prev_p, position, strict=True)]
            status, values = solve(Pose((p[0], p[1], p[2]), tuple(slerp(prev_q, orientation, t))), q)  # type: ignore[arg-type]
            if status != IKStatus.SUCCESS:
                break
            q = values
            points.append(q)
            reached = k
        if reached == steps:
            fraction = (i + 1) / len(waypoints)
        else:
            fraction += (reached / steps) / len(waypoints)
            break
        prev_p, prev_q = position, orientation
    return points, fraction
