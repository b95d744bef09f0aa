"""Fresh scenario steps: what a sequence mutator may use, and new steps made from a scenario.

:class:`SequenceContext` is what a sequence mutator (``fuzzer.scenario.mutate``) gets besides
the steps; :func:`new_step` and :func:`fresh_message` make a step to insert: a copy of one of
the scenario's (or the other parent's), or a fresh one whose values come from the scenario,
the engine's interesting values or the registry's defaults. The only source of randomness is
the injected ``ctx.rng``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from random import Random
from typing import Any, Final

from fuzzer.generation.spacefill import Reachable
from fuzzer.input.mapping import FOCUS
from fuzzer.input.msgdef import MessageRegistry
from fuzzer.mutation import fields
from fuzzer.mutation.fields import clone
from fuzzer.mutation.mutators import MutationContext, NotApplicable

StepDict = dict[str, Any]
Steps = list[StepDict]

COPY_PROBABILITY: Final = 0.5
"""``seq_insert``: chance of copying an existing step (when there is one) rather than a fresh one."""
FRESH_WEIGHTS: Final[Mapping[str, float]] = {"/go": 3.0, "/plan": 2.0, "/execute": 2.0, "/joint_target": 2.0}
"""Weights of the topics of a fresh step (other topics: 1)."""
FRESH_FLOATS: Final = (0.0, 0.01, 0.1, 0.5, 1.0)
"""Values a fresh ``std_msgs/Float64`` step may take, besides the scenario's and the engine's."""
FRESH_NAMES: Final = ("home",)
"""Named targets a fresh ``std_msgs/String`` step may take, besides the scenario's strings."""
KNOWN_NAME_PROBABILITY: Final = 0.75
"""Fresh ``/named_target`` step: chance that it names a target that exists where it is inserted
("home", or a name a ``/remember`` step before it stored), as syzkaller gives a call a resource an
earlier call made; otherwise any string of the scenario, "home" or a joint or link name (an
unknown target: the error path)."""
INTERESTING_PROBABILITY: Final = 0.5
"""Fresh joint target: chance that one joint takes an engine interesting value."""


@dataclass
class Tables:
    """Per-topic tables derived from the message registry (types, defaults, value contexts)."""

    registry: MessageRegistry
    types: dict[str, str]
    """Topic -> ROS message type."""
    fields: dict[str, dict[str, str]]
    """ROS message type -> dotted field path -> builtin type (``MutationContext.field_types``)."""
    contexts: dict[str, tuple[MutationContext, MutationContext]] = dataclasses.field(default_factory=dict)
    box: tuple[tuple[float, ...], tuple[float, ...]] | None = None
    """The robot's joint limits (lower, upper; rad, m; finite: a continuous joint's are -pi, pi),
    for a fresh joint target in a scenario that has none to recombine; None: no such target."""
    reachable: Reachable | None = None
    """The robot's FK: a configuration, shape (n_joints,) in rad and m, -> the tip's position (m)
    and unit quaternion (x, y, z, w), for a goal given as the tip's pose; None: no such goal."""
    joint_names: tuple[str, ...] = ()
    """The robot's joints in order (what ``reachable`` takes)."""

    def default(self, topic: str) -> dict[str, Any]:
        """The zero message of ``topic``'s type, unit quaternions instead of zero ones."""
        message: dict[str, Any] = unit_quaternions(self.registry.default(self.types[topic]))
        return message

    def value_context(self, msg_type: str, outer: MutationContext) -> MutationContext:
        """A context like ``outer`` for messages of ``msg_type`` (cached per outer context)."""
        cached = self.contexts.get(msg_type)
        if cached is None or cached[0] is not outer:
            inner = dataclasses.replace(
                outer, field_types=self.fields[msg_type], focus=FOCUS.get(msg_type, ()), other=None, memo={}
            )
            cached = (outer, inner)
            self.contexts[msg_type] = cached
        cached[1].rng = outer.rng
        return cached[1]


@dataclass
class SequenceContext:
    """What a sequence mutator may use besides the steps.

    Attributes
    ----------
    rng : random.Random
        The only source of randomness (the value context's).
    value : MutationContext
        The campaign's context (interesting floats, dictionary, options) for ``seq_step``.
    max_steps : int
        Largest number of steps of a child.
    tables : Tables
        Registry-derived tables.
    other : list of dict or None
        The other parent's steps (from ``value.other``), for copies and ``seq_splice``.
    inner : str or None
        The value mutator ``seq_step`` tries first (from a name ``seq_step:<inner>``).
    """

    rng: Random
    value: MutationContext
    max_steps: int
    tables: Tables
    other: Steps | None = None
    inner: str | None = None


def field_types(registry: MessageRegistry, msg_type: str) -> dict[str, str]:
    """Dotted field path -> ROS type of every field of ``msg_type`` the value mutators may touch,
    arrays of messages included (``fuzzer.mutation.fields.field_types``)."""
    return fields.field_types(registry, msg_type, message_arrays=True)


def unit_quaternions(node: Any) -> Any:
    """``node`` with every all-zero ``orientation`` quaternion made the identity (w = 1)."""
    if isinstance(node, dict):
        out = {key: unit_quaternions(value) for key, value in node.items()}
        quaternion = out.get("orientation")
        if not isinstance(quaternion, dict) or set(quaternion) != {"x", "y", "z", "w"}:
            return out
        if all(v == 0.0 for v in quaternion.values()):
            out["orientation"] = {**quaternion, "w": 1.0}
        return out
    if isinstance(node, list):
        return [unit_quaternions(item) for item in node]
    return node


def msg_type_of(step: Any, ctx: SequenceContext) -> str | None:
    """The message type of a well-formed step, else None."""
    if not isinstance(step, dict) or not isinstance(step.get("msg"), dict):
        return None
    topic = step.get("topic")
    return ctx.tables.types.get(topic) if isinstance(topic, str) else None


def known_names(before: Steps) -> list[str]:
    """Named targets that exist after ``before`` has run: "home" and every remembered name."""
    remembered = [
        s["msg"]["data"]
        for s in before
        if isinstance(s, dict) and s.get("topic") == "/remember" and isinstance(s.get("msg"), dict)
    ]
    return [*FRESH_NAMES, *(name for name in remembered if isinstance(name, str))]


def fresh_message(topic: str, steps: Steps, ctx: SequenceContext, at: int | None = None) -> dict[str, Any]:
    """A new message for ``topic`` made from the scenario's values (or registry defaults), for a
    step inserted before ``steps[at]`` (at the end when ``at`` is None)."""
    msg_type = ctx.tables.types[topic]
    same = [s["msg"] for s in steps if msg_type_of(s, ctx) == msg_type]
    msg = ctx.tables.default(topic)
    if msg_type == "sensor_msgs/JointState":
        vectors = [m for m in same if isinstance(m.get("position"), list) and m["position"]]
        if vectors:
            msg = clone(ctx.rng.choice(vectors))
            width = range(len(msg["position"]))
            columns = [[v["position"][i] for v in vectors if i < len(v["position"])] for i in width]
            msg["position"] = [ctx.rng.choice(column) for column in columns]
        elif ctx.tables.box is not None:  # every joint in order, uniform within its limits
            msg["position"] = [ctx.rng.uniform(lo, hi) for lo, hi in zip(*ctx.tables.box, strict=True)]
        else:
            raise NotApplicable("no joint target to make a new one from")
        engine = ctx.value.interesting_floats
        if engine and msg["position"] and ctx.rng.random() < INTERESTING_PROBABILITY:
            msg["position"][ctx.rng.randrange(len(msg["position"]))] = float(ctx.rng.choice(engine))
    elif msg_type == "std_msgs/Float64":
        pool = [float(m["data"]) for m in same if isinstance(m.get("data"), float)]
        msg["data"] = ctx.rng.choice([*pool, *FRESH_FLOATS])
    elif topic == "/named_target" and ctx.rng.random() < KNOWN_NAME_PROBABILITY:
        msg["data"] = ctx.rng.choice(known_names(steps[:at]))
    elif msg_type == "std_msgs/String":
        pool = [m["data"] for m in same if isinstance(m.get("data"), str)]
        names = [t for t in ctx.value.dictionary if isinstance(t, str)]
        msg["data"] = ctx.rng.choice([*pool, *FRESH_NAMES, *names])
    elif msg_type == "geometry_msgs/PoseArray":
        poses = [s["msg"]["pose"] for s in steps if msg_type_of(s, ctx) == "geometry_msgs/PoseStamped"]
        pose = ctx.rng.choice(poses) if poses else ctx.tables.registry.default("geometry_msgs/Pose")
        msg["poses"] = [unit_quaternions(pose)]
    elif same and msg:  # poses, points: a copy of one of the scenario's
        msg = clone(ctx.rng.choice(same))
    return msg


GO: Final[StepDict] = {"topic": "/go", "msg": {}}


def new_step(steps: Steps, ctx: SequenceContext, at: int | None = None) -> StepDict:
    """A copy of a step of this scenario or the other parent, or a fresh step, to go before
    ``steps[at]`` (at the end when ``at`` is None)."""
    copies = [s for s in (*steps, *(ctx.other or ())) if msg_type_of(s, ctx) is not None]
    if copies and ctx.rng.random() < COPY_PROBABILITY:
        return clone(ctx.rng.choice(copies))
    pool = {topic: FRESH_WEIGHTS.get(topic, 1.0) for topic in ctx.tables.types}
    while pool:
        topic = ctx.rng.choices(list(pool), weights=list(pool.values()))[0]
        try:
            return {"topic": topic, "msg": fresh_message(topic, steps, ctx, at)}
        except NotApplicable:
            del pool[topic]
    raise NotApplicable("no step can be made")  # pragma: no cover - Empty topics always can
