"""The oracle: do two outcomes agree, and if not, how do they differ?

Statuses are compared first (class and code of errors included). Values are
compared after canonicalization, modulo true equivalence:

* positions: Euclidean distance (m);
* orientations: rotation distance ``4 atan2(|qa - qb|, |qa + qb|)`` (rad): the
  rotation angle of ``qa^-1 qb`` for the nearer of qb and -qb, so q and -q are one
  rotation;
* joint values: revolute and continuous joints modulo 2pi (rad), prismatic
  joints as they are (m).

A pair equal modulo equivalence but not as numbers (4.0 vs 4.0 - 2pi, q vs -q)
is a *representation* difference: the paper's "positive and negative"
inconsistency, reported as its own kind. IK outcomes compare by the pose they
reach, never by joint vectors. Two IK failures agree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fuzzer.records import Comparison, Kind, Outcome, Status
from fuzzer.tolerance import Tolerance

TWO_PI = 2.0 * math.pi


def bucket(difference: float) -> int:
    """Decade of a difference, clipped to [-16, 3] (-99 for zero)."""
    if difference <= 0.0 or not math.isfinite(difference):
        return -99 if difference == 0.0 else 3
    return max(-16, min(3, math.floor(math.log10(difference))))


def _wrap(delta: float) -> float:
    r = math.fmod(delta, TWO_PI)
    if r <= -math.pi:
        r += TWO_PI
    elif r > math.pi:
        r -= TWO_PI
    return r


def _finite_gap(a: float, b: float) -> float:
    if a == b:
        return 0.0
    gap = abs(a - b)
    return gap if math.isfinite(gap) else math.inf


@dataclass(frozen=True)
class _FieldDiff:
    field: str
    raw: float  # as numbers
    equivalent: float  # modulo equivalence
    tolerance: float
    sign_flip: bool
    joints: tuple[int, ...] = ()


def _joint_diff(
    a: tuple[float, ...], b: tuple[float, ...], prismatic: tuple[bool, ...], tol: Tolerance
) -> _FieldDiff:
    raw = equivalent = 0.0
    joints: list[int] = []
    flip = False
    worst = -1.0
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        linear = i < len(prismatic) and prismatic[i]
        limit = tol.metres if linear else tol.radians
        gap = _finite_gap(x, y)
        eq = gap if linear or not math.isfinite(gap) else abs(_wrap(x - y))
        raw, equivalent = max(raw, gap), max(equivalent, eq)
        if gap > limit:
            joints.append(i)
            if gap / limit > worst:
                worst, flip = gap / limit, (x < 0) != (y < 0)
    return _FieldDiff("joint_values", raw, equivalent, tol.radians, flip, tuple(joints))


def _position_diff(a: tuple[float, ...], b: tuple[float, ...], tol: Tolerance) -> _FieldDiff:
    gap = math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b, strict=True)))
    gap = gap if math.isfinite(gap) else math.inf
    flip = any((x < 0) != (y < 0) and abs(x - y) > tol.metres for x, y in zip(a, b, strict=True))
    return _FieldDiff("position", gap, gap, tol.metres, flip)


def _orientation_diff(a: tuple[float, ...], b: tuple[float, ...], tol: Tolerance) -> _FieldDiff:
    raw = max((_finite_gap(x, y) for x, y in zip(a, b, strict=True)), default=0.0)
    minus = math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b, strict=True)))
    plus = math.sqrt(sum((x + y) ** 2 for x, y in zip(a, b, strict=True)))
    # atan2 gives half the 4-D angle between the quaternions; the rotation angle is twice that
    distance = 4.0 * math.atan2(min(minus, plus), max(minus, plus))
    if not math.isfinite(distance):
        distance = math.inf
    flip = plus < minus  # closer to -q than to q
    return _FieldDiff("orientation", raw, distance, tol.radians, flip)


def compare(
    a: Outcome, b: Outcome, tol: Tolerance, prismatic: tuple[bool, ...] = (), op: str = ""
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
    """
    if Status.CRASHED in (a.status, b.status):
        return Comparison(Kind.CRASH, "status")
    if a.label != b.label:
        return Comparison(Kind.STATUS, "status")
    if a.status is Status.REJECTED or (op == "ik" and a.status is Status.FAILED):
        return Comparison(Kind.AGREE)
    for name in set(a.values) & set(b.values):
        if len(a.values[name]) != len(b.values[name]):
            return Comparison(Kind.VALUE, name, math.inf, False, bucket(math.inf), largest=math.inf)
    diffs = []
    if "joint_values" in a.values and "joint_values" in b.values and op != "ik":
        diffs.append(_joint_diff(a.values["joint_values"], b.values["joint_values"], prismatic, tol))
    if "position" in a.values and "position" in b.values:
        diffs.append(_position_diff(a.values["position"], b.values["position"], tol))
    if "orientation" in a.values and "orientation" in b.values:
        diffs.append(_orientation_diff(a.values["orientation"], b.values["orientation"], tol))
    largest = max((d.raw for d in diffs), default=0.0)
    value = [d for d in diffs if d.equivalent > d.tolerance]
    if value:
        worst = max(value, key=lambda d: d.equivalent / d.tolerance)
        return Comparison(
            Kind.VALUE,
            worst.field,
            worst.equivalent,
            worst.sign_flip,
            bucket(worst.equivalent),
            worst.joints,
            largest,
        )
    representation = [d for d in diffs if d.raw > d.tolerance]
    if representation:
        worst = max(representation, key=lambda d: d.raw / d.tolerance)
        return Comparison(
            Kind.REPRESENTATION,
            worst.field,
            worst.raw,
            worst.sign_flip,
            bucket(worst.raw),
            worst.joints,
            largest,
        )
    return Comparison(Kind.AGREE, difference=max((d.equivalent for d in diffs), default=0.0), largest=largest)
