"""The two implementations expose the same API: names, signatures, constants."""

from __future__ import annotations

import inspect

import pytest

import native
import python_impl
from robot_api import constants
from robot_api.protocol import GROUP_METHODS, MODEL_METHODS, MODEL_PROPERTIES, MoveGroupAPI, RobotModelAPI
from robot_api.robots import default_robot_path


def public(cls: type) -> set[str]:
    return {name for name in dir(cls) if not name.startswith("_")}


def params(func) -> list[tuple[str, object, object]]:  # type: ignore[no-untyped-def]
    sig = inspect.signature(func)
    return [(p.name, p.kind, p.default) for p in sig.parameters.values()]


def test_protocol_lists_match_the_protocol_classes() -> None:
    assert public(RobotModelAPI) == set(MODEL_METHODS) | set(MODEL_PROPERTIES)
    assert public(MoveGroupAPI) == set(GROUP_METHODS)


@pytest.mark.parametrize("impl", [native, python_impl], ids=["native", "python"])
def test_implements_the_protocol(impl) -> None:  # type: ignore[no-untyped-def]
    # The twin may add helpers for its own MoveGroup (they are not in the protocol).
    extra_model = public(impl.RobotModel) - set(MODEL_METHODS) - set(MODEL_PROPERTIES)
    assert extra_model <= {"chain", "check_vector", "link_index", "pose_of"}
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


@pytest.mark.parametrize("impl", [native, python_impl], ids=["native", "python"])
def test_every_public_call_is_documented(impl) -> None:  # type: ignore[no-untyped-def]
    for cls in (impl.RobotModel, impl.MoveGroup):
        assert cls.__doc__
        for name in public(cls):
            assert getattr(cls, name).__doc__, f"{cls.__name__}.{name}"


def test_native_constants_equal_the_contract() -> None:
    expected = {name: getattr(constants, name) for name in native.constants}
    assert native.constants == expected
    documented = {name for name in dir(constants) if name.isupper()}
    assert set(native.constants) == documented


def test_models_of_one_implementation_do_not_mix() -> None:
    from robot_api import InvalidInputError

    with pytest.raises(InvalidInputError):
        native.MoveGroup(python_impl.RobotModel(default_robot_path()))  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError):
        python_impl.MoveGroup(native.RobotModel(default_robot_path()))  # type: ignore[arg-type]


@pytest.mark.parametrize("impl", [native, python_impl], ids=["native", "python"])
def test_new_group_methods_return_the_contract_records(impl) -> None:  # type: ignore[no-untyped-def]
    from robot_api import MoveItErrorCode, PlanResult, Pose, RobotState, RobotTrajectory

    g = impl.MoveGroup(impl.RobotModel(default_robot_path()))
    result = g.plan([0.1] * 6)
    assert type(result) is PlanResult and type(result.error_code) is MoveItErrorCode
    assert type(result.success) is bool and type(result.planning_time) is float
    assert type(result.trajectory) is RobotTrajectory
    state = g.get_current_state()
    assert type(state) is RobotState and type(state.joint_state.position) is tuple
    path = g.compute_cartesian_path([g.get_current_pose()], 0.01)
    assert type(path) is tuple and len(path) == 2
    assert type(path[0]) is RobotTrajectory and type(path[1]) is float
    assert g.set_pose_target(Pose((0.2, 0.0, 0.3), (0.0, 0.0, 0.0, 1.0))) is None
    assert g.set_position_target([0.2, 0.0, 0.3]) is None
    assert g.clear_pose_targets() is None and g.stop() is None
