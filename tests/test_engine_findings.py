"""The library behaviours FINDINGS.md reports for MuJoCo, PyBullet, Drake, yourdfpy, pytransform3d, placo.

Pinned: each test fails once the library changes (a fix, or a new behaviour), so
``FINDINGS.md`` and the adapters' docstrings get updated. A missing library is a
failure under ``RROSFUZZ_REQUIRE_ADAPTERS=1`` (placo excepted: it is in no extra,
``third_party.md``).
"""

from __future__ import annotations

import io
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import native
import python_impl
from fuzzer.execution.targets import load_target
from robot_api.errors import ErrorCode, URDFError
from tests.support import import_or_skip, robot_path
from tests.test_adapters_engines import ENGINES, URDFS, fk_gap


def test_crafted_urdfs_agree_in_mujoco_and_drake() -> None:
    """MuJoCo and Drake normalize axes, ignore <link><origin> and turn tilted axes right."""
    for name in ("mujoco", "drake"):
        import_or_skip(ENGINES[name].library)
        for urdf in ("tilted.urdf", "scaled_axes.urdf", "link_origin.urdf"):
            assert fk_gap(ENGINES[name].spec, URDFS / urdf, [0.5, 0.3], "l2") <= 1e-12, (name, urdf)


def test_non_unit_axes_are_used_as_given() -> None:
    """Not URDF (axes are directions); urdfdom 3.0.1 keeps the length too, native and the twin normalize."""
    for name in ("pybullet", "yourdfpy", "klampt"):
        import_or_skip(ENGINES[name].library)
        spec = ENGINES[name].spec
        assert fk_gap(spec, URDFS / "scaled_axes.urdf", [0.0, 0.3], "l2") == pytest.approx(0.6, abs=1e-6)
    # the revolute `0 0 2`: Klampt turns twice as far, PyBullet and yourdfpy normalize it
    assert fk_gap(ENGINES["klampt"].spec, URDFS / "scaled_axes.urdf", [0.5, 0.0], "l2") > 0.1
    for name in ("pybullet", "yourdfpy"):
        assert fk_gap(ENGINES[name].spec, URDFS / "scaled_axes.urdf", [0.5, 0.0], "l2") <= 1e-6


def test_pybullet_reads_the_urdf_in_single_precision() -> None:
    import_or_skip("pybullet")
    model = load_target(ENGINES["pybullet"].spec).RobotModel(robot_path("probot_anno"))
    z = model.forward_kinematics([0.0] * 6, "link_1").position[2]  # <origin xyz="0 0 0.0315">
    assert z == float(np.float32(0.0315)) != 0.0315


def test_pytransform3d_clips_to_limits_and_ignores_mimic() -> None:
    """Documented clipping (set_joint); <mimic> is not read at all (the mimic joint stays at 0)."""
    import_or_skip("pytransform3d")
    from pytransform3d.urdf import UrdfTransformManager

    spec = ENGINES["pytransform3d"].spec
    beyond, within = [0.0, 0.0, 0.0, 0.0, 4.5, 0.0], [0.0, 0.0, 0.0, 0.0, 3.5, 0.0]  # joint_5 <= 3.927
    assert fk_gap(spec, robot_path("probot_anno"), beyond) > 0.1
    assert fk_gap(spec, robot_path("probot_anno"), within) <= 1e-12
    urdf = robot_path("panda").read_text()
    manager = UrdfTransformManager(check=False)
    manager.load_urdf(urdf)
    manager.set_joint("panda_finger_joint1", 0.03)
    native_panda = native.RobotModel(robot_path("panda"), "panda_rightfinger")
    expected = native_panda.forward_kinematics([0.0] * 7 + [0.03], "panda_rightfinger").matrix
    got = manager.get_transform("panda_rightfinger", native_panda.root_link)
    assert np.max(np.abs(got[:3, :3] - expected[:3, :3])) <= 1e-12
    assert np.linalg.norm(got[:3, 3] - expected[:3, 3]) == pytest.approx(0.03, abs=1e-12)  # finger 2 stayed


def test_pytransform3d_clips_continuous_joints_to_their_limit_element() -> None:
    """pytransform3d bug (F-PT3D-1): a continuous joint has no limits, whatever <limit> says."""
    import_or_skip("pytransform3d")
    from pytransform3d.urdf import UrdfTransformManager

    urdf = (
        '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="continuous">'
        '<parent link="a"/><child link="b"/><axis xyz="0 0 1"/>'
        '<limit lower="0" upper="0" effort="1" velocity="1"/></joint></robot>'
    )
    manager = UrdfTransformManager()
    manager.load_urdf(urdf)
    manager.set_joint("j", 1.0)
    np.testing.assert_array_equal(manager.get_transform("b", "a"), np.eye(4))  # expected: 1 rad about z
    assert native.RobotModel(urdf).forward_kinematics([1.0]).orientation[2] == pytest.approx(math.sin(0.5))
    spec = ENGINES["pytransform3d"].spec
    assert fk_gap(spec, robot_path("double_pendulum_continuous"), [1.1, 0.0], "link1") > 0.5


def test_yourdfpy_drops_joint_updates_below_1e_8() -> None:
    """yourdfpy bug (F-YOURDFPY-1): update_cfg skips transforms within 1e-8 of the stored one."""
    import_or_skip("yourdfpy")
    import yourdfpy

    urdf = (
        b'<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="revolute"><parent link="a"/>'
        b'<child link="b"/><origin xyz="0 0 1"/><axis xyz="0 0.6 0.8"/>'
        b'<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    robot = yourdfpy.URDF.load(io.BytesIO(urdf))
    robot.update_cfg({"j": 5e-9})
    assert robot.cfg[0] == 5e-9
    np.testing.assert_array_equal(robot.get_transform("b", "a")[:3, :3], np.eye(3))  # the q = 0 frame
    robot.update_cfg({"j": 0.1})
    robot.update_cfg({"j": 5e-9})
    assert robot.get_transform("b", "a")[1, 0] == pytest.approx(5e-9 * 0.8, rel=1e-6)  # now it turned


CRASHERS = {  # contract-accepted URDFs that kill the library's process (FINDINGS.md)
    "pybullet": [
        '<robot name="r"><link name=""/></robot>',
        '<robot name="r"><link name="a"/><link name="b"/><joint name="" type="fixed">'
        '<parent link="a"/><child link="b"/></joint></robot>',
    ],
    "drake": [
        '<robot name=""><link name="a"/></robot>',
        '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="revolute">'
        '<parent link="a"/><child link="b"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="-1"/></joint></robot>',
    ],
}
CRASH_SCRIPTS = {
    "pybullet": "import pybullet as p, sys; p.connect(p.DIRECT); p.loadURDF(sys.argv[1])",
    "drake": (
        "import sys\nfrom pydrake.multibody.parsing import Parser\n"
        "from pydrake.multibody.plant import MultibodyPlant\nplant = MultibodyPlant(0.0)\n"
        "Parser(plant).AddModels(sys.argv[1])"
    ),
}


@pytest.mark.parametrize("name", sorted(CRASHERS))
def test_urdfs_that_crash_the_library_are_refused_before_it_sees_them(name: str, tmp_path: Path) -> None:
    import_or_skip(ENGINES[name].library)
    impl = load_target(ENGINES[name].spec)
    for i, urdf in enumerate(CRASHERS[name]):
        native.RobotModel(urdf)  # the contract accepts it
        with pytest.raises(URDFError, match="refused before loading") as err:
            impl.RobotModel(urdf)
        assert err.value.code == ErrorCode.URDF_UNSUPPORTED
        # pinned: the library itself still kills the process (not an exception)
        path = tmp_path / f"crash{i}.urdf"
        path.write_text(urdf)
        run = subprocess.run(
            [sys.executable, "-c", CRASH_SCRIPTS[name], str(path)],
            capture_output=True,
            text=True,
            timeout=300,
            check=False,
        )
        assert run.returncode != 0 and "Traceback" not in run.stderr, (run.returncode, run.stderr[-500:])


def test_urdfdom_refuses_tab_separated_vectors_the_twin_reads() -> None:
    """XML normalizes a tab in an attribute value to a space; urdfdom 3.0.1 (TinyXML) does not."""
    urdf = (
        '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="fixed"><parent link="a"/>'
        '<child link="b"/><origin xyz="1\t0 0"/></joint></robot>'
    )
    with pytest.raises(URDFError, match="Unable to parse component"):
        native.RobotModel(urdf)
    assert python_impl.RobotModel(urdf).forward_kinematics([], "b").position == (1.0, 0.0, 0.0)


def test_placo_cannot_name_a_link_that_shares_a_joint_s_name() -> None:
    """placo bug: get_T_world_frame(name) is ambiguous for Z1's gripperStator (link and joint)."""
    pytest.importorskip("placo")  # not in any extra: it pins pin==3.8.0
    model = load_target("adapters.placo_adapter:api").RobotModel(robot_path("z1"))
    assert model.forward_kinematics([0.0] * model.dof, "gripperMover") is not None
    with pytest.raises(ValueError, match="Several frames match"):
        model.forward_kinematics([0.0] * model.dof, "gripperStator")
