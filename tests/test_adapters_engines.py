"""FK adapters around simulators and URDF stacks: MuJoCo, PyBullet, Drake, yourdfpy, pytransform3d, Klampt.

Each adapter (``adapters/<lib>_adapter.py``, shared code in ``adapters/_engines.py``)
takes FK from its library and everything else from the contract. Per adapter
(a failure under ``RROSFUZZ_REQUIRE_ADAPTERS=1`` when its library is missing):

* it plugs in as ``module:attribute`` and matches ``robot_api.protocol``;
* FK of every link agrees with ``native`` on 300 random configurations on
  PROBOT Anno, UR5 (root ``world``), Kinova (continuous joints), Panda's left
  finger (prismatic) and Unitree Z1 (a link and a joint of the same name);
* no twin kinematics leaks in; IK is refused as unsupported after the contract's
  argument checks; argument errors are the contract's;
* a short real campaign against ``native`` exits 0.

The library behaviours ``FINDINGS.md`` reports are pinned in
``tests/test_engine_findings.py``.

placo is tested only where it is installed (it pins ``pin==3.8.0``, which the
project's pinocchio 4 excludes: ``third_party.md``).

Tolerances
----------
MuJoCo, Drake, yourdfpy, pytransform3d and Klampt compute in float64 from float64
URDF constants: the contract's 1e-9 (measured: below 4e-15). PyBullet returns
single-precision frames (measured 6e-7 on these robots): 1e-6, and the test
requires the error to stay above 1e-9 so it fails once PyBullet is double.
"""

from __future__ import annotations

import inspect
import json
import math
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import native
import python_impl
import python_impl.kinematics
from fuzzer.execution.targets import load_target
from robot_api.errors import ErrorCode, InvalidInputError, URDFError
from robot_api.protocol import GROUP_METHODS, MODEL_METHODS, MODEL_PROPERTIES, MoveGroupAPI, RobotModelAPI
from robot_api.records import Pose
from tests.support import import_or_skip, outcome, robot_path, sample_configurations

ROOT = Path(__file__).resolve().parents[1]
URDFS = ROOT / "tests" / "regressions" / "urdfs"


@dataclass(frozen=True)
class Engine:
    name: str
    library: str
    fk_tol: float

    @property
    def spec(self) -> str:
        return f"adapters.{self.name}_adapter:api"


ENGINES = {
    e.name: e
    for e in (
        Engine("mujoco", "mujoco", 1e-9),
        Engine("pybullet", "pybullet", 1e-6),  # single precision: see the module docstring
        Engine("drake", "pydrake", 1e-9),
        Engine("yourdfpy", "yourdfpy", 1e-9),
        Engine("pytransform3d", "pytransform3d", 1e-9),
        Engine("klampt", "klampt", 1e-9),
    )
}

IK_ENGINES = {"pybullet"}  # the others are FK-only
FK_ROBOTS = [
    ("probot_anno", None),
    ("ur5", None),
    ("kinova", None),
    ("panda", "panda_leftfinger"),
    ("z1", None),
]
_MODELS: dict[tuple[str, str, str | None], Any] = {}


@pytest.fixture(params=sorted(ENGINES), scope="module")
def engine(request: pytest.FixtureRequest) -> tuple[Engine, Any]:
    spec = ENGINES[request.param]
    import_or_skip(spec.library)
    return spec, load_target(spec.spec)


def model_of(spec: Engine, impl: Any, robot: str, tip: str | None = None) -> Any:
    key = (spec.name, robot, tip)
    if key not in _MODELS:
        _MODELS[key] = impl.RobotModel(robot_path(robot), tip)
    return _MODELS[key]


def public(cls: type) -> set[str]:
    return {name for name in dir(cls) if not name.startswith("_")}


def params(func: Any) -> list[tuple[str, object, object]]:
    return [(p.name, p.kind, p.default) for p in inspect.signature(func).parameters.values()]


def fk_gap(spec: str, urdf: str | Path, q: list[float], link: str | None = None) -> float:
    got = load_target(spec).RobotModel(urdf).forward_kinematics(q, link).matrix
    return float(np.max(np.abs(got - native.RobotModel(urdf).forward_kinematics(q, link).matrix)))


# -- plugging in -------------------------------------------------------------------------------


def test_loads_as_a_target_and_implements_the_protocol(engine: tuple[Engine, Any]) -> None:
    spec, impl = engine
    assert impl is load_target(spec.spec)
    model = model_of(spec, impl, "probot_anno")
    assert isinstance(model, RobotModelAPI)
    assert isinstance(impl.MoveGroup(model), MoveGroupAPI)
    assert public(impl.RobotModel) - set(MODEL_METHODS) - set(MODEL_PROPERTIES) <= {
        "chain",
        "check_vector",
        "link_index",
        "pose_of",
        "LIBRARY",
    }
    assert public(impl.MoveGroup) == set(GROUP_METHODS)
    for name in MODEL_METHODS:
        assert params(getattr(impl.RobotModel, name)) == params(getattr(RobotModelAPI, name)), name
    assert params(impl.RobotModel.__init__) == params(RobotModelAPI.__init__)
    for cls in (impl.RobotModel, impl.MoveGroup):
        assert cls.__doc__
    module = sys.modules[impl.RobotModel.__module__]
    assert module.__doc__ and "Conventions normalized" in module.__doc__
    for model in (
        python_impl.RobotModel(robot_path("probot_anno")),
        native.RobotModel(robot_path("probot_anno")),
    ):
        with pytest.raises(InvalidInputError) as err:
            impl.MoveGroup(model)
        assert err.value.code == ErrorCode.INVALID_ARGUMENT


def test_describes_the_contract_chain(engine: tuple[Engine, Any]) -> None:
    spec, impl = engine
    for robot, tip in FK_ROBOTS:
        a, b = model_of(spec, impl, robot, tip), native.RobotModel(robot_path(robot), tip)
        assert (a.name, a.root_link, a.tip_link, a.joint_names, a.link_names) == (
            b.name,
            b.root_link,
            b.tip_link,
            b.joint_names,
            b.link_names,
        )
        assert a.joint_limits == b.joint_limits and a.home_values == b.home_values


def test_mimic_chains_are_unsupported_at_load(engine: tuple[Engine, Any]) -> None:
    _, impl = engine
    with pytest.raises(URDFError) as err:
        impl.RobotModel(robot_path("panda"), "panda_rightfinger")  # finger_joint2 mimics finger_joint1
    assert err.value.code == ErrorCode.URDF_UNSUPPORTED


# -- forward kinematics ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("robot", "tip"), FK_ROBOTS, ids=[r if t is None else f"{r}:{t}" for r, t in FK_ROBOTS]
)
def test_fk_of_every_link_agrees_with_native(engine: tuple[Engine, Any], robot: str, tip: str | None) -> None:
    spec, impl = engine
    a, b = model_of(spec, impl, robot, tip), native.RobotModel(robot_path(robot), tip)
    q = sample_configurations(b, 300, seed=11)  # within the limits; continuous joints over [-2pi, 2pi]
    worst = 0.0
    for link in b.link_names:
        error = float(
            np.max(np.abs(a.forward_kinematics_batch(q, link) - b.forward_kinematics_batch(q, link)))
        )
        assert error <= spec.fk_tol, f"{spec.name} on {robot}, link {link}: {error:.3g}"
        worst = max(worst, error)
    if spec.fk_tol > 1e-9 and robot == "probot_anno":  # pinned: PyBullet is still single precision
        assert worst > 1e-9, f"{spec.name} now reaches 1e-9: tighten its tolerance"
    for row, t in zip(q[:20], b.forward_kinematics_batch(q[:20]), strict=True):
        pose = a.forward_kinematics(row)
        assert np.max(np.abs(pose.matrix - t)) <= spec.fk_tol
        assert pose.orientation[3] >= 0.0
    np.testing.assert_array_equal(a.forward_kinematics(list(q[0]), a.root_link).matrix, np.eye(4))


def test_no_twin_kinematics_is_used(engine: tuple[Engine, Any], monkeypatch: pytest.MonkeyPatch) -> None:
    _, impl = engine

    def poisoned(*args: object, **kwargs: object) -> None:
        raise AssertionError("the twin's kinematics were called")

    for name in ("fk", "fk_batch", "jacobian", "ik"):
        monkeypatch.setattr(python_impl.kinematics, name, poisoned)
    model = impl.RobotModel(robot_path("ur5"))
    model.forward_kinematics([0.1] * 6)
    model.forward_kinematics_batch(np.zeros((3, 6)), "forearm_link")


def test_argument_errors_are_the_contract_s_and_ik_is_unsupported(engine: tuple[Engine, Any]) -> None:
    spec, impl = engine
    a, twin = model_of(spec, impl, "probot_anno"), python_impl.RobotModel(robot_path("probot_anno"))
    pose = Pose((0.2, 0.0, 0.3), (0.0, 0.0, 0.0, 1.0))
    if spec.name not in IK_ENGINES:
        with pytest.raises(InvalidInputError) as err:
            a.inverse_kinematics(pose)
        assert err.value.code == ErrorCode.UNSUPPORTED_OPERATION
    calls = [
        lambda m: m.forward_kinematics([0.0] * 5),
        lambda m: m.forward_kinematics([math.nan] * 6),
        lambda m: m.forward_kinematics({1, 2}),
        lambda m: m.forward_kinematics([0.0] * 6, "nowhere"),
        lambda m: m.forward_kinematics_batch(np.zeros((2, 5))),
        lambda m: m.forward_kinematics_batch(np.full((2, 6), math.inf)),
        lambda m: m.inverse_kinematics(((0, 0, 0), (0, 0, 0, 0))),
        lambda m: m.inverse_kinematics(pose, [0.0] * 7),
        lambda m: m.inverse_kinematics("pose"),
    ]
    for call in calls:
        assert outcome(lambda c=call: c(a))[0] == outcome(lambda c=call: c(twin))[0] != "ok"
    for urdf in (
        "<robot",
        "/does/not/exist.urdf",
        "<robot name='r'><link name='a'/><link name='a'/></robot>",
    ):
        assert (
            outcome(lambda u=urdf: impl.RobotModel(u))[0]
            == outcome(lambda u=urdf: python_impl.RobotModel(u))[0]
        )


@pytest.mark.parametrize("robot", ["probot_anno", "ur5"])
def test_pybullet_ik_is_honest_and_deterministic(robot: str) -> None:
    """Every SUCCESS meets the contract's criterion by native's FK (up to PyBullet's float32 frames)."""
    import_or_skip("pybullet")
    a = load_target(ENGINES["pybullet"].spec).RobotModel(robot_path(robot))
    b = native.RobotModel(robot_path(robot))
    lows, highs = [lim.lower for lim in b.joint_limits], [lim.upper for lim in b.joint_limits]
    successes = 0
    for q in sample_configurations(b, 20, seed=5, margin=0.0):
        pose, seed = b.forward_kinematics(q), list(np.clip(q + 0.1, lows, highs))
        first, again = a.inverse_kinematics(pose, seed), a.inverse_kinematics(pose, seed)
        assert first == again
        assert len(first.joint_values) == b.dof
        if first.status.name == "SUCCESS":
            successes += 1
            reached = b.forward_kinematics(list(first.joint_values)).matrix
            assert np.max(np.abs(reached - pose.matrix)) <= 1e-5
            assert first.position_error <= 2e-6
    assert successes < 20  # pinned: PyBullet's float32 solver rarely reaches 1e-6 (measured 0 and 7 of 30)


def test_move_group_plans_with_library_poses(engine: tuple[Engine, Any]) -> None:
    spec, impl = engine
    a, b = model_of(spec, impl, "probot_anno"), native.RobotModel(robot_path("probot_anno"))
    ga, gb = impl.MoveGroup(a), native.MoveGroup(b)
    for group in (ga, gb):
        assert group.go({"joint_2": 0.4, "joint_5": 1.0}) is True
    assert np.max(np.abs(ga.get_current_pose().matrix - gb.get_current_pose().matrix)) <= spec.fk_tol


def test_short_fk_campaign_exits_0(engine: tuple[Engine, Any], tmp_path: Path) -> None:
    spec, _ = engine
    run = subprocess.run(
        [
            sys.executable,
            str(ROOT / "fuzz_diff.py"),
            str(tmp_path / "corpus"),
            "-runs=200",
            "-seed=1",
            "--op=fk",
            f"--targets=native,{spec.spec}",
            f"--artifacts={tmp_path / 'a'}",
            "--no-progress",
            f"--tolerance={'1e-5' if spec.name == 'pybullet' else '1e-6'}",  # PyBullet: single precision
        ],
        cwd=ROOT,
        env=dict(os.environ, PYTHONPATH=str(ROOT)),
        text=True,
        capture_output=True,
        timeout=600,
        check=False,
    )
    assert run.returncode in (0, 1), run.stderr[-3000:]
    summary = next(line for line in run.stderr.splitlines() if "divergences:" in line)
    if spec.name == "pytransform3d":  # C-CLIP: every value divergence is a value beyond a limit
        limits = native.RobotModel(robot_path("probot_anno")).joint_limits
        files = list((tmp_path / "a").glob("crash-*.json"))
        assert files and run.returncode == 1, summary
        for path in files:
            values = json.loads(path.read_text())["call"]["joint_values"]
            assert any(not lim.lower <= v <= lim.upper for v, lim in zip(values, limits, strict=True)), values
        return
    assert not any(kind in summary for kind in ("crash", "status", "value")), summary


def test_geometry_removal_keeps_the_kinematics(engine: tuple[Engine, Any]) -> None:
    """A commented-out <visual> before a joint must not take the joint with it."""
    spec, _ = engine
    urdf = (
        '<robot name="r"><!-- <visual> --><link name="a"><visual><geometry><box size="1 1 1"/></geometry>'
        '</visual><collision/></link><link name="b"/><joint name="j" type="revolute"><parent link="a"/>'
        '<child link="b"/><origin xyz="0 0 1"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    assert fk_gap(spec.spec, urdf, [0.3]) <= spec.fk_tol


def test_mujoco_warnings_do_not_write_a_log_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import_or_skip("mujoco")
    monkeypatch.chdir(tmp_path)
    urdf = (
        '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="revolute">'
        '<parent link="a"/><child link="b"/><axis xyz="0 0 1"/>'
        '<limit lower="0" upper="0" effort="1" velocity="1"/></joint></robot>'
    )
    with pytest.warns(RuntimeWarning, match="equal lower and upper limits"):
        assert fk_gap(ENGINES["mujoco"].spec, urdf, [0.5]) <= 1e-12  # MuJoCo ignores that limit
    assert list(tmp_path.iterdir()) == []  # no MUJOCO_LOG.TXT
