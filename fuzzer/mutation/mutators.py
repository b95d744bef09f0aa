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

import functools
from collections.abc import Callable, Mapping
from random import Random
from typing import Any

from fuzzer.mutation.base import (
    ARITH_MAX,
    DICTIONARY_INSERT_PROBABILITY,
    FUTURE_WORK,
    HAVOC_EXCLUDED,
    HAVOC_MAX_STACK,
    HAVOC_MIN_STACK,
    INTERESTING_FLOATS,
    INTERESTING_INTS,
    INTERESTING_STRINGS,
    NOOP,
    PAPER_STRATEGIES,
    Message,
    MutationContext,
    Mutator,
    NotApplicable,
)
from fuzzer.mutation.fields import (
    _TIME_SECS,
    ArrayRef,
    _choose,
    _coerce,
    _get,
    _inventory,
    _scalar_spec,
    clone,
)
from fuzzer.mutation.leaves import (
    LEAF_OPS,
    LeafOp,
    _apply_leaf_ops,
    _dictionary_pool,
    _eligible_leaves,
    apply_compared,
)
from fuzzer.mutation.structure import choose_array, growable, new_element, splice_both

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
]

# ----------------------------------------------------------------------------------------------------------
# Registry
# ----------------------------------------------------------------------------------------------------------

MUTATORS: dict[str, Mutator] = {}
"""Registered mutators by name.  Each one works on a deep copy and raises :class:`NotApplicable`."""
WEIGHTS: dict[str, float] = {}
"""Relative selection weights of :data:`MUTATORS` (same keys)."""


def register(name: str, weight: float = 1.0) -> Callable[[Mutator], Mutator]:
    """Register an in-place mutator under ``name``; the registered function works on a deep copy.

    Parameters
    ----------
    name : str
        Unique mutator name.
    weight : float
        Relative weight for :func:`mutate`'s random choice.

    Returns
    -------
    Callable
        A decorator returning the copying wrapper.
    """

    def decorator(fn: Mutator) -> Mutator:
        if name in MUTATORS:
            raise ValueError(f"mutator {name!r} is already registered")

        @functools.wraps(fn)
        def wrapper(message: dict[str, Any], ctx: MutationContext) -> dict[str, Any]:
            copied = clone(message)
            outer = ctx.memo.get("_source")
            ctx.memo["_source"] = (copied, message)  # lets _inventory reuse the input's inventory
            try:
                return fn(copied, ctx)
            finally:
                ctx.memo["_source"] = outer

        MUTATORS[name] = wrapper
        WEIGHTS[name] = weight
        return wrapper

    return decorator


# --- Paper, Table II ---------------------------------------------------------------------------------------
# Weights follow the paper's Fig. 6: arithmetic and interesting beat bit flip, comb3 is the best combination.


@register("bit_flip", weight=1.0)
def bit_flip(message: Message, ctx: MutationContext) -> Message:
    """Flip 1, 2 or 4 consecutive bits of one leaf (paper Table II "bit flip"; AFL bitflip 1/1, 2/1, 4/1).

    Floats: only the integer part changes (``sign * flip(|trunc(x)|) + frac``, bits 0..7), so 0.5 may
    become 1.5; ints: inside the type's width with two's complement; bools toggle.
    """
    return _apply_leaf_ops(message, ctx, ("bit_flip",))


@register("arithmetic", weight=2.0)
def arithmetic(message: Message, ctx: MutationContext) -> Message:
    """Add or subtract a bounded amount (paper Table II "arithmetic"; AFL arith with ``ARITH_MAX`` = 35).

    Ints: +-1..35, wrapping in the type's width; floats: +-k*scale with k in 1..35 and scale in
    :data:`FLOAT_ARITH_SCALES` (1e-9 .. 1), so ``|delta| <= 35``.
    """
    return _apply_leaf_ops(message, ctx, ("arithmetic",))


@register("interesting", weight=2.0)
def interesting(message: Message, ctx: MutationContext) -> Message:
    """Replace one leaf with an interesting value (paper Table II, Fig. 3; AFL interesting values).

    Ints: AFL's table filtered to the width plus the width's edges; floats: :data:`INTERESTING_FLOATS`
    plus ``ctx.interesting_floats`` (NaN/inf only when allowed); strings: :data:`INTERESTING_STRINGS`
    plus dictionary names; time: secs/nsecs extremes within range.
    """
    return _apply_leaf_ops(message, ctx, ("interesting",))


@register("comb1", weight=1.0)
def comb1(message: Message, ctx: MutationContext) -> Message:
    """Paper Comb1: bit flip then arithmetic, on the same numeric leaf."""
    return _apply_leaf_ops(message, ctx, ("bit_flip", "arithmetic"))


@register("comb2", weight=1.0)
def comb2(message: Message, ctx: MutationContext) -> Message:
    """Paper Comb2: interesting value then bit flip, on the same leaf (near-boundary values)."""
    return _apply_leaf_ops(message, ctx, ("interesting", "bit_flip"))


@register("comb3", weight=2.0)
def comb3(message: Message, ctx: MutationContext) -> Message:
    """Paper Comb3: interesting value then arithmetic, on the same numeric leaf (boundary +- delta)."""
    return _apply_leaf_ops(message, ctx, ("interesting", "arithmetic"))


@register("comb4", weight=1.0)
def comb4(message: Message, ctx: MutationContext) -> Message:
    """Paper Comb4: interesting value, bit flip, then arithmetic, on the same numeric leaf."""
    return _apply_leaf_ops(message, ctx, ("interesting", "bit_flip", "arithmetic"))


# --- Paper, Section V (future work) ------------------------------------------------------------------------


def _insert_token(message: Message, ctx: MutationContext, ref: ArrayRef) -> Message:
    """Insert a dictionary token of the element type at a random index of ``ref``."""
    spec = _scalar_spec(ref.ftype.base)
    assert spec is not None
    array = _get(message, ref.loc)
    array.insert(
        ctx.rng.randint(0, len(array)), _coerce(ctx.rng.choice(_dictionary_pool(spec, ctx)), spec, ctx)
    )
    return message


def _token_arrays(message: Message, ctx: MutationContext) -> list[ArrayRef]:
    """Variable-length scalar arrays with room for one more dictionary token."""
    refs = []
    for ref in _inventory(message, ctx).arrays:
        spec = _scalar_spec(ref.ftype.base)
        growable = ref.ftype.fixed is None and len(_get(message, ref.loc)) < ref.capacity
        if spec is not None and growable and _dictionary_pool(spec, ctx):
            refs.append(ref)
    return refs


@register("dictionary", weight=1.0)
def dictionary(message: Message, ctx: MutationContext) -> Message:
    """Replace a leaf with, or insert into an array, a dictionary token (AFL/libFuzzer dictionaries).

    Strings take string tokens; numbers take numeric tokens (and string tokens that parse as numbers),
    ints only integral ones within the width.  Insertion (variable-length arrays only) is chosen with
    probability :data:`DICTIONARY_INSERT_PROBABILITY` when both are possible.
    """
    leaves = _eligible_leaves(message, ctx, ("dictionary",))
    arrays = _token_arrays(message, ctx)
    if arrays and (not leaves or ctx.rng.random() < DICTIONARY_INSERT_PROBABILITY):
        return _insert_token(message, ctx, _choose(arrays, lambda ref: ref.name, ctx))
    return _apply_leaf_ops(message, ctx, ("dictionary",))


def _weighted_choice(pool: Mapping[str, float], rng: Random) -> str:
    """A name of ``pool`` drawn with probability proportional to its weight."""
    names = [name for name, weight in pool.items() if weight > 0]
    if not names:
        raise NotApplicable("no mutator left")
    return rng.choices(names, weights=[pool[name] for name in names])[0]


def _dispatch(
    message: Message, ctx: MutationContext, pool: dict[str, float], first: str | None
) -> tuple[Message, str]:
    """Run ``first`` (or a weighted pick), falling back through ``pool`` while mutators do not apply."""
    name = first if first is not None else _weighted_choice(pool, ctx.rng)
    while True:
        try:
            return MUTATORS[name](message, ctx), name
        except NotApplicable:
            pool.pop(name, None)
            name = _weighted_choice(pool, ctx.rng)


@register("havoc", weight=1.0)
def havoc(message: Message, ctx: MutationContext) -> Message:
    """Stack 2..16 random mutations (AFL havoc), each picked by weight, never havoc or splice itself."""
    applied = 0
    for _ in range(ctx.rng.randint(HAVOC_MIN_STACK, HAVOC_MAX_STACK)):
        pool = {name: weight for name, weight in WEIGHTS.items() if name not in HAVOC_EXCLUDED}
        try:
            message, _ = _dispatch(message, ctx, pool, None)
        except NotApplicable:
            break
        applied += 1
    if not applied:
        raise NotApplicable("no stackable mutator applies")
    return message


@register("splice", weight=0.5)
def splice(message: Message, ctx: MutationContext) -> Message:
    """Join the message with ``ctx.other`` (AFL splice): arrays prefix + suffix, scalars from either.

    Not applicable without ``ctx.other``.  The shape and field order of ``message`` are kept.
    """
    if ctx.other is None:
        raise NotApplicable("splice needs ctx.other")
    return splice_both(message, ctx.other, ctx)


# --- libFuzzer ---------------------------------------------------------------------------------------------


@register("libfuzzer", weight=1.0)
def libfuzzer(message: Message, ctx: MutationContext) -> Message:
    """Mutate the bytes of one float (``'<d'``; ``'<f'`` for float32) or string with libFuzzer's mutator.

    ``ctx.libfuzzer_mutate(data, size)`` (``atheris.Mutate``) brings libFuzzer's dictionaries and CMP
    tables; its output is padded/truncated to ``size`` bytes (8, or 4 for float32) and decoded; strings
    are UTF-8 encoded and decoded with ``errors='replace'``.  Not applicable without the callable.
    """
    return _apply_leaf_ops(message, ctx, ("libfuzzer",))


@register("compared", weight=1.0)
def compared(message: Message, ctx: MutationContext) -> Message:
    """Set one float to a comparison threshold of the targets or a value just either side of it
    (libFuzzer's TORC, AFL++'s CmpLog, for floats): ``ctx.compared`` learns them during the
    campaign (``fuzzer.selection.compared``), and which leaf a comparison saw (input-to-state,
    :func:`fuzzer.mutation.leaves.apply_compared`). Not applicable before one is known."""
    return apply_compared(message, ctx)


# --- Robotics-aware structure and semantics ----------------------------------------------------------------


@register("sign_flip", weight=0.5)
def sign_flip(message: Message, ctx: MutationContext) -> Message:
    """Negate one float leaf (joint angles and limits are often asymmetric)."""
    return _apply_leaf_ops(message, ctx, ("sign_flip",))


@register("wrap_2pi", weight=1.0)
def wrap_2pi(message: Message, ctx: MutationContext) -> Message:
    """Add or subtract 2*pi or pi to one float (the "positive and negative" differences of Table III)."""
    return _apply_leaf_ops(message, ctx, ("wrap_2pi",))


@register("zero", weight=0.5)
def zero(message: Message, ctx: MutationContext) -> Message:
    """Set one non-zero numeric leaf to zero."""
    return _apply_leaf_ops(message, ctx, ("zero",))


@register("string_swap", weight=0.5)
def string_swap(message: Message, ctx: MutationContext) -> Message:
    """Replace one string with another string of the same array or of the dictionary (joint names)."""
    return _apply_leaf_ops(message, ctx, ("string_swap",))


@register("array_insert", weight=0.5)
def array_insert(message: Message, ctx: MutationContext) -> Message:
    """Insert an element (interesting value) into a variable-length array; parallel arrays may mismatch."""

    def keep(ref: ArrayRef, array: list[Any]) -> bool:
        is_message = ref.ftype.base not in _TIME_SECS and _scalar_spec(ref.ftype.base) is None
        return growable(ref, array) and not (is_message and not array)

    ref = choose_array(message, ctx, keep)
    array = _get(message, ref.loc)
    array.insert(ctx.rng.randint(0, len(array)), new_element(ref, array, ctx))
    return message


@register("array_delete", weight=0.5)
def array_delete(message: Message, ctx: MutationContext) -> Message:
    """Delete one element of a non-empty variable-length array; parallel arrays may mismatch."""
    ref = choose_array(message, ctx, lambda ref, array: ref.ftype.fixed is None and bool(array))
    array = _get(message, ref.loc)
    del array[ctx.rng.randrange(len(array))]
    return message


@register("array_duplicate", weight=0.5)
def array_duplicate(message: Message, ctx: MutationContext) -> Message:
    """Duplicate an array element next to itself; in fixed-length arrays, copy it over another one."""

    def keep(ref: ArrayRef, array: list[Any]) -> bool:
        if ref.ftype.fixed is None:
            return bool(array) and growable(ref, array)
        return len(array) >= 2

    ref = choose_array(message, ctx, keep)
    array = _get(message, ref.loc)
    source = ctx.rng.randrange(len(array))
    if ref.ftype.fixed is None:
        array.insert(source + 1, clone(array[source]))
    else:
        target = ctx.rng.choice([i for i in range(len(array)) if i != source])
        array[target] = clone(array[source])
    return message


# ----------------------------------------------------------------------------------------------------------
# Entry points
# ----------------------------------------------------------------------------------------------------------


def mutate(
    message: dict[str, Any], ctx: MutationContext, name: str | None = None
) -> tuple[dict[str, Any], str]:
    """Mutate a copy of ``message`` with the named mutator, or one picked by :data:`WEIGHTS`.

    Parameters
    ----------
    message : dict
        The seed; never modified.
    ctx : MutationContext
        Randomness, types and options.
    name : str, optional
        Mutator to try first; when it does not apply, others are tried by weight.

    Returns
    -------
    tuple[dict, str]
        The new message and the name of the mutator actually used (:data:`NOOP` and an unchanged copy
        when none applies).

    Raises
    ------
    KeyError
        If ``name`` is not a registered mutator.
    """
    if name is not None and name not in MUTATORS:
        raise KeyError(f"unknown mutator {name!r}; known: {sorted(MUTATORS)}")
    try:
        return _dispatch(message, ctx, dict(WEIGHTS), name)
    except NotApplicable:
        return clone(message), NOOP


def crossover(a: dict[str, Any], b: dict[str, Any], ctx: MutationContext) -> dict[str, Any]:
    """Splice two messages of the same type (for libFuzzer's custom crossover); inputs are not modified.

    Parameters
    ----------
    a, b : dict
        Parents; the child has the shape and field order of ``a``.
    ctx : MutationContext
        Randomness and field types (``ctx.other`` is ignored).

    Returns
    -------
    dict
        The child; equal to ``a`` when ``a == b``.
    """
    return splice_both(a, b, ctx)
