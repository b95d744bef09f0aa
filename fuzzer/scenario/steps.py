"""Scenario test cases: steps as ROS messages on named topics, their validation and their call.

A scenario test case is ``TestCase(msg_type=MSG_TYPE, message={"steps": [STEP, ...]})`` with
1..max_steps steps, each ``{"topic": TOPIC, "msg": MSG}``: MSG is the ordinary dict form of
the topic's ROS message type (``MessageRegistry.validate`` accepts it, headers included).
The step kind is the topic without its ``/`` (``/go`` -> ``go``).

Nothing here runs a target: :func:`to_call` only turns a validated message into a
:class:`ScenarioCall`, which ``fuzzer.scenario.execute.run_scenario`` executes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

MSG_TYPE = "rrosfuzz/Scenario"
"""The test case type of ``--op scenario`` (not a ROS message type: a list of steps)."""

MAX_STEPS = 16
"""Default bound on the number of steps (``--max-steps``)."""

MAX_STEPS_LIMIT = 256
"""Largest ``--max-steps`` accepted."""


@dataclass(frozen=True)
class TopicSpec:
    """One scenario topic.

    Attributes
    ----------
    msg_type : str
        ROS message type of its messages (``pkg/Type``).
    kind : str
        Step kind: the topic without its leading ``/``.
    doc : str
        The call it makes, in one line.
    """

    msg_type: str
    kind: str
    doc: str


def _topic(msg_type: str, name: str, doc: str) -> tuple[str, TopicSpec]:
    return f"/{name}", TopicSpec(msg_type, name, doc)


TOPICS: dict[str, TopicSpec] = dict(
    [
        _topic(
            "sensor_msgs/JointState",
            "joint_target",
            "set_joint_value_target(position) if name is empty, else set_joint_value_target(name, position)",
        ),
        _topic(
            "geometry_msgs/PoseStamped",
            "pose_target",
            "set_pose_target(((x, y, z), (qx, qy, qz, qw)), header.frame_id or None): frame_id is the link",
        ),
        _topic(
            "geometry_msgs/PointStamped",
            "position_target",
            "set_position_target([x, y, z], header.frame_id or None): frame_id names the link",
        ),
        _topic("std_msgs/String", "named_target", "set_named_target(data)"),
        _topic("std_msgs/String", "remember", "remember_joint_values(data): the current state"),
        _topic("std_msgs/Float64", "velocity_scaling", "set_max_velocity_scaling_factor(data)"),
        _topic("std_msgs/Float64", "acceleration_scaling", "set_max_acceleration_scaling_factor(data)"),
        _topic("std_msgs/Float64", "goal_tolerance", "set_goal_joint_tolerance(data)"),
        _topic("std_msgs/Float64", "eef_step", "no call: eef_step (m, default 0.01) of later paths"),
        _topic("std_msgs/Float64", "jump_threshold", "no call: jump_threshold (default 0) of later paths"),
        _topic(
            "geometry_msgs/PoseArray",
            "cartesian_path",
            "compute_cartesian_path(poses, eef_step, jump_threshold); the trajectory becomes the last plan",
        ),
        _topic("std_msgs/Empty", "plan", "plan(); a successful plan's trajectory becomes the last plan"),
        _topic("std_msgs/Empty", "execute", "execute(this target's last plan); no call without one"),
        _topic("std_msgs/Empty", "go", "go()"),
        _topic("std_msgs/Empty", "stop", "stop()"),
        _topic("std_msgs/Empty", "clear_pose_targets", "clear_pose_targets()"),
    ]
)
"""Topic -> its message type, step kind and call (docs/engine.md, "Scenarios")."""

KINDS: dict[str, str] = {spec.kind: topic for topic, spec in TOPICS.items()}
"""Step kind -> topic."""


@dataclass(frozen=True)
class Step:
    """One step of a scenario: a message on a topic.

    Attributes
    ----------
    kind : str
        Step kind (``go``, ``joint_target``, ...; ``TOPICS[topic].kind``).
    message : dict
        The topic's message, validated, in its plain dict form.
    """

    kind: str
    message: dict[str, Any]

    @property
    def topic(self) -> str:
        return KINDS[self.kind]


@dataclass(frozen=True)
class ScenarioCall:
    """A scenario: its steps, run in order on one new ``MoveGroup`` per target."""

    steps: tuple[Step, ...]


class ScenarioError(ValueError):
    """A scenario message of the wrong shape; the text names the step and the problem."""


def _type_name(value: Any) -> str:
    return "null" if value is None else type(value).__name__


def validate(message: Any, registry: Any, max_steps: int = MAX_STEPS) -> None:
    """Check a scenario message (data only; nothing is evaluated).

    Parameters
    ----------
    message : Any
        ``{"steps": [{"topic": TOPIC, "msg": MSG}, ...]}`` as decoded from a test case.
    registry : fuzzer.input.msgdef.MessageRegistry
        Where the topics' message types are looked up and validated.
    max_steps : int
        Largest number of steps accepted.

    Raises
    ------
    ScenarioError
        A ``ValueError`` naming the problem, and for a bad step its index and topic,
        e.g. ``step 3 (/go): invalid std_msgs/Empty value at 'x': unexpected field``.
    """
    if not isinstance(message, dict):
        raise ScenarioError(f"a scenario is an object with 'steps', not a {_type_name(message)}")
    extra = sorted(str(k) for k in message if k != "steps")
    if extra:
        raise ScenarioError(f"unexpected field(s) in a scenario: {', '.join(extra)} (only 'steps')")
    steps = message.get("steps")
    if not isinstance(steps, list):
        raise ScenarioError(f"'steps' must be a list of steps, not {_type_name(steps)}")
    if not 1 <= len(steps) <= max_steps:
        raise ScenarioError(f"a scenario has 1..{max_steps} steps, this one {len(steps)}")
    for index, step in enumerate(steps):
        _validate_step(index, step, registry)


def _validate_step(index: int, step: Any, registry: Any) -> None:
    where = f"step {index}"
    if not isinstance(step, dict):
        raise ScenarioError(f"{where}: expected an object with 'topic' and 'msg', not {_type_name(step)}")
    topic = step.get("topic")
    if not isinstance(topic, str):
        raise ScenarioError(f"{where}: 'topic' must be a string, not {_type_name(topic)}")
    spec = TOPICS.get(topic)
    if spec is None:
        raise ScenarioError(f"{where} ({topic!r:.80}): unknown topic; known: {', '.join(TOPICS)}")
    extra = sorted(str(k) for k in step if k not in ("topic", "msg"))
    if extra:
        raise ScenarioError(f"{where} ({topic}): unexpected field(s) {', '.join(extra)} (only topic, msg)")
    if "msg" not in step:
        raise ScenarioError(f"{where} ({topic}): missing 'msg' ({spec.msg_type})")
    try:
        registry.validate(spec.msg_type, step["msg"])
    except ValueError as exc:
        raise ScenarioError(f"{where} ({topic}): {exc}") from None


def to_call(message: dict[str, Any]) -> ScenarioCall:
    """The call of a validated scenario message (the mapping of ``--op scenario``)."""
    return ScenarioCall(tuple(Step(TOPICS[s["topic"]].kind, s["msg"]) for s in message["steps"]))


def to_message(call: ScenarioCall) -> dict[str, Any]:
    """The scenario message of a call (inverse of :func:`to_call`)."""
    return {"steps": [{"topic": step.topic, "msg": step.message} for step in call.steps]}
