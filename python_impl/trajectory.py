"""Straight-line joint trajectories with a synchronized trapezoidal profile (twin).

The path is ``start + delta * s(t)`` with ``s`` going from 0 to 1 under the
tightest velocity and acceleration bounds of all moving joints, which makes
the profile time-optimal along the line (docs/api.md, "plan()").
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from python_impl.angles import normalize_angle, normalize_angles
from robot_api.constants import ACCELERATION_LIMIT, MAX_TRAJECTORY_DURATION, TRAJECTORY_DT
from robot_api.errors import PlanningError
from robot_api.records import JointLimit, JointType, RobotTrajectory

Array = NDArray[np.float64]


def plan_trajectory(
    limits: tuple[JointLimit, ...],
    start: list[float],
    goal: list[float],
    velocity_scaling: float,
    acceleration_scaling: float,
) -> RobotTrajectory:
    """Trajectory from ``start`` to ``goal`` (both within limits), sampled every TRAJECTORY_DT."""
    n = len(limits)
    names = tuple(lim.name for lim in limits)
    continuous = np.array([lim.type == JointType.CONTINUOUS for lim in limits], dtype=bool)
    delta = []
    vs = math.inf
    accel = math.inf
    moving = False  # not vs == inf: a subnormal distance makes vmax / d overflow to inf legitimately
    for lim, a, b in zip(limits, start, goal, strict=True):
        d = b - a
        if lim.type == JointType.CONTINUOUS:
            d = normalize_angle(d)
        delta.append(d)
        if abs(d) > 0.0:
            moving = True
            vs = min(vs, lim.velocity * velocity_scaling / abs(d))
            accel = min(accel, ACCELERATION_LIMIT * acceleration_scaling / abs(d))
    goal_row = np.array(goal, dtype=np.float64).reshape(1, n)
    if not moving:
        zero = np.zeros((1, n))
        return RobotTrajectory(names, np.zeros(1), goal_row, zero, zero.copy())

    if vs == 0.0 or accel == 0.0:
        # a scaling factor so small that the bound underflows (e.g. 5e-324 / 2.0 == 0.0):
        # the move would take forever. C++ gets there through 1/0 = inf; Python would raise.
        raise PlanningError(f"the move would never end (velocity bound {vs!r}, acceleration bound {accel!r})")
    if vs * vs < accel:  # reaches cruise speed
        ta = vs / accel
        total = 1.0 / vs + ta
        peak = vs
    else:  # triangular
        ta = math.sqrt(1.0 / accel)
        total = 2.0 * ta
        peak = accel * ta

    if not total <= MAX_TRAJECTORY_DURATION:
        raise PlanningError(f"the move would last {total!r} s, more than {MAX_TRAJECTORY_DURATION!r} s")
    k = math.ceil(total / TRAJECTORY_DT)
    t = np.arange(k, dtype=np.float64) * TRAJECTORY_DT
    t = t[t < total]
    rest = total - t
    accelerating = t < ta
    cruising = ~accelerating & (t < total - ta)
    s = np.where(
        accelerating,
        0.5 * accel * t * t,
        np.where(cruising, 0.5 * accel * ta * ta + peak * (t - ta), 1.0 - 0.5 * accel * rest * rest),
    )
    sd = np.where(accelerating, accel * t, np.where(cruising, peak, accel * rest))
    sdd = np.where(accelerating, accel, np.where(cruising, 0.0, -accel))

    deltas = np.array(delta, dtype=np.float64)
    start_row = np.array(start, dtype=np.float64)
    positions = start_row + deltas * s[:, None]
    lower = np.array([lim.lower for lim in limits])
    upper = np.array([lim.upper for lim in limits])
    positions = np.where(
        continuous, normalize_angles(positions), np.minimum(np.maximum(positions, lower), upper)
    )
    zero = np.zeros((1, n))
    return RobotTrajectory(
        names,
        np.append(t, total),
        np.vstack([positions, goal_row]),
        np.vstack([deltas * sd[:, None], zero]),
        np.vstack([deltas * sdd[:, None], zero]),
    )
