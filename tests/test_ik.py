"""Inverse kinematics: round trips, limits, determinism, native vs twin."""

from __future__ import annotations

import math

import numpy as np
import pytest

import native
import python_impl
from python_impl.model import ik_rotation_errors
from robot_api import ErrorCode, IKStatus, InvalidInputError
from robot_api.constants import IK_EPS
from robot_api.records import JointType, Pose
from tests.support import IMPLEMENTATIONS, ROOT, robot_id, robot_path, sample_configurations

IK_ROBOTS = [("probot_anno", None), ("ur5", None), ("panda", None), ("kinova", None), ("xarm7", None)]
N = 300
# Convergence means every error-twist component is within IK_EPS, so the pose
# error is at most sqrt(3) * IK_EPS in position (m) and in orientation (rad).
POSE_TOL = math.sqrt(3) * IK_EPS * 1.01


def rotation_distance(a: Pose, b: Pose) -> float:
    dot = abs(float(np.dot(a.orientation, b.orientation)))
    return 2.0 * math.acos(min(1.0, dot))


def within_limits(model, values) -> bool:  # type: ignore[no-untyped-def]
    for v, lim in zip(values, model.joint_limits, strict=True):
        if lim.type == JointType.CONTINUOUS:
            if not -math.pi < v <= math.pi:
                return False
        elif not lim.lower <= v <= lim.upper:
            return False
    return True


@pytest.fixture(params=IK_ROBOTS, ids=robot_id, scope="module")
def models(request: pytest.FixtureRequest):  # type: ignore[no-untyped-def]
    name, tip = request.param
    path = robot_path(name)
    return {key: impl.RobotModel(path, tip) for key, impl in IMPLEMENTATIONS.items()}


def test_round_trip_from_a_nearby_seed(models) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(10)
    for key, model in models.items():
        q = sample_configurations(model, N, seed=11)
        successes = 0
        for row in q:
            pose = model.forward_kinematics(row)
            seed = row + rng.uniform(-0.2, 0.2, size=row.shape)
            result = model.inverse_kinematics(pose, seed)
            assert within_limits(model, result.joint_values), key
            if result.status != IKStatus.SUCCESS:
                continue
            successes += 1
            reached = model.forward_kinematics(result.joint_values)
            assert np.linalg.norm(np.subtract(reached.position, pose.position)) <= POSE_TOL
            assert rotation_distance(reached, pose) <= POSE_TOL
            assert result.position_error <= POSE_TOL and result.orientation_error <= POSE_TOL
        assert successes >= 0.9 * N, (key, successes)


def test_native_and_twin_reach_the_same_outcome(models) -> None:  # type: ignore[no-untyped-def]
    """From non-singular nearby seeds the two converge alike.

    From a singular seed (UR5's home, all zeros) Newton-Raphson is chaotic:
    changing the seed by 1e-12 flips each implementation's own status in about
    5% of random targets, so statuses there are not expected to agree
    (docs/api.md, "Inverse kinematics").
    """
    a, b = models["native"], models["python"]
    q = sample_configurations(a, N, seed=12)
    rng = np.random.default_rng(13)
    same_status = 0
    for row in q:
        pose = a.forward_kinematics(row)
        seed = row + rng.uniform(-0.2, 0.2, size=row.shape)
        ra, rb = a.inverse_kinematics(pose, seed), b.inverse_kinematics(pose, seed)
        same_status += ra.status == rb.status
        if ra.status == rb.status == IKStatus.SUCCESS:
            pa, pb = a.forward_kinematics(ra.joint_values), b.forward_kinematics(rb.joint_values)
            assert np.linalg.norm(np.subtract(pa.position, pb.position)) <= 2 * POSE_TOL
    # Same algorithm, different SVD and rotation log: statuses rarely differ.
    assert same_status >= 0.99 * N


def test_deterministic_for_a_given_seed(impl) -> None:  # type: ignore[no-untyped-def]
    model = impl.RobotModel(robot_path("probot_anno"))
    pose = model.forward_kinematics([0.3, -0.4, 1.2, 0.5, 1.0, -0.7])
    first = model.inverse_kinematics(pose, [0.0] * 6)
    for _ in range(3):
        assert model.inverse_kinematics(pose, [0.0] * 6) == first


def test_seed_outside_limits_is_clamped(impl) -> None:  # type: ignore[no-untyped-def]
    model = impl.RobotModel(robot_path("probot_anno"))
    # The pose of a configuration beyond joint_1's limit (3.1416): the seed is
    # exactly there, yet the answer must stay within limits.
    q = [3.5, 0.0, 0.5, 0.0, 0.5, 0.0]
    result = model.inverse_kinematics(model.forward_kinematics(q), q)
    assert within_limits(model, result.joint_values)
    assert result.joint_values[0] <= 3.1416


def test_unreachable_pose_reports_no_solution(impl) -> None:  # type: ignore[no-untyped-def]
    model = impl.RobotModel(robot_path("probot_anno"))
    result = model.inverse_kinematics(Pose((5.0, 5.0, 5.0), (0.0, 0.0, 0.0, 1.0)))
    assert result.status == IKStatus.NO_SOLUTION
    assert result.position_error > 1.0
    assert within_limits(model, result.joint_values)


def test_ik_through_a_mimic_joint_is_unsupported(impl) -> None:  # type: ignore[no-untyped-def]
    model = impl.RobotModel(robot_path("panda"), "panda_rightfinger")
    pose = model.forward_kinematics([0.0] * model.dof)
    with pytest.raises(InvalidInputError) as err:
        model.inverse_kinematics(pose)
    assert err.value.code == ErrorCode.UNSUPPORTED_OPERATION
    # ... but IK to a link before the mimic joint works.
    q = [0.1, 0.2, 0.1, -1.0, 0.1, 1.0, 0.1, 0.02]
    seed = [v + 0.1 for v in q]
    result = model.inverse_kinematics(model.forward_kinematics(q, "panda_hand"), seed, link="panda_hand")
    assert result.status == IKStatus.SUCCESS


def test_ik_normalizes_the_target_quaternion(impl) -> None:  # type: ignore[no-untyped-def]
    model = impl.RobotModel(robot_path("probot_anno"))
    pose = model.forward_kinematics([0.2, 0.3, 0.4, 0.1, 0.6, 0.2])
    scaled = Pose(pose.position, tuple(3.0 * c for c in pose.orientation))  # type: ignore[arg-type]
    assert model.inverse_kinematics(scaled, [0.2, 0.3, 0.4, 0.1, 0.6, 0.0]).status == IKStatus.SUCCESS


@pytest.mark.parametrize("scale", [1e200, 1e305, 1.7e308 / 4])
def test_ik_normalizes_huge_quaternions(impl, scale: float) -> None:  # type: ignore[no-untyped-def]
    """Found by the adapter campaigns: x*x overflowed to inf in the quaternion's norm.

    The quaternion is divided by its largest component before it is normalized,
    so any finite multiple of a rotation is that rotation (to rounding).
    """
    model = impl.RobotModel(robot_path("probot_anno"))
    pose = model.forward_kinematics([0.2, 0.3, 0.4, 0.1, 0.6, 0.2])
    scaled = Pose(pose.position, tuple(scale * c for c in pose.orientation))  # type: ignore[arg-type]
    seed = [0.2, 0.3, 0.4, 0.1, 0.6, 0.0]
    got, expected = model.inverse_kinematics(scaled, seed), model.inverse_kinematics(pose, seed)
    assert got.status == expected.status == IKStatus.SUCCESS
    assert np.allclose(got.joint_values, expected.joint_values, rtol=0.0, atol=1e-12)


@pytest.mark.parametrize("scale", [1e-10, 1e-200, 5e-320])
def test_ik_refuses_near_zero_quaternions_without_underflow(impl, scale: float) -> None:  # type: ignore[no-untyped-def]
    """Below QUATERNION_NORM_EPS (1e-9) a quaternion is INVALID_ARGUMENT, also where x*x underflows."""
    model = impl.RobotModel(robot_path("probot_anno"))
    pose = model.forward_kinematics([0.2, 0.3, 0.4, 0.1, 0.6, 0.2])
    tiny = Pose(pose.position, tuple(scale * c for c in pose.orientation))  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError) as err:
        model.inverse_kinematics(tiny)
    assert err.value.code == ErrorCode.INVALID_ARGUMENT
    assert "quaternion" in str(err.value)


def test_ik_with_non_finite_iterates_is_no_solution(impl) -> None:  # type: ignore[no-untyped-def]
    """Found by native vs python on Kinova: a 1e308 target made NaN iterates.

    Native returned NaN joint values, the twin raised LinAlgError; both now stop
    with NO_SOLUTION and the clamped seed (tests/regressions/crash-71f78e4f...).
    """
    model = impl.RobotModel(robot_path("kinova"))
    seed = [0.1] * model.dof
    result = model.inverse_kinematics(Pose((1.7976931348623157e308, 0.15, 0.2), (0.0, 0.0, 0.0, 1.0)), seed)
    assert result.status == IKStatus.NO_SOLUTION
    assert all(math.isfinite(v) for v in result.joint_values)
    assert within_limits(model, result.joint_values)


def test_continuous_joints_come_back_normalized() -> None:
    for impl in (native, python_impl):
        model = impl.RobotModel(robot_path("kinova"))
        q = [5.0, 2.0, 2.0, -4.0, 1.5, 6.0]
        result = model.inverse_kinematics(model.forward_kinematics(q), q)
        assert result.status == IKStatus.SUCCESS
        assert within_limits(model, result.joint_values)


@pytest.mark.parametrize("robot", ["zoo_arm", "ur5", "kinova"])
def test_twin_jacobian_is_the_derivative_of_its_fk(robot: str) -> None:
    """``fk_and_jacobian`` (one pass for the twin's IK iteration): its transform is ``fk``'s,
    bit for bit, and its Jacobian matches central differences of ``fk`` for every link of the
    chain (``zoo_arm`` has revolute, continuous, prismatic and fixed joints)."""
    from python_impl import kinematics

    path = ROOT / "benchmarks" / "robots" / "zoo_arm.urdf" if robot == "zoo_arm" else robot_path(robot)
    model = python_impl.RobotModel(path)
    chain = model.chain
    h = 1e-6
    for q in sample_configurations(model, 5, seed=3):
        for link in range(len(chain.link_names)):
            nvars = int(np.count_nonzero(chain.variable[:link] >= 0))
            transform, jac = kinematics.fk_and_jacobian(chain, q, link, nvars)
            assert np.array_equal(transform, kinematics.fk(chain, q, link))
            assert jac.shape == (6, nvars)
            for v in range(nvars):
                dq = np.zeros_like(q)
                dq[v] = h
                ahead, behind = kinematics.fk(chain, q + dq, link), kinematics.fk(chain, q - dq, link)
                linear = (ahead[:3, 3] - behind[:3, 3]) / (2 * h)
                spin = (ahead[:3, :3] - behind[:3, :3]) / (2 * h) @ transform[:3, :3].T  # [w]x
                angular = np.array([spin[2, 1], spin[0, 2], spin[1, 0]])
                np.testing.assert_allclose(jac[:3, v], linear, atol=1e-7)
                np.testing.assert_allclose(jac[3:, v], angular, atol=1e-7)


@pytest.mark.parametrize("robot", ["zoo_arm", "ur5", "double_pendulum_continuous"])
def test_the_twins_ik_errors_are_those_of_fk_at_its_answer(robot: str) -> None:
    """``_ik`` measures its answer's position and orientation errors on the loop's own transform
    when the loop ended there (converged, and no continuous joint solved for, whose normalized
    value may differ from the iterate's), else on a fresh ``fk``:
    either way they are exactly those of ``fk`` at the values it returns. Reached and unreachable
    targets are both among these, and the double pendulum's continuous joints start up to two
    turns out, so that some answers wrap."""
    from python_impl import kinematics
    from python_impl.transforms import rotation_angle

    path = ROOT / "benchmarks" / "robots" / "zoo_arm.urdf" if robot == "zoo_arm" else robot_path(robot)
    chain = python_impl.RobotModel(path).chain
    tip = len(chain.link_names) - 1
    nvars = int(np.count_nonzero(chain.variable[:tip] >= 0))
    lower = np.array([max(lim.lower, -2 * math.pi) for lim in chain.limits])
    upper = np.array([min(lim.upper, 2 * math.pi) for lim in chain.limits])
    rng = np.random.default_rng(5)
    outcomes = set()
    for i in range(60):
        q = rng.uniform(lower, upper)
        target = kinematics.fk(chain, q, tip).copy()
        if i % 4 == 0:
            target[:3, 3] *= 3.0  # out of reach
        seed = np.clip(q + rng.normal(0.0, 0.2, q.shape), lower, upper).tolist()
        converged, values, position_error, orientation_error = kinematics._ik(
            chain, target, seed, tip, nvars, None
        )
        reached = kinematics.fk(chain, np.array(values), tip)
        d = reached[:3, 3] - target[:3, 3]
        assert position_error == math.sqrt(float(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
        assert orientation_error == rotation_angle(reached[:3, :3].T @ target[:3, :3])
        outcomes.add(converged)
    assert outcomes == {True, False}


def test_the_twins_ik_setup_is_read_only() -> None:
    """What IK problems of one chain share (``kinematics._setup``: the movable segments, the
    limits) is made once and kept, so none of its arrays can be written."""
    from python_impl import kinematics

    chain = python_impl.RobotModel(robot_path("ur5")).chain
    tip = len(chain.link_names) - 1
    movable, lower, upper = kinematics._setup(chain, tip, chain.dof)
    assert kinematics._setup(chain, tip, chain.dof)[0] is movable
    for array in (lower, upper, movable.columns, movable.axes, movable.revolute, movable.origins):
        with pytest.raises(ValueError):
            array[...] = 0


def test_the_twins_iterate_replay_follows_inverse_kinematics() -> None:
    """``ik_rotation_errors`` (the oracle's replay of Newton-Raphson, not part of the protocol)
    starts at the seed's rotation error, ends where IK stops, and has one entry per iterate."""
    m = python_impl.RobotModel(robot_path("ur5"))
    for q in sample_configurations(m, 20, seed=3):
        target = m.forward_kinematics(q)
        seed = [0.9 * v for v in q]
        errors = ik_rotation_errors(m, target, seed)
        result = m.inverse_kinematics(target, seed)
        assert 1 <= len(errors) <= 100
        assert errors[0] == pytest.approx(rotation_distance(m.forward_kinematics(seed), target), abs=1e-9)
        assert all(0.0 <= e <= math.pi for e in errors)
        if result.status is IKStatus.SUCCESS:
            assert errors[-1] <= math.sqrt(3) * IK_EPS  # the loop stopped on the tolerance
        else:
            assert len(errors) == 100
    with pytest.raises(InvalidInputError):
        ik_rotation_errors(m, ((0.1, 0.2, 0.3), (0.0, 0.0, 0.0, 0.0)))


def _every_iteration(chain, target, seed, link, nvars, trace):  # type: ignore[no-untyped-def]
    """The twin's Newton-Raphson loop written out with no shortcut: all IK_MAX_ITERATIONS
    iterations run unless one converges or goes non-finite (the reference for the next test)."""
    from python_impl import kinematics as k

    lower = np.array([lim.lower for lim in chain.limits[:nvars]])
    upper = np.array([lim.upper for lim in chain.limits[:nvars]])
    q = np.array(seed, dtype=np.float64)
    start, converged = q.copy(), False
    for _ in range(k.IK_MAX_ITERATIONS):
        current, jac = k.fk_and_jacobian(chain, q, link, nvars)
        twist = k.error_twist(current, target)
        trace.append(float(np.linalg.norm(twist[3:])))
        if k.is_small(twist):
            converged = True
            break
        if not (np.isfinite(twist).all() and np.isfinite(jac).all()):
            return False, start.tolist()
        q[:nvars] += k.pinv_step(jac, twist)
        q[:nvars] = np.minimum(np.maximum(q[:nvars], lower), upper)
    return converged, q.tolist()


@pytest.mark.parametrize("robot", ["probot_anno", "ur5", "panda"])
def test_the_twins_ik_ends_a_cycle_as_running_it_would(robot: str, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Unreachable targets make Newton-Raphson revisit an iterate (clamped joints, steps that
    undo each other); ``kinematics._ik`` then skips to the end of the cycle (``_cycle_end``).
    Its answer and trace equal those of running every iteration, bit for bit, and some of
    the cases below do cycle (with periods above 1)."""
    from python_impl import kinematics

    periods: list[int] = []
    real_end = kinematics._cycle_end

    def counted(iterates, first, now, trace, base=0):  # type: ignore[no-untyped-def]
        periods.append(now - first)
        return real_end(iterates, first, now, trace, base)

    monkeypatch.setattr(kinematics, "_cycle_end", counted)
    model = python_impl.RobotModel(robot_path(robot))
    chain, tip = model.chain, len(model.chain.link_names) - 1
    nvars = model._ik_variables(tip)
    rng = np.random.default_rng(5)
    for q in sample_configurations(model, 60, seed=4):
        target = kinematics.fk(chain, q, tip).copy()
        target[:3, 3] += rng.normal(0.0, 0.4, 3)  # mostly out of reach
        seed = model._ik_start(model.forward_kinematics(q), q + rng.normal(0.0, 0.5, len(q)), None)[2]
        expected_trace: list[float] = []
        expected = _every_iteration(chain, target, seed, tip, nvars, expected_trace)
        trace: list[float] = []
        converged, values, _, _ = kinematics._ik(chain, target, list(seed), tip, nvars, trace)
        assert (converged, values) == (expected[0], [float(v) for v in expected[1]])
        assert trace == expected_trace
        assert kinematics._ik(chain, target, list(seed), tip, nvars, None)[:2] == (converged, values)
    assert periods and max(periods) > 1


@pytest.mark.parametrize(
    ("offset", "status"),
    [
        (IK_EPS, IKStatus.NO_SOLUTION),
        (-IK_EPS, IKStatus.NO_SOLUTION),
        (0.999999 * IK_EPS, IKStatus.SUCCESS),
        (-0.999999 * IK_EPS, IKStatus.SUCCESS),
    ],
)
def test_ik_tolerance_is_strict_in_both_targets(offset: float, status: IKStatus) -> None:
    """A chain without joints (UR5 to its base) reaches only its own pose: a target exactly IK_EPS
    from it is not within IK_EPS in KDL (``Equal``: ``|x| < eps``), and the twin agrees (its
    closed interval made it a success there; a helper's probe found it as ``ill_conditioned``)."""
    for name, impl in IMPLEMENTATIONS.items():
        model = impl.RobotModel(robot_path("ur5"), "base")
        home = model.forward_kinematics([])
        target = ((home.position[0] + offset, home.position[1], home.position[2]), home.orientation)
        assert model.inverse_kinematics(target).status is status, name
