"""Typed seed mutators for ROS messages: a registry in the style of libFuzzer's MutationDispatcher.

A message is a JSON-friendly ``dict`` in field order (nested messages are dicts, arrays are lists,
``time``/``duration`` values are ``{"secs": ..., "nsecs": ...}`` dicts).  Every mutator is a small named
function ``(message, ctx) -> message`` registered with a weight; :func:`mutate` picks one by weight (or by
name), falls back to another one when the chosen mutator does not apply to the message, and reports the
name actually used, which is what the paper's "mapping dict" of Algorithm 2 records.

Strategies
----------
* Paper, Section III.C, Table II: ``bit_flip``, ``arithmetic``, ``interesting`` (Fig. 3) and the four
  combinations ``comb1`` .. ``comb4``.
* Paper, Section V (future work, after AFL): ``dictionary``, ``havoc``, ``splice``.
* Byte level: ``libfuzzer`` hands the IEEE-754 bytes of a float (or the UTF-8 bytes of a string) to
  libFuzzer's own mutator (``atheris.Mutate``), which brings its dictionaries and CMP tables.
* The targets' own float comparisons: ``compared`` writes a threshold the campaign has seen the targets
  compare a float against (``ctx.compared``), or a value just either side of it.
* Robotics-aware structure and semantics: ``sign_flip``, ``wrap_2pi``, ``array_insert``, ``array_delete``,
  ``array_duplicate``, ``string_swap``, ``zero``.

Decisions where the paper is silent
-----------------------------------
* **Type safety first.**  Every new leaf value goes through one coercion step: ints are wrapped into
  their width, floats of ``float32`` fields are clamped to the float32 range and rounded to float32,
  bounded strings are truncated, and a result that is NaN/inf while ``ctx.allow_special`` is false makes
  the mutator not applicable (the dispatcher then falls back).  Scalar fields whose type is not in
  ``ctx.field_types`` are never touched (their width is unknown); dicts without a type are descended.
* **Integer overflow wraps** (two's complement per width, like the C++ targets and AFL's byte
  arithmetic) instead of clamping; ``nsecs`` wraps modulo 10**9 so it stays in ``[0, 999999999]``.
* **bit_flip windows.**  Floats: the flipped bits lie in bits 0..7 of ``|trunc(x)|``; ints: anywhere in
  the type's width (so the sign bit of an ``int64`` is reachable), ``nsecs`` within its 30 bits.
* **Combinations act on one leaf**, and ``interesting`` always comes first: a replacement applied last
  would erase the previous steps.  So ``comb1`` = bit_flip -> arithmetic, ``comb2`` = interesting ->
  bit_flip, ``comb3`` = interesting -> arithmetic (the "boundary +- a little" values the paper found most
  productive), ``comb4`` = interesting -> bit_flip -> arithmetic.  A later step that cannot apply to the
  intermediate value (bit flip of NaN) is skipped.
* **splice** cuts every array at one aligned index (prefix of one parent + suffix of the other, so a
  spliced array keeps joint ``i`` at index ``i`` and its length lies between the parents' lengths);
  scalars and time values come whole from either parent.  Hence splicing identical parents yields the
  same message.
"""

from __future__ import annotations

from fuzzer.mutation import paper, robotics  # registers their mutators, in this order
from fuzzer.mutation.base import (
    ARITH_MAX,
    FUTURE_WORK,
    INTERESTING_FLOATS,
    INTERESTING_INTS,
    INTERESTING_STRINGS,
    NOOP,
    PAPER_STRATEGIES,
    MutationContext,
    Mutator,
    NotApplicable,
)
from fuzzer.mutation.leaves import LEAF_OPS, LeafOp
from fuzzer.mutation.registry import MUTATORS, WEIGHTS, crossover, mutate, register, weighted_choice

__all__ = [
    "ARITH_MAX",
    "FUTURE_WORK",
    "INTERESTING_FLOATS",
    "INTERESTING_INTS",
    "INTERESTING_STRINGS",
    "LEAF_OPS",
    "MUTATORS",
    "NOOP",
    "PAPER_STRATEGIES",
    "WEIGHTS",
    "LeafOp",
    "MutationContext",
    "Mutator",
    "NotApplicable",
    "crossover",
    "mutate",
    "register",
    "weighted_choice",
]

del paper, robotics
