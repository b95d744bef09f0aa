"""Targets: implementations of the API, and running one call on one of them.

A target spec is ``native``, ``python`` or ``module:attribute``, where the
attribute is any object with ``RobotModel`` and ``MoveGroup`` that follow
``robot_api.protocol`` (a module, a ``types.SimpleNamespace``, a class...).
"""

from __future__ import annotations

import importlib
import importlib.util
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from fuzzer.execution.records import Outcome, Status
from fuzzer.input.mapping import Call, FkCall, IkCall, MoveCall
from fuzzer.scenario.steps import ScenarioCall
from robot_api.errors import RobotAPIError

BUILTIN = {"native": "native", "python": "python_impl", "ros_tf": "adapters.ros_tf:api"}
"""Short target names: a module, or a ``module:attribute`` (``ros_tf``: robot_state_publisher + tf2)."""


class TargetError(ValueError):
    """A target spec that cannot be loaded."""


def module_of(spec: str) -> str:
    """Top-level module a spec imports (for instrumentation)."""
    return BUILTIN.get(spec, spec).split(":", 1)[0]


def _hint(spec: str) -> str:
    """For a bare library name with an adapter (``pinocchio``): the spec that names it."""
    adapter = f"{spec.replace('-', '_')}_adapter"
    if not adapter.isidentifier():
        return ""
    found = importlib.util.find_spec(f"adapters.{adapter}") is not None  # found, not imported
    return f" (an adapter: adapters.{adapter}:api)" if found else ""


def load_target(spec: str) -> Any:
    """Import a target by spec.

    Raises
    ------
    TargetError
        With a message naming the spec and what is wrong.
    """
    if spec in BUILTIN:
        module_name, _, name = BUILTIN[spec].partition(":")
        attribute = name or None
    elif ":" in spec:
        module_name, attribute = spec.split(":", 1)
        if not module_name or not attribute:
            raise TargetError(f"target {spec!r}: expected module:attribute")
    else:
        raise TargetError(f"target {spec!r}: expected {', '.join(BUILTIN)} or module:attribute{_hint(spec)}")
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # noqa: BLE001 - any import failure is reported the same way
        raise TargetError(f"target {spec!r}: cannot import {module_name}: {exc}") from None
    except SystemExit as exc:  # a library that calls exit() on import ended the command without a word
        raise TargetError(f"target {spec!r}: importing {module_name} called exit({exc.code!r})") from None
    impl = module
    if attribute is not None:
        try:
            for part in attribute.split("."):
                impl = getattr(impl, part)
        except AttributeError:
            raise TargetError(f"target {spec!r}: {module_name} has no attribute {attribute}") from None
    for name in ("RobotModel", "MoveGroup"):
        if not callable(getattr(impl, name, None)):
            raise TargetError(f"target {spec!r}: it has no callable {name} (see robot_api.protocol)")
    return impl


@dataclass
class Runner:
    """One target with its model loaded, ready to run calls."""

    name: str
    impl: Any
    model: Any
    urdf: str | os.PathLike[str] | None = None
    tip_link: str | None = None

    @classmethod
    def create(cls, spec: str, urdf: str | os.PathLike[str], tip_link: str | None) -> Runner:
        impl = load_target(spec)
        return cls(spec, impl, impl.RobotModel(urdf, tip_link), urdf, tip_link)

    def fresh(self) -> Runner:
        """The same target newly constructed (new model; every call makes a new group):
        no state from earlier calls. Without a known URDF, a copy sharing this model."""
        if self.urdf is None:
            return Runner(self.name, self.impl, self.model)
        model = self.impl.RobotModel(self.urdf, self.tip_link)
        return Runner(self.name, self.impl, model, self.urdf, self.tip_link)

    @property
    def home(self) -> tuple[float, ...]:
        return tuple(self.model.home_values)

    def run(self, call: Call, ik_seed: tuple[float, ...] | None = None) -> Outcome:
        """Execute ``call``; never raises (failures become the outcome)."""
        try:
            return self._run(call, ik_seed)
        except RobotAPIError as exc:
            return Outcome(Status.REJECTED, type(exc).__name__, int(exc.code), str(exc)[:500])
        except KeyboardInterrupt:
            raise
        except BaseException as exc:  # noqa: BLE001 - a crash of the target (SystemExit too) is a finding
            return Outcome(Status.CRASHED, type(exc).__name__, None, str(exc)[:500])

    def _run(self, call: Call, ik_seed: tuple[float, ...] | None) -> Outcome:
        if isinstance(call, MoveCall):
            group = self.impl.MoveGroup(self.model)
            if call.velocity_scaling is not None:
                group.set_max_velocity_scaling_factor(call.velocity_scaling)
            if call.acceleration_scaling is not None:
                group.set_max_acceleration_scaling_factor(call.acceleration_scaling)
            if call.names is None:
                group.set_joint_value_target(list(call.positions))
            else:
                group.set_joint_value_target(list(call.names), list(call.positions))
            moved = group.go()
            pose = group.get_current_pose()
            values: dict[str, Sequence[float]] = {
                "joint_values": tuple(map(float, group.get_current_joint_values())),
                "position": tuple(map(float, pose.position)),
                "orientation": tuple(map(float, pose.orientation)),
            }
            return Outcome(Status.OK if moved is True else Status.FAILED, values=values)
        if isinstance(call, FkCall):
            pose = self.model.forward_kinematics(list(call.joint_values), call.link)
            return Outcome(
                Status.OK,
                values={
                    "position": tuple(map(float, pose.position)),
                    "orientation": tuple(map(float, pose.orientation)),
                },
            )
        if isinstance(call, IkCall):
            seed = list(ik_seed) if ik_seed is not None else None
            result = self.model.inverse_kinematics((call.position, call.orientation), seed, call.link)
            reached = self.model.forward_kinematics(list(result.joint_values), call.link)
            converged = str(result.status) == "success"
            return Outcome(
                Status.OK if converged else Status.FAILED,
                values={
                    "joint_values": tuple(map(float, result.joint_values)),
                    "position": tuple(map(float, reached.position)),
                    "orientation": tuple(map(float, reached.orientation)),
                },
            )
        if isinstance(call, ScenarioCall):
            from fuzzer.scenario.execute import run_scenario

            return run_scenario(self, call)
        raise TypeError(f"unknown call {call!r}")
