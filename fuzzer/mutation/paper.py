"""The paper's mutators (Section III.C, Table II, and Section V's future work) and the
byte-level ones that hand a value to libFuzzer (``libfuzzer``) or to the targets' own float
comparisons (``compared``); the design notes are in :mod:`fuzzer.mutation.mutators`."""

from __future__ import annotations

from fuzzer.mutation.base import (
    DICTIONARY_INSERT_PROBABILITY,
    HAVOC_EXCLUDED,
    HAVOC_MAX_STACK,
    HAVOC_MIN_STACK,
    Message,
    MutationContext,
    NotApplicable,
)
from fuzzer.mutation.fields import (
    ArrayRef,
    _choose,
    _coerce,
    _get,
    _inventory,
    _scalar_spec,
)
from fuzzer.mutation.leaves import (
    _apply_leaf_ops,
    _dictionary_pool,
    _eligible_leaves,
    apply_compared,
)
from fuzzer.mutation.registry import WEIGHTS, dispatch, register
from fuzzer.mutation.structure import splice_both

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


@register("havoc", weight=1.0)
def havoc(message: Message, ctx: MutationContext) -> Message:
    """Stack 2..16 random mutations (AFL havoc), each picked by weight, never havoc or splice itself."""
    applied = 0
    for _ in range(ctx.rng.randint(HAVOC_MIN_STACK, HAVOC_MAX_STACK)):
        pool = {name: weight for name, weight in WEIGHTS.items() if name not in HAVOC_EXCLUDED}
        try:
            message, _ = dispatch(message, ctx, pool, None)
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
