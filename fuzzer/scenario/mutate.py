"""Sequence mutators for scenarios: a registry in the style of :mod:`fuzzer.mutation.mutators`.

A scenario is ``{"steps": [{"topic": TOPIC, "msg": MSG}, ...]}`` (``fuzzer.scenario.steps``).
Every sequence mutator is a small named function ``(steps, ctx) -> (steps, name)`` registered
with a weight; it works on a deep copy of the steps and raises
:class:`fuzzer.mutation.mutators.NotApplicable` when it cannot apply (the dispatcher then falls back to
another one by weight, as :func:`fuzzer.mutation.mutators.mutate` does). The only source of randomness
is the injected ``ctx.rng``.

Mutators
--------
* ``seq_insert``: insert a step, a copy of a step of this scenario or of ``ctx.other`` (the
  other parent), or a fresh one (``/go``, ``/plan``, ``/execute``..., a joint target
  recombined column by column from the scenario's joint targets, a scaling factor, a named
  target that mostly names one that exists at that point...).
  The context and the fresh steps are ``fuzzer.scenario.fresh``.
* ``seq_motion``: insert a move (a fresh joint target and ``/go``, or ``/plan`` and
  ``/execute``; often after a fresh scaling factor), often right after a ``/remember X`` and
  then often followed by ``/named_target X`` and a move back.
* ``seq_observe``: one ``/go`` replaced by ``/plan`` and ``/execute``, the same move with its
  trajectory in the outputs.
* ``seq_pose_goal``: one joint target (every joint, in order) replaced by the tip's pose at that
  configuration (``/pose_target``), a quarter of the time its position (``/position_target``):
  the same destination through MoveIt's pose-goal path (needs the campaign's FK); a ``/go``
  to it becomes ``/plan`` + ``/execute`` when there is room (``seq_pose_goal:observe``).
* ``seq_delete``, ``seq_duplicate`` (a copy next to the original), ``seq_swap`` (two steps
  that differ), ``seq_move`` (one step elsewhere; the order always changes).
* ``seq_step``: one step's message mutated by the value mutators of :func:`fuzzer.mutation.mutators.mutate`
  with that step type's field types; lineage name ``seq_step:<inner>`` (``seq_step:arithmetic``).
* ``seq_compared``: one float of one step set to a comparison threshold of the targets, or a
  value just either side of it (the value mutator ``compared``); the ``/go`` steps after it
  are observed too (``seq_compared:observe``).
* ``seq_splice`` (also the crossover): a prefix of one scenario + a suffix of the other.

The dispatcher that draws one by weight and the crossover are ``fuzzer.scenario.dispatch``.

Every child has 1..``max_steps`` steps and, when its parents validate, validates
(``fuzzer.scenario.steps.validate``): steps are only copied, moved, removed or made from
registry defaults, and values change through the type-safe value mutators.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from random import Random
from typing import Any, Final

from fuzzer.generation.spacefill import configuration_message
from fuzzer.mutation import mutators
from fuzzer.mutation.fields import clone
from fuzzer.mutation.mutators import NOOP, MutationContext, NotApplicable
from fuzzer.scenario.fresh import (
    GO,
    SequenceContext,
    StepDict,
    Steps,
    fresh_message,
    msg_type_of,
    new_step,
)

SeqMutator = Callable[[Steps, "SequenceContext"], tuple[Steps, str]]

SPLICE: Final = "seq_splice"
"""Lineage name of the crossover."""
SEQ_STEP: Final = "seq_step"
SEQ_COMPARED: Final = "seq_compared"
POSE_GOAL: Final = "seq_pose_goal"
AFTER_REMEMBER_PROBABILITY: Final = 0.5
"""``seq_motion``: chance that the move goes right after a ``/remember`` (when there is one)."""
RETURN_PROBABILITY: Final = 0.5
"""``seq_motion`` after a ``/remember X``: chance that ``/named_target X`` and a move follow the move."""
PLAN_EXECUTE_PROBABILITY: Final = 0.5
"""``seq_motion``: chance that a move is ``/plan`` + ``/execute`` rather than ``/go``."""
SETTING_PROBABILITY: Final = 0.5
"""``seq_motion``: chance that the move starts by setting one of :data:`MOVE_SETTINGS`."""
MOVE_SETTINGS: Final = ("/velocity_scaling", "/acceleration_scaling")
"""What a script sets just before a move (MoveIt's tutorials slow a move down this way)."""
SPLICE_ATTEMPTS: Final = 8
POSITION_PROBABILITY: Final = 0.25
"""``seq_pose_goal``: chance that the goal is the tip's position only (``set_position_target``)
rather than its pose."""
OBSERVE: Final = "observe"
"""Lineage suffix of a ``seq_compared`` child whose later ``/go`` steps were also observed, and
of a ``seq_pose_goal`` child whose ``/go`` to the new goal was."""
OBSERVE_PROBABILITY: Final = 1.0
"""``seq_compared``: chance that each ``/go`` after the changed step becomes ``/plan`` +
``/execute`` (when there is one; the earlier ones while there is room). 0.5 until 2026-11-28:
``profile_switch_band``'s band was reached by children that moved with ``/go``, whose
trajectory the oracle never sees (docs/benchmarks-log.md, seventeenth session)."""


# ----------------------------------------------------------------------------------------------------------
# Registry
# ----------------------------------------------------------------------------------------------------------

SEQ_MUTATORS: dict[str, SeqMutator] = {}
"""Registered sequence mutators by name; each works on a deep copy of the steps."""
SEQ_WEIGHTS: dict[str, float] = {}
"""Relative selection weights of :data:`SEQ_MUTATORS` (same keys)."""


def register(name: str, weight: float = 1.0) -> Callable[[SeqMutator], SeqMutator]:
    """Register a sequence mutator under ``name``; the registered function works on a deep copy."""

    def decorator(fn: SeqMutator) -> SeqMutator:
        if name in SEQ_MUTATORS:
            raise ValueError(f"sequence mutator {name!r} is already registered")

        @functools.wraps(fn)
        def wrapper(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
            return fn(clone(steps), ctx)

        SEQ_MUTATORS[name] = wrapper
        SEQ_WEIGHTS[name] = weight
        return wrapper

    return decorator


@register("seq_insert", weight=2.0)
def seq_insert(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
    """Insert a new step (a copy, or a fresh ``/go``, ``/plan``, joint target...) anywhere."""
    if len(steps) >= ctx.max_steps:
        raise NotApplicable("the scenario has max_steps steps")
    at = ctx.rng.randint(0, len(steps))
    steps.insert(at, new_step(steps, ctx, at))
    return steps, "seq_insert"


@register("seq_motion", weight=1.0)
def seq_motion(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
    """Insert a move, a call template as syzkaller's: a fresh joint target, then ``/go`` or,
    half the time, ``/plan`` and ``/execute`` (MoveIt's two ways to move; the second shows the
    oracle the trajectory). Half the time a velocity or acceleration scaling factor is set
    first (a fresh value), as a script slows a move down. Half the time it goes right after a
    ``/remember X`` (when there is one), and then half the time ``/named_target X`` and a move
    come back to the remembered state (pick and place), when there is room."""
    remembered = [
        (i + 1, s["msg"]["data"])
        for i, s in enumerate(steps)
        if msg_type_of(s, ctx) == "std_msgs/String" and s["topic"] == "/remember"
    ]
    if remembered and ctx.rng.random() < AFTER_REMEMBER_PROBABILITY:
        at, name = ctx.rng.choice(remembered)
    else:
        at, name = ctx.rng.randint(0, len(steps)), None
    target = {"topic": "/joint_target", "msg": fresh_message("/joint_target", steps, ctx, at)}
    template = [target, *_move(ctx)]
    if ctx.rng.random() < SETTING_PROBABILITY:
        topic = ctx.rng.choice(MOVE_SETTINGS)
        template.insert(0, {"topic": topic, "msg": fresh_message(topic, steps, ctx, at)})
    if len(steps) + len(template) > ctx.max_steps:
        raise NotApplicable("no room for a move")
    if name is not None and ctx.rng.random() < RETURN_PROBABILITY:
        named = {**ctx.tables.default("/named_target"), "data": name}
        back = [{"topic": "/named_target", "msg": named}, *_move(ctx)]
        if len(steps) + len(template) + len(back) <= ctx.max_steps:  # else the move alone
            template += back
    steps[at:at] = clone(template)
    return steps, "seq_motion"


def _move(ctx: SequenceContext) -> Steps:
    """``/go``, or ``/plan`` and ``/execute`` with probability ``PLAN_EXECUTE_PROBABILITY``."""
    if ctx.rng.random() < PLAN_EXECUTE_PROBABILITY:
        return [{"topic": "/plan", "msg": {}}, {"topic": "/execute", "msg": {}}]
    return [GO]


@register("seq_observe", weight=1.0)
def seq_observe(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
    """Replace one ``/go`` by ``/plan`` and ``/execute``: the same move (go() plans, then
    executes the plan), now with its trajectory among the outputs the oracle compares. A fault
    that shows only in a trajectory (where it starts, how it is timed) is invisible behind a
    ``/go``, and the scripts a campaign starts from mostly move with ``/go``."""
    gos = [i for i, s in enumerate(steps) if s["topic"] == "/go"]
    if not gos:
        raise NotApplicable("no /go to observe")
    if len(steps) >= ctx.max_steps:
        raise NotApplicable("no room for /plan and /execute")
    _observe(steps, ctx.rng.choice(gos))
    return steps, "seq_observe"


def _observe(steps: Steps, at: int) -> None:
    """Replace the ``/go`` at ``at`` by ``/plan`` and ``/execute`` (the caller checks for room)."""
    steps[at : at + 1] = [{"topic": "/plan", "msg": {}}, {"topic": "/execute", "msg": {}}]


@register(POSE_GOAL, weight=1.0)
def seq_pose_goal(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
    """Give one joint target as a goal for the tip: its pose at that configuration
    (``/pose_target``, the campaign's FK) or, with probability :data:`POSITION_PROBABILITY`,
    only its position (``/position_target``). The move still heads where the joint target
    led, but through MoveIt's other goal path: IK seeded with the state the scenario stands in
    (which may answer another configuration), then the plan to that answer. The tutorials
    move to pose goals as often as to joint goals; the seed scripts and ``seq_motion`` mostly
    set joint targets, and a fault of the pose-goal path (its timing, its IK seed) shows only
    behind one. Applies to a joint target of every joint in order (``name`` empty or the
    robot's joints), finite, when the campaign gave its FK (``Tables.reachable``).

    When the move to that goal is a ``/go`` and ``max_steps`` leaves room, it becomes ``/plan`` +
    ``/execute`` (lineage ``seq_pose_goal:observe``), as ``seq_compared`` observes the moves
    after the value it changes: the new goal changes that move, and a ``/go`` shows the oracle
    where it ended, not its trajectory (how it was timed, the way it took)."""
    fk, names = ctx.tables.reachable, list(ctx.tables.joint_names)
    if fk is None or not names:
        raise NotApplicable("no forward kinematics to give a goal as a pose")
    targets = [
        i for i, s in enumerate(steps) if s["topic"] == "/joint_target" and _every_joint(s, names, ctx)
    ]
    if not targets:
        raise NotApplicable("no joint target of every joint, in order, to give as a pose")
    at = ctx.rng.choice(targets)
    values = tuple(steps[at]["msg"]["position"])
    goal = configuration_message(
        "geometry_msgs/PoseStamped", ctx.tables.default("/pose_target"), values, (), fk
    )
    assert goal is not None  # a PoseStamped always carries a pose
    topic = "/pose_target"
    if ctx.rng.random() < POSITION_PROBABILITY:
        topic, goal = (
            "/position_target",
            {**ctx.tables.default("/position_target"), "point": goal["pose"]["position"]},
        )
    steps[at] = {"topic": topic, "msg": goal}
    move = _move_to(steps, at)
    if move is not None and steps[move]["topic"] == "/go" and len(steps) < ctx.max_steps:
        _observe(steps, move)
        return steps, f"{POSE_GOAL}:{OBSERVE}"
    return steps, POSE_GOAL


GOALS: Final = ("/joint_target", "/pose_target", "/position_target", "/named_target")
"""Steps that set the goal of the next move."""


def _move_to(steps: Steps, at: int) -> int | None:
    """The index of the move (``/go`` or ``/plan``) to the goal ``steps[at]`` sets: the first
    after it, unless another goal is set first; None without one."""
    for i in range(at + 1, len(steps)):
        if steps[i]["topic"] in GOALS:
            return None
        if steps[i]["topic"] in ("/go", "/plan"):
            return i
    return None


def _every_joint(step: StepDict, names: list[str], ctx: SequenceContext) -> bool:
    """Whether a well-formed JointState step sets every joint of ``names``, in order, to a finite value."""
    if msg_type_of(step, ctx) != "sensor_msgs/JointState":
        return False
    msg = step["msg"]
    position = msg.get("position")
    if not isinstance(position, list) or len(position) != len(names) or msg.get("name") not in ([], names):
        return False
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in position)


@register("seq_delete", weight=1.0)
def seq_delete(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
    """Delete one step (never the last one)."""
    if len(steps) <= 1:
        raise NotApplicable("a scenario keeps at least one step")
    del steps[ctx.rng.randrange(len(steps))]
    return steps, "seq_delete"


@register("seq_duplicate", weight=1.0)
def seq_duplicate(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
    """Repeat one step right after itself (``/go`` twice, the same target twice...)."""
    if not steps or len(steps) >= ctx.max_steps:
        raise NotApplicable("no room for a duplicate")
    index = ctx.rng.randrange(len(steps))
    steps.insert(index + 1, clone(steps[index]))
    return steps, "seq_duplicate"


@register("seq_swap", weight=1.0)
def seq_swap(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
    """Exchange two steps that differ."""
    if len(steps) < 2 or all(s == steps[0] for s in steps):
        raise NotApplicable("no two different steps")
    i = ctx.rng.randrange(len(steps))
    j = ctx.rng.choice([k for k, s in enumerate(steps) if s != steps[i]])  # not all equal: never empty
    steps[i], steps[j] = steps[j], steps[i]
    return steps, "seq_swap"


@register("seq_move", weight=1.0)
def seq_move(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
    """Move one step to another place; the order always changes."""
    if len(steps) < 2 or all(s == steps[0] for s in steps):
        raise NotApplicable("no step can change place")
    n = len(steps)
    i = ctx.rng.randrange(n)
    # moving i to j changes the list iff a step between them (j included) differs from steps[i]
    after = next((k for k in range(i + 1, n) if steps[k] != steps[i]), n)
    before = next((k for k in range(i - 1, -1, -1) if steps[k] != steps[i]), -1)
    targets = [*range(before + 1), *range(after, n)]
    step = steps.pop(i)
    steps.insert(ctx.rng.choice(targets), step)
    return steps, "seq_move"


def _one_step(
    steps: Steps,
    ctx: SequenceContext,
    change: Callable[[StepDict, MutationContext], tuple[dict[str, Any], str]],
) -> tuple[Steps, str, int]:
    """``steps`` with one step's message replaced by ``change(step, value context)`` (a step
    drawn among those with values; another one when it raises ``NotApplicable`` or changes
    nothing), the name it gives, and that step's index."""
    candidates = [i for i, s in enumerate(steps) if ctx.tables.fields.get(msg_type_of(s, ctx) or "")]
    while candidates:
        index = candidates.pop(ctx.rng.randrange(len(candidates)))
        step = steps[index]
        inner = ctx.tables.value_context(ctx.tables.types[step["topic"]], ctx.value)
        try:
            message, name = change(step, inner)
        except NotApplicable:
            continue
        if message != step["msg"]:  # a value splice of equal fields changes nothing
            steps[index] = {**step, "msg": message}
            return steps, name, index
    raise NotApplicable("no step has a value to mutate")


@register(SEQ_STEP, weight=4.0)
def seq_step(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
    """Mutate one step's message with the value mutators (that step type's field types)."""

    def change(step: StepDict, inner: MutationContext) -> tuple[dict[str, Any], str]:
        msg_type = ctx.tables.types[step["topic"]]
        peers = [  # for the value splice: other messages of this type (this scenario, the other parent)
            s["msg"]
            for s in (*steps, *(ctx.other or ()))
            if msg_type_of(s, ctx) == msg_type and s["msg"] != step["msg"]
        ]
        inner.other = ctx.rng.choice(peers) if peers else None
        try:
            message, name = mutators.mutate(step["msg"], inner, ctx.inner)
        finally:
            inner.other = None
        if name == NOOP:
            raise NotApplicable("no value mutator applies to this step")
        return message, f"{SEQ_STEP}:{name}"

    steps, name, _ = _one_step(steps, ctx, change)
    return steps, name


@register(SEQ_COMPARED, weight=1.0)
def seq_compared(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
    """Set one float of one step to a comparison threshold of the targets, or a value just
    either side of it (the value mutator ``compared``; its own bandit arm, as it needs no other
    value mutator to come up first).

    With probability :data:`OBSERVE_PROBABILITY` (1.0: always) every ``/go`` after that step also becomes
    ``/plan`` + ``/execute`` (as ``seq_observe``; lineage ``seq_compared:observe``), the
    earlier ones while ``max_steps`` leaves room: the comparison this step aims to flip
    changes a later move's trajectory, and a ``/go`` shows the oracle where the move ended,
    not the trajectory. Which move is not the first one after it for a band of the start
    state: a joint target written into the band is compared by the move *after* the one that
    takes the arm there (a profile's switch on a ratio of the scaling factors is compared by
    the first)."""
    if ctx.value.compared is None or not len(ctx.value.compared):
        raise NotApplicable("no comparison threshold known yet")
    steps, name, index = _one_step(
        steps, ctx, lambda step, inner: (mutators.MUTATORS["compared"](step["msg"], inner), SEQ_COMPARED)
    )
    gos = [i for i in range(index + 1, len(steps)) if steps[i]["topic"] == "/go"]
    room = ctx.max_steps - len(steps)
    if gos and room > 0 and ctx.rng.random() < OBSERVE_PROBABILITY:
        for go in reversed(gos[:room]):  # from the last, so the indices before it hold
            _observe(steps, go)
        return steps, f"{SEQ_COMPARED}:{OBSERVE}"
    return steps, name


def splice_steps(a: Steps, b: Steps, rng: Random, max_steps: int) -> Steps:
    """``a[:i] + b[j:]`` with 1..max_steps steps, avoiding a copy of a parent when possible."""
    child = clone(a)
    for _ in range(SPLICE_ATTEMPTS):
        i = rng.randint(0, min(len(a), max_steps))
        # the suffix length s = len(b) - j must satisfy 1 <= i + s <= max_steps
        low, high = max(1 - i, 0), min(max_steps - i, len(b))
        if low > high:
            continue
        child = clone(a[:i] + b[len(b) - rng.randint(low, high) :])
        if a == b or (child != a and child != b):
            break
    return child


@register(SPLICE, weight=0.5)
def seq_splice(steps: Steps, ctx: SequenceContext) -> tuple[Steps, str]:
    """A prefix of this scenario + a suffix of the other parent (``ctx.other``)."""
    if not ctx.other:
        raise NotApplicable("seq_splice needs another scenario")
    return splice_steps(steps, ctx.other, ctx.rng, ctx.max_steps), SPLICE
