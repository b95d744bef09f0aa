"""The entry points of the sequence mutators (``fuzzer.scenario.mutate``): the dispatcher a
campaign calls for a scenario, with the signature of :func:`fuzzer.mutation.mutators.mutate`,
and the crossover, with that of :func:`fuzzer.mutation.mutators.crossover`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from fuzzer.generation.spacefill import Reachable
from fuzzer.input.msgdef import MessageRegistry
from fuzzer.mutation import mutators
from fuzzer.mutation.fields import clone
from fuzzer.mutation.mutators import NOOP, MutationContext, NotApplicable
from fuzzer.scenario.fresh import SequenceContext, Steps, Tables, field_types
from fuzzer.scenario.mutate import SEQ_MUTATORS, SEQ_STEP, SEQ_WEIGHTS, SPLICE, splice_steps
from fuzzer.scenario.steps import MAX_STEPS, MAX_STEPS_LIMIT, TOPICS


def _steps_of(message: Any, what: str = "message") -> Steps:
    """The steps list of a scenario message, or ValueError naming the problem."""
    if not isinstance(message, dict) or not isinstance(message.get("steps"), list):
        raise ValueError(f"the {what} is not a scenario: expected an object with a 'steps' list")
    steps: Steps = message["steps"]
    return steps


def _with_steps(message: dict[str, Any], steps: Steps) -> dict[str, Any]:
    """A copy of ``message`` whose steps are ``steps``."""
    out = {key: clone(value) for key, value in message.items() if key != "steps"}
    out["steps"] = steps
    return out


@dataclass(frozen=True)
class SequenceMutator:
    """``mutate(message, ctx, name=None) -> (message, name)`` for scenarios (as ``mutators.mutate``).

    ``name`` is a sequence mutator (``seq_delete``) or ``seq_step:<value mutator>``; when it
    does not apply, others are tried by :data:`SEQ_WEIGHTS`; :data:`fuzzer.mutation.mutators.NOOP` and an
    unchanged copy when none applies. ``ctx.other``, when a scenario, is the other parent.
    """

    tables: Tables
    max_steps: int
    uses_other: bool = True
    """Tells the harness to pass a second parent as ``ctx.other`` (copies, value splices)."""

    def __call__(
        self, message: dict[str, Any], ctx: MutationContext, name: str | None = None
    ) -> tuple[dict[str, Any], str]:
        first, inner = name, None
        if name is not None:
            first, _, inner_name = name.partition(":")
            inner = inner_name or None
            if first not in SEQ_MUTATORS or (inner is not None and first != SEQ_STEP):
                raise KeyError(f"unknown sequence mutator {name!r}; known: {sorted(SEQ_MUTATORS)}")
            if inner is not None and inner not in mutators.MUTATORS:
                raise KeyError(f"unknown value mutator {inner!r}; known: {sorted(mutators.MUTATORS)}")
        steps = _steps_of(message)
        other = _steps_of(ctx.other, "other parent") if isinstance(ctx.other, dict) else None
        sctx = SequenceContext(ctx.rng, ctx, self.max_steps, self.tables, other, inner)
        pool = dict(SEQ_WEIGHTS)
        pick = first if first is not None else mutators.weighted_choice(pool, ctx.rng)
        while True:
            try:
                new, used = SEQ_MUTATORS[pick](steps, sctx)
                return _with_steps(message, new), used
            except NotApplicable:
                pool.pop(pick, None)
                try:
                    pick = mutators.weighted_choice(pool, ctx.rng)
                except NotApplicable:
                    return clone(message), NOOP


@dataclass(frozen=True)
class SequenceCrossover:
    """``crossover(a, b, ctx) -> message`` for scenarios: ``seq_splice`` of ``a`` and ``b``.

    ``lineage_name`` is the name the harness records for the child.
    """

    max_steps: int
    lineage_name: str = SPLICE

    def __call__(self, a: dict[str, Any], b: dict[str, Any], ctx: MutationContext) -> dict[str, Any]:
        first, second = _steps_of(a, "first parent"), _steps_of(b, "second parent")
        return _with_steps(a, splice_steps(first, second, ctx.rng, self.max_steps))


def for_registry(
    registry: MessageRegistry,
    max_steps: int = MAX_STEPS,
    box: tuple[tuple[float, ...], tuple[float, ...]] | None = None,
    reachable: Reachable | None = None,
    joint_names: tuple[str, ...] = (),
) -> tuple[SequenceMutator, SequenceCrossover]:
    """The scenario mutator and crossover for messages known to ``registry``.

    Parameters
    ----------
    registry : MessageRegistry
        Where the topics' message types (``fuzzer.scenario.steps.TOPICS``) are looked up.
    max_steps : int
        Children have 1..max_steps steps (1 <= max_steps <= ``MAX_STEPS_LIMIT``).
    box : tuple of two tuples of float, optional
        The robot's joint limits (lower, upper), each of shape (n_joints,), finite (rad, m):
        a fresh joint target in a scenario without one is then drawn uniformly inside them.
    reachable : callable, optional
        The robot's FK: a configuration, shape (n_joints,) in rad and m, -> the tip's position
        (3,) in m and unit quaternion (4,) as (x, y, z, w); with ``joint_names`` (the robot's
        joints in order) it lets ``seq_pose_goal`` give a joint target as the tip's pose.
    joint_names : tuple of str, optional
        The robot's joints in the order ``reachable`` takes them.

    Returns
    -------
    tuple
        ``(mutate, crossover)`` with the signatures of :func:`fuzzer.mutation.mutators.mutate` and
        :func:`fuzzer.mutation.mutators.crossover`; the crossover's ``lineage_name`` is ``seq_splice``.

    Raises
    ------
    ValueError
        If ``max_steps`` is out of range or a topic's message type is unknown to ``registry``.
    """
    if isinstance(max_steps, bool) or not isinstance(max_steps, int) or not 1 <= max_steps <= MAX_STEPS_LIMIT:
        raise ValueError(f"max_steps must be an integer in 1..{MAX_STEPS_LIMIT}, not {max_steps!r}")
    types = {topic: spec.msg_type for topic, spec in TOPICS.items()}
    fields = {msg_type: field_types(registry, msg_type) for msg_type in sorted(set(types.values()))}
    tables = Tables(registry, types, fields, box=box, reachable=reachable, joint_names=tuple(joint_names))
    return SequenceMutator(tables, max_steps), SequenceCrossover(max_steps)
