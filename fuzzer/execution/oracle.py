"""The oracle: do two outcomes agree, and if not, how do they differ?

Statuses are compared first (class and code of errors included). Values are
compared after canonicalization, modulo true equivalence:

* positions: Euclidean distance (m), within the tolerance plus 16 ulps of the position's
  magnitude (``ROUNDING``: rounding, where the tolerance is below float64's resolution);
* orientations: rotation distance ``4 atan2(|qa - qb|, |qa + qb|)`` (rad): the
  rotation angle of ``qa^-1 qb`` for the nearer of qb and -qb, so q and -q are one
  rotation;
* joint values: revolute and continuous joints modulo 2pi (rad), prismatic
  joints as they are (m).

A pair equal modulo equivalence but not as numbers (4.0 vs 4.0 - 2pi, q vs -q)
is a *representation* difference: the paper's "positive and negative"
inconsistency, reported as its own kind, but only where the canonical form is
unambiguous. Where the canonical form's own rule is decided by a quantity within
tolerance of its boundary, two answers on either side of it are the same answer
(agreement): quaternions whose ``w`` is within the orientation tolerance of 0 (the
rule ``w >= 0`` and its tie-break on ``x, y, z`` are then decided by rounding noise),
and continuous joints whose values both lie in (-pi, pi] within the tolerance of
+-pi. A value outside its canonical range (``-pi`` exactly, ``w`` clearly negative)
is not ambiguous and stays reported.

IK outcomes compare by the pose they reach, never by joint vectors. Two IK
failures agree. Beside the differential check, ``ik_property`` checks one
target's IK success on its own: joint values within the limits (continuous joints
in (-pi, pi]) and residual within the solver's tolerance (docs/api.md).

Each verdict has one headline difference with its unit (``m``, ``rad``, or
``status``): the difference modulo equivalence of the first differing field in
the order joint values, position, orientation (the later ones follow from the
earlier ones), so the same bug is reported on the same field.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from fuzzer.execution.records import Comparison, Kind, Outcome, Status
from fuzzer.execution.tolerance import Tolerance
from robot_api.constants import IK_EPS

TWO_PI = 2.0 * math.pi
IK_RESIDUAL = math.sqrt(3.0) * IK_EPS
"""The solver's documented tolerance as a distance: every twist component within IK_EPS."""


def bucket(difference: float) -> int:
    """Decade of a difference, clipped to [-16, 3] (-99 for zero)."""
    if difference <= 0.0 or not math.isfinite(difference):
        return -99 if difference == 0.0 else 3
    return max(-16, min(3, math.floor(math.log10(difference))))


def wrap(delta: float) -> float:
    """``delta`` (rad) moved by whole turns into (-pi, pi] (a continuous joint's range)."""
    r = math.fmod(delta, TWO_PI)
    if r <= -math.pi:
        r += TWO_PI
    elif r > math.pi:
        r -= TWO_PI
    return r


def _finite_gap(a: float, b: float) -> float:
    """``|a - b|``; 0 for the same value (the same infinity, or NaN on both sides: no difference
    between the targets, whatever each is worth), inf for a gap that is not finite."""
    if a == b or (a != a and b != b):
        return 0.0
    gap = abs(a - b)
    return gap if math.isfinite(gap) else math.inf


@dataclass(frozen=True)
class _FieldDiff:
    field: str
    raw: float  # as numbers
    equivalent: float  # modulo equivalence
    tolerance: float  # of ``equivalent``
    sign_flip: bool
    joints: tuple[int, ...] = ()
    unit: str = "rad"
    raw_tolerance: float | None = None  # of ``raw``, when not ``tolerance``
    # (sign_flip, unit) of a value divergence's own joint, when not the field's (joint values:
    # ``sign_flip`` and ``unit`` are those of the joint farthest apart as numbers, a
    # representation's; a value divergence's headline is the joint farthest modulo equivalence)
    value_view: tuple[bool, str] | None = None
    # a representation divergence's headline: the gap modulo equivalence of the joint farthest
    # apart as numbers (the one ``sign_flip`` and ``unit`` describe), when not ``equivalent``
    representation_view: float | None = None
    # an agreement's unit: that of the joint farthest apart modulo equivalence (``equivalent``'s)
    equivalent_unit: str | None = None


def _near_pi(x: float, tol: float) -> bool:
    """In the canonical range (-pi, pi] and within ``tol`` of its boundary."""
    return -math.pi < x <= math.pi and math.pi - abs(x) <= tol


def _joint_diff(
    a: Sequence[float],
    b: Sequence[float],
    prismatic: tuple[bool, ...],
    tol: Tolerance,
    continuous: tuple[bool, ...] = (),
) -> _FieldDiff:
    # each joint against its own limit (m or rad): the field reports the joint farthest beyond
    # its limit, as numbers and modulo equivalence (with one limit for all, the largest gaps).
    # Kept as (gap / limit, gap, limit) and max(): no comparison or branch of its own for
    # Atheris to trace (the campaign's feedback is this module's edges and comparisons).
    raw_worst = (0.0, 0.0, tol.radians)
    eq_worst = (0.0, 0.0, tol.radians, "rad")
    joints: list[int] = []
    flip = False
    worst = -1.0
    unit = "rad"
    numbers_eq = 0.0  # the gap modulo equivalence of the joint farthest apart as numbers
    value = (-1.0, 0.0, 0.0, 0, False, "rad")  # (eq / limit, eq, limit, -i, flip, unit)
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        linear = i < len(prismatic) and prismatic[i]
        limit = tol.metres if linear else tol.radians
        gap = _finite_gap(x, y)
        eq = gap if linear or not math.isfinite(gap) else abs(wrap(x - y))
        if (
            i < len(continuous)
            and continuous[i]
            and eq <= limit
            and _near_pi(x, limit)
            and _near_pi(y, limit)
        ):
            gap = eq  # either side of the (-pi, pi] boundary is the canonical answer
        raw_worst = max(raw_worst, (gap / limit, gap, limit))  # a NaN never wins a max()
        eq_worst = max(eq_worst, (eq / limit, eq, limit, "m" if linear else "rad"))
        if gap > limit:
            joints.append(i)
            here = ((x < 0) != (y < 0), "m" if linear else "rad")
            if gap / limit > worst:
                worst, (flip, unit), numbers_eq = gap / limit, here, eq
            # only a joint beyond its limit as numbers can be beyond it modulo equivalence
            value = max(value, (eq / limit, eq, limit, -i, *here))
    (_, raw, raw_limit), (_, equivalent, eq_limit, eq_unit) = raw_worst, eq_worst
    return _FieldDiff(
        "joint_values",
        raw,
        equivalent,
        eq_limit,
        flip,
        tuple(joints),
        unit,
        raw_limit,
        value[4:],
        numbers_eq,
        eq_unit,
    )


ROUNDING = 16 * 2.0**-52
"""Per unit of a position's magnitude, what summing its terms in another order may move it: 16
units in the last place. Far below the tolerance on any real arm (1.4e-14 m at 4 m), it decides
only where the tolerance is below float64's resolution: a prismatic joint at 6e12 m (a
``--no-filter`` campaign) put pinocchio's tip one ulp (0.000977 m) from KDL's, the correctly
rounded value, and was a finding between two correct implementations."""


def _position_diff(a: Sequence[float], b: Sequence[float], tol: Tolerance) -> _FieldDiff:
    # hypot, not the square root of squares: a gap above 1.3e154 m raised OverflowError
    gap = math.hypot(*(_finite_gap(x, y) for x, y in zip(a, b, strict=True)))
    # one comparison, not one per coordinate: each is a site the float tracer spends its budget
    # on; and the magnitude only for a gap past the tolerance (a move campaign's samples in this
    # function: 1.4% without it, 1.9% with it computed for every pair)
    limit = tol.metres
    if gap > limit:
        scale = max(map(abs, (*a, *b)), default=0.0)
        if scale < math.inf:  # an infinity or a NaN: no magnitude to scale by
            limit += ROUNDING * scale
    flip = any((x < 0) != (y < 0) and abs(x - y) > limit for x, y in zip(a, b, strict=True))
    return _FieldDiff("position", gap, gap, limit, flip, unit="m")


def rotation_distance(a: Sequence[float], b: Sequence[float]) -> float:
    """Rotation angle (rad) between two unit quaternions, q and -q being one rotation."""
    minus = math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b, strict=True)))
    plus = math.sqrt(sum((x + y) ** 2 for x, y in zip(a, b, strict=True)))
    # atan2 gives half the 4-D angle between the quaternions; the rotation angle is twice that
    distance = 4.0 * math.atan2(min(minus, plus), max(minus, plus))
    return distance if math.isfinite(distance) else math.inf


def _orientation_diff(a: Sequence[float], b: Sequence[float], tol: Tolerance) -> _FieldDiff:
    raw = max((_finite_gap(x, y) for x, y in zip(a, b, strict=True)), default=0.0)
    if raw == 0.0:  # the same numbers, non-finite ones too: one rotation, whatever it is
        return _FieldDiff("orientation", 0.0, 0.0, tol.radians, False)
    minus = math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b, strict=True)))
    plus = math.sqrt(sum((x + y) ** 2 for x, y in zip(a, b, strict=True)))
    distance = rotation_distance(a, b)
    flip = plus < minus  # closer to -q than to q
    if flip and len(a) == 4 and abs(a[3]) <= tol.radians and abs(b[3]) <= tol.radians:
        # w within tolerance of 0: the sign rule (w >= 0, then the tie-break on x, y, z) is
        # decided by rounding noise, so q and -q are both the canonical answer
        raw = max((_finite_gap(x, -y) for x, y in zip(a, b, strict=True)), default=0.0)
    return _FieldDiff("orientation", raw, distance, tol.radians, flip)


FIELD_ORDER = ("joint_values", "position", "orientation")


def compare(
    a: Outcome,
    b: Outcome,
    tol: Tolerance,
    prismatic: tuple[bool, ...] = (),
    op: str = "",
    continuous: tuple[bool, ...] = (),
) -> Comparison:
    """The oracle's verdict on two outcomes of the same input.

    Parameters
    ----------
    a, b : Outcome
        Outcomes of the two targets.
    tol : Tolerance
        Reasonable difference per quantity.
    prismatic : tuple of bool
        Per joint, whether it is prismatic (compared in metres, not modulo 2pi).
    op : str
        ``ik`` compares only reached poses, and only when both converged.
    continuous : tuple of bool
        Per joint, whether it is continuous (canonical range (-pi, pi], whose boundary is
        ambiguous within tolerance).
    """
    if Status.CRASHED in (a.status, b.status):
        return Comparison(Kind.CRASH, "status")
    if a.label != b.label:
        return Comparison(Kind.STATUS, "status")
    if a.status is Status.REJECTED or (op == "ik" and a.status is Status.FAILED):
        return Comparison(Kind.AGREE)
    for name in set(a.values) & set(b.values):
        if len(a.values[name]) != len(b.values[name]):
            unit = "m" if name == "position" else "rad"
            return Comparison(
                Kind.VALUE, name, math.inf, False, bucket(math.inf), largest=math.inf, unit=unit, raw=math.inf
            )
    diffs = []
    if "joint_values" in a.values and "joint_values" in b.values and op != "ik":
        diffs.append(
            _joint_diff(a.values["joint_values"], b.values["joint_values"], prismatic, tol, continuous)
        )
    if "position" in a.values and "position" in b.values:
        diffs.append(_position_diff(a.values["position"], b.values["position"], tol))
    if "orientation" in a.values and "orientation" in b.values:
        diffs.append(_orientation_diff(a.values["orientation"], b.values["orientation"], tol))
    largest = max((d.raw for d in diffs), default=0.0)
    for kind in (Kind.VALUE, Kind.REPRESENTATION):
        # one comparison site, as before the per-joint limits (the campaign traces it)
        found = [
            d
            for d in diffs
            if (d.equivalent if kind is Kind.VALUE else d.raw)
            > (d.tolerance if kind is Kind.VALUE or d.raw_tolerance is None else d.raw_tolerance)
        ]
        if found:
            first = min(found, key=lambda d: FIELD_ORDER.index(d.field))
            flip, unit = (
                first.value_view
                if kind is Kind.VALUE and first.value_view is not None
                else (first.sign_flip, first.unit)
            )
            headline = (
                first.representation_view
                if kind is Kind.REPRESENTATION and first.representation_view is not None
                else first.equivalent
            )
            return Comparison(
                kind,
                first.field,
                headline,
                flip,
                bucket(headline),
                first.joints,
                largest,
                unit,
                first.raw,
            )
    top = max(diffs, key=lambda d: d.equivalent / d.tolerance, default=None)
    return Comparison(
        Kind.AGREE,
        difference=top.equivalent if top else 0.0,
        largest=largest,
        unit=(top.equivalent_unit or top.unit) if top else "status",
    )


@dataclass(frozen=True)
class JointFacts:
    """What the IK property check needs to know about one joint."""

    continuous: bool
    lower: float
    upper: float


def ik_property(
    outcome: Outcome,
    target: str,
    requested: tuple[tuple[float, ...], tuple[float, ...]],
    joints: tuple[JointFacts, ...],
) -> Comparison | None:
    """A property violation of one target's IK success, or None.

    A success must have every joint value within its limits (continuous joints in
    (-pi, pi]) and reach the requested pose within ``IK_RESIDUAL`` (m and rad): the
    solver stops when every component of its error twist is within ``IK_EPS``.

    Parameters
    ----------
    outcome : Outcome
        The target's IK outcome (``joint_values`` and the pose they reach).
    target : str
        Its name, reported with the violation.
    requested : (position, orientation)
        The requested pose (the quaternion is normalized here).
    joints : tuple of JointFacts
        Per joint of the robot.
    """
    if outcome.status is not Status.OK:
        return None
    values = outcome.values.get("joint_values", ())
    outside: list[tuple[int, float]] = []
    for i, (x, facts) in enumerate(zip(values, joints, strict=False)):
        if facts.continuous:
            excess = 0.0 if -math.pi < x <= math.pi else max(abs(x) - math.pi, math.ulp(math.pi))
        else:
            excess = max(facts.lower - x, x - facts.upper, 0.0)
        if excess > 0.0 or not math.isfinite(x):
            outside.append((i, excess if math.isfinite(x) else math.inf))
    if outside:
        worst = max(e for _, e in outside)
        return Comparison(
            Kind.PROPERTY,
            "joint_limits",
            worst,
            False,
            bucket(worst),
            tuple(i for i, _ in outside),
            unit="rad",
            raw=worst,
            target=target,
        )
    for unit, found in zip(("m", "rad"), pose_gaps(outcome, requested), strict=True):
        gap = 0.0 if found is None else found  # a part the outcome does not report is not checked
        if gap > IK_RESIDUAL * (1.0 + 1e-6) or not math.isfinite(gap):
            return Comparison(
                Kind.PROPERTY, "residual", gap, False, bucket(gap), (), unit=unit, raw=gap, target=target
            )
    return None


def pose_gaps(
    outcome: Outcome, requested: tuple[tuple[float, ...], tuple[float, ...]]
) -> tuple[float | None, float | None]:
    """How far the pose an IK outcome reports is from ``requested``: (m, rad).

    The rotation is 0.0 for a position-only request (no orientation, or one of no finite
    length; the quaternion asked for is normalized here); a part the outcome does not report
    (its position, or the orientation a pose asks for) is None.
    """
    position, orientation = requested
    reached_p = outcome.values.get("position", ())
    reached_q = outcome.values.get("orientation", ())
    norm = math.sqrt(sum(x * x for x in orientation))
    moved = math.dist(reached_p, position) if len(reached_p) == len(position) else None
    if not (norm > 0.0 and math.isfinite(norm)):
        return moved, 0.0
    if len(reached_q) != 4:
        return moved, None
    return moved, rotation_distance(reached_q, tuple(x / norm for x in orientation))
