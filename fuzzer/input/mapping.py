"""How a ROS message becomes a call on a target (documented in docs/engine.md).

========  ==========================  ==============================================================
op        message type                call
========  ==========================  ==============================================================
move      sensor_msgs/JointState      ``velocity[0]`` (if any) -> ``set_max_velocity_scaling_factor``;
                                      ``effort[0]`` (if any) -> ``set_max_acceleration_scaling_factor``;
                                      ``name`` empty: ``set_joint_value_target(position)``, else
                                      ``set_joint_value_target(name, position)``; then ``go()``
move      std_msgs/Float64MultiArray  ``set_joint_value_target(data)``; ``go()``
fk        sensor_msgs/JointState      ``forward_kinematics(position, header.frame_id or None)``
fk        std_msgs/Float64MultiArray  ``forward_kinematics(data)``
ik        geometry_msgs/PoseStamped   ``inverse_kinematics(pose, None, header.frame_id or None)``
ik        geometry_msgs/Pose          ``inverse_kinematics(pose)``
scenario  rrosfuzz/Scenario           its steps, in order, on one live ``MoveGroup``
                                      (``fuzzer.scenario``: a list of messages on named topics)
========  ==========================  ==============================================================

Names that do not match the robot's joints are valid inputs: both targets must
reject them the same way. The mapping itself never validates anything.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

from fuzzer.scenario.steps import MAX_STEPS_LIMIT, MSG_TYPE, ScenarioCall, to_call, to_message

if TYPE_CHECKING:  # Hypothesis is imported where strategies are built: it costs about 0.12 s, which
    # only the seeds need, and the dry run's first child is forked before them (fuzzer/dry_run.py)
    from hypothesis.strategies import SearchStrategy

OPS = ("move", "fk", "ik", "scenario")
DEFAULT_MSG_TYPE = {
    "move": "sensor_msgs/JointState",
    "fk": "sensor_msgs/JointState",
    "ik": "geometry_msgs/PoseStamped",
    "scenario": MSG_TYPE,
}


@dataclass(frozen=True)
class MoveCall:
    names: tuple[str, ...] | None
    positions: tuple[float, ...]
    velocity_scaling: float | None = None
    acceleration_scaling: float | None = None


@dataclass(frozen=True)
class FkCall:
    joint_values: tuple[float, ...]
    link: str | None = None


@dataclass(frozen=True)
class IkCall:
    position: tuple[float, ...]
    orientation: tuple[float, ...]
    link: str | None = None


Call = MoveCall | FkCall | IkCall | ScenarioCall


class CallError(ValueError):
    """A stored call (a sidecar's call history) that is not a call."""


def call_to_json(call: Call, seed: tuple[float, ...] | None = None) -> dict[str, Any]:
    """A call (and the IK seed it ran with) as plain JSON data."""
    data: dict[str, Any] = {"kind": type(call).__name__}
    if isinstance(call, ScenarioCall):
        data["steps"] = to_message(call)["steps"]
    else:
        for name, value in vars(call).items():
            data[name] = list(value) if isinstance(value, tuple) else value
    if seed is not None:
        data["seed"] = list(seed)
    return data


def _floats(data: dict[str, Any], name: str) -> tuple[float, ...]:
    value = data.get(name)
    if not isinstance(value, list) or not all(
        isinstance(x, int | float) and not isinstance(x, bool) for x in value
    ):
        raise CallError(f"call field {name!r} must be a list of numbers")
    return tuple(float(x) for x in value)


def _optional(data: dict[str, Any], name: str, kind: type) -> Any:
    value: Any = data.get(name)
    accepted = (int, float) if kind is float else (kind,)
    if value is not None and (not isinstance(value, accepted) or isinstance(value, bool)):
        raise CallError(f"call field {name!r} must be a {kind.__name__} or null")
    if kind is float and value is not None:
        return float(cast(float, value))
    return value


def call_from_json(data: Any) -> tuple[Call, tuple[float, ...] | None]:
    """Read a call written by ``call_to_json`` (data only: nothing is evaluated).

    Raises
    ------
    CallError
        Naming the field that is wrong.
    """
    if not isinstance(data, dict):
        raise CallError("a stored call must be an object")
    kind = data.get("kind")
    call: Call
    if kind == "MoveCall":
        names = data.get("names")
        if names is not None and (not isinstance(names, list) or not all(isinstance(n, str) for n in names)):
            raise CallError("call field 'names' must be a list of strings or null")
        call = MoveCall(
            None if names is None else tuple(names),
            _floats(data, "positions"),
            _optional(data, "velocity_scaling", float),
            _optional(data, "acceleration_scaling", float),
        )
    elif kind == "FkCall":
        call = FkCall(_floats(data, "joint_values"), _optional(data, "link", str))
    elif kind == "IkCall":
        call = IkCall(_floats(data, "position"), _floats(data, "orientation"), _optional(data, "link", str))
    elif kind == "ScenarioCall":
        call = _scenario_call(data)
    else:
        raise CallError(f"unknown call kind {kind!r}: expected MoveCall, FkCall, IkCall or ScenarioCall")
    return call, (_floats(data, "seed") if data.get("seed") is not None else None)


@functools.cache
def _shipped_registry() -> Any:
    """The registry of the shipped message types (every scenario topic's type is one)."""
    from fuzzer.input.msgdef import MessageRegistry

    return MessageRegistry()


def _scenario_call(data: dict[str, Any]) -> ScenarioCall:
    """A stored scenario call, validated as a scenario test case (the shipped message types)."""
    from fuzzer.scenario.steps import validate

    extra = sorted(str(k) for k in data if k not in ("kind", "steps", "seed"))
    if extra:
        raise CallError(f"unexpected field(s) in a ScenarioCall: {', '.join(extra)}")
    try:
        validate({"steps": data.get("steps")}, _shipped_registry(), MAX_STEPS_LIMIT)
    except ValueError as exc:
        raise CallError(f"call field 'steps': {exc}") from None
    return to_call({"steps": data["steps"]})


def _joint_state_move(m: dict[str, Any]) -> MoveCall:
    names = tuple(m["name"])
    return MoveCall(
        names or None,
        tuple(m["position"]),
        m["velocity"][0] if m["velocity"] else None,
        m["effort"][0] if m["effort"] else None,
    )


def _pose(m: dict[str, Any]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    p, q = m["position"], m["orientation"]
    return (p["x"], p["y"], p["z"]), (q["x"], q["y"], q["z"], q["w"])


MAPPINGS: dict[tuple[str, str], Callable[[dict[str, Any]], Call]] = {
    ("move", "sensor_msgs/JointState"): _joint_state_move,
    ("move", "std_msgs/Float64MultiArray"): lambda m: MoveCall(None, tuple(m["data"])),
    ("fk", "sensor_msgs/JointState"): lambda m: FkCall(tuple(m["position"]), m["header"]["frame_id"] or None),
    ("fk", "std_msgs/Float64MultiArray"): lambda m: FkCall(tuple(m["data"])),
    ("ik", "geometry_msgs/PoseStamped"): lambda m: IkCall(*_pose(m["pose"]), m["header"]["frame_id"] or None),
    ("ik", "geometry_msgs/Pose"): lambda m: IkCall(*_pose(m)),
    ("scenario", MSG_TYPE): to_call,
}

# The fields mutators should prefer, per message type (dotted paths).
FOCUS = {
    "sensor_msgs/JointState": ("position", "name"),
    "std_msgs/Float64MultiArray": ("data",),
    "geometry_msgs/PoseStamped": ("pose.position", "pose.orientation"),
    "geometry_msgs/Pose": ("position", "orientation"),
}


class MappingError(ValueError):
    """No mapping for this (op, message type)."""


def mapping_for(op: str, msg_type: str) -> Callable[[dict[str, Any]], Call]:
    try:
        return MAPPINGS[(op, msg_type)]
    except KeyError:
        supported = ", ".join(t for o, t in MAPPINGS if o == op)
        raise MappingError(f"--op {op} cannot use {msg_type}; supported: {supported}") from None


@dataclass(frozen=True)
class RobotFacts:
    """What seed hints need to know about the robot."""

    joint_names: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    link_names: tuple[str, ...]
    reachable: Callable[[tuple[float, ...]], tuple[tuple[float, ...], tuple[float, ...]]]
    """FK of a configuration (position, orientation), for reachable IK seeds."""


def _joint_value(lo: float, hi: float) -> SearchStrategy[float]:
    from hypothesis import strategies as st

    lo = -2 * math.pi if math.isinf(lo) else lo
    hi = 2 * math.pi if math.isinf(hi) else hi
    return st.one_of(st.floats(lo, hi), st.sampled_from([lo, hi, 0.0, min(max(0.0, lo), hi)]))


def _configuration(facts: RobotFacts) -> SearchStrategy[tuple[float, ...]]:
    from hypothesis import strategies as st

    return st.tuples(*(_joint_value(lo, hi) for lo, hi in zip(facts.lower, facts.upper, strict=True)))


def seed_hints(msg_type: str, facts: RobotFacts) -> dict[str, SearchStrategy[Any]]:
    """Robot-aware strategies for the fields that matter (Table I's generic strategies
    would almost never produce a joint name or a reachable pose)."""
    from hypothesis import strategies as st

    configuration = _configuration(facts)
    if msg_type == "sensor_msgs/JointState":
        return {
            "name": st.one_of(st.just(list(facts.joint_names)), st.just([])),
            "position": configuration.map(list),
            "velocity": st.one_of(st.just([]), st.lists(st.floats(0.05, 1.0), min_size=1, max_size=1)),
            "effort": st.one_of(st.just([]), st.lists(st.floats(0.05, 1.0), min_size=1, max_size=1)),
            "header.frame_id": st.sampled_from(["", *facts.link_names]),
        }
    if msg_type == "std_msgs/Float64MultiArray":
        return {"data": configuration.map(list)}
    poses = configuration.map(facts.reachable).map(
        lambda p: {
            "position": dict(zip("xyz", p[0], strict=True)),
            "orientation": dict(zip("xyzw", p[1], strict=True)),
        }
    )
    if msg_type == "geometry_msgs/PoseStamped":
        # one configuration gives both halves, so the pose is reachable
        return {"pose": poses, "header.frame_id": st.just("")}
    if msg_type == "geometry_msgs/Pose":
        return {
            "position": poses.map(lambda p: p["position"]),
            "orientation": poses.map(lambda p: p["orientation"]),
        }
    if msg_type == "geometry_msgs/PointStamped":
        return {"point": poses.map(lambda p: p["position"]), "header.frame_id": st.just("")}
    if msg_type == "geometry_msgs/PoseArray":
        return {"poses": st.lists(poses, min_size=1, max_size=3), "header.frame_id": st.just("")}
    return {}


SCENARIO_WEIGHTS = {
    "joint_target": 4,
    "named_target": 2,
    "pose_target": 2,
    "position_target": 1,
    "remember": 2,
    "velocity_scaling": 1,
    "acceleration_scaling": 1,
    "goal_tolerance": 1,
    "eef_step": 1,
    "jump_threshold": 1,
    "cartesian_path": 2,
    "plan": 3,
    "execute": 3,
    "go": 4,
    "stop": 1,
    "clear_pose_targets": 1,
}
"""Relative frequency of each step kind in generated scenarios."""

REMEMBERED = ("a", "b", "pick", "place")
"""Names ``/remember`` steps of generated scenarios store (``/named_target`` uses them after)."""


def scenario_strategy(
    registry: Any, facts: RobotFacts, max_steps: int, allow_special_floats: bool = False
) -> SearchStrategy[dict[str, Any]]:
    """Scenario messages (``{"steps": [...]}``) of 1..max_steps steps that are mostly
    meaningful scripts: joint targets within the limits, reachable pose targets and
    Cartesian waypoints, named targets ``home`` or a name remembered before, scaling factors
    in (0, 1], goal tolerances and Cartesian settings in sensible ranges.

    Each step's message is drawn from the registry's strategy of its type
    (``fuzzer.generation.strategies.strategy_for``) with the robot hints of :func:`seed_hints`.
    """
    from hypothesis import strategies as st

    from fuzzer.generation.strategies import strategy_for
    from fuzzer.scenario.steps import KINDS, TOPICS

    def message(msg_type: str, **extra: SearchStrategy[Any]) -> SearchStrategy[dict[str, Any]]:
        hints = {**seed_hints(msg_type, facts), **extra}
        if msg_type == "sensor_msgs/JointState":  # the scaling fields are not read by /joint_target
            hints.update(velocity=st.just([]), effort=st.just([]), **{"header.frame_id": st.just("")})
        return strategy_for(registry, msg_type, hints=hints, allow_special_floats=allow_special_floats)

    def number(values: SearchStrategy[float]) -> SearchStrategy[dict[str, Any]]:
        return message("std_msgs/Float64", data=values)

    by_kind: dict[str, SearchStrategy[dict[str, Any]]] = {
        "velocity_scaling": number(st.one_of(st.floats(0.05, 1.0), st.just(1.0))),
        "acceleration_scaling": number(st.one_of(st.floats(0.05, 1.0), st.just(1.0))),
        "goal_tolerance": number(st.sampled_from([0.0, 1e-6, 1e-4, 1e-3, 1e-2])),
        "eef_step": number(st.one_of(st.floats(0.01, 0.1), st.just(0.01))),
        "jump_threshold": number(st.one_of(st.just(0.0), st.floats(1.0, 10.0))),
    }
    for kind, topic in KINDS.items():
        if kind not in by_kind and kind not in ("named_target", "remember"):
            by_kind[kind] = message(TOPICS[topic].msg_type)
    kinds = [kind for kind, weight in SCENARIO_WEIGHTS.items() for _ in range(weight)]

    @st.composite
    def scenario(draw: st.DrawFn) -> dict[str, Any]:
        remembered: list[str] = []
        steps = []
        for _ in range(draw(st.integers(1, max_steps))):
            kind = draw(st.sampled_from(kinds))
            if kind == "remember":
                name = draw(st.sampled_from(REMEMBERED))
                remembered.append(name)
                msg: dict[str, Any] = {"data": name}
            elif kind == "named_target":
                msg = {"data": draw(st.sampled_from(["home", *remembered]))}
            else:
                msg = draw(by_kind[kind])
            steps.append({"topic": KINDS[kind], "msg": msg})
        return {"steps": steps}

    return scenario()
