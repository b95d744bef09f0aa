"""Property checks of a scenario on each target alone (``Kind.PROPERTY``, the target named).

With what is in effect before the step (``fuzzer.scenario.oracle_facts``), on every step
that completed (status ok):

=======================  ==========================================================  ============
field                    property                                                    unit
=======================  ==========================================================  ============
<kind>.trajectory.shape  /plan, /cartesian_path: positions, velocities and           points
                         accelerations hold (M, dof) values for the M times
<kind>.joint_limits      every sample within [lower - tol, upper + tol] (tol: the    rad (m)
                         goal tolerance); continuous joints in (-pi, pi]
<kind>.velocity_limits   abs(velocity) <= velocity limit x velocity scaling          rad/s (m/s)
<kind>.acceleration_     abs(acceleration) <= ACCELERATION_LIMIT x acceleration      rad/s^2
limits                   scaling                                                     (m/s^2)
<kind>.time_from_start   starts at 0 exactly, strictly increasing                    s
<kind>.start             /plan, /cartesian_path: the first point is the state the    rad (m)
                         step began in (MoveIt plans from the current state)
plan.goal                /plan with a joint goal: the last point is the goal         rad (m)
go.goal                  /go with a joint goal: the state after it is the goal       rad (m)
go.pose_goal,            /go, /plan with a pose or position goal: the link at the     m or rad
plan.pose_goal           goal's position (and orientation) in the state after it (the
                         plan's last point), within ``REACH_SLACK`` plus what the goal
                         tolerance moves it by
execute.last_point       /execute of a plan: the state after it is its last point    rad (m)
=======================  ==========================================================  ============

At a ``/plan`` or ``/cartesian_path`` step where the two targets diverge and the oracle does not
count it, each target's trajectory is also checked against the contract's making of its own
answer (``violation_at``, ``check_own_timing``): ``<kind>.timing`` (s or points) and
``plan.profile`` (rad or m).

Velocity and acceleration bounds get a relative slack of ``RELATIVE_SLACK`` plus
``ABSOLUTE_SLACK``; the start, goal and last-point checks allow the goal tolerance (``execute``
clamps a last point up to that far past a limit) plus the same slack; continuous joints
compare modulo 2pi. The reported ``difference`` is how far past the bound the worst sample is.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from fuzzer.execution import oracle
from fuzzer.execution.records import Comparison, Kind, Outcome, Status, as_array
from fuzzer.execution.tolerance import Tolerance
from fuzzer.scenario.oracle_facts import Context, ScenarioFacts, contexts
from fuzzer.scenario.oracle_timing import profile_gap, timing_gap
from fuzzer.scenario.steps import ScenarioCall
from robot_api.constants import ACCELERATION_LIMIT, IK_EPS

RELATIVE_SLACK = 1e-9
ABSOLUTE_SLACK = 1e-12


def _violation(
    target: str, field_name: str, excess: float, unit: str, joints: Sequence[int] = ()
) -> Comparison:
    excess = excess if math.isfinite(excess) else math.inf
    return Comparison(
        Kind.PROPERTY,
        field_name,
        excess,
        False,
        oracle.bucket(excess),
        tuple(sorted({int(j) for j in joints})),
        unit=unit,
        raw=excess,
        target=target,
    )


def _unit(base: str, facts: ScenarioFacts, joints: Sequence[int]) -> str:
    linear = bool(len(joints)) and all(facts.joints[j].prismatic for j in joints)
    return base.replace("rad", "m") if linear else base


def _excess(values: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """How far each ``|value|`` is past ``bound`` with the slack (NaN counts as infinitely)."""
    over = np.abs(values) - (bound * (1.0 + RELATIVE_SLACK) + ABSOLUTE_SLACK)
    return np.where(np.isnan(over), math.inf, over)


def _worst(
    target: str, field_name: str, excess: np.ndarray, base_unit: str, facts: ScenarioFacts
) -> Comparison | None:
    bad = excess > 0.0
    if not bad.any():
        return None
    joints = np.flatnonzero(bad.any(axis=0)).tolist()
    return _violation(target, field_name, float(excess.max()), _unit(base_unit, facts, joints), joints)


def _outside_limits(positions: np.ndarray, facts: ScenarioFacts, tol: float) -> np.ndarray:
    """Per sample and joint, how far past its limits (plus ``tol``); continuous: (-pi, pi]."""
    excess = np.zeros_like(positions)
    for j, spec in enumerate(facts.joints):
        x = positions[:, j]
        if spec.continuous:
            inside = (x > -math.pi) & (x <= math.pi)
            excess[:, j] = np.where(inside, 0.0, np.maximum(np.abs(x) - math.pi, math.ulp(math.pi)))
        else:
            excess[:, j] = np.maximum(np.maximum(spec.lower - tol - x, x - spec.upper - tol), 0.0)
    return np.where(np.isnan(positions), math.inf, excess)


def check_trajectory(
    kind: str, outcome: Outcome, before: Context, facts: ScenarioFacts, target: str
) -> Comparison | None:
    """The properties of the trajectory a ``/plan`` or ``/cartesian_path`` step returned."""
    dof = len(facts.joints)
    times = as_array(outcome.values.get("trajectory.time_from_start", ()))
    m = len(times)
    arrays = []
    for name in ("positions", "velocities", "accelerations"):
        flat = as_array(outcome.values.get(f"trajectory.{name}", ()))
        if flat.size != m * dof:
            return _violation(target, f"{kind}.trajectory.shape", abs(flat.size - m * dof), "points")
        arrays.append(flat.reshape(m, dof))
    if m == 0 or dof == 0:
        return None
    positions, velocities, accelerations = arrays
    limits = _worst(
        target, f"{kind}.joint_limits", _outside_limits(positions, facts, before.goal_tolerance), "rad", facts
    )
    if limits is not None:
        return limits
    vmax = np.array([spec.velocity for spec in facts.joints]) * before.velocity_scaling
    found = _worst(target, f"{kind}.velocity_limits", _excess(velocities, vmax), "rad/s", facts)
    if found is not None:
        return found
    amax = np.full(dof, ACCELERATION_LIMIT * before.acceleration_scaling)
    found = _worst(target, f"{kind}.acceleration_limits", _excess(accelerations, amax), "rad/s^2", facts)
    if found is not None:
        return found
    if times[0] != 0.0 or not math.isfinite(times[0]):
        return _violation(target, f"{kind}.time_from_start", abs(float(times[0])), "s")
    steps = np.diff(times)
    if m > 1 and not bool(np.all(steps > 0.0)):
        back = float(np.max(-steps)) if not np.isnan(steps).any() else math.inf
        return _violation(target, f"{kind}.time_from_start", back, "s")
    if before.state is not None:  # MoveIt plans from the current state
        start = _equal(target, f"{kind}.start", tuple(positions[0].tolist()), before.state, before, facts)
        if start is not None:
            return start
    if kind == "plan" and before.pose_goal is not None:
        return _reaches_pose(target, "plan.pose_goal", tuple(positions[-1].tolist()), before, facts)
    if kind == "plan" and before.joint_goal is not None:
        return _equal(target, "plan.goal", tuple(positions[-1].tolist()), before.joint_goal, before, facts)
    return None


def _equal(
    target: str,
    field_name: str,
    actual: Sequence[float],
    expected: Sequence[float],
    before: Context,
    facts: ScenarioFacts,
) -> Comparison | None:
    """``actual`` within the goal tolerance (plus slack) of ``expected``; continuous modulo 2pi."""
    if len(actual) != len(expected) or len(actual) != len(facts.joints):
        return _violation(target, field_name, math.inf, "rad", range(len(facts.joints)))
    excess = np.zeros((1, len(actual)))
    bound = before.goal_tolerance * (1.0 + RELATIVE_SLACK) + ABSOLUTE_SLACK
    for j, (x, y, spec) in enumerate(zip(actual, expected, facts.joints, strict=True)):
        gap = abs(x - y)
        if spec.continuous and math.isfinite(gap):
            gap = abs(math.remainder(x - y, 2.0 * math.pi))
        excess[0, j] = gap - bound if math.isfinite(gap) else math.inf
    return _worst(target, field_name, excess, "rad", facts)


REACH_SLACK = 2.0 * math.sqrt(3.0) * IK_EPS
"""How far (m, rad) a link may be from a pose goal its target reports reached, before the goal
tolerance's share: IK stops once every component of the error twist is within ``IK_EPS``
(``sqrt(3) IK_EPS`` in all), doubled for the FK of the reference target against the target's own."""

LEVER_STEP = 1e-6
"""The joint step (rad, m) of the finite differences in ``_lever``."""


def _turn(q: Sequence[float], r: Sequence[float]) -> float | None:
    """The angle (rad) between two orientations (x, y, z, w), or None if either is no rotation."""
    a, b = np.asarray(q, dtype=float), np.asarray(r, dtype=float)
    na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
    if not (math.isfinite(na) and math.isfinite(nb)) or na == 0.0 or nb == 0.0:
        return None
    a, b = a / na, b / nb
    w = abs(float(np.dot(a, b)))  # cos of half the angle between them (q and -q are one rotation)
    return 2.0 * math.atan2(math.sqrt(max(0.0, 1.0 - min(w, 1.0) ** 2)), w)


def _lever(facts: ScenarioFacts, state: Sequence[float], link: str | None) -> tuple[float, float]:
    """How far the link moves (m, rad) when every joint moves by 1 (first order, summed over
    the joints): what a stop within the goal tolerance of the IK answer moves it by, per unit of
    that tolerance. Finite differences of the reference target's FK."""
    assert facts.forward is not None
    base_p, base_q = facts.forward(state, link)
    metres = radians = 0.0
    for j in range(len(state)):
        moved = list(state)
        moved[j] += LEVER_STEP
        p, q = facts.forward(moved, link)
        metres += math.dist(p, base_p) / LEVER_STEP
        radians += (_turn(q, base_q) or 0.0) / LEVER_STEP
    return metres, radians


def _reaches_pose(
    target: str, field_name: str, state: Sequence[float], before: Context, facts: ScenarioFacts
) -> Comparison | None:
    """A pose or position goal its target reports reached: the link within ``REACH_SLACK`` plus
    what the goal tolerance moves it by (``_lever``) of the goal's position and orientation."""
    goal = before.pose_goal
    if goal is None or goal.position is None or facts.forward is None or len(state) != len(facts.joints):
        return None
    if not all(math.isfinite(x) for x in state):
        return None  # the joint-limit checks name a non-finite state
    try:
        position, orientation = facts.forward(state, goal.link)
    except Exception:  # noqa: BLE001 - a link the reference model does not know: no verdict here
        return None
    gap = math.dist(position, goal.position)
    turn = (_turn(orientation, goal.orientation) or 0.0) if goal.orientation is not None else 0.0
    if gap <= REACH_SLACK and turn <= REACH_SLACK:
        return None
    metres, radians = _lever(facts, state, goal.link)
    tol = before.goal_tolerance * (1.0 + RELATIVE_SLACK) + ABSOLUTE_SLACK
    over_m = gap - (REACH_SLACK + 2.0 * tol * metres)  # 2: the first order's margin
    over_rad = turn - (REACH_SLACK + 2.0 * tol * radians)
    if over_m <= 0.0 and over_rad <= 0.0:
        return None
    joints = range(len(facts.joints))
    if over_m >= over_rad:
        return _violation(target, field_name, over_m, "m", joints)
    return _violation(target, field_name, over_rad, "rad", joints)


def check_step(
    kind: str, outcome: Outcome, before: Context, facts: ScenarioFacts, target: str
) -> Comparison | None:
    """The first property violation of one step's outcome on one target, or None."""
    if outcome.status is not Status.OK:
        return None
    if kind in ("plan", "cartesian_path"):
        return check_trajectory(kind, outcome, before, facts, target)
    state = outcome.values.get("joint_values")
    if state is None:
        return None
    if kind == "go" and before.pose_goal is not None:
        return _reaches_pose(target, "go.pose_goal", state, before, facts)
    if kind == "go" and before.joint_goal is not None:
        return _equal(target, "go.goal", state, before.joint_goal, before, facts)
    if kind == "execute" and before.last_plan is not None:
        return _equal(target, "execute.last_point", state, before.last_plan, before, facts)
    return None


def first_property(
    call: ScenarioCall, outcomes: tuple[Outcome, Outcome], facts: ScenarioFacts
) -> Comparison | None:
    """The earliest property violation of either target (the first target first at a step),
    with ``step``/``step_kind`` set, or None."""
    found: list[Comparison] = []
    for target, outcome in zip(facts.targets, outcomes, strict=True):
        for i, (step, before) in enumerate(zip(call.steps, contexts(call, outcome, facts), strict=False)):
            c = check_step(step.kind, outcome.steps[i], before, facts, target)
            if c is not None:
                found.append(replace(c, step=i, step_kind=step.kind))
                break
    return min(found, key=lambda c: c.step if c.step is not None else 0, default=None)


def check_own_timing(
    kind: str, outcome: Outcome, before: Context, facts: ScenarioFacts, tol: Tolerance, target: str
) -> Comparison | None:
    """Whether one target's ``/plan`` or ``/cartesian_path`` is what the contract makes of its
    own answer: timed as the contract times its own positions (``<kind>.timing``, s or points;
    ``oracle_timing.timing_gap``), and a plan's positions and velocities those of the contract's
    plan between its own ends (``plan.profile``, rad or m; ``oracle_timing.profile_gap``)."""
    if outcome.status is not Status.OK or kind not in ("plan", "cartesian_path"):
        return None
    timing = timing_gap(kind, outcome, before, facts)
    if timing is not None:
        return _violation(target, f"{kind}.timing", *timing)
    if kind != "plan":
        return None
    excess, joints = profile_gap(outcome, before, facts, tol)
    return _violation(target, "plan.profile", excess, _unit("rad", facts, joints), joints) if joints else None


def violation_at(
    call: ScenarioCall,
    outcomes: tuple[Outcome, Outcome],
    differential: Comparison,
    facts: ScenarioFacts,
    tol: Tolerance,
) -> Comparison | None:
    """``first_property``, and, where ``differential`` is a divergence the oracle does not count
    (``known_limitation``, ``ill_conditioned``) at a ``/plan`` or ``/cartesian_path`` step
    before any property violation, whether each target's trajectory there is what the contract
    makes of its own answer (``check_own_timing``, the first target first).

    The rules that explain such a divergence (IK answers apart at one pose, a timing that follows
    inputs a rounding apart, a nudge that moves an IK answer) explain why the two trajectories
    differ, not a target that times or shapes its own wrongly. The check is not run at every step:
    re-deriving a 2,201-point plan costs about 2 ms, and where the two targets agree one of them
    checks the other."""
    found = first_property(call, outcomes, facts)
    step = differential.step
    if (
        not differential.divergent
        or differential.kind not in (Kind.KNOWN_LIMITATION, Kind.ILL_CONDITIONED)
        or step is None
        or (found is not None and found.step is not None and found.step <= step)
    ):
        return found
    kind = call.steps[step].kind
    for target, outcome in zip(facts.targets, outcomes, strict=True):
        if step < len(outcome.steps):
            before = contexts(call, outcome, facts)[step]
            own = check_own_timing(kind, outcome.steps[step], before, facts, tol, target)
            if own is not None:
                return replace(own, step=step, step_kind=kind)
    return found
