"""Whether a target's trajectory is timed as the contract times its own positions.

``fuzzer.scenario.oracle_ik`` calls a divergence of what the contract computes from a
trajectory's positions (point count, ``time_from_start``, velocities, accelerations) a known
limitation when the two targets' IK answers or start states differ as numbers within the
tolerance: the timing's sensitivity to its inputs is unbounded as segments shrink, so no
tolerance on the difference of the two timings can hold. That rule alone would also explain
away a target that times its path wrongly, e.g. at full speed whatever the scaling factors
(MoveIt's ``compute_cartesian_path`` did: moveit/moveit#1065), since two IK implementations
almost never agree to 1e-12.

So the rule asks one more thing: on each target, the trajectory's duration is the duration
the contract gives that target's own positions with that target's scaling factors in effect
(docs/api.md, "plan()" and "compute_cartesian_path()"). The reference is the twin's timing
functions (``python_impl.trajectory``), run on each target's reported points; a fault in them
would make the correct target's timing fail this check, so it can only keep a divergence, never
explain one away. The duration is compared, not every time: it is a sum and a square root of
sums (well conditioned), while times in the deceleration phase take a square root of a
difference that cancels (an absolute rounding of about 1e-8 s).

``fuzzer.scenario.oracle_properties.violation_at`` asks the same of each target (``timing_gap``),
and of a plan its positions and velocities (``profile_gap``), as a property at a step where the
two targets diverge and the oracle does not count it: a fault in the reference would be reported
there against a correct target, but only where the targets already diverge.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from fuzzer.execution.records import Outcome, as_array
from fuzzer.execution.tolerance import Tolerance
from fuzzer.scenario.oracle_facts import Context, ScenarioFacts
from robot_api.constants import ACCELERATION_LIMIT, TRAJECTORY_DT
from robot_api.errors import RobotAPIError
from robot_api.records import JointLimit, JointType

RETIME_TOLERANCE = 1e-9
"""Relative tolerance of a duration against the reference's (plus ``RETIME_ABSOLUTE`` s)."""
RETIME_ABSOLUTE = 1e-12
"""Absolute slack (s) of the duration check."""


def limits_of(facts: ScenarioFacts) -> tuple[JointLimit, ...]:
    """The facts' joints as the contract's ``JointLimit`` records (planning velocities)."""
    return tuple(
        JointLimit(f"joint_{j}", JointType(spec.type), spec.lower, spec.upper, spec.velocity)
        for j, spec in enumerate(facts.joints)
    )


def reference_duration(kind: str, rows: np.ndarray, before: Context, facts: ScenarioFacts) -> float | None:
    """The duration (s) the contract gives a ``plan`` from ``rows[0]`` to ``rows[-1]`` or a
    ``cartesian_path`` through ``rows`` (M, dof), with ``before``'s scaling factors; None when
    the contract would refuse them (a planning error, a bad value).

    Remembered for the last ``DURATIONS`` questions, keyed by the bits of the points and the
    factors: mutants of one script share its steps, so one campaign asks the same again and again
    (the thirty-seventh session counted 326 questions of 48 kinds over 1,157 corpus inputs). A
    plan's key holds its two ends only, all its duration depends on: a plan may have 60,001
    points, 2.9 MB of bits on six joints, and 512 of those would stay in the cache."""
    if kind == "plan" and len(rows) > 2:
        rows = rows[[0, -1]]
    rows = np.ascontiguousarray(rows, dtype=np.float64)
    scaling = np.array([before.velocity_scaling, before.acceleration_scaling], dtype=np.float64)
    limits = limits_of(facts)  # its repr tells -0.0 from 0.0, which == does not
    return _duration(kind, limits, repr(limits), rows.shape[1], rows.tobytes(), scaling.tobytes())


DURATIONS = 512
"""How many of ``reference_duration``'s answers are remembered."""


@functools.lru_cache(maxsize=DURATIONS)
def _duration(
    kind: str, limits: tuple[JointLimit, ...], exact: str, dof: int, points: bytes, factors: bytes
) -> float | None:
    """``reference_duration`` of the points and factors as bits (float64); ``exact`` is
    ``repr(limits)``, for the cache's key only."""
    from python_impl.trajectory import plan_trajectory, time_parameterize

    rows = np.frombuffer(points, dtype=np.float64).reshape(-1, dof)
    scaling = tuple(float(f) for f in np.frombuffer(factors, dtype=np.float64))
    try:
        if kind == "plan":
            timed = plan_trajectory(limits, rows[0].tolist(), rows[-1].tolist(), *scaling)
        else:
            timed = time_parameterize(limits, rows.tolist(), *scaling)
    except (RobotAPIError, ArithmeticError, ValueError):
        return None
    return float(timed.time_from_start[-1])


def plan_points(duration: float) -> int:
    """How many points the contract's plan of ``duration`` s has: one every ``TRAJECTORY_DT``
    strictly before the end, then the end (``python_impl.trajectory.plan_trajectory``)."""
    if not (duration > 0.0 and math.isfinite(duration)):
        return 1
    steps = np.arange(math.ceil(duration / TRAJECTORY_DT), dtype=np.float64) * TRAJECTORY_DT
    return int(np.count_nonzero(steps < duration)) + 1


def timed_as_contract(kind: str, outcome: Outcome, before: Context, facts: ScenarioFacts) -> bool:
    """Whether ``outcome`` (one target's ``plan`` or ``cartesian_path`` step) lasts what the
    contract's timing of its own positions gives (``timing_gap`` is None)."""
    return kind in ("plan", "cartesian_path") and timing_gap(kind, outcome, before, facts) is None


def timing_gap(
    kind: str, outcome: Outcome, before: Context, facts: ScenarioFacts
) -> tuple[float, str] | None:
    """How far one target's ``plan`` or ``cartesian_path`` is from lasting what the contract's
    timing of its own positions gives, as ``(difference, unit)``, or None when it does: its
    duration within ``RETIME_TOLERANCE`` (relative) of the reference's (else the gap in s; inf
    when its points are not finite or the contract would refuse them) and, for a plan, as many
    points as a plan of a duration within that tolerance has (else the gap in points: a sample
    more or fewer at the same duration, e.g. the start repeated at t = 0, is not the contract's
    timing; a duration near a multiple of ``TRAJECTORY_DT`` allows either count)."""
    dof = len(facts.joints)
    times = as_array(outcome.values.get("trajectory.time_from_start", ()))
    flat = as_array(outcome.values.get("trajectory.positions", ()))
    if not dof or times.size == 0 or flat.size != times.size * dof or not np.isfinite(flat).all():
        return math.inf, "s"
    expected = reference_duration(kind, flat.reshape(-1, dof), before, facts)
    actual = float(times[-1])
    if expected is None or not math.isfinite(actual):
        return math.inf, "s"
    slack = RETIME_TOLERANCE * max(abs(actual), abs(expected)) + RETIME_ABSOLUTE
    if abs(actual - expected) > slack:
        return abs(actual - expected), "s"
    if kind != "plan":
        return None
    fewest, most = plan_points(expected - slack), plan_points(expected + slack)
    if fewest <= times.size <= most:
        return None
    return float(fewest - times.size if times.size < fewest else times.size - most), "points"


def profile_gap(
    outcome: Outcome, before: Context, facts: ScenarioFacts, tol: Tolerance
) -> tuple[float, list[int]]:
    """How far one target's ``plan`` (timed as the contract: ``timing_gap`` is None) is from the
    contract's plan between its own first and last points: the largest difference of its
    positions and velocities from the reference's (``python_impl.trajectory.plan_trajectory``),
    sample by sample, beyond the campaign tolerance (``tol``; metres for a prismatic joint), and
    the joints beyond it; ``(0.0, [])`` when none is, every joint when the contract would refuse
    its ends (``timing_gap`` reports that first). With a sample more or fewer near a multiple
    of ``TRAJECTORY_DT`` the samples both have are compared, then the ends. Continuous joints
    compare modulo 2pi; one whose plan ends a half turn from its start within the tolerance is
    not compared (the short way round is either way)."""
    from python_impl.angles import normalize_angles
    from python_impl.trajectory import plan_trajectory

    dof = len(facts.joints)
    rows = as_array(outcome.values.get("trajectory.positions", ())).reshape(-1, dof)
    speeds = as_array(outcome.values.get("trajectory.velocities", ())).reshape(-1, dof)
    try:
        ref = plan_trajectory(
            limits_of(facts),
            rows[0].tolist(),
            rows[-1].tolist(),
            before.velocity_scaling,
            before.acceleration_scaling,
        )
    except (RobotAPIError, ArithmeticError, ValueError):  # the contract would refuse its ends
        return math.inf, list(range(dof))
    keep = np.r_[0 : min(len(rows), len(ref.positions)) - 1, -1]
    continuous = np.array(facts.continuous, dtype=bool)
    apart = rows[keep] - np.asarray(ref.positions)[keep]
    gap = np.abs(np.where(continuous, normalize_angles(apart), apart))
    with np.errstate(invalid="ignore"):  # inf - inf
        speed_gap = np.abs(speeds[keep] - np.asarray(ref.velocities)[keep])
    speed_gap[np.isnan(speed_gap)] = math.inf  # a velocity that is not a number: beyond any limit
    gap = np.maximum(gap, speed_gap)
    turn = np.abs(normalize_angles(rows[-1] - rows[0]))
    gap[:, continuous & (math.pi - turn <= tol.radians)] = 0.0
    limit = np.where(np.array(facts.prismatic, dtype=bool), tol.metres, tol.radians)
    beyond = (gap > limit).any(axis=0)
    return (float(gap.max()) if beyond.any() else 0.0), np.flatnonzero(beyond).tolist()


PHASE_EDGE = 1e-9
"""A point whose path coordinate is this close (relative to the path's length) to a switch of
the time law's phase is on it."""


Coordinate = tuple[np.ndarray, np.ndarray, np.ndarray, float, float]
"""``_coordinate``'s result: deltas, costs, ``u``, ``A``, ``ua``."""


def _coordinate(rows: np.ndarray, before: Context, facts: ScenarioFacts) -> Coordinate:
    """Of a ``cartesian_path``'s points (M, dof): the segments' deltas (M - 1, dof; continuous
    joints the short way) and costs ``max_j |delta_j| / vmax_j`` (M - 1,), the path coordinate
    ``u`` (M,; their running sum, docs/api.md), the acceleration bound ``A`` on ``u``, and where
    the acceleration ends (``ua``; the deceleration starts at ``u[-1] - ua``)."""
    from python_impl.angles import normalize_angles

    vmax = np.array([spec.velocity for spec in facts.joints]) * before.velocity_scaling
    continuous = np.array([spec.continuous for spec in facts.joints], dtype=bool)
    delta = np.diff(rows, axis=0)
    delta = np.where(continuous, normalize_angles(delta), delta)
    moving = delta != 0.0
    cost = np.where(moving, np.abs(delta) / vmax, 0.0).max(axis=1)
    u = np.concatenate([[0.0], np.cumsum(cost)])
    ratio = np.where(moving, cost[:, None] / np.where(moving, np.abs(delta), 1.0), np.inf)
    accel = float(ACCELERATION_LIMIT * before.acceleration_scaling * ratio.min(initial=np.inf))
    total = float(u[-1])
    ua = 0.5 / accel if accel * total > 1.0 else 0.5 * total
    return delta, cost, u, accel, ua


def phase_knife_edge(
    a: Outcome, b: Outcome, before: tuple[Context, Context], facts: ScenarioFacts, limit: float
) -> bool:
    """Whether every point of a ``cartesian_path`` whose accelerations differ beyond ``limit``
    lies, on each target, on a switch of its time law (its path coordinate within
    ``PHASE_EDGE`` of where the acceleration ends or the deceleration starts) and reports there
    one of the three values the contract allows (accelerating, cruising, decelerating:
    ``A * delta / cost`` with ``A`` its sign or 0). A triangular profile switches at half the
    path, which a path of equal segments puts a point on: ``u < ua`` then falls on the last
    bits of two sums."""
    dof = len(facts.joints)
    key = "trajectory.accelerations"
    flat = [as_array(o.values.get(key, ())) for o in (a, b)]
    rows = [as_array(o.values.get("trajectory.positions", ())) for o in (a, b)]
    if (
        not dof
        or flat[0].size != flat[1].size
        or any(r.size != f.size or r.size < 3 * dof for r, f in zip(rows, flat, strict=True))
    ):
        return False
    acc = [f.reshape(-1, dof) for f in flat]
    differ = np.flatnonzero(~(np.abs(acc[0] - acc[1]) <= limit).all(axis=1))
    for acc_i, flat_rows, ctx in zip(acc, rows, before, strict=True):
        points = flat_rows.reshape(-1, dof)
        if not np.isfinite(points).all():
            return False
        with np.errstate(all="ignore"):  # a subnormal scaling factor: inf, which fails below
            delta, costs, u, accel, ua = _coordinate(points, ctx, facts)
        total = float(u[-1])
        if not (math.isfinite(total) and math.isfinite(accel) and accel > 0.0):
            return False
        for r in differ.tolist():
            if not 0 < r < len(u) - 1:
                return False
            if min(abs(u[r] - ua), abs(u[r] - (total - ua))) > PHASE_EDGE * total:
                return False
            cost = float(costs[r - 1])
            allowed = [s * accel * delta[r - 1] / cost for s in (1.0, 0.0, -1.0)] if cost > 0.0 else []
            if not any(np.all(np.abs(acc_i[r] - x) <= limit) for x in allowed):
                return False
    return differ.size > 0
