"""Structure-aware helpers of the message mutators (:mod:`fuzzer.mutation.mutators`).

AFL's splice on typed messages (every array cut at one aligned index, scalars and time values
whole from either parent, the shape and field order of the first parent kept) and the choice
of an array and of a new element for the array mutators (``array_insert``,
``array_delete``, ``array_duplicate``). Each takes the mutation context's RNG; none is a
registered mutator.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from fuzzer.mutation.base import MAX_ARRAY_LEN, SPLICE_ATTEMPTS, Message, MutationContext
from fuzzer.mutation.fields import (
    _TIME_SECS,
    NSECS_SPEC,
    ArrayRef,
    FieldType,
    _choose,
    _coerce,
    _get,
    _inventory,
    _parse_type,
    _scalar_spec,
    _valid,
    _valid_time,
    clone,
)
from fuzzer.mutation.leaves import _interesting_value


def valid_element(item: Any, base: str, ctx: MutationContext) -> bool:
    """Whether ``item`` may be an element of an array of ``base`` (message elements: any dict)."""
    if base in _TIME_SECS:
        return _valid_time(item, base, ctx)
    spec = _scalar_spec(base)
    return _valid(item, spec, ctx) if spec is not None else isinstance(item, dict)


def splice_array(a: list[Any], b: Any, ftype: FieldType, ctx: MutationContext) -> list[Any]:
    """Prefix of one parent + suffix of the other, cut at one aligned index (fixed lengths kept)."""
    if not isinstance(b, list) or (ftype.fixed is not None and len(b) != len(a)):
        return clone(a)
    if len(b) > max(len(a), ftype.bound or MAX_ARRAY_LEN):
        return clone(a)
    if not all(valid_element(item, ftype.base, ctx) for item in b):
        return clone(a)
    first, second = (a, b) if ctx.rng.random() < 0.5 else (b, a)
    cut = ctx.rng.randint(0, len(first))  # cut <= len(first): element i always comes from a[i] or b[i]
    return clone(first[:cut] + second[cut:])


def splice_scalar(a: Any, b: Any, base: str, ctx: MutationContext) -> Any:
    """``a`` or ``b`` (coin flip) when ``b`` is a valid value of the same type, else ``a``."""
    spec = _scalar_spec(base)
    valid = _valid(b, spec, ctx) if spec is not None else base in _TIME_SECS and _valid_time(b, base, ctx)
    return clone(b if valid and ctx.rng.random() < 0.5 else a)


def splice_dict(a: Message, b: Any, prefix: str, ctx: MutationContext) -> Message:
    """Field-by-field splice of ``a`` with ``b`` (shape and order of ``a``)."""
    out: Message = {}
    for key, value in a.items():
        name = f"{prefix}.{key}" if prefix else str(key)
        other = b.get(key) if isinstance(b, dict) else None
        text = ctx.field_types.get(name)
        ftype = _parse_type(text) if text is not None else None
        if other is None:
            out[key] = clone(value)
        elif ftype is not None and ftype.is_array and isinstance(value, list):
            out[key] = splice_array(value, other, ftype, ctx)
        elif isinstance(value, dict) and (ftype is None or ftype.base not in _TIME_SECS):
            out[key] = splice_dict(value, other, name, ctx)
        elif ftype is not None:
            out[key] = splice_scalar(value, other, ftype.base, ctx)
        else:
            out[key] = clone(value)
    return out


def splice_both(a: Message, b: Message, ctx: MutationContext) -> Message:
    """Splice ``a`` and ``b``, retrying (up to :data:`SPLICE_ATTEMPTS`) while one parent is reproduced."""
    child = splice_dict(a, b, "", ctx)
    for _ in range(SPLICE_ATTEMPTS - 1):
        if a == b or (child != a and child != b):
            break
        child = splice_dict(a, b, "", ctx)
    return child


def choose_array(
    message: Message, ctx: MutationContext, keep: Callable[[ArrayRef, list[Any]], bool]
) -> ArrayRef:
    """An array of ``message`` that ``keep`` accepts (focus honoured), or :class:`NotApplicable`."""
    refs = [ref for ref in _inventory(message, ctx).arrays if keep(ref, _get(message, ref.loc))]
    return _choose(refs, lambda ref: ref.name, ctx)


def new_element(ref: ArrayRef, array: list[Any], ctx: MutationContext) -> Any:
    """A fresh element: an interesting scalar or time, or a copy of an element of a message array."""
    base = ref.ftype.base
    if base in _TIME_SECS:
        return {
            "secs": _interesting_value(_TIME_SECS[base], ctx),
            "nsecs": _interesting_value(NSECS_SPEC, ctx),
        }
    spec = _scalar_spec(base)
    if spec is not None:
        return _coerce(_interesting_value(spec, ctx), spec, ctx)
    return clone(ctx.rng.choice(array))


def growable(ref: ArrayRef, array: list[Any]) -> bool:
    """Whether ``array`` is variable-length and below its capacity."""
    return ref.ftype.fixed is None and len(array) < ref.capacity
