"""The oracle: statuses first, then values modulo true equivalence, every divergence classified."""

from __future__ import annotations

import math

import pytest

from fuzzer.execution.oracle import bucket, compare
from fuzzer.execution.records import Kind, Outcome, Status, signature_of
from fuzzer.execution.tolerance import Tolerance

TOL = Tolerance(1e-6, 1e-6)
Q = (0.1, 0.2, 0.3, math.sqrt(1 - 0.14))


def ok(**values: tuple[float, ...]) -> Outcome:
    return Outcome(Status.OK, values=values)


def rejected(error: str = "OutOfBoundsError", code: int = 30) -> Outcome:
    return Outcome(Status.REJECTED, error, code, "msg")


def test_identical_outcomes_agree() -> None:
    a = ok(joint_values=(0.1, 0.2), position=(1.0, 2.0, 3.0), orientation=Q)
    c = compare(a, a, TOL)
    assert c.kind is Kind.AGREE and not c.divergent and c.largest == 0.0


def test_differences_within_tolerance_agree() -> None:
    a = ok(position=(1.0, 2.0, 3.0))
    b = ok(position=(1.0 + 5e-7, 2.0, 3.0))
    assert compare(a, b, TOL).kind is Kind.AGREE
    assert compare(a, b, Tolerance(1e-7, 1e-7)).kind is Kind.VALUE


def test_status_divergences_compare_class_and_code() -> None:
    assert compare(ok(), rejected(), TOL).kind is Kind.STATUS
    assert (
        compare(rejected("OutOfBoundsError", 30), rejected("InvalidInputError", 11), TOL).kind is Kind.STATUS
    )
    assert (
        compare(rejected("InvalidInputError", 10), rejected("InvalidInputError", 11), TOL).kind is Kind.STATUS
    )
    assert compare(rejected(), rejected(), TOL).kind is Kind.AGREE
    assert compare(ok(), Outcome(Status.FAILED), TOL).kind is Kind.STATUS


def test_a_crash_is_its_own_kind() -> None:
    crash = Outcome(Status.CRASHED, "TypeError", None, "boom")
    assert compare(crash, ok(), TOL).kind is Kind.CRASH
    assert compare(crash, crash, TOL).kind is Kind.CRASH


def test_quaternion_sign_is_representation_not_value() -> None:
    minus = tuple(-c for c in Q)
    c = compare(ok(orientation=Q), ok(orientation=minus), TOL)
    assert c.kind is Kind.REPRESENTATION and c.field == "orientation" and c.sign_flip


def test_a_real_rotation_difference_is_a_value_divergence() -> None:
    a = ok(orientation=(0.0, 0.0, 0.0, 1.0))
    b = ok(orientation=(0.0, 0.0, math.sin(0.005), math.cos(0.005)))  # 0.01 rad about z
    c = compare(a, b, TOL)
    assert c.kind is Kind.VALUE and c.field == "orientation"
    assert c.difference == pytest.approx(0.01, rel=1e-9) and c.bucket == -2


def test_continuous_wrap_is_the_papers_positive_and_negative_inconsistency() -> None:
    a = ok(joint_values=(4.0, 0.5))
    b = ok(joint_values=(4.0 - 2 * math.pi, 0.5))
    c = compare(a, b, TOL)
    assert c.kind is Kind.REPRESENTATION and c.field == "joint_values"
    # the headline difference is the one modulo equivalence (same angle: 0 rad); the 2pi gap
    # as numbers is a detail (raw), never the headline (issue 12: one difference, with its unit)
    assert c.joints == (0,) and c.sign_flip and c.unit == "rad"
    assert c.difference == 0.0 and c.raw == pytest.approx(2 * math.pi)


def test_prismatic_joints_are_not_periodic() -> None:
    a = ok(joint_values=(0.0, 1.0))
    b = ok(joint_values=(0.0, 1.0 + 2 * math.pi))
    assert compare(a, b, TOL, prismatic=(False, False)).kind is Kind.REPRESENTATION
    c = compare(a, b, TOL, prismatic=(False, True))
    assert c.kind is Kind.VALUE and c.joints == (1,)


def test_value_divergence_reports_the_worst_field_and_joints() -> None:
    a = ok(joint_values=(0.0, 0.0, 0.0), position=(0.0, 0.0, 0.0))
    b = ok(joint_values=(0.0, 0.02, -0.5), position=(1e-3, 0.0, 0.0))
    c = compare(a, b, TOL)
    assert c.kind is Kind.VALUE and c.field == "joint_values"
    assert c.joints == (1, 2) and c.difference == pytest.approx(0.5)
    assert c.largest == pytest.approx(0.5)


def test_ik_compares_reached_poses_not_joint_vectors() -> None:
    a = ok(joint_values=(1.0, 2.0), position=(0.1, 0.2, 0.3), orientation=Q)
    b = ok(joint_values=(-1.0, 0.5), position=(0.1, 0.2, 0.3), orientation=Q)
    assert compare(a, b, TOL, op="ik").kind is Kind.AGREE
    assert compare(a, b, TOL, op="move").kind is Kind.VALUE
    failed_a = Outcome(Status.FAILED, values={"position": (0.0, 0.0, 0.0)})
    failed_b = Outcome(Status.FAILED, values={"position": (5.0, 0.0, 0.0)})
    assert compare(failed_a, failed_b, TOL, op="ik").kind is Kind.AGREE


def test_length_mismatch_and_non_finite_values_are_value_divergences() -> None:
    assert compare(ok(joint_values=(0.0,)), ok(joint_values=(0.0, 0.0)), TOL).kind is Kind.VALUE
    c = compare(ok(position=(math.nan, 0.0, 0.0)), ok(position=(0.0, 0.0, 0.0)), TOL)
    assert c.kind is Kind.VALUE and c.difference == math.inf


def test_the_same_non_finite_values_on_both_sides_agree() -> None:
    """Two targets that give the same NaN or infinity do not differ (a URDF whose 1e308 m
    origins overflow): each field is judged on its own, and the one that differs is named."""
    nan_pose = ok(joint_values=(math.nan, 0.0), position=(math.nan,) * 3, orientation=(math.nan,) * 4)
    assert compare(nan_pose, nan_pose, TOL).kind is Kind.AGREE
    far = ok(position=(math.inf, 0.0, 0.0), orientation=(0.0, 0.0, 0.0, 1.0))
    assert compare(far, far, TOL).kind is Kind.AGREE
    poisoned = ok(position=(math.inf, 0.0, 0.0), orientation=(math.nan,) * 4)
    c = compare(far, poisoned, TOL)
    assert c.kind is Kind.VALUE and c.field == "orientation" and c.difference == math.inf
    c = compare(ok(position=(math.inf, 0.0, 0.0)), ok(position=(-math.inf, 0.0, 0.0)), TOL)
    assert c.kind is Kind.VALUE and c.field == "position"


@pytest.mark.parametrize(
    ("difference", "expected"),
    [(0.0, -99), (5e-7, -7), (1e-2, -2), (0.05, -2), (3.0, 0), (1e9, 3), (1e-30, -16)],
)
def test_bucket(difference: float, expected: int) -> None:
    assert bucket(difference) == expected


def test_tolerance_parsing() -> None:
    assert Tolerance.parse("1e-5") == Tolerance(1e-5, 1e-5)
    assert Tolerance.parse("m=1e-4,rad=1e-6") == Tolerance(1e-4, 1e-6)
    assert Tolerance.parse("rad=2e-6") == Tolerance(1e-6, 2e-6)
    for bad in ("0", "-1e-6", "nan", "inf", "x", "deg=1", "m=", "m=abc"):
        with pytest.raises(ValueError):
            Tolerance.parse(bad)
    # a part left out or given twice was the defaults or the last value, silently
    for bad, says in (("", "an empty part"), (",", "an empty part"), ("1e-6,", "an empty part"),
                      ("m=1e-5,,rad=1e-6", "an empty part"), ("m=1e-5,m=1e-6", "m given twice")):  # fmt: skip
        with pytest.raises(ValueError, match=says):
            Tolerance.parse(bad)


def test_signatures_are_stable_and_discriminating() -> None:
    a, b = ok(joint_values=(4.0,)), ok(joint_values=(4.0 - 2 * math.pi,))
    c = compare(a, b, TOL)
    s1, s2 = signature_of("move", a, b, c), signature_of("move", a, b, c)
    assert s1 == s2 and s1.key == s2.key and len(s1.key) == 12
    assert signature_of("fk", a, b, c).key != s1.key
    assert type(s1).from_json(s1.to_json()) == s1
