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

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeGuard

from fuzzer.input.filtering import is_reasonable
from fuzzer.input.msgdef import MessageRegistry
from fuzzer.input.testcase import MAX_BYTES
from fuzzer.ros import bags, env
from fuzzer.scenario.steps import KINDS, MAX_STEPS_LIMIT, TOPICS, validate

SCENARIO_NS = "/rrosfuzz/scenario"
"""Where a scenario's step topics are in a bag (``/go`` -> ``/rrosfuzz/scenario/go``)."""

STEP_SECONDS = 1
"""Record time between two steps of an exported scenario (s): ``rosbag play`` at one step a second."""

KEPT_BYTES = 64 << 20
"""The most a bag's scenarios hold in all (encoded): 300 steps of 130,000 positions each took
1.6 GB to keep before."""

ENVELOPE = 300
"""Bytes a test case adds around its steps (its format, type, origin, lineage), for packing."""

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
    """Each target's joint state after each step, and its pose after each step that reports one,
    from a scenario sidecar's outcomes
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
    path: Path,
    validate: Callable[[Any], None],
    max_steps: int,
    joints: Sequence[str],
    max_bytes: int = MAX_BYTES,
    filtering: bool = True,
) -> list[dict[str, Any]]:
    """A bag's scenario steps (or, if it has none, its recorded states as moves) as scenario
    messages of at most ``max_steps`` steps and ``max_bytes`` bytes encoded each (libFuzzer's
    ``-max_len``: a longer seed was cut into a malformed input), each passing ``validate`` (and,
    with ``filtering``, the campaign's filter: one NaN state dropped its script's seven valid
    moves with it); at most ``bags.MAX_SEEDS`` of them, holding at most :data:`KEPT_BYTES`.
    ``joints``: the chain's joints, the order a recorded state's positions are put in
    (``bags.recorded_state``).

    Raises
    ------
    BagError
        The file is not a readable bag, or holds nothing that makes a valid scenario.
    """
    types = sorted({spec.msg_type for spec in TOPICS.values()} | set(MOVES))
    held: list[str] = []
    mode: list[str] = []
    packer = _Packer(max_steps, max_bytes)
    seen = 0
    for topic, msg_type, data in bags.iter_messages(path, types, held, lambda c: _chooser(c, mode)):
        if mode == ["script"]:
            unit = [{"topic": topic[len(SCENARIO_NS) :], "msg": data}]
        else:
            if msg_type == "sensor_msgs/JointState":
                data = bags.recorded_state(data, joints)
            unit = [{"topic": KINDS[MOVES[msg_type]], "msg": data}, {"topic": KINDS["go"], "msg": {}}]
        seen += 1
        size = packer.size_of(unit)  # before the validation, which a 130,000-value step made slow
        if size is None or not _usable(unit, validate, filtering) or packer.add(unit, size):
            continue
        break  # full: MAX_SEEDS scripts, or KEPT_BYTES of them
    scenarios = packer.done()
    if not scenarios:
        moves = "a move takes two steps: --max-steps must be 2 or more" if max_steps < 2 and seen else ""
        raise bags.BagError(
            f"--seeds-from-bag {path}: no valid scenario step on {SCENARIO_NS}/<step> and no valid "
            f"JointState or PoseStamped to move to{f' ({moves})' if moves else ''} "
            f"(the bag holds: {bags.holdings(held)})"
        )
    return scenarios


def _chooser(connections: Sequence[tuple[str, str]], mode: list[str]) -> Callable[[str, str], bool]:
    """The connections to read, from the bag's index: its step topics (each of its step's type)
    if it has any, else its recorded states (JointState and PoseStamped on any topic); ``mode``
    gets which. A recording ahead of the steps hid them (the reading stopped at its limit)."""

    def step(topic: str, datatype: str) -> bool:
        spec = TOPICS.get(topic[len(SCENARIO_NS) :]) if topic.startswith(SCENARIO_NS + "/") else None
        return spec is not None and spec.msg_type == datatype

    if any(step(topic, datatype) for topic, datatype in connections):
        mode.append("script")
        return step
    mode.append("recording")
    return lambda topic, datatype: datatype in MOVES and not topic.startswith(SCENARIO_NS + "/")


def _usable(unit: list[dict[str, Any]], validate: Callable[[Any], None], filtering: bool) -> bool:
    """Whether ``unit`` (steps) passes ``validate`` as a scenario, and the filter."""
    try:
        validate({"steps": unit})
    except ValueError:
        return False
    return not filtering or is_reasonable({"steps": unit})


class _Packer:
    """Units of steps, in order, packed into scenarios of at most ``max_steps`` steps and
    ``max_bytes`` bytes (their test case's encoding, about), a unit never split."""

    def __init__(self, max_steps: int, max_bytes: int) -> None:
        self.max_steps, self.max_bytes = max_steps, max_bytes
        self.scenarios: list[dict[str, Any]] = []
        self.current: list[dict[str, Any]] = []
        self.size = self.kept = 0

    def size_of(self, unit: list[dict[str, Any]]) -> int | None:
        """``unit``'s size encoded (bytes, with a test case's envelope), or None when it can never
        be packed: a move in scripts of one step, a step larger than a scenario may be."""
        if len(unit) > self.max_steps:
            return None
        size = len(json.dumps(unit, separators=(",", ":"), ensure_ascii=False).encode()) + ENVELOPE
        return size if size <= self.max_bytes else None

    def add(self, unit: list[dict[str, Any]], size: int) -> bool:
        """Keep ``unit`` (``size_of`` it); False once full (no room for it)."""
        if self.current and (
            len(self.current) + len(unit) > self.max_steps or self.size + size > self.max_bytes
        ):
            self._close()
        if len(self.scenarios) >= bags.MAX_SEEDS or self.kept + size > KEPT_BYTES:
            return False
        self.current += unit
        self.size += size
        self.kept += size
        return True

    def _close(self) -> None:
        self.scenarios.append({"steps": self.current})
        self.current, self.size = [], 0

    def done(self) -> list[dict[str, Any]]:
        if self.current and len(self.scenarios) < bags.MAX_SEEDS:
            self._close()
        return self.scenarios
