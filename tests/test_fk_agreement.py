"""Forward kinematics: native and twin agree with each other and with pinocchio.

For every robot: 10,000 random configurations (within limits widened by 0.5,
continuous joints over [-2pi, 2pi]), batch FK to 1e-9, single-call FK against
the batch, and both against pinocchio (an independent implementation with its
own URDF reader).
"""

from __future__ import annotations

import numpy as np
import pytest

import native
import python_impl
from tests.support import AGREEMENT_ROBOTS, PinocchioReference, robot_id, robot_path, sample_configurations

N_CONFIGS = 10_000
TOL = 1e-9


@pytest.fixture(params=AGREEMENT_ROBOTS, ids=robot_id, scope="module")
def pair(request: pytest.FixtureRequest):  # type: ignore[no-untyped-def]
    name, tip = request.param
    path = robot_path(name)
    return path, native.RobotModel(path, tip), python_impl.RobotModel(path, tip)


def test_models_describe_the_same_chain(pair) -> None:  # type: ignore[no-untyped-def]
    _, a, b = pair
    assert a.name == b.name
    assert a.root_link == b.root_link and a.tip_link == b.tip_link
    assert a.joint_names == b.joint_names and a.dof == b.dof > 0
    assert a.link_names == b.link_names
    assert a.joint_limits == b.joint_limits
    assert a.mimic_joints == b.mimic_joints
    assert a.home_values == b.home_values


def test_batch_fk_agrees_on_every_link(pair) -> None:  # type: ignore[no-untyped-def]
    _, a, b = pair
    q = sample_configurations(a, N_CONFIGS, seed=1, margin=0.5)
    for link in (None, *a.link_names[1:-1:2]):
        ta = a.forward_kinematics_batch(q, link)
        tb = b.forward_kinematics_batch(q, link)
        assert ta.shape == tb.shape == (N_CONFIGS, 4, 4)
        assert np.max(np.abs(ta - tb)) <= TOL, link


def test_single_fk_matches_batch(pair) -> None:  # type: ignore[no-untyped-def]
    _, a, b = pair
    q = sample_configurations(a, N_CONFIGS, seed=2, margin=0.5)
    batch = a.forward_kinematics_batch(q)
    for model in (a, b):
        single = np.array([model.forward_kinematics(row).matrix for row in q])
        assert np.max(np.abs(single - batch)) <= TOL


def test_single_fk_poses_are_canonical_and_agree(pair) -> None:  # type: ignore[no-untyped-def]
    _, a, b = pair
    for row in sample_configurations(a, 2_000, seed=3):
        pa, pb = a.forward_kinematics(row), b.forward_kinematics(row)
        assert np.max(np.abs(np.subtract(pa.position, pb.position))) <= TOL
        for pose in (pa, pb):
            assert abs(np.linalg.norm(pose.orientation) - 1.0) <= 1e-12
            assert pose.orientation[3] >= 0.0
        assert np.max(np.abs(np.subtract(pa.orientation, pb.orientation))) <= TOL


def test_both_agree_with_pinocchio(pair) -> None:  # type: ignore[no-untyped-def]
    path, a, b = pair
    ref = PinocchioReference.load(path, a.joint_names)
    q = sample_configurations(a, 2_000, seed=4, margin=0.5)
    for link in (a.tip_link, a.link_names[len(a.link_names) // 2]):
        expected = np.array([ref.transform(row, link) for row in q])
        for model in (a, b):
            got = model.forward_kinematics_batch(q, link)
            assert np.max(np.abs(got - expected)) <= TOL, (type(model).__module__, link)


def test_fk_to_root_is_identity(pair) -> None:  # type: ignore[no-untyped-def]
    _, a, b = pair
    q = sample_configurations(a, 5, seed=5)
    for model in (a, b):
        assert np.array_equal(
            model.forward_kinematics_batch(q, model.root_link), np.broadcast_to(np.eye(4), (5, 4, 4))
        )
