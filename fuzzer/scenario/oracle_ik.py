"""Steps that solve IK in a scenario: the documented limitations, and nudge checks.

A step solves IK when it is ``go`` or ``plan`` with a pose or position target in effect, or
``cartesian_path``. IK's answer is a pose within the solver's tolerance, not a unique joint
vector (``fuzzer.execution.oracle`` compares single IK calls by pose only). At such a step a divergence
(other than of the status) is ``known_limitation`` when

* ``cartesian_path``: the two paths' point counts or fractions differ and a segment both
  began is on the knife edge of its step count (``d / eef_step`` within ``KNIFE_EDGE``
  relative of an integer >= 1: ``floor`` may fall either way);
* ``cartesian_path``: the accelerations differ only at points on a switch of the time law's
  phase, each target reporting one of the contract's values there
  (``oracle_timing.phase_knife_edge``);
* the IK answers (the state after ``go``, a plan's last point, every point of a path with the
  same point count) differ beyond the campaign tolerance in joint space (modulo 2pi) but put the
  link at the same pose within ``IK_AGREEMENT`` (KDL's rotation dead zone, docs/api.md);
* the IK answers differ as numbers (by any amount) but within the campaign tolerance, and
  the divergence is of what the contract computes *from* them (the point count,
  ``time_from_start``, velocities, accelerations): with different inputs the timing differs by
  the inputs' gap times a sensitivity that grows without bound as a segment shrinks (a move of
  2.3e-13 rad lasts 2 sqrt(d / A), about 9.5e-7 s, and a rounding error of its length changes
  that by 1e-9 s), so no tolerance on the timing itself can hold; provided each target's
  trajectory lasts what the contract's timing of its own positions gives (``oracle_timing``),
  so a target that times its path wrongly is still reported. Inputs equal as numbers must time
  alike.

The timing rule holds at any ``plan`` or ``cartesian_path`` step whose start states differ as
numbers (within the tolerance, or an earlier step would have been reported): an earlier IK
answer left the two arms that far apart. It holds as well at a ``plan`` or ``go`` to joint goals
that differ as numbers by no more than the tolerance: a named target remembered after an IK
answer (``_goal_gap``). And at any step, a
divergence of the end effector's position or orientation is ``known_limitation`` when the two
joint vectors agree within the campaign tolerance but not as numbers (``IK_EXACT``) and the
reported poses are no farther apart than the reference FK of the two vectors plus the
tolerance: FK amplifies a joint gap within tolerance (rad) into a pose gap beyond it (m).

At a ``plan`` step, a divergence of the trajectory's positions is ``known_limitation`` when
every joint it names is continuous and on each target that joint's last point is a half turn
from its first within the campaign tolerance: the short way round is then either way, and
a start a rounding error either side of the boundary picks it (``_either_way_round``).

A status divergence (ok vs failed) of ``go``/``plan`` with a pose target, or a ``plan`` that
failed on both with ``NO_IK_SOLUTION`` on one only (``split_on_ik``: the other's IK answered and
its plan failed after it), is ``known_limitation`` when the requested orientation is within
``DEAD_ZONE`` of a half turn from the orientation the state before the step gives the link
(``fuzzer.execution.evaluate``'s rule for single IK calls). Other IK divergences go to the
evaluator's nudge check (``ik_answer_changed``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from fuzzer.execution import oracle
from fuzzer.execution.records import Comparison, Kind, Outcome, Status, as_array
from fuzzer.execution.tolerance import Tolerance
from fuzzer.scenario.oracle_facts import Context, ScenarioFacts
from fuzzer.scenario.oracle_switch import ACCELERATION_TOLERANCE
from fuzzer.scenario.oracle_timing import phase_knife_edge, timed_as_contract
from fuzzer.scenario.steps import ScenarioCall
from robot_api.records import MoveItErrorCode

FRACTION_TOLERANCE = 1e-9
"""Cartesian path fraction."""
IK_AGREEMENT = 2.0 * oracle.IK_RESIDUAL
"""Two IK answers each within the solver's tolerance of one pose are this close (m, rad)."""
IK_EXACT = 1e-12
"""Joint vectors closer than this (rad, m) are the same answer (rounding): the pose rule does not
explain their poses, and ``state_gap`` does not nudge by it. (The timing rule takes any gap.)"""
KNIFE_EDGE = 1e-9
"""Relative distance of ``d / eef_step`` to an integer within which its floor is rounding."""
DEAD_ZONE = 1e-6
"""KDL's rotation dead zone at a half turn (rad; ``fuzzer.execution.ik_check.DEAD_ZONE``)."""
NO_IK = (float(MoveItErrorCode.NO_IK_SOLUTION),)
"""A step's ``error_code`` when its IK found no solution."""
DERIVED = (
    "trajectory.points",
    "trajectory.time_from_start",
    "trajectory.velocities",
    "trajectory.accelerations",
)
"""What the contract computes from a trajectory's positions."""

Pairs = list[tuple[Sequence[float], Sequence[float]]]


def value_divergence(
    field_name: str, difference: float, unit: str, joints: tuple[int, ...] = ()
) -> Comparison:
    """A ``value`` divergence with its headline ``difference`` in ``unit``."""
    bucket = oracle.bucket(difference)
    return Comparison(Kind.VALUE, field_name, difference, False, bucket, joints, difference, unit, difference)


def absolute(
    key: str,
    a: np.ndarray,
    b: np.ndarray,
    limit: float,
    unit: str,
    dof: int = 0,
    prismatic: tuple[bool, ...] = (),
) -> Comparison | None:
    """Element-wise ``|a - b| <= limit`` (NaN on both sides agrees); with ``dof`` the arrays
    are (M * dof,) and the divergence names the joints (columns) beyond the limit, its unit
    (``rad/s``...) read in metres (``m/s``) when the largest gap is a ``prismatic`` joint's."""
    gap = np.abs(a - b)
    gap[np.isnan(gap) & ~(np.isnan(a) & np.isnan(b))] = math.inf
    gap[np.isnan(gap)] = 0.0
    worst = float(gap.max(initial=0.0))
    if worst <= limit:
        return None
    joints: tuple[int, ...] = ()
    if dof:
        columns = gap.reshape(-1, dof).max(axis=0)
        joints = tuple(int(j) for j in np.flatnonzero(columns > limit))
        top = int(np.argmax(columns))
        unit = unit.replace("rad", "m") if top < len(prismatic) and prismatic[top] else unit
    return value_divergence(key, worst, unit, joints)


def joints_apart(
    key: str, a: Sequence[float], b: Sequence[float], tol: Tolerance, facts: ScenarioFacts
) -> Comparison | None:
    """``fuzzer.execution.oracle.compare`` on two joint vectors (modulo 2pi, canonical boundary rule):
    its divergence with ``field = key``, or None when they agree."""
    c = oracle.compare(
        Outcome(Status.OK, values={"joint_values": tuple(a)}),
        Outcome(Status.OK, values={"joint_values": tuple(b)}),
        tol,
        facts.prismatic,
        continuous=facts.continuous,
    )
    return replace(c, field=key) if c.divergent else None


def apart_rows(x: np.ndarray, y: np.ndarray, tol: Tolerance, facts: ScenarioFacts) -> np.ndarray:
    """Indices of the rows of ``x`` and ``y`` (N, dof) that ``joints_apart`` may call apart: those
    with a joint whose values differ as numbers beyond its limit (``tol.metres`` for a prismatic
    joint, ``tol.radians`` otherwise). ``joints_apart`` never calls apart a row within its limits
    as numbers (its rules only ever lower a gap), so the rest need no call."""
    linear = facts.prismatic
    dof = x.shape[1]
    limits = np.array([tol.metres if j < len(linear) and linear[j] else tol.radians for j in range(dof)])
    with np.errstate(invalid="ignore"):  # inf - inf: NaN, which is beyond any limit
        near = (x == y) | (np.abs(x - y) <= limits)
    return np.flatnonzero(~near.all(axis=1))


def pairs_apart(pairs: Pairs, tol: Tolerance, facts: ScenarioFacts) -> Pairs:
    """The pairs of joint vectors ``joints_apart`` calls apart, in order; only the pairs that
    differ as numbers beyond the tolerance (``apart_rows``) are compared."""
    try:
        x, y = (np.array([pair[k] for pair in pairs], dtype=float) for k in (0, 1))
        maybe = apart_rows(x, y, tol, facts).tolist() if x.ndim == 2 and x.shape == y.shape else None
    except ValueError:  # vectors of unequal lengths
        maybe = None
    if maybe is None:  # each pair compared on its own
        maybe = list(range(len(pairs)))
    return [(p, q) for p, q in (pairs[r] for r in maybe) if joints_apart("", p, q, tol, facts) is not None]


def solves_ik(call: ScenarioCall, step: int, before: Context) -> bool:
    """Whether the step at ``step`` solves IK (its goal or path), given what is in effect."""
    kind = call.steps[step].kind
    return kind == "cartesian_path" or (kind in ("go", "plan") and before.pose_goal is not None)


def ik_answers(kind: str, a: Outcome, b: Outcome, dof: int) -> Pairs | None:
    """The pairs of IK answers of a step: the state after ``go``, a plan's last points, every
    point of a path (None when a path's point counts differ or a shape is wrong)."""
    if kind == "go":
        pair = (a.values.get("joint_values", ()), b.values.get("joint_values", ()))
        return [pair] if len(pair[0]) == len(pair[1]) == dof else None
    rows = [as_array(o.values.get("trajectory.positions", ())) for o in (a, b)]
    if not dof or any(r.size == 0 or r.size % dof for r in rows):
        return None
    ra, rb = (r.reshape(-1, dof) for r in rows)
    if kind == "plan":
        return [(tuple(ra[-1].tolist()), tuple(rb[-1].tolist()))]
    if len(ra) != len(rb):
        return None
    return [(tuple(x), tuple(y)) for x, y in zip(ra.tolist(), rb.tolist(), strict=True)]


def classify(
    call: ScenarioCall,
    i: int,
    a: Outcome,
    b: Outcome,
    c: Comparison,
    before: tuple[Context, Context],
    facts: ScenarioFacts,
    tol: Tolerance,
) -> Comparison:
    """A divergence at step ``i`` that a documented limitation explains is ``known_limitation``
    (module docstring); any other stays as it is. ``before`` is what is in effect on each target."""
    if c.kind is Kind.CRASH:
        return c
    if c.field.rsplit(".", 1)[-1] in ("position", "orientation") and _pose_follows_joints(
        a, b, c, facts, tol
    ):
        return replace(c, kind=Kind.KNOWN_LIMITATION)
    ik = solves_ik(call, i, before[0])
    kind = call.steps[i].kind
    if c.kind is Kind.STATUS or split_on_ik(c, a, b):
        return _half_turn(a, b, c, before[0], facts) if ik else c
    gap = max(_gap([(before[0].state or (), before[1].state or ())]), _goal_gap(kind, before, tol))
    if ik:
        if (
            kind == "cartesian_path"
            and extent_changed(kind, a, b)
            and _knife_edge(call, i, before[0], facts, a, b)
        ):
            return replace(c, kind=Kind.KNOWN_LIMITATION)
        switch = kind == "cartesian_path" and c.field.endswith(".trajectory.accelerations")
        if switch and phase_knife_edge(a, b, before, facts, ACCELERATION_TOLERANCE):
            return replace(c, kind=Kind.KNOWN_LIMITATION)
        pairs = ik_answers(kind, a, b, len(facts.joints))
        if pairs is None:
            return c
        apart = pairs_apart(pairs, tol, facts)
        if apart:
            link = before[0].pose_goal.link if (kind != "cartesian_path" and before[0].pose_goal) else None
            same = all(_same_pose(x, y, link, facts) for x, y in apart)
            return replace(c, kind=Kind.KNOWN_LIMITATION) if same else c
        gap = max(gap, _gap(pairs))
    positions = kind == "plan" and c.field.endswith(".trajectory.positions")
    if positions and _either_way_round(a, b, c, facts, tol):
        return replace(c, kind=Kind.KNOWN_LIMITATION)
    derived = any(c.field.endswith("." + name) for name in DERIVED)
    if not (derived and gap > 0.0):  # inputs equal as numbers: their timings must agree
        return c
    own = all(timed_as_contract(kind, o, ctx, facts) for o, ctx in zip((a, b), before, strict=True))
    return replace(c, kind=Kind.KNOWN_LIMITATION) if own else c


def split_on_ik(c: Comparison, a: Outcome, b: Outcome) -> bool:
    """Whether a divergence of a step's ``error_code`` is its IK answering on one target only:
    both steps failed, one with ``NO_IK_SOLUTION`` and the other after its IK answered (a plan
    that would last longer than ``MAX_TRAJECTORY_DURATION`` fails with ``PLANNING_FAILED``).
    That is a status divergence of the IK call inside the step, as ok vs failed is of the step:
    the rules for those apply to it (``_half_turn`` here, ``ik_check.step_meets_half_turn``
    after the re-runs)."""
    if not c.field.endswith(".error_code") or a.status is not Status.FAILED or b.status is not Status.FAILED:
        return False
    codes = [tuple(o.values.get("error_code", ())) for o in (a, b)]
    return (codes[0] == NO_IK) != (codes[1] == NO_IK)


def _goal_gap(kind: str, before: tuple[Context, Context], tol: Tolerance) -> float:
    """For ``plan``/``go`` to a joint goal: how far apart as numbers the two targets' goals are,
    when that is within the tolerance (0 otherwise). A goal remembered from an IK answer
    (``/remember`` after an IK ``/go``, then ``/named_target``) differs by as much as the IK
    answers did."""
    if kind not in ("plan", "go") or before[0].pose_goal or before[1].pose_goal:
        return 0.0
    gap = _gap([(before[0].joint_goal or (), before[1].joint_goal or ())])
    return gap if gap <= min(tol.radians, tol.metres) else 0.0


def _either_way_round(a: Outcome, b: Outcome, c: Comparison, facts: ScenarioFacts, tol: Tolerance) -> bool:
    """Whether every joint of a plan's position divergence is continuous and, on each target,
    its plan's last point is a half turn from its first within the tolerance: the short way
    round (MoveIt's interpolation of a continuous joint) is then either way, and which one a
    target takes depends on where within the tolerance its start lies."""
    dof = len(facts.joints)
    rows = [as_array(o.values.get("trajectory.positions", ())) for o in (a, b)]
    if not c.joints or not dof or any(r.size == 0 or r.size % dof for r in rows):
        return False
    for j in c.joints:
        if j >= dof or not facts.continuous[j]:
            return False
        for r in rows:
            first, last = r[j], r[r.size - dof + j]
            turn = abs(math.remainder(last - first, 2.0 * math.pi))  # in [0, pi]
            if not math.pi - turn <= tol.radians:
                return False
    return True


def _pose_follows_joints(a: Outcome, b: Outcome, c: Comparison, facts: ScenarioFacts, tol: Tolerance) -> bool:
    """A pose divergence of the end effector whose joint values agree within tolerance but not as
    numbers (``IK_EXACT``), no larger than the reference FK of the two joint vectors is apart plus
    the tolerance: FK amplifies a joint gap within tolerance (rad) into a pose gap (m) beyond it."""
    x, y = a.values.get("joint_values", ()), b.values.get("joint_values", ())
    if facts.forward is None or len(x) != len(y) or _gap([(x, y)]) <= IK_EXACT:
        return False
    if joints_apart("", x, y, tol, facts) is not None:
        return False
    try:
        (pa, qa), (pb, qb) = facts.forward(x, None), facts.forward(y, None)
    except Exception:  # noqa: BLE001 - a pose the reference cannot compute explains nothing
        return False
    if c.field.endswith("position"):
        return c.difference <= math.dist(pa, pb) + tol.metres
    return c.difference <= oracle.rotation_distance(qa, qb) + tol.radians


def _gap(pairs: Pairs) -> float:
    """The largest difference as numbers over pairs of vectors of equal length (0 otherwise)."""
    gaps = [abs(p - q) for x, y in pairs if len(x) == len(y) for p, q in zip(x, y, strict=True)]
    return max(gaps, default=0.0)


def _half_turn(a: Outcome, b: Outcome, c: Comparison, before: Context, facts: ScenarioFacts) -> Comparison:
    goal = before.pose_goal
    if goal is None or goal.orientation is None or before.state is None or facts.forward is None:
        return c
    if not {a.status, b.status} <= {Status.OK, Status.FAILED}:
        return c
    norm = math.sqrt(sum(x * x for x in goal.orientation))
    if not (norm > 0.0 and math.isfinite(norm)):
        return c
    try:
        start = facts.forward(before.state, goal.link)[1]
    except Exception:  # noqa: BLE001 - a pose the reference cannot compute is no known limitation
        return c
    target = tuple(x / norm for x in goal.orientation)
    if oracle.rotation_distance(start, target) >= math.pi - DEAD_ZONE:
        return replace(c, kind=Kind.KNOWN_LIMITATION)
    return c


def _knife_edge(
    call: ScenarioCall, i: int, before: Context, facts: ScenarioFacts, a: Outcome, b: Outcome
) -> bool:
    """Whether a segment both paths began (each ``fraction`` at least the segment's index over the
    number of waypoints) has its ``d / eef_step`` within rounding of an integer >= 1.

    Its caller asks it only when the two paths' point counts or fractions differ (what a step
    count decided either way changes): any segment on the edge, reached or not, explained any
    divergence of the step, and round waypoints, which the fuzzer makes often, hid a fault of a
    target's path points (the scenario probe)."""
    if before.state is None or facts.forward is None or not before.eef_step > 0.0:
        return False
    try:
        poses = call.steps[i].message["poses"]
        began = min(float(as_array(o.values.get("fraction", (0.0,))).min()) for o in (a, b))
        previous = facts.forward(before.state, None)[0]
        for j, pose in enumerate(poses):
            if j / len(poses) > began + 1e-12:  # one path never began this segment
                return False
            point = tuple(float(pose["position"][k]) for k in "xyz")
            ratio = math.dist(previous, point) / before.eef_step
            nearest = round(ratio) if math.isfinite(ratio) else 0
            if nearest >= 1 and abs(ratio - nearest) <= KNIFE_EDGE * ratio:
                return True
            previous = point
    except Exception:  # noqa: BLE001 - a malformed pose, or the reference's FK failing: no knife edge
        return False
    return False


def _same_pose(x: Sequence[float], y: Sequence[float], link: str | None, facts: ScenarioFacts) -> bool:
    if facts.forward is None:
        return False
    try:
        (pa, qa), (pb, qb) = facts.forward(x, link), facts.forward(y, link)
    except Exception:  # noqa: BLE001 - a pose the reference cannot compute explains nothing
        return False
    return math.dist(pa, pb) <= IK_AGREEMENT and oracle.rotation_distance(qa, qb) <= IK_AGREEMENT


EXTENT_FIELDS = ("cartesian_path.fraction", "cartesian_path.trajectory.points")
"""Divergences of how far a path got: the nudge check asks whether that changes
(``extent_changed``), not whether the points move."""


def extent_changed(kind: str, first: Outcome, second: Outcome) -> bool:
    """Whether one target's step ended differently between two runs: its status, for a step
    that failed its ``error_code``, a plan's or path's point count or a path's fraction
    (beyond ``FRACTION_TOLERANCE``)."""
    if first.label != second.label:
        return True
    if first.status is not Status.OK:
        return tuple(first.values.get("error_code", ())) != tuple(second.values.get("error_code", ()))
    if kind == "go":
        return False
    times = [len(o.values.get("trajectory.time_from_start", ())) for o in (first, second)]
    fa, fb = (as_array(o.values.get("fraction", (0.0,))) for o in (first, second))
    if times[0] != times[1] or fa.size != fb.size:
        return True
    return absolute("", fa, fb, FRACTION_TOLERANCE, "") is not None


def ik_answer_changed(
    kind: str, first: Outcome, second: Outcome, tol: Tolerance, facts: ScenarioFacts
) -> bool:
    """Whether one target's answer at a step that solves IK changed between two runs: its
    extent (``extent_changed``), or the IK answer beyond the campaign tolerance (modulo 2pi):
    the state after ``go``, the last point of a plan, any point of a path; for a step that
    failed, its ``error_code`` (a plan that fails in IK, ``NO_IK_SOLUTION``, or after it).
    Timing is not compared (it follows the answer)."""
    if extent_changed(kind, first, second):
        return True
    if first.status is not Status.OK:
        return False
    pairs = ik_answers(kind, first, second, len(facts.joints))
    if pairs is None:
        return True
    return bool(pairs_apart(pairs, tol, facts))


STATE_GAP_MAX = 1e-3
"""``state_gap``: larger gaps between the arms are not nudged by (rad, m)."""


def state_gap(outcomes: Sequence[Outcome], step: int) -> float:
    """How far apart as numbers the two targets' states are before ``step`` (the largest
    joint difference after the step before it), when that is above ``IK_EXACT`` and at most
    :data:`STATE_GAP_MAX`; else 0."""
    if step < 1 or len(outcomes) < 2 or any(step > len(o.steps) for o in outcomes[:2]):
        return 0.0
    x, y = (tuple(o.steps[step - 1].values.get("joint_values", ())) for o in outcomes[:2])
    if not x or len(x) != len(y):
        return 0.0
    gap = max(abs(p - q) for p, q in zip(x, y, strict=True))
    return gap if IK_EXACT < gap <= STATE_GAP_MAX else 0.0
