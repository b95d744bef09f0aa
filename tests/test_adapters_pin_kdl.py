"""Adapters around pinocchio and PyKDL (``adapters/pinocchio_adapter.py``, ``adapters/pykdl_adapter.py``).

Each adapter exposes the API with kinematics from its library and everything
else (chain, variables, limits, argument checks, MoveGroup) from the contract
through ``python_impl``. Per target (skipped when its library cannot load):

* it plugs in as ``module:attribute`` and matches ``robot_api.protocol``;
* FK agrees with ``native`` to 1e-9 on 1000 random configurations (limits
  widened by 0.5, continuous joints over [-2pi, 2pi]) on PROBOT Anno, UR5,
  Panda's right finger (a mimic joint whose master is off the chain) and Kinova
  (continuous joints), on every link;
* no twin kinematics leaks in (the twin's kinematics module is poisoned);
* IK round trips from nearby seeds, in the contract's form;
* argument errors are the contract's;
* a short real campaign against ``native`` exits 0.

It also pins the library behaviours the adapters document, so that a test
fails once a library changes and the docstrings can be updated: KDL's rotation
logarithm has a dead zone (the cause of IK status divergences between the
KDL-based targets and the exact-logarithm ones), pinocchio cannot mimic across
joint models of different sizes, and PyKDL with kdl_parser's origins is
``native`` bit for bit.
"""

from __future__ import annotations

import inspect
import math
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
from fuzzer.execution.targets import TargetError, load_target
from robot_api.errors import ErrorCode, InvalidInputError, URDFError
from robot_api.protocol import GROUP_METHODS, MODEL_METHODS, MODEL_PROPERTIES, MoveGroupAPI, RobotModelAPI
from robot_api.records import IKStatus, JointType, Pose
from tests.support import outcome, robot_path, sample_configurations, skip_or_fail

ROOT = Path(__file__).resolve().parents[1]
TOL = 1e-9


@dataclass(frozen=True)
class Adapter:
    name: str
    spec: str


ADAPTERS = {
    a.name: a
    for a in (
        Adapter("pinocchio", "adapters.pinocchio_adapter:api"),
        Adapter("pykdl", "adapters.pykdl_adapter:api"),
        Adapter("pykdl_kdl_parser", "adapters.pykdl_adapter:kdl_parser_api"),
    )
}

FK_ROBOTS = [("probot_anno", None), ("ur5", None), ("panda", "panda_rightfinger"), ("kinova", None)]
IK_ROBOTS = [("probot_anno", None), ("ur5", None), ("panda", None), ("kinova", None)]

_IMPLS: dict[str, Any] = {}
_MODELS: dict[tuple[str, str, str | None], Any] = {}


def load(name: str) -> Any:
    """The target, or a skip naming why its library cannot load."""
    if name not in _IMPLS:
        try:
            _IMPLS[name] = load_target(ADAPTERS[name].spec)
        except TargetError as exc:
            skip_or_fail(str(exc))
    return _IMPLS[name]


@pytest.fixture(params=sorted(ADAPTERS), scope="module")
def adapter(request: pytest.FixtureRequest) -> tuple[str, Any]:
    return request.param, load(request.param)


def model_of(name: str, impl: Any, robot: str, tip: str | None = None) -> Any:
    key = (name, robot, tip)
    if key not in _MODELS:
        _MODELS[key] = impl.RobotModel(robot_path(robot), tip)
    return _MODELS[key]


def native_model(robot: str, tip: str | None = None) -> Any:
    key = ("native", robot, tip)
    if key not in _MODELS:
        _MODELS[key] = native.RobotModel(robot_path(robot), tip)
    return _MODELS[key]


def case_ids(cases: list[tuple[str, str | None]]) -> list[str]:
    return [robot if tip is None else f"{robot}:{tip}" for robot, tip in cases]


# -- plugging in and API parity ---------------------------------------------------------------


def public(cls: type) -> set[str]:
    return {name for name in dir(cls) if not name.startswith("_")}


def params(func: Any) -> list[tuple[str, object, object]]:
    return [(p.name, p.kind, p.default) for p in inspect.signature(func).parameters.values()]


def test_loads_through_load_target(adapter: tuple[str, Any]) -> None:
    name, impl = adapter
    assert impl is load_target(ADAPTERS[name].spec)
    model = model_of(name, impl, "probot_anno")
    assert isinstance(model, RobotModelAPI)
    assert isinstance(impl.MoveGroup(model), MoveGroupAPI)


def test_implements_the_protocol(adapter: tuple[str, Any]) -> None:
    _, impl = adapter
    # the twin's helpers (MoveGroup uses them) and nothing else
    extra = public(impl.RobotModel) - set(MODEL_METHODS) - set(MODEL_PROPERTIES)
    assert extra <= {"chain", "check_vector", "link_index", "pose_of"}
    assert set(MODEL_METHODS) | set(MODEL_PROPERTIES) <= public(impl.RobotModel)
    assert public(impl.MoveGroup) == set(GROUP_METHODS)
    for name in MODEL_PROPERTIES:
        assert isinstance(inspect.getattr_static(impl.RobotModel, name), property), name
    for name in MODEL_METHODS:
        assert params(getattr(impl.RobotModel, name)) == params(getattr(RobotModelAPI, name)), name
    for name in GROUP_METHODS:
        assert params(getattr(impl.MoveGroup, name)) == params(getattr(MoveGroupAPI, name)), name
    assert params(impl.RobotModel.__init__) == params(RobotModelAPI.__init__)
    assert params(impl.MoveGroup.__init__) == params(MoveGroupAPI.__init__)
    for cls in (impl.RobotModel, impl.MoveGroup):
        assert cls.__doc__
        for name in public(cls):
            assert getattr(cls, name).__doc__, f"{cls.__name__}.{name}"


def test_models_of_other_implementations_are_refused(adapter: tuple[str, Any]) -> None:
    _, impl = adapter
    for model in (
        python_impl.RobotModel(robot_path("probot_anno")),
        native.RobotModel(robot_path("probot_anno")),
    ):
        with pytest.raises(InvalidInputError) as err:
            impl.MoveGroup(model)
        assert err.value.code == ErrorCode.INVALID_ARGUMENT


@pytest.mark.parametrize(("robot", "tip"), FK_ROBOTS, ids=case_ids(FK_ROBOTS))
def test_describes_the_contract_chain(adapter: tuple[str, Any], robot: str, tip: str | None) -> None:
    name, impl = adapter
    a, b = model_of(name, impl, robot, tip), native_model(robot, tip)
    assert (a.name, a.root_link, a.tip_link) == (b.name, b.root_link, b.tip_link)
    assert a.joint_names == b.joint_names and a.link_names == b.link_names
    assert a.joint_limits == b.joint_limits and a.home_values == b.home_values
    assert a.mimic_joints == b.mimic_joints


def test_urdf_text_and_errors_follow_the_contract(adapter: tuple[str, Any]) -> None:
    _, impl = adapter
    text = robot_path("probot_anno").read_text()
    a, b = impl.RobotModel(text), native_model("probot_anno")
    q = sample_configurations(b, 50, seed=11)
    assert np.max(np.abs(a.forward_kinematics_batch(q) - b.forward_kinematics_batch(q))) <= TOL
    for urdf, tip in (("<robot", None), ("/no/such/file.urdf", None), (text, "no_such_link"), (42, None)):
        assert outcome(lambda u=urdf, t=tip: impl.RobotModel(u, t)) == outcome(
            lambda u=urdf, t=tip: native.RobotModel(u, t)
        )


# -- forward kinematics ------------------------------------------------------------------------


@pytest.mark.parametrize(("robot", "tip"), FK_ROBOTS, ids=case_ids(FK_ROBOTS))
def test_fk_agrees_with_native(adapter: tuple[str, Any], robot: str, tip: str | None) -> None:
    name, impl = adapter
    a, b = model_of(name, impl, robot, tip), native_model(robot, tip)
    q = sample_configurations(b, 1000, seed=7, margin=0.5)
    for link in b.link_names:
        got, expected = a.forward_kinematics_batch(q, link), b.forward_kinematics_batch(q, link)
        error = float(np.max(np.abs(got - expected)))
        assert error <= TOL, (link, error)
    identity = np.broadcast_to(np.eye(4), (5, 4, 4))
    assert np.array_equal(a.forward_kinematics_batch(q[:5], b.root_link), identity)
    assert a.forward_kinematics_batch(np.zeros((0, b.dof))).shape == (0, 4, 4)
    for row in q[:300]:
        pa, pb = a.forward_kinematics(row), b.forward_kinematics(row)
        assert isinstance(pa, Pose)
        assert abs(math.fsum(c * c for c in pa.orientation) - 1.0) <= 1e-12
        assert pa.orientation[3] >= 0.0
        assert np.max(np.abs(np.subtract(pa.position, pb.position))) <= TOL
        assert np.max(np.abs(np.subtract(pa.orientation, pb.orientation))) <= TOL


def test_move_group_poses_come_from_the_library(adapter: tuple[str, Any]) -> None:
    name, impl = adapter
    a, b = model_of(name, impl, "kinova"), native_model("kinova")
    ga, gb = impl.MoveGroup(a), native.MoveGroup(b)
    target = [3.0, 2.0, 1.0, -3.0, 2.0, 0.5]
    assert ga.go(target) is True and gb.go(target) is True
    assert ga.get_current_joint_values() == pytest.approx(gb.get_current_joint_values(), abs=1e-12)
    pa, pb = ga.get_current_pose(), gb.get_current_pose()
    assert np.max(np.abs(np.subtract(pa.position, pb.position))) <= TOL


def test_no_twin_kinematics_leaks_in(adapter: tuple[str, Any], monkeypatch: pytest.MonkeyPatch) -> None:
    _, impl = adapter

    def poisoned(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError("the adapter called the twin's kinematics")

    for function in ("fk", "fk_batch", "jacobian", "ik", "error_twist", "pinv_step"):
        monkeypatch.setattr(python_impl.kinematics, function, poisoned)
    model = impl.RobotModel(robot_path("ur5"))
    q = sample_configurations(model, 3, seed=1)
    model.forward_kinematics(q[0])
    model.forward_kinematics_batch(q)
    model.inverse_kinematics(model.forward_kinematics(q[1]), q[1] + 0.01)
    group = impl.MoveGroup(model)
    group.go(list(q[2]))
    group.get_current_pose()


# -- inverse kinematics ------------------------------------------------------------------------


@pytest.mark.parametrize(("robot", "tip"), IK_ROBOTS, ids=case_ids(IK_ROBOTS))
def test_ik_round_trips(adapter: tuple[str, Any], robot: str, tip: str | None) -> None:
    name, impl = adapter
    a, b = model_of(name, impl, robot, tip), native_model(robot, tip)
    rng = np.random.default_rng(3)
    q = sample_configurations(b, 100, seed=8)
    lower = np.array([lim.lower for lim in b.joint_limits])
    upper = np.array([lim.upper for lim in b.joint_limits])
    solved = agree = 0
    for row in q:
        target = b.forward_kinematics(row)
        seed = np.clip(row + rng.normal(0.0, 0.05, row.shape), lower, upper)  # nearby, not singular
        result = a.inverse_kinematics(target, seed)
        agree += result.status == b.inverse_kinematics(target, seed).status
        assert len(result.joint_values) == a.dof
        for v, lim in zip(result.joint_values, a.joint_limits, strict=True):
            if lim.type == JointType.CONTINUOUS:
                assert -math.pi < v <= math.pi
            else:
                assert lim.lower <= v <= lim.upper
        reached = b.forward_kinematics(list(result.joint_values))  # checked by native's FK
        distance = math.dist(reached.position, target.position)
        assert result.position_error == pytest.approx(distance, abs=1e-9)
        if result.status == IKStatus.SUCCESS:
            solved += 1
            assert distance <= 2e-6 and result.orientation_error <= 2e-6
        else:
            assert result.status == IKStatus.NO_SOLUTION
    assert solved >= 95, solved
    assert agree >= 98, agree  # the contract: nearby seeds agree on all but rare chaotic targets


def test_ik_is_deterministic_and_clamps_the_seed(adapter: tuple[str, Any]) -> None:
    name, impl = adapter
    a, b = model_of(name, impl, "probot_anno"), native_model("probot_anno")
    target = b.forward_kinematics([0.3, -0.4, 0.5, 0.2, -0.6, 0.1])
    first = a.inverse_kinematics(target, [0.2, -0.3, 0.4, 0.1, -0.5, 0.0])
    assert first == a.inverse_kinematics(target, [0.2, -0.3, 0.4, 0.1, -0.5, 0.0])
    # A seed far outside the limits that reaches the pose is clamped first (docs/api.md, step 1).
    outside = [lim.upper + 10.0 for lim in b.joint_limits]
    assert a.inverse_kinematics(b.forward_kinematics(outside), outside).status == (
        b.inverse_kinematics(b.forward_kinematics(outside), outside).status
    )
    root = a.inverse_kinematics(((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)), None, a.root_link)
    assert root.status == IKStatus.SUCCESS and root.joint_values == a.home_values


@pytest.mark.parametrize("far", [1e200, 1e308])
def test_ik_of_an_absurd_target_is_the_clamped_seed_never_nan(adapter: tuple[str, Any], far: float) -> None:
    """docs/api.md: a non-finite iterate gives ``NO_SOLUTION`` with the clamped seed (NaN from both
    adapters before, which the fuzzer read through the runner's FK as a rejected argument)."""
    name, impl = adapter
    a, b = model_of(name, impl, "probot_anno"), native_model("probot_anno")
    seed = [0.2, -0.3, 0.4, 0.1, -0.5, 0.0]
    target = ((far, 0.0, 0.3), (0.0, 0.0, 0.0, 1.0))
    result, expected = a.inverse_kinematics(target, seed), b.inverse_kinematics(target, seed)
    assert result.status == expected.status == IKStatus.NO_SOLUTION
    assert all(math.isfinite(v) for v in result.joint_values), result.joint_values
    if far == 1e308:  # the first step is already non-finite: native keeps the clamped seed
        assert result.joint_values == expected.joint_values == tuple(seed)


def test_argument_errors_are_the_contract(adapter: tuple[str, Any]) -> None:
    name, impl = adapter
    a, b = model_of(name, impl, "panda", "panda_rightfinger"), native_model("panda", "panda_rightfinger")
    good = [0.1] * b.dof
    pose = b.forward_kinematics(good)
    calls: list[tuple[str, tuple[Any, ...]]] = [
        ("forward_kinematics", ([0.0] * (b.dof - 1),)),
        ("forward_kinematics", ([math.nan] * b.dof,)),
        ("forward_kinematics", ({1, 2},)),
        ("forward_kinematics", (good, "no_such_link")),
        ("forward_kinematics_batch", (np.zeros((2, b.dof + 1)),)),
        ("forward_kinematics_batch", (np.full((2, b.dof), np.inf),)),
        ("inverse_kinematics", (pose,)),  # through the mimic joint: UNSUPPORTED_OPERATION
        ("inverse_kinematics", (pose, None, "panda_hand")),
        ("inverse_kinematics", (((0, 0, 0), (0, 0, 0, 0)),)),
        ("inverse_kinematics", (((0, 0, 0), (0, 0, 0, 1)), [0.0])),
        ("inverse_kinematics", ("pose",)),
    ]
    for method, args in calls:
        got = outcome(lambda m=method, x=args: getattr(a, m)(*x))
        expected = outcome(lambda m=method, x=args: getattr(b, m)(*x))
        if got[0] == "ok":
            assert expected[0] == "ok", (method, args)
        else:
            assert got == expected, (method, args)


# -- the campaign ------------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(ADAPTERS))
def test_short_campaign_against_native_exits_0(name: str, tmp_path: Path) -> None:
    load(name)
    artifacts = tmp_path / "a"
    proc = subprocess.run(
        [
            sys.executable,
            str(ROOT / "fuzz_diff.py"),
            str(tmp_path / "corpus"),
            "-runs=500",
            "-seed=1",
            "--op=fk",
            f"--targets=native,{ADAPTERS[name].spec}",
            f"--artifacts={artifacts}",
            "--no-progress",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "divergences: 0" in proc.stderr, proc.stderr[-3000:]  # FK agrees to ~1e-15
    assert not list(artifacts.glob("crash-*"))


# -- library behaviours the adapters document --------------------------------------------------


def test_pykdl_loads_without_dist_packages_on_sys_path() -> None:
    load("pykdl")
    assert "PyKDL" in sys.modules
    assert not any(p.rstrip("/") == "/usr/lib/python3/dist-packages" for p in sys.path)


def test_pykdl_missing_is_a_clear_import_error(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    load("pykdl")
    import adapters._kdl as module  # the adapter's PyKDL loader

    monkeypatch.delitem(sys.modules, "PyKDL")
    monkeypatch.setattr(module, "DEBIAN_DIST_PACKAGES", tmp_path)
    with pytest.raises(ImportError, match="python3-pykdl"):
        module.load_pykdl()


def test_kdl_parser_origins_make_pykdl_native_bit_for_bit() -> None:
    impl = load("pykdl_kdl_parser")
    for robot, tip in FK_ROBOTS:
        a, b = model_of("pykdl_kdl_parser", impl, robot, tip), native_model(robot, tip)
        q = sample_configurations(b, 500, seed=9, margin=0.5)
        assert np.array_equal(a.forward_kinematics_batch(q), b.forward_kinematics_batch(q)), robot
        if b.mimic_joints:
            continue
        for row in q[:40]:
            target = b.forward_kinematics(row)
            ra, rb = a.inverse_kinematics(target), b.inverse_kinematics(target)
            assert (ra.status, ra.joint_values) == (rb.status, rb.joint_values), robot  # errors: own formulas


def test_kdl_rotation_log_has_a_dead_zone() -> None:
    """KDL's ``Rotation::GetRot`` (hence ``diff`` and NR_JL's error twist) is zero below ~5e-7 rad.

    ``GetRotAngle(axis, eps = KDL::epsilon = 1e-6)`` calls a rotation whose
    antisymmetric part is below ``eps`` the identity. pinocchio's ``log3`` (and
    the twin) are exact, so near convergence KDL takes translation-only steps
    where the others also correct the orientation.
    """
    load("pykdl")
    import pinocchio as pin

    from adapters.pykdl_adapter import KDL

    axis = np.array([1.0, 1.0, 1.0]) / math.sqrt(3.0)
    for angle, kdl_is_zero in ((8e-7, True), (4.9e-7, True), (2e-6, False)):
        rotation = KDL.Rotation.Rot(KDL.Vector(*axis), angle)
        got = rotation.GetRot()
        assert (got.Norm() == 0.0) is kdl_is_zero, angle
        matrix = np.array([[rotation[i, j] for j in range(3)] for i in range(3)])
        assert np.allclose(pin.log3(matrix), axis * angle, rtol=1e-9, atol=0.0)


def test_kdl_dead_zone_splits_ik_statuses_on_so100() -> None:
    """A target where the dead zone decides: KDL targets converge, exact-log targets stall.

    From home, Newton-Raphson creeps along the limit of ``shoulder_pan``; at
    iteration 41 the rotation error is ~5e-7 rad, KDL's twist drops it and
    converges; the exact twist keeps it and stalls at a 1.15e-6 m error.
    """
    pin_impl, kdl_impl = load("pinocchio"), load("pykdl")
    path = robot_path("so100")
    pose = (
        (0.31890127615932284, 0.10074749462560141, 0.025516047714090315),
        (0.6899433731376523, -0.15486291950939143, 0.4279235728500477, 0.5629183189626326),
    )
    statuses = {
        "native": native.RobotModel(path).inverse_kinematics(pose).status,
        "pykdl": kdl_impl.RobotModel(path).inverse_kinematics(pose).status,
        "python": python_impl.RobotModel(path).inverse_kinematics(pose).status,
        "pinocchio": pin_impl.RobotModel(path).inverse_kinematics(pose).status,
    }
    assert statuses == {
        "native": IKStatus.SUCCESS,
        "pykdl": IKStatus.SUCCESS,
        "python": IKStatus.NO_SOLUTION,
        "pinocchio": IKStatus.NO_SOLUTION,
    }


MIMIC_ACROSS_SIZES = """<robot name="mimic_sizes">
  <link name="base"/><link name="l1"/><link name="l2"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="continuous"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.1 0 0"/><axis xyz="0 0 1"/><mimic joint="j1" multiplier="2"/></joint>
</robot>"""


def test_pinocchio_cannot_mimic_across_joint_sizes() -> None:
    impl = load("pinocchio")
    native.RobotModel(MIMIC_ACROSS_SIZES)  # the contract accepts it
    with pytest.raises(URDFError) as err:
        impl.RobotModel(MIMIC_ACROSS_SIZES)
    assert err.value.code == ErrorCode.URDF_UNSUPPORTED
    assert "pinocchio" in str(err.value)
    q = np.array([[0.3], [-0.9]])
    expected = native.RobotModel(MIMIC_ACROSS_SIZES).forward_kinematics_batch(q)
    got = load("pykdl").RobotModel(MIMIC_ACROSS_SIZES).forward_kinematics_batch(q)  # KDL has no such limit
    assert np.max(np.abs(got - expected)) <= TOL


def _mimic_siblings(master: str, mimic: str) -> str:
    limit = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'
    return (
        '<robot name="r"><link name="a"/><link name="b"/><link name="c"/>'
        f'<joint name="{master}" type="revolute"><parent link="a"/><child link="b"/>'
        f'<axis xyz="0 0 1"/>{limit}</joint>'
        f'<joint name="{mimic}" type="revolute"><parent link="a"/><child link="c"/>'
        f'<axis xyz="0 0 1"/>{limit}'
        f'<mimic joint="{master}" multiplier="2" offset="0"/></joint></robot>'
    )


def test_pinocchio_refuses_a_mimic_joint_whose_name_sorts_before_its_master_s() -> None:
    """F-PIN-2 (FINDINGS.md): the same valid tree builds with master m and mimic s, and is
    refused with master z and mimic a; native accepts both."""
    impl = load("pinocchio")
    for names in (("m", "s"), ("z", "a")):
        assert native.RobotModel(_mimic_siblings(*names), "c").dof == 1
    assert impl.RobotModel(_mimic_siblings("m", "s"), "c").dof == 1
    with pytest.raises(URDFError, match="The parent joint of the mimic joint is not in the kinematic tree"):
        impl.RobotModel(_mimic_siblings("z", "a"), "c")


def test_absurd_ik_targets_do_not_escape() -> None:
    """1e308 targets make NaN iterates: NO_SOLUTION everywhere (the twin once raised LinAlgError there)."""
    path = robot_path("kinova")
    pose = ((1.7976931348623157e308, 0.15, 0.24), (0.31, 0.01, 0.48, 0.65))
    assert native.RobotModel(path).inverse_kinematics(pose).status == IKStatus.NO_SOLUTION
    assert python_impl.RobotModel(path).inverse_kinematics(pose).status == IKStatus.NO_SOLUTION
    for name in ("pinocchio", "pykdl"):
        result = load(name).RobotModel(path).inverse_kinematics(pose)
        assert result.status == IKStatus.NO_SOLUTION, name
