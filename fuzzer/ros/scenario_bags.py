"""Scenarios in bags (``--op scenario``): a scenario crash file as a bag of its steps, and a
bag's messages as scenario seeds.

A scenario's steps are ROS messages on named topics (``fuzzer.scenario.steps.TOPICS``), so a
bag records one as it is: step ``i`` on ``/rrosfuzz/scenario`` + its topic
(``/rrosfuzz/scenario/go``, ...) at ``i`` seconds after the start, its message as in the test
case (the header untouched; the order is the record time's). ``export-bag`` adds each target's
state after each step, at the step's time: ``/rrosfuzz/target_k/joint_states`` and
``/rrosfuzz/target_k/pose``, so that ``rosbag play`` with a ``robot_state_publisher`` per target
shows both arms go through the script.

Read back (``--seeds-from-bag`` with ``--op scenario``), a bag with messages on those topics is
a record of scripts, read in the bag's order. A bag without them is a recording: each of its
``sensor_msgs/JointState`` and ``geometry_msgs/PoseStamped`` messages (any topic) becomes a move,
a joint or pose target and ``go`` (the paper's successive moves, on states a robot was recorded
in). The steps are cut into scripts of at most ``--max-steps`` steps, a move's two never apart;
a step (or move) the campaign's validation refuses is skipped.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any, TypeGuard

from fuzzer.input.msgdef import MessageRegistry
from fuzzer.ros import bags, env
from fuzzer.scenario.steps import KINDS, MAX_STEPS_LIMIT, TOPICS, validate

SCENARIO_NS = "/rrosfuzz/scenario"
"""Where a scenario's step topics are in a bag (``/go`` -> ``/rrosfuzz/scenario/go``)."""

STEP_SECONDS = 1
"""Record time between two steps of an exported scenario (s): ``rosbag play`` at one step a second."""

MOVES = {"sensor_msgs/JointState": "joint_target", "geometry_msgs/PoseStamped": "pose_target"}
"""The message types of a recording that become moves, and the step kind each sets."""

Record = tuple[str, Any, Any]
"""(topic, genpy message, record time) of a bag to write."""


def export_records(
    crash: Path, message: dict[str, Any], sidecar: dict[str, Any], model: Any, start: Any
) -> list[Record]:
    """The bag records of a scenario crash file (``message``, its test case's): its steps, and
    each target's state after each step from its ``sidecar``; ``model``: the twin's model of
    its robot; ``start``: the first step's record time (``rospy.Time``).

    Raises
    ------
    BagError
        A step is not a valid step of a scenario.
    """
    try:
        validate(message, MessageRegistry(()), MAX_STEPS_LIMIT)
    except ValueError as exc:
        raise bags.BagError(f"{crash}: not a scenario: {exc}") from None
    outcomes = sidecar.get("outcomes", [])
    return [
        *step_records(message["steps"], start),
        *state_records(
            outcomes if isinstance(outcomes, list) else [], model.joint_names, model.root_link, start
        ),
    ]


def step_records(steps: Sequence[dict[str, Any]], start: Any) -> list[Record]:
    """The bag records of a scenario's steps (``{"topic", "msg"}`` dicts, validated).

    Raises
    ------
    BagError
        A step's message is not its topic's type.
    """
    rospy = env.import_module("rospy")
    out: list[Record] = []
    for index, step in enumerate(steps):
        spec = TOPICS[step["topic"]]
        try:
            message = bags.from_data(bags.message_class(spec.msg_type), step["msg"])
        except (LookupError, TypeError, ValueError, AttributeError) as exc:
            raise bags.BagError(
                f"step {index} ({step['topic']}): its message is not a {spec.msg_type}: "
                f"{type(exc).__name__}: {exc}"
            ) from None
        out.append((SCENARIO_NS + step["topic"], message, start + rospy.Duration(index * STEP_SECONDS)))
    return out


def state_records(outcomes: Sequence[Any], joint_names: Sequence[str], root: str, start: Any) -> list[Record]:
    """Each target's joint state and pose after each step, from a scenario sidecar's outcomes
    (``outcomes[k]["steps"][i]["values"]``), at step ``i``'s time; what a step did not report
    is left out."""
    rospy = env.import_module("rospy")
    sensor_msgs = env.import_module("sensor_msgs.msg")
    out: list[Record] = []
    for k, outcome in enumerate(outcomes[:2]):
        steps = outcome.get("steps") if isinstance(outcome, dict) else None
        for index, step in enumerate(steps if isinstance(steps, list) else []):
            values = step.get("values") if isinstance(step, dict) else None
            if not isinstance(values, dict):
                continue
            when = start + rospy.Duration(index * STEP_SECONDS)
            joints = values.get("joint_values")
            if _numbers(joints, len(joint_names)):
                state = sensor_msgs.JointState()
                state.header.stamp = when
                state.name, state.position = list(joint_names), [float(v) for v in joints]
                out.append((f"/rrosfuzz/target_{k}/joint_states", state, when))
            position, orientation = values.get("position"), values.get("orientation")
            if _numbers(position, 3) and _numbers(orientation, 4):
                pose = bags.pose_stamped({"position": position, "orientation": orientation}, root)
                pose.header.stamp = when
                out.append((f"/rrosfuzz/target_{k}/pose", pose, when))
    return out


def _numbers(value: Any, length: int) -> TypeGuard[list[float]]:
    return (
        isinstance(value, list)
        and len(value) == length
        and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
    )


def read_scenarios(
    path: Path, validate: Callable[[Any], None], max_steps: int, joints: Sequence[str]
) -> list[dict[str, Any]]:
    """A bag's scenario steps (or, if it has none, its recorded states as moves) as scenario
    messages of at most ``max_steps`` steps each, each passing ``validate``; at most
    ``bags.MAX_SEEDS`` of them. ``joints``: the chain's joints, the order a recorded state's
    positions are put in (``bags.recorded_state``).

    Raises
    ------
    BagError
        The file is not a readable bag, or holds nothing that makes a valid scenario.
    """
    types = sorted({spec.msg_type for spec in TOPICS.values()} | set(MOVES))
    limit = bags.MAX_SEEDS * max_steps
    held: list[str] = []
    script: list[list[dict[str, Any]]] = []
    moves: list[list[dict[str, Any]]] = []
    for topic, msg_type, data in bags.iter_messages(path, types, held):
        spec = TOPICS.get(topic[len(SCENARIO_NS) :]) if topic.startswith(SCENARIO_NS + "/") else None
        if spec is not None:
            if spec.msg_type == msg_type:
                _keep(script, [{"topic": KINDS[spec.kind], "msg": data}], validate)
        elif msg_type in MOVES and not script:
            if msg_type == "sensor_msgs/JointState":
                data = bags.recorded_state(data, joints)
            target = {"topic": KINDS[MOVES[msg_type]], "msg": data}
            _keep(moves, [target, {"topic": KINDS["go"], "msg": {}}], validate)
        if len(script) >= limit or (not script and len(moves) >= limit):
            break
    scenarios = _cut(script or moves, max_steps)[: bags.MAX_SEEDS]
    if not scenarios:
        holds = ", ".join(sorted(held)) or "no messages"
        raise bags.BagError(
            f"--seeds-from-bag {path}: no valid scenario step on {SCENARIO_NS}/<step> and no valid "
            f"JointState or PoseStamped to move to (the bag holds: {holds})"
        )
    return scenarios


Steps = list[dict[str, Any]]


def _keep(units: list[Steps], unit: Steps, validate: Callable[[Any], None]) -> None:
    """Append ``unit`` (steps) to ``units`` when ``validate`` takes it as a scenario."""
    try:
        validate({"steps": unit})
    except ValueError:
        return
    units.append(unit)


def _cut(units: Iterable[list[dict[str, Any]]], max_steps: int) -> list[dict[str, Any]]:
    """Units of steps in order, packed into scenarios of at most ``max_steps`` steps."""
    out: list[dict[str, Any]] = []
    current: list[dict[str, Any]] = []
    for unit in units:
        if len(unit) > max_steps:
            continue  # a move (two steps) in scripts of one step
        if current and len(current) + len(unit) > max_steps:
            out.append({"steps": current})
            current = []
        current = current + unit
    if current:
        out.append({"steps": current})
    return out
