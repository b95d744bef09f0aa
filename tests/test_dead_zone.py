"""KDL's rotation dead zone as the oracle puts it into the twin (``fuzzer.execution.dead_zone``)."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzer.execution.dead_zone import KDL_EPSILON, twin_with_kdl_dead_zone, within_dead_zone
from python_impl import kinematics
from python_impl.transforms import homogeneous, quaternion_matrix


def _turn(angle: float, axis: tuple[float, float, float] = (0.3, -0.5, 0.81)) -> np.ndarray:
    a = np.array(axis) / np.linalg.norm(axis)
    half = angle / 2.0
    x, y, z = a * np.sin(half)
    return quaternion_matrix(x, y, z, np.cos(half))


@pytest.mark.parametrize(
    ("angle", "inside"),
    [(0.0, True), (1.5e-8, True), (4e-7, True), (2e-6, False), (0.01, False), (np.pi, False)],
)
def test_the_band_is_kdls(angle: float, inside: bool) -> None:
    """About 5e-7 rad: an asymmetry of 2 sin(angle) times an axis component below 1e-6."""
    assert within_dead_zone(_turn(angle)) is inside


def test_only_the_rotation_part_of_a_twist_inside_the_band_is_dropped() -> None:
    current = homogeneous(np.eye(3), (0.1, 0.2, 0.3))
    target = homogeneous(_turn(1.5e-8), (0.1, 0.2, 0.31))
    exact = kinematics.error_twist(current, target)
    assert abs(exact[3:]).max() > 0.0
    with twin_with_kdl_dead_zone() as swapped:
        assert swapped
        zoned = kinematics.error_twist(current, target)
        outside = kinematics.error_twist(current, homogeneous(_turn(1e-5), (0.1, 0.2, 0.31)))
    assert list(zoned[:3]) == list(exact[:3]) and not zoned[3:].any()
    assert np.linalg.norm(outside[3:]) == pytest.approx(1e-5, rel=1e-6)
    assert list(kinematics.error_twist(current, target)) == list(exact)  # put back


def test_the_twin_gets_its_own_function_back_after_an_error() -> None:
    exact = kinematics.error_twist
    with pytest.raises(RuntimeError), twin_with_kdl_dead_zone():
        assert kinematics.error_twist is not exact
        raise RuntimeError("boom")
    assert kinematics.error_twist is exact
    assert KDL_EPSILON == 1e-6
