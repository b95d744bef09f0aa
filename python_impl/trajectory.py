"""Straight-line joint trajectories with a synchronized trapezoidal profile (twin).

The path is ``start + delta * s(t)`` with ``s`` going from 0 to 1 under the
tightest velocity and acceleration bounds of all moving joints, which makes
the profile time-optimal along the line (docs/api.md, "plan()").
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from python_impl.angles import normalize_angle, normalize_angles
from robot_api.constants import (
    ACCELERATION_LIMIT,
    EXECUTE_START_TOLERANCE,
    MAX_TRAJECTORY_DURATION,
    TRAJECTORY_DT,
)
from robot_api.errors import ErrorCode, InvalidInputError, OutOfBoundsError, PlanningError
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


def _segments(
    limits: tuple[JointLimit, ...], points: list[list[float]], velocity_scaling: float
) -> tuple[list[list[float]], list[tuple[list[float], float]]]:
    """Points without exact repeats, and per segment (delta, cost = max_j |delta_j| / vmax_j)."""
    vmax = [lim.velocity * velocity_scaling for lim in limits]
    kept = [points[0]]
    segments: list[tuple[list[float], float]] = []
    for q in points[1:]:
        prev = kept[-1]
        delta = []
        cost = 0.0
        for lim, v, a, b in zip(limits, vmax, prev, q, strict=True):
            d = b - a
            if lim.type == JointType.CONTINUOUS:
                d = normalize_angle(d)
            delta.append(d)
            if d != 0.0:
                c = abs(d) / v if v > 0.0 else math.inf
                cost = max(cost, c)
        if cost > 0.0:  # an exact repeat of the previous point adds nothing
            kept.append(q)
            segments.append((delta, cost))
    return kept, segments


def time_parameterize(
    limits: tuple[JointLimit, ...],
    points: list[list[float]],
    velocity_scaling: float,
    acceleration_scaling: float,
) -> RobotTrajectory:
    """Time a joint-space polyline with plan()'s trapezoid on its path coordinate (docs/api.md).

    ``points`` (at least one) are within limits. The path coordinate ``u`` grows by
    ``max_j |delta_j| / vmax_j`` over each segment, so ``du/dt <= 1`` keeps every joint
    within its scaled velocity limit; its acceleration bound ``A`` is the tightest
    ``amax * cost / |delta_j|`` over all segments and joints.
    """
    names = tuple(lim.name for lim in limits)
    n = len(limits)
    kept, segments = _segments(limits, points, velocity_scaling)
    if not segments:
        zero = np.zeros((1, n))
        return RobotTrajectory(names, np.zeros(1), np.array([kept[0]], dtype=np.float64), zero, zero.copy())
    amax = ACCELERATION_LIMIT * acceleration_scaling
    total_u = 0.0
    accel = math.inf
    for delta, cost in segments:
        total_u += cost
        for d in delta:
            if d != 0.0:
                accel = min(accel, amax * cost / abs(d))
    if not (accel > 0.0 and total_u < math.inf):
        raise PlanningError(f"the path would never end (length {total_u!r}, acceleration bound {accel!r})")
    if accel * total_u > 1.0:  # reaches the cruise speed du/dt = 1
        ta = 1.0 / accel
        total = total_u + ta
        peak = 1.0
    else:  # triangular
        ta = math.sqrt(total_u / accel)
        total = 2.0 * ta
        peak = accel * ta
    if not total <= MAX_TRAJECTORY_DURATION:
        raise PlanningError(f"the path would last {total!r} s, more than {MAX_TRAJECTORY_DURATION!r} s")
    ua = 0.5 * accel * ta * ta
    times = [0.0]
    rows = [kept[0]]
    still = [0.0] * n
    first = segments[0]
    velocities = [still]
    accelerations = [[d * (accel / first[1]) for d in first[0]]]
    u = 0.0
    last = len(segments) - 1
    for k, (delta, cost) in enumerate(segments):
        u += cost  # the same sums as total_u: the last point has u == total_u exactly
        if u < ua:
            t = math.sqrt(2.0 * u / accel)
            ud, udd = accel * t, accel
        elif u <= total_u - ua:
            t = ta + (u - ua) / peak
            ud, udd = peak, 0.0
        else:
            r = math.sqrt(2.0 * (total_u - u) / accel)
            t = total - r
            ud, udd = accel * r, -accel
        if k == last:
            if not t > times[-1]:  # the end takes the place (and time) of the point before
                t = times.pop()
                rows.pop()
                velocities.pop()
                accelerations.pop()
            times.append(t)
            rows.append(kept[k + 1])
            velocities.append(still)
            accelerations.append(still)
        elif t > times[-1]:
            times.append(t)
            rows.append(kept[k + 1])
            velocities.append([d * (ud / cost) for d in delta])
            accelerations.append([d * (udd / cost) for d in delta])
    return RobotTrajectory(
        names,
        np.array(times, dtype=np.float64),
        np.array(rows, dtype=np.float64).reshape(len(rows), n),
        np.array(velocities, dtype=np.float64).reshape(len(rows), n),
        np.array(accelerations, dtype=np.float64).reshape(len(rows), n),
    )


def check_execution(
    limits: tuple[JointLimit, ...],
    joint_names: Sequence[str],
    current: Sequence[float],
    tolerance: float,
    names: Sequence[str],
    times: Sequence[float] | NDArray[np.float64],
    positions: NDArray[np.float64],
) -> None:
    """What ``MoveGroup.execute`` and ``go`` check before they move (docs/api.md, ``execute``).

    Parameters
    ----------
    limits : tuple of JointLimit, shape (dof,)
    joint_names : sequence of str, shape (dof,)
        The group's joints, in order.
    current : sequence of float, shape (dof,)
        The current state (rad, m).
    tolerance : float
        The goal joint tolerance (rad, m): how far past a limit a point may be.
    names : sequence of str
        The trajectory's joints.
    times : sequence of float, shape (M,)
        Time from start of each point (s).
    positions : ndarray, shape (M, dof)

    Raises
    ------
    InvalidInputError
        ``INVALID_TRAJECTORY``: other joints, no points, times not finite, negative or not
        increasing, a non-finite position, a start farther than ``EXECUTE_START_TOLERANCE``.
    OutOfBoundsError
        A point beyond a limit by more than ``tolerance``.
    """

    def invalid(message: str) -> InvalidInputError:
        return InvalidInputError(message, ErrorCode.INVALID_TRAJECTORY)

    if len(names) != len(joint_names):
        raise invalid("trajectory joints do not match the group's joints")
    for j, (theirs, ours) in enumerate(zip(names, joint_names, strict=True)):
        if theirs != ours:
            raise invalid(f"trajectory joint #{j} is '{theirs}', the group's is '{ours}'")
    if not len(times):
        raise invalid("trajectory has no points")
    stamps = np.asarray(times, dtype=np.float64)
    # one vector test, not a Python loop over the points: finite, the first >= 0, each
    # after the one before (NaN fails every comparison, so it fails here too)
    if not (np.isfinite(stamps).all() and stamps[0] >= 0.0 and (np.diff(stamps) > 0.0).all()):
        raise invalid("trajectory times must be finite, >= 0 and strictly increasing")
    if not np.isfinite(positions).all():
        raise invalid("trajectory has a non-finite position")
    first = positions[0].tolist()
    for j, lim in enumerate(limits):
        dev = first[j] - current[j]
        if lim.type == JointType.CONTINUOUS:
            dev = normalize_angle(dev)
        if abs(dev) > EXECUTE_START_TOLERANCE:
            raise invalid(f"trajectory starts {abs(dev)!r} away from the current value of joint '{lim.name}'")
    bounded = [j for j, lim in enumerate(limits) if lim.type != JointType.CONTINUOUS]
    if bounded:
        lower = np.array([limits[j].lower for j in bounded]) - tolerance
        upper = np.array([limits[j].upper for j in bounded]) + tolerance
        p = positions[:, bounded]
        bad = (p < lower) | (p > upper)
        if bad.any():
            i, k = (int(x) for x in np.argwhere(bad)[0])
            lim = limits[bounded[k]]
            raise OutOfBoundsError(
                f"trajectory point {i} puts joint '{lim.name}' at {p[i, k]!r}, outside "
                f"[{lim.lower!r}, {lim.upper!r}]"
            )
