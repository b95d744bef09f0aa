"""Robotics-aware mutators of structure and semantics: signs, 2*pi wraps, zeros, joint-name
swaps, and arrays that grow, shrink or repeat an element (so parallel arrays may mismatch)."""

from __future__ import annotations

from typing import Any

from fuzzer.mutation.base import (
    Message,
    MutationContext,
)
from fuzzer.mutation.fields import (
    _TIME_SECS,
    ArrayRef,
    _get,
    _scalar_spec,
    clone,
)
from fuzzer.mutation.leaves import (
    _apply_leaf_ops,
)
from fuzzer.mutation.registry import register
from fuzzer.mutation.structure import choose_array, growable, new_element

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
