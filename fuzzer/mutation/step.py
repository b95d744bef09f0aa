"""The custom mutator and crossover of a campaign: one input made from libFuzzer's parent.

``MutationStep`` is the half of ``fuzzer.harness.Harness`` that libFuzzer calls as its
``CustomMutator`` and ``CustomCrossOver``. Each call decodes the parent, picks what to make (a
space-filling or aligned input from the bandit over sources; a high-difference parent from the
pool, Algorithm 3; an input queued for its input-to-state stage, ``fuzzer.selection.i2s``), applies
one registered mutator (``fuzzer.mutation.mutators``, or for ``--op scenario`` the sequence
mutators of ``fuzzer.scenario.mutate``) with an RNG seeded by libFuzzer, records it in the
lineage, and encodes. It never raises: an exception there would hang Atheris.
"""

from __future__ import annotations

import hashlib
import random
from typing import TYPE_CHECKING, Any, Protocol

from fuzzer.input.testcase import TestCase
from fuzzer.mutation import mutators

if TYPE_CHECKING:
    from fuzzer.selection.floatcmp import FloatCompareTracer
    from fuzzer.selection.i2s import I2SQueue
    from fuzzer.selection.state import Made, Pool, Sources

POOL_PARENT_CHANCE = 0.2


class MessageMutator(Protocol):
    """``fuzzer.mutation.mutators.mutate``'s signature: ``(message, ctx, name=None) -> (message, name)``."""

    def __call__(
        self, message: dict[str, Any], ctx: mutators.MutationContext, name: str | None = None
    ) -> tuple[dict[str, Any], str]: ...


class MessageCrossover(Protocol):
    """``fuzzer.mutation.mutators.crossover``'s signature: ``(a, b, ctx) -> message``. A crossover may
    name itself in the lineage with a ``lineage_name`` attribute (default ``splice``)."""

    def __call__(
        self, a: dict[str, Any], b: dict[str, Any], ctx: mutators.MutationContext
    ) -> dict[str, Any]: ...


def digest(data: bytes) -> bytes:
    """A short key of an input's bytes (``ComparedValues``' memory of what each input compared)."""
    return hashlib.blake2b(data, digest_size=16).digest()


class MutationStep:
    """libFuzzer's custom mutator and crossover, mixed into ``fuzzer.harness.Harness``, whose
    fields these are (described there)."""

    context: mutators.MutationContext
    seeds: list[TestCase]
    mutate_message: MessageMutator
    crossover_message: MessageCrossover
    sources: Sources | None
    float_tracer: FloatCompareTracer | None
    i2s: I2SQueue | None
    pool: Pool
    _last: tuple[bytes, TestCase] | None
    _credit: bytes | None
    """The child the last step made (not a parent emitted in its place): the only input whose
    run credits the bandit's arms (``Harness.test_one_input``)."""

    if TYPE_CHECKING:

        def _decode(self, data: bytes) -> tuple[TestCase | None, bool]: ...

    def mutate(self, data: bytes, max_size: int, seed: int) -> bytes:
        return self._step(data, None, max_size, seed)

    def crossover(self, data1: bytes, data2: bytes, max_size: int, seed: int) -> bytes:
        """libFuzzer's CustomCrossOver, which it calls for about half of its mutations. With the
        bandit (``sources``) this is one more bandit step on ``data1``: the crossover with
        ``data2`` only when the bandit picks the crossover's arm (``splice``, ``seq_splice``),
        so crossovers get the share they earn; without it, the crossover libFuzzer asked for."""
        return self._step(data1, data2, max_size, seed)

    def _step(self, data: bytes, partner: bytes | None, max_size: int, seed: int) -> bytes:
        """One input made from ``data`` (and ``partner``, libFuzzer's second parent in a crossover):
        a space-filling one, or the bandit's mutator, or libFuzzer's choice without a bandit."""
        self._credit = None
        try:
            rng = random.Random(seed)
            taken = self.i2s.take(rng) if self.i2s is not None and partner is None else None
            queued, focus = taken if taken is not None else (None, None)  # an input and the site it aims at
            parent = self._parent(queued or data, rng, partner is None and queued is None, True, focus)
            origin, fresh = self._fresh(parent, rng) if queued is None else (parent, None)
            if fresh is not None:
                return self._emit(origin.child(*fresh), origin, max_size, data)
            ctx = self.context
            ctx.rng = rng
            splice = str(getattr(self.crossover_message, "lineage_name", "splice"))
            if self.sources is None and partner is not None:
                other = self._parent(partner, rng, False)
                message = self.crossover_message(parent.message, other.message, ctx)
                return self._emit(parent.child(message, splice), parent, max_size, data)
            wanted = self.sources.mutators.choose(rng) if self.sources is not None else None
            if queued is not None and self.i2s is not None:
                wanted = self.i2s.arm  # the input-to-state stage of a new input
            if wanted == splice or getattr(self.mutate_message, "uses_other", False):
                other = self._parent(partner, rng, False) if partner is not None else self._other_parent(rng)
                ctx.other = other.message
            try:
                message, name = self.mutate_message(parent.message, ctx, wanted)
            finally:
                ctx.other = None
            return self._emit(parent.child(message, name), parent, max_size, data)
        except Exception:  # noqa: BLE001 - must never raise into libFuzzer
            return data[:max_size]

    def _parent(
        self,
        data: bytes,
        rng: random.Random,
        pool: bool = True,
        select: bool = False,
        focus: int | None = None,
    ) -> TestCase:
        """The test case of ``data`` (or, ``pool``, sometimes a high-difference input instead);
        ``select``: the one to mutate, whose compared values ``ComparedValues.operands`` gives
        (those at the site ``focus`` only, when given)."""
        if pool and rng.random() < POOL_PARENT_CHANCE:
            preferred = self.pool.pick(rng)
            if preferred is not None:
                data = preferred
        case, _ = self._decode(data)
        if select and self.float_tracer is not None and self.float_tracer.compared is not None:
            self.float_tracer.compared.select(digest(data), focus)
        if case is None:
            # not a test case (a foreign or damaged file): restart from a generated seed
            base = rng.choice(self.seeds)
            return TestCase(base.msg_type, base.message, base.sequence, "repair", ("repair",), 1)
        return case

    def _fresh(self, parent: TestCase, rng: random.Random) -> tuple[TestCase, Made]:
        """When the source bandit picks a source other than mutation: the input it starts from
        (``parent``, or the walk's own choice) and the fresh input (space-filling, aligned or
        walked) with its lineage name; else ``parent`` and None."""
        if self.sources is None:
            return parent, None
        arm = self.sources.source.choose(rng)
        origin = self.sources.parent(arm, parent, rng)
        return origin, self.sources.make(arm, origin.message, rng)

    def _other_parent(self, rng: random.Random) -> TestCase:
        """A second parent for a mutator that uses one (``uses_other``, the scenario mutator's
        step copies; the bandit's crossover arm outside libFuzzer's crossover): a high-difference
        input half the time when there is one, else a seed."""
        data = self.pool.pick(rng) if rng.random() < 0.5 else None
        case = self._decode(data)[0] if data is not None else None
        return case if case is not None else rng.choice(self.seeds)

    def _emit(self, case: TestCase, parent: TestCase, max_size: int, fallback: bytes) -> bytes:
        """The child's bytes; if too large, the (valid) parent's; if still too large, the input cut."""
        for candidate in (case, parent):
            out = candidate.encode()
            if len(out) <= max_size:
                self._last = (out, candidate)
                self._credit = out if candidate is case else None  # the parent made nothing new
                return out
        return fallback[:max_size]
