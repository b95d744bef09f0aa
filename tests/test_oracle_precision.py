"""Oracle precision (issue 15) and one bug, one bucket (issue 12).

Correct implementations must agree where the canonical form is ambiguous; real
faults must still be reported, confirmed on fresh targets, with one headline
difference in m or rad and joint names for people.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from fuzzer.execution.evaluate import Evaluator
from fuzzer.execution.history import history_of
from fuzzer.execution.oracle import compare
from fuzzer.execution.records import Comparison, Kind, Outcome, Signature, Status, describe, signature_of
from fuzzer.execution.session import RunConfig, Session
from fuzzer.execution.tolerance import Tolerance, default_tolerance
from fuzzer.input.mapping import CallError, FkCall, IkCall, call_from_json, call_to_json, mapping_for
from fuzzer.input.testcase import TestCase
from python_impl.model import ik_rotation_errors
from tests.support import KNIFE_EDGE_POSES

ROOT = Path(__file__).resolve().parents[1]
TOL = Tolerance(1e-6, 1e-6)
PLUGINS = "tests.plugins.stateful_faults"


def ok(**values: tuple[float, ...]) -> Outcome:
    return Outcome(Status.OK, values=values)


# -- 1. representation only where the canonical form is unambiguous ---------------------------------


def test_panda_finger_half_turn_is_agreement() -> None:
    """The false positive of issue 15: FK of Panda's finger at a rotation of about pi, where
    each implementation's rounding noise put w on the positive side (w >= 0 is canonical for
    both) and the tie then flipped x: q and -q, both canonical within tolerance."""
    y = math.sqrt(1.0 - 0.898**2)
    native = (-0.898, y, 0.0, 9.8e-17)
    twin = (0.898, -y, 0.0, 2.5e-17)
    c = compare(
        ok(position=(0.1, 0.2, 0.3), orientation=native), ok(position=(0.1, 0.2, 0.3), orientation=twin), TOL
    )
    assert c.kind is Kind.AGREE and c.difference < 1e-15


@pytest.mark.parametrize("w", [0.5, 0.01, 2e-6])
def test_q_minus_q_away_from_the_boundary_stays_a_representation_divergence(w: float) -> None:
    s = math.sqrt(1.0 - w * w)
    q = (s, 0.0, 0.0, w)
    c = compare(ok(orientation=q), ok(orientation=tuple(-x for x in q)), TOL)
    assert c.kind is Kind.REPRESENTATION and c.field == "orientation"
    # the headline is the rotation between them (none), in rad; the raw gap is a detail
    assert c.unit == "rad" and c.difference < 1e-6 and c.raw == pytest.approx(2 * s)


def test_a_position_one_ulp_apart_past_float64_s_resolution_is_agreement() -> None:
    """A helper's ``--no-filter`` campaign: PR2's torso at 6e12 m put pinocchio's tip at
    6000000000000.791 and KDL's at 6000000000000.79, one ulp (0.000977 m) apart, the first the
    correctly rounded value; it was a finding between correct implementations. Near the arm,
    a 2e-6 m gap stays a divergence, and so does a real gap at that magnitude."""
    quat = (0.0, 0.0, 0.0, 1.0)
    z = 6000000000000.79
    far = compare(
        ok(position=(0.1, 0.2, z), orientation=quat),
        ok(position=(0.1, 0.2, math.nextafter(z, math.inf)), orientation=quat),
        TOL,
    )
    assert far.kind is Kind.AGREE
    near = compare(
        ok(position=(0.1, 0.2, 0.3), orientation=quat),
        ok(position=(0.1, 0.2, 0.300002), orientation=quat),
        TOL,
    )
    assert near.kind is Kind.VALUE and near.field == "position"
    wrong = compare(
        ok(position=(0.1, 0.2, z), orientation=quat), ok(position=(0.1, 0.2, z + 1.0), orientation=quat), TOL
    )
    assert wrong.kind is Kind.VALUE
    huge = compare(
        ok(position=(0.0, 0.0, 1e200), orientation=quat), ok(position=(0.0, 0.0, 1.0), orientation=quat), TOL
    )
    assert huge.kind is Kind.VALUE  # the square of the gap raised OverflowError
    for odd in (math.inf, math.nan):  # no magnitude: the tolerance alone, as before
        gap = compare(
            ok(position=(odd, 0.0, 1.0), orientation=quat),
            ok(position=(1.0, 0.0, 1.0), orientation=quat),
            TOL,
        )
        assert gap.kind is Kind.VALUE


def test_continuous_joint_at_the_pi_boundary() -> None:
    near, other = math.pi - 1e-12, -math.pi + 1e-12
    a, b = ok(joint_values=(near, 0.1)), ok(joint_values=(other, 0.1))
    assert compare(a, b, TOL, continuous=(True, False)).kind is Kind.AGREE
    # not continuous: no canonical (-pi, pi] range to be ambiguous about
    assert compare(a, b, TOL, continuous=(False, False)).kind is Kind.REPRESENTATION
    # -pi is outside (-pi, pi]: not ambiguous, the pi_boundary bug of the zoo stays reported
    exact = compare(
        ok(joint_values=(math.pi, 0.1)), ok(joint_values=(-math.pi, 0.1)), TOL, continuous=(True, False)
    )
    assert exact.kind is Kind.REPRESENTATION and exact.joints == (0,)
    # away from the boundary (the wrap_positive bug): reported
    far = compare(
        ok(joint_values=(-1.0, 0.1)), ok(joint_values=(2 * math.pi - 1.0, 0.1)), TOL, continuous=(True, False)
    )
    assert far.kind is Kind.REPRESENTATION


# -- 7. one difference, with its unit; joint names ---------------------------------------------------


def test_headline_difference_has_a_unit() -> None:
    c = compare(ok(joint_values=(0.0, 0.0)), ok(joint_values=(0.0, 0.02)), TOL, prismatic=(False, True))
    assert (c.kind, c.field, c.unit) == (Kind.VALUE, "joint_values", "m")
    assert c.difference == pytest.approx(0.02)
    p = compare(ok(position=(0.0, 0.0, 0.0)), ok(position=(7e-6, 0.0, 0.0)), TOL)
    assert p.unit == "m" and p.difference == pytest.approx(7e-6)
    status = compare(ok(), Outcome(Status.FAILED), TOL)
    assert status.unit == "status" and status.difference == 0.0


def test_each_joint_is_judged_against_its_own_tolerance() -> None:
    """A prismatic joint in metres, a revolute one in radians, with different tolerances. Until
    the thirty-seventh session the field was judged against the radians for every joint: a gap
    of 2e-6 m within a 1e-5 m tolerance was a divergence naming no joint, and a gap of 5e-6 m
    beyond a 1e-6 m tolerance agreed when the radians were 1e-5."""
    loose_m = Tolerance(metres=1e-5, radians=1e-6)
    within = compare(ok(joint_values=(0.0, 0.1)), ok(joint_values=(0.0, 0.1 + 2e-6)), loose_m, (False, True))
    assert within.kind is Kind.AGREE
    tight_m = Tolerance(metres=1e-6, radians=1e-5)
    beyond = compare(ok(joint_values=(0.0, 0.1)), ok(joint_values=(0.0, 0.1 + 5e-6)), tight_m, (False, True))
    assert (beyond.kind, beyond.joints, beyond.unit) == (Kind.VALUE, (1,), "m")
    assert beyond.difference == pytest.approx(5e-6)
    # the revolute joint within its radians while the prismatic one is beyond its metres: the
    # headline is the prismatic joint's gap, not the larger number of the revolute joint
    both = compare(ok(joint_values=(0.0, 0.1)), ok(joint_values=(8e-6, 0.1 + 2e-6)), tight_m, (False, True))
    assert (both.kind, both.joints) == (Kind.VALUE, (1,)) and both.difference == pytest.approx(2e-6)
    # a whole turn on the revolute joint is a representation divergence under either tolerance
    turn = compare(ok(joint_values=(0.0, 0.1)), ok(joint_values=(2 * math.pi, 0.1)), loose_m, (False, True))
    assert (turn.kind, turn.joints) == (Kind.REPRESENTATION, (0,))


def test_a_value_divergence_reports_the_unit_and_sign_of_its_own_joint() -> None:
    """A value divergence's unit and sign flip describe the joint its headline difference is
    from. Until the thirty-eighth session they came from the joint farthest apart as numbers:
    beside a revolute joint a whole turn off (a representation), a prismatic joint 0.02 m off
    was reported as "0.02 rad", and the turn's opposite signs made the value divergence a
    sign flip (Table III's coordinates row instead of its size row)."""
    turn = -3.0 + 2 * math.pi
    mixed = compare(ok(joint_values=(-3.0, 0.1)), ok(joint_values=(turn, 0.12)), TOL, prismatic=(False, True))
    assert (mixed.kind, mixed.joints, mixed.unit, mixed.sign_flip) == (Kind.VALUE, (0, 1), "m", False)
    assert mixed.difference == pytest.approx(0.02)
    both = compare(ok(joint_values=(-3.0, 0.1)), ok(joint_values=(turn, 0.3)), TOL)
    assert (both.kind, both.unit, both.sign_flip) == (Kind.VALUE, "rad", False)
    assert both.difference == pytest.approx(0.2)
    crossing = compare(ok(joint_values=(-3.0, 0.1)), ok(joint_values=(turn, -0.1)), TOL)
    assert (crossing.kind, crossing.sign_flip) == (Kind.VALUE, True)
    # a representation alone keeps the numbers that differ: the turn's radians and signs
    alone = compare(ok(joint_values=(-3.0, 0.1)), ok(joint_values=(turn, 0.1)), TOL, prismatic=(False, True))
    assert (alone.kind, alone.unit, alone.sign_flip) == (Kind.REPRESENTATION, "rad", True)
    assert alone.raw == pytest.approx(2 * math.pi)


def test_a_representation_reports_the_difference_of_its_own_joint() -> None:
    """A representation's headline difference, unit and sign flip all describe the joint
    farthest apart as numbers. Until the forty-eighth session the difference was the largest
    gap modulo equivalence of any joint: beside a revolute joint a whole turn off, a prismatic
    joint 5e-7 m apart (within its tolerance) made the headline "5e-07 rad". An agreement's
    unit is that of its headline's joint too (it was the field's, rad for joint values)."""
    turn = -3.0 + 2 * math.pi
    a, b = ok(joint_values=(-3.0, 0.1)), ok(joint_values=(turn, 0.1 + 5e-7))
    c = compare(a, b, TOL, prismatic=(False, True))
    assert (c.kind, c.joints, c.unit, c.sign_flip) == (Kind.REPRESENTATION, (0,), "rad", True)
    assert c.difference < 1e-12 and c.raw == pytest.approx(2 * math.pi)
    # the same pair with both joints revolute: the headline is still the turned joint's
    revolute = compare(a, b, TOL)
    assert (revolute.kind, revolute.joints) == (Kind.REPRESENTATION, (0,)) and revolute.difference < 1e-12
    # an agreement's headline stays the largest gap modulo equivalence
    agree = compare(
        ok(joint_values=(-3.0, 0.1)), ok(joint_values=(-3.0, 0.1 + 5e-7)), TOL, prismatic=(False, True)
    )
    assert (agree.kind, agree.unit) == (Kind.AGREE, "m") and agree.difference == pytest.approx(5e-7)


def test_value_field_precedence_is_stable() -> None:
    """joint values, then position, then orientation: the same bug lands on one field."""
    q1, q2 = (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, math.sin(0.1), math.cos(0.1))
    small_pos = compare(
        ok(position=(0, 0, 0), orientation=q1), ok(position=(2e-6, 0, 0), orientation=q2), TOL
    )
    big_pos = compare(ok(position=(0, 0, 0), orientation=q1), ok(position=(1.0, 0, 0), orientation=q2), TOL)
    assert small_pos.field == big_pos.field == "position"


def test_describe_uses_joint_names_and_units() -> None:
    text = describe(
        "value", "joint_values", 0.0123, "rad", (1, 4), ("joint_1", "joint_2", "j3", "j4", "joint_5")
    )
    assert text == "value on joint_values (joint_2, joint_5), difference 0.0123 rad"
    assert describe("status", "status", 0.0, "status") == "status on status"
    c = Comparison(Kind.PROPERTY, "joint_limits", 2.64, joints=(0,), unit="rad", target="twin")
    assert c.headline(("joint_1",)) == "property on joint_limits of twin (joint_1), difference 2.64 rad"


# -- 6. one bug, one bucket -----------------------------------------------------------------------------


def test_signature_ignores_size_and_sign_of_the_difference() -> None:
    a = ok(joint_values=(0.0, 0.0, 0.0))
    small = compare(a, ok(joint_values=(0.0, 1e-4, 0.0)), TOL)
    large = compare(a, ok(joint_values=(0.0, 0.0, -0.5)), TOL)
    assert small.bucket != large.bucket and small.joints != large.joints
    types = ("revolute", "revolute", "revolute")
    keys = {signature_of("move", a, a, c, types).key for c in (small, large)}
    assert len(keys) == 1
    other = signature_of("move", a, a, large, ("revolute", "revolute", "continuous"))
    assert other.key not in keys  # a continuous joint is another problem
    assert other.joint_types == ("continuous",)


def test_old_signatures_still_read() -> None:
    old = {
        "op": "fk",
        "outcome_a": "ok",
        "outcome_b": "ok",
        "kind": "value",
        "field": "position",
        "sign_flip": False,
        "bucket": -3,
        "joints": [],
        "key": "9aacff7e3a3a",
    }
    sig = Signature.from_json(old)
    assert sig == Signature("fk", "ok", "ok", "value", "position")
    with pytest.raises(TypeError):
        Signature.from_json({**old, "kind": 3})


# -- 3. per-target IK properties ------------------------------------------------------------------------


def session(targets: tuple[str, str], op: str, robot: str = "probot_anno") -> Session:
    return Session.open(RunConfig(op=op, robot=robot, targets=targets, tolerance=default_tolerance(op)))


def evaluator(s: Session) -> Evaluator:
    ev = s.evaluator()
    assert isinstance(ev, Evaluator)
    return ev


def ik_case(position: tuple[float, ...], orientation: tuple[float, ...]) -> TestCase:
    message = {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "pose": {
            "position": dict(zip("xyz", position, strict=True)),
            "orientation": dict(zip("xyzw", orientation, strict=True)),
        },
    }
    return TestCase("geometry_msgs/PoseStamped", message)


def reachable_pose(s: Session, q: list[float]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    pose = s.reference.forward_kinematics(q)
    return tuple(pose.position), tuple(pose.orientation)


def test_ik_success_outside_the_limits_is_reported_naming_the_target() -> None:
    s = session(("native", f"{PLUGINS}:ik_out_of_limits"), "ik")
    ev = evaluator(s)
    result = ev.evaluate(ik_case(*reachable_pose(s, [-0.503, 0.3, 0.4, 0.2, 0.5, 0.1])))
    assert result.outcomes[1].values["joint_values"][0] == pytest.approx(-0.503 + 2 * math.pi, abs=1e-3)
    native, twin = result.outcomes
    assert compare(native, twin, ev.tolerance, op="ik").kind is Kind.AGREE  # same pose
    c = result.comparison
    assert (c.kind, c.field, c.target, c.joints, c.unit) == (
        Kind.PROPERTY,
        "joint_limits",
        f"{PLUGINS}:ik_out_of_limits",
        (0,),
        "rad",
    )
    assert c.difference == pytest.approx(-0.503 + 2 * math.pi - 3.1416, abs=1e-3)
    assert result.signature is not None and result.signature.target == c.target


def test_ik_of_correct_targets_has_no_property_violation() -> None:
    s = session(("native", "python"), "ik")
    ev = evaluator(s)
    for q in ([0.2, 0.3, 0.4, 0.2, 0.5, 0.1], [-1.0, 0.5, 1.0, -0.4, 1.2, 2.0]):
        assert not ev.evaluate(ik_case(*reachable_pose(s, q))).divergent


# -- 4. ill-conditioning judged for what it is ----------------------------------------------------------

# A requested orientation a half turn from where home puts the tool (found by
# rotating home's orientation by pi about random axes: 33 of 137 such targets at
# 1e-9 or less from pi split native and the twin, none of 163 at 1e-6 or more).
DEAD_ZONE_POSE = (
    (0.22885535000000004, -1.471118577552194e-06, 0.4319999999972982),
    (-0.7425064239734345, 0.6575042177781192, 0.12795473402850951, 1.3636948769302101e-06),
)


def test_kdl_rotation_dead_zone_is_a_known_limitation() -> None:
    s = session(("native", "python"), "ik")
    result = evaluator(s).evaluate(ik_case(*DEAD_ZONE_POSE))
    assert {o.status for o in result.outcomes} == {Status.OK, Status.FAILED}
    assert result.comparison.kind is Kind.KNOWN_LIMITATION


# Reachable UR5 targets (FK of random joint vectors) on which IK from home (all zeros, singular)
# splits native and the twin. Newton-Raphson's first step from home clamps most joints at their
# limits, so a 1e-9 move of the seed changes neither answer; a 1e-9 m move of the target does.
# Which of them split depends on the CPU's BLAS kernels (numpy's OpenBLAS picks them at run
# time): the first two were found on an Intel Xeon, where both split; on an AMD EPYC the first
# one fails on both targets, and the third (seed 0, draw 144 of uniform joint vectors) splits.
UR5_CLAMPED_POSES = (
    (
        (-0.011415478125947485, 0.25515797629826104, -0.5071837507834365),
        (-0.7127701955068181, 0.5126616643561172, 0.33949321407230104, 0.3374626259241863),
    ),
    (
        (-0.25060921321852114, -0.14157702576289524, -0.2585842756225812),
        (-0.489579913557609, -0.6432193202664225, -0.5526389967928211, 0.20290528209179254),
    ),
    (
        (-0.20262758259464564, -0.6161848175383535, -0.3844908567405429),
        (-0.32686268637020405, -0.580105019686674, 0.6077722945852071, 0.4327259968245602),
    ),
)


def test_an_ik_status_flip_that_only_a_target_nudge_shows_is_ill_conditioned(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Every clamped pose that splits the two targets on this machine is ill-conditioned, and
    at least one is so only through the goal nudges: without them it stays a divergence."""
    from fuzzer.execution import ik_check

    def judged(pose: tuple[tuple[float, ...], tuple[float, ...]]) -> tuple[set[Status], Kind]:
        result = evaluator(session(("native", "python"), "ik", robot="ur5")).evaluate(ik_case(*pose))
        return {o.status for o in result.outcomes}, result.comparison.kind

    splits = [pose for pose in UR5_CLAMPED_POSES if judged(pose)[0] == {Status.OK, Status.FAILED}]
    assert splits, "no clamped UR5 pose splits native and the twin here"
    assert all(judged(pose)[1] is Kind.ILL_CONDITIONED for pose in splits)
    monkeypatch.setattr(ik_check, "GOAL_NUDGES", ())
    assert any(judged(pose)[1] is Kind.STATUS for pose in splits)


# UR5's home pose turned a half turn about the base (aligned inputs find it): clamped iterates
# meet rotation errors of exactly pi, whose axis sign KDL and the twin pick differently; the
# twin's answer is a coin flip under a 1e-9 rad turn of the target (22 of 50), none under a move
# of its position. From home, native converges and the twin does not.
UR5_HALF_TURN_POSES = (
    (
        (-0.817250000000927, -0.10915000000000011, -0.005490999995998461),
        (-0.7071067811865475, -0.7071067811865476, 3.3161611206572236e-12, 3.6086531637446316e-12),
    ),
    (
        (-0.8172500000008878, -0.10915000000000011, -0.005490999996336315),
        (-0.7071067811865475, -0.7071068021865475, 3.1698285035078956e-12, 3.462320546595304e-12),
    ),
)


@pytest.mark.parametrize("pose", UR5_HALF_TURN_POSES)
def test_an_ik_status_flip_that_only_a_turn_of_the_target_shows_is_ill_conditioned(
    pose: tuple[tuple[float, ...], tuple[float, ...]],
) -> None:
    result = evaluator(session(("native", "python"), "ik", robot="ur5")).evaluate(ik_case(*pose))
    assert [o.status for o in result.outcomes] == [Status.OK, Status.FAILED]
    assert result.comparison.kind is Kind.ILL_CONDITIONED


# control@ik/ur5's false positive (seed 2 of its first run): a target on the base axis with an
# unnormalized quaternion. Native fails robustly, the twin converges; no seed move or position
# move flips either, a turn of the target flips the twin 18% of the time. Newton-Raphson's
# iterate 11 meets a rotation error of pi - 5e-14, where KDL's diff and the twin's logarithm
# pick opposite axes: KDL's half-turn dead zone, met on the way rather than at the seed.
UR5_ITERATE_HALF_TURN_POSE = (
    (-1.0873020135321469e-12, 0.10915, 0.21655900000000006),
    (3.14159268759, 0.7071067811865476, -3.462320546595305e-12, 3.462407142200927e-12),
)


def test_an_ik_status_split_after_an_iterate_meets_a_half_turn_is_a_known_limitation() -> None:
    s = session(("native", "python"), "ik", robot="ur5")
    result = evaluator(s).evaluate(ik_case(*UR5_ITERATE_HALF_TURN_POSE))
    assert [o.status for o in result.outcomes] == [Status.FAILED, Status.OK]
    assert result.comparison.kind is Kind.KNOWN_LIMITATION
    errors = ik_rotation_errors(s.runners[1].model, UR5_ITERATE_HALF_TURN_POSE)
    assert max(errors[1:]) > math.pi - 1e-6 > errors[0]  # not at the seed: on the way


def test_the_iterate_rule_needs_an_iterate_at_a_half_turn() -> None:
    """The rule is not a blanket pass for status splits: the clamped UR5 splits, judged
    ill-conditioned by the nudges, meet no half turn on the way."""
    from fuzzer.execution.ik_check import meets_half_turn

    s = session(("native", "python"), "ik", robot="ur5")
    ev = evaluator(s)
    home = s.runners[0].home
    assert meets_half_turn(ev.replay, IkCall(*UR5_ITERATE_HALF_TURN_POSE), home)
    for pose in UR5_CLAMPED_POSES:
        assert not meets_half_turn(ev.replay, IkCall(*pose), home)


# The controls' two false positives on 312c459 (benchmarks/results/control-fp-312c459/): a pose
# just out of reach with joints at a limit or at pi. Both targets stall at one configuration
# about IK_EPS short; KDL's largest error-twist component ends just inside IK_EPS (9.2e-7 and
# 9.5e-7 m), the twin's just outside (1.07e-6 and 1.10e-6 m). No seed or goal nudge of the
# judge moves the stall point; a goal move of 5e-7 m gives both the same status. Whether a
# pose splits the two depends on the CPU's rounding (found on an AMD EPYC).
def judged_pose(
    robot: str, position: tuple[float, ...], orientation: tuple[float, ...]
) -> tuple[list[Status], Kind]:
    """The two targets' statuses and the oracle's verdict on one IK pose, from the default seed."""
    result = evaluator(session(("native", "python"), "ik", robot=robot)).evaluate(
        ik_case(position, orientation)
    )
    return [o.status for o in result.outcomes], result.comparison.kind


@pytest.mark.parametrize("robot,position,orientation", KNIFE_EDGE_POSES, ids=[p[0] for p in KNIFE_EDGE_POSES])
def test_a_status_split_on_the_convergence_criterion_is_ill_conditioned(
    robot: str, position: tuple[float, ...], orientation: tuple[float, ...], monkeypatch: pytest.MonkeyPatch
) -> None:
    from fuzzer.execution import ik_check

    def judged() -> tuple[list[Status], Kind]:
        return judged_pose(robot, position, orientation)

    statuses, kind = judged()
    if statuses != [Status.OK, Status.FAILED]:
        pytest.skip(f"{robot}'s pose does not split the targets on this CPU ({statuses})")
    assert kind is Kind.ILL_CONDITIONED  # the knife edge (step 3) is judged first
    monkeypatch.setattr(ik_check, "at_knife_edge", lambda call, outcomes: False)
    # without it, the twin with KDL's small-rotation dead zone (step 6) stalls where KDL does
    assert judged() == (statuses, Kind.KNOWN_LIMITATION), "the dead-zone re-run explains it too"
    monkeypatch.setattr(ik_check, "agree_in_kdl_dead_zone", lambda *args: False)
    assert judged() == (statuses, Kind.STATUS), "only those two rules explain it"


# control@ik/ur5, seed 9, on 02efcff (the controls run of the forty-seventh session): an
# unnormalized quaternion, a pose reached with the elbow 4e-4 rad inside its pi limit. From
# the default seed both solvers take the same path up to rounding until the rotation error
# left is about 4e-7 rad: KDL's diff reports none there (its dead zone), the twin's logarithm
# does, and through the near-singular Jacobian (smallest singular value 1.6e-4) the twin's
# step overshoots the elbow's limit; clamped there, it stalls 1.3e-4 m short. KDL converges.
DEAD_ZONE_SPLIT = (
    "ur5",
    (0.032750000000946515, 0.10915, -0.005490999999920754),
    (-61.0, 0.7071067811865475, -0.0010302689771379031, 3.681819472319296e-12),
)


def test_a_status_split_from_kdls_small_rotation_dead_zone_is_a_known_limitation(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from fuzzer.execution import ik_check

    robot, position, orientation = DEAD_ZONE_SPLIT

    def judged() -> tuple[list[Status], Kind]:
        return judged_pose(robot, position, orientation)

    statuses, kind = judged()
    if statuses != [Status.OK, Status.FAILED]:
        pytest.skip(f"the pose does not split the targets on this CPU ({statuses})")
    assert kind is Kind.KNOWN_LIMITATION
    monkeypatch.setattr(ik_check, "agree_in_kdl_dead_zone", lambda *args: False)
    assert judged() == (statuses, Kind.STATUS), "only the dead-zone re-run explains it"


def test_the_dead_zone_rerun_needs_the_targets_to_agree_after_it() -> None:
    from fuzzer.execution.ik_check import agree_in_kdl_dead_zone

    call = IkCall((0.3, 0.0, 0.5), (0.0, 0.0, 0.0, 1.0))
    ok, failed = Outcome(Status.OK), Outcome(Status.FAILED)
    agree = Comparison(Kind.AGREE)

    def rerun(pair: tuple[Outcome, ...]):  # type: ignore[no-untyped-def]
        return lambda c, seeds, runners: pair

    homes = ((0.0,), (0.0,))
    assert agree_in_kdl_dead_zone(call, homes, (), rerun((ok, ok)), lambda pair: agree)
    assert not agree_in_kdl_dead_zone(call, homes, (), rerun((ok, failed)), lambda pair: agree)
    value = Comparison(Kind.VALUE, "position", 1.0)
    assert not agree_in_kdl_dead_zone(call, homes, (), rerun((ok, ok)), lambda pair: value)
    explained = Comparison(Kind.ILL_CONDITIONED, "position", 1.0)
    assert agree_in_kdl_dead_zone(call, homes, (), rerun((ok, ok)), lambda pair: explained)


def test_the_knife_edge_needs_every_last_iterate_within_the_solvers_tolerance() -> None:
    from fuzzer.execution.ik_check import at_knife_edge
    from fuzzer.execution.oracle import IK_RESIDUAL

    call = IkCall((0.3, 0.0, 0.5), (0.0, 0.0, 0.0, 2.0))  # an unnormalized quaternion: the identity

    def reached(dx: float, turn: float = 0.0, status: Status = Status.FAILED) -> Outcome:
        half = turn / 2.0
        values = {"position": (0.3 + dx, 0.0, 0.5), "orientation": (math.sin(half), 0.0, 0.0, math.cos(half))}
        return Outcome(status, values=values)

    inside = 0.9 * IK_RESIDUAL
    assert at_knife_edge(call, (reached(-inside, status=Status.OK), reached(inside)))
    assert at_knife_edge(call, (reached(0.0, status=Status.OK), reached(0.0, turn=inside)))
    assert not at_knife_edge(call, (reached(0.0, status=Status.OK), reached(1.1 * IK_RESIDUAL)))
    assert not at_knife_edge(call, (reached(0.0, status=Status.OK), reached(0.0, turn=1.1 * IK_RESIDUAL)))
    assert not at_knife_edge(call, (reached(1.1 * IK_RESIDUAL, status=Status.OK), reached(0.0)))
    assert not at_knife_edge(call, (reached(0.0, status=Status.OK), reached(math.nan)))
    no_pose = Outcome(Status.FAILED, values={"joint_values": (0.0,) * 6})
    assert not at_knife_edge(call, (reached(0.0, status=Status.OK), no_pose))
    no_turn = Outcome(Status.FAILED, values={"position": (0.3, 0.0, 0.5)})
    assert not at_knife_edge(call, (reached(0.0, status=Status.OK), no_turn)), (
        "a pose asks for the orientation"
    )
    position_only = IkCall((0.3, 0.0, 0.5), ())
    assert at_knife_edge(position_only, (reached(0.0, status=Status.OK), no_turn))
    assert not at_knife_edge(position_only, (reached(0.0, status=Status.OK), reached(1.1 * IK_RESIDUAL)))


def test_a_success_claimed_without_reaching_the_pose_is_not_masked_as_ill_conditioned() -> None:
    """Native's status flips under a target nudge here, so the status split is no finding; the
    faulty twin's success, without reaching the pose, still is (its own property)."""
    pose = (
        (-0.08812751212201637, 0.11269857479629511, 0.13261871684559495),
        (-0.9282298575400337, 0.3017013886489345, -0.03236728050005287, 0.2152160839982558),
    )
    misread = "benchmarks.zoo.bugs:ik_status_misread"
    result = evaluator(session(("native", misread), "ik", robot="ur5")).evaluate(ik_case(*pose))
    assert [o.status for o in result.outcomes] == [Status.FAILED, Status.OK]
    c = result.comparison
    assert (c.kind, c.field, c.target) == (Kind.PROPERTY, "residual", misread)


def test_a_different_default_seed_is_not_masked_as_ill_conditioned() -> None:
    s = session(("python", f"{PLUGINS}:ik_other_default_seed"), "ik")
    ev = evaluator(s)
    kinds = []
    for i in range(40):
        q = [0.9 * math.sin(1.7 * i + j) for j in range(6)]
        pose = reachable_pose(s, q)
        result = ev.evaluate(ik_case(*pose))
        if result.divergent:
            kinds.append(result.comparison.kind)
    assert kinds and set(kinds) <= {Kind.STATUS}


# -- 2. confirmed on fresh targets; state-dependent divergences replay ---------------------------------


def fk_case(q: list[float]) -> TestCase:
    message = {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "name": [],
        "position": q,
        "velocity": [],
        "effort": [],
    }
    return TestCase("sensor_msgs/JointState", message)


def test_a_stateful_fault_is_state_dependent_and_replays_from_its_history() -> None:
    s = session(("native", f"{PLUGINS}:fk_cache"), "fk")
    ev = evaluator(s)
    first = ev.evaluate(fk_case([0.1, 0.2, 0.3, 0.4, 0.5, 0.6]))
    assert not first.divergent  # a fresh cache is right
    second = ev.evaluate(fk_case([0.12, 0.2, 0.3, 0.4, 0.5, 0.6]))  # within the cache radius
    assert second.comparison.kind is Kind.STATE_DEPENDENT and second.history
    assert second.signature is not None
    # the history is data: it round-trips through JSON and replays on fresh targets
    stored = json.loads(json.dumps({"history": list(second.history)}))
    again = evaluator(session(("native", f"{PLUGINS}:fk_cache"), "fk")).evaluate(
        fk_case([0.12, 0.2, 0.3, 0.4, 0.5, 0.6]), history=history_of(stored)
    )
    assert again.signature == second.signature
    # without its history the same input agrees: the history is what reproduces it
    alone = evaluator(session(("native", f"{PLUGINS}:fk_cache"), "fk")).evaluate(
        fk_case([0.12, 0.2, 0.3, 0.4, 0.5, 0.6]), history=[]
    )
    assert not alone.divergent


def test_stored_calls_are_validated_data() -> None:
    call = IkCall((0.1, 0.2, 0.3), (0.0, 0.0, 0.0, 1.0), "link_6")
    assert call_from_json(json.loads(json.dumps(call_to_json(call, (0.0,) * 6)))) == (call, (0.0,) * 6)
    assert call_from_json({"kind": "FkCall", "joint_values": [1, 2]}) == (FkCall((1.0, 2.0)), None)
    bad: Any
    for bad in (
        [],
        {"kind": "os.system"},
        {"kind": "FkCall", "joint_values": "rm -rf"},
        {"kind": "MoveCall", "names": [1], "positions": []},
        {"kind": "IkCall", "position": [0, 0, 0], "orientation": [0, 0, 0, 1], "link": 3},
    ):
        with pytest.raises(CallError):
            call_from_json(bad)
    with pytest.raises(ValueError, match="history"):
        history_of({"history": {"kind": "FkCall"}})


def run_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(ROOT / "fuzz_diff.py"), *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


def test_a_campaign_reports_the_stateful_fault_and_its_file_replays(tmp_path: Path) -> None:
    artifacts = tmp_path / "artifacts"
    done = run_cli(
        str(tmp_path / "corpus"),
        "-runs=600",
        "-seed=1",
        "--op=fk",
        f"--artifacts={artifacts}",
        f"--targets=native,{PLUGINS}:fk_cache",
        "--no-progress",
    )
    assert done.returncode in (0, 1), done.stderr[-2000:]
    sidecars: list[tuple[Path, dict[str, Any]]] = []
    for p in sorted(artifacts.glob("crash-*.json")):
        sidecars.append((p, json.loads(p.read_text())))
    stateful = [(p, d) for p, d in sidecars if d["signature"]["kind"] == "state_dependent"]
    assert stateful, [d["signature"]["kind"] for _, d in sidecars]
    path, sidecar = stateful[0]
    assert 0 < len(sidecar["history"]) <= 32
    crash = path.with_suffix("")
    replayed = run_cli(str(crash), f"--targets=native,{PLUGINS}:fk_cache")
    assert "still diverges (same signature)" in replayed.stdout, replayed.stdout + replayed.stderr


def test_mapping_is_used_for_fk_cases() -> None:
    assert mapping_for("fk", "sensor_msgs/JointState")(fk_case([0.0] * 6).message) == FkCall((0.0,) * 6)


def test_fk_of_a_chain_without_joint_variables_agrees() -> None:
    """Found by the fk control on baxter (its default chain has no joint variable): the twin
    raised IndexError on ``forward_kinematics([])`` where native returns the identity."""
    s = session(("native", "python"), "fk", robot="baxter")
    assert s.reference.dof == 0
    result = evaluator(s).evaluate(fk_case([]))
    assert result.verdict == "evaluated" and not result.divergent


def test_status_signatures_name_the_problem_not_the_side_effect() -> None:
    """silent_clamp: native rejects, the twin then moves (ok) or fails planning (failed):
    one problem, one key; ok vs failed is one problem whichever target failed."""
    rejected = Outcome(Status.REJECTED, "OutOfBoundsError", 30)
    status = Comparison(Kind.STATUS, "status")
    after_ok = signature_of("move", rejected, ok(), status)
    after_failed = signature_of("move", rejected, Outcome(Status.FAILED), status)
    assert after_ok == after_failed and after_ok.outcome_b == "completed"
    assert signature_of("ik", ok(), Outcome(Status.FAILED), status) == signature_of(
        "ik", Outcome(Status.FAILED), ok(), status
    )
    other_error = signature_of("move", Outcome(Status.REJECTED, "InvalidArgumentError", 2), ok(), status)
    assert other_error != after_ok


def test_bench_controls_cover_every_zoo_configuration_and_report_false_positives() -> None:
    from benchmarks import bench_zoo
    from benchmarks.zoo import CONTROLS, ZOO
    from robot_api.robots import DEFAULT_ROBOT, known_robots

    configs = {(c.op, c.robot, c.tip_link) for c in CONTROLS}
    assert {(b.op, b.robot, b.tip_link) for b in ZOO} <= configs
    assert {("fk", r, None) for r in known_robots()} <= configs and ("ik", DEFAULT_ROBOT, None) in configs
    assert {("scenario", "ur5", None), ("ik", "ur5", None)} <= configs
    assert all(c.target == "benchmarks.zoo.bugs:control" and c.is_control for c in CONTROLS)

    def run(bug: str, divergences: int, signatures: int = 0) -> dict[str, Any]:
        return {
            "bug": bug,
            "engine": "full",
            "seed": 1,
            "budget": 10.0,
            "detected_at": 1.0 if divergences else None,
            "signatures": signatures,
            "executions": 100,
            "elapsed": 30.0,
            "op": "fk",
            "returncode": 0,
            "divergences": divergences,
            "replayed": signatures,
            "replay_same": signatures,
            "replay_misses": [],
        }

    runs = [
        run(CONTROLS[0].name, 0),
        run(CONTROLS[1].name, 6),
        run("wrap_positive", 40, 1),
        run("silent_clamp", 9, 3),
    ]
    bugs = [CONTROLS[0].name, CONTROLS[1].name, "wrap_positive", "silent_clamp"]
    result: dict[str, Any] = {
        "mode": "t",
        "bugs": bugs,
        "engines": ["full"],
        "seeds": 1,
        "budget": 10.0,
        "jobs": 1,
        "cpus": 2,
        "machine": "x",
        "command": "c",
        "runs": runs,
    }
    result["cells"] = bench_zoo.summarize([bench_zoo.Run(**r) for r in runs], ("full",), tuple(bugs))
    text = bench_zoo.markdown(result)
    assert f"| {CONTROLS[1].name} | {CONTROLS[1].op} | 1/1 | 12.0 |" in text
    assert "1 of 2 control runs reported a divergence; 6 divergences in 1.0 min (6.0 per minute)" in text
    assert "median 2, max 3 (silent_clamp) over 2 bugs" in text
    assert "Replay fidelity: 4 of 4 crash files (100%)" in text


def test_panda_finger_half_turn_agrees_on_the_real_targets() -> None:
    """The same false positive on the real targets: each flips its own rounding noise of w."""
    s = Session.open(
        RunConfig(op="fk", robot="panda", tip_link="panda_rightfinger", tolerance=default_tolerance("fk"))
    )
    q = [math.pi / 4, math.pi / 2, math.pi / 4, 0.0, 0.5, -math.pi / 2, 0.0, 0.5]
    result = evaluator(s).evaluate(fk_case(q))
    native, twin = (o.values["orientation"] for o in result.outcomes)
    assert abs(native[3]) < 1e-15 and abs(twin[3]) < 1e-15
    assert max(abs(x + y) for x, y in zip(native, twin, strict=True)) < 1e-12  # q and -q
    assert not result.divergent and result.comparison.kind is Kind.AGREE


def test_the_summary_shows_the_largest_value_difference_with_its_unit(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Never a representation gap, never an agreement's rounding: the largest headline
    difference of a value divergence, with its unit."""
    from fuzzer import reporting
    from fuzzer.selection.state import Stats

    stats = Stats(execs=10)
    reporting.summary(stats, 0, "a", ["c"], [])
    assert "largest value difference: none (no value divergence)" in capsys.readouterr().err
    stats.max_difference, stats.max_difference_unit = 7e-3, "m"
    reporting.summary(stats, 0, "a", ["c"], [])
    assert "largest value difference: 0.007 m" in capsys.readouterr().err
