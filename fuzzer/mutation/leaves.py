"""Leaf operations: the building blocks of the leaf mutators and of ``comb1`` .. ``comb4``."""

from __future__ import annotations

import functools
import math
import struct
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from random import Random
from typing import Any, Final

from fuzzer.mutation.base import (
    _TWO_PI,
    ARITH_MAX,
    ENGINE_INTERESTING_PROBABILITY,
    FLIP_AMOUNTS,
    FLOAT32_MAX,
    FLOAT_ARITH_SCALES,
    FLOAT_FLIP_WINDOW,
    INTERESTING_FLOATS,
    INTERESTING_INTS,
    INTERESTING_STRINGS,
    LIBFUZZER_ATTEMPTS,
    LIBFUZZER_STRING_SLACK,
    SPECIAL_FLOATS,
    Message,
    MutationContext,
    NotApplicable,
)
from fuzzer.mutation.fields import (
    Leaf,
    ScalarSpec,
    _choose,
    _coerce,
    _get,
    _inventory,
    _set,
    _to_float32,
    _wrap,
)
from fuzzer.mutation.thresholds import _compared, _has_thresholds, _past

# ----------------------------------------------------------------------------------------------------------
# Leaf operations: the building blocks of the leaf mutators and of comb1..comb4
# ----------------------------------------------------------------------------------------------------------

LeafFn = Callable[[Any, Leaf, Message, MutationContext], Any]


def _always(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> bool:
    return True


@dataclass(frozen=True)
class LeafOp:
    """A value-level operation: which leaf kinds it handles, a guard, and the operation itself."""

    kinds: frozenset[str]
    apply: LeafFn
    accepts: Callable[[Any, Leaf, Message, MutationContext], bool] = _always

    def eligible(self, value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> bool:
        """Whether this op can act on ``value`` stored at ``leaf``."""
        return leaf.spec.kind in self.kinds and self.accepts(value, leaf, message, ctx)


def _finite(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> bool:
    """Guard: floats must be finite (ints and bools always are)."""
    return leaf.spec.kind != "float" or math.isfinite(value)


def _flip_bits(number: int, width: int, rng: Random) -> int:
    """Flip 1, 2 or 4 consecutive bits of ``number`` inside bits ``0..width-1``."""
    amount = rng.choice([a for a in FLIP_AMOUNTS if a <= width])
    position = rng.randint(0, width - amount)
    return number ^ (((1 << amount) - 1) << position)


def _bit_flip(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> Any:
    """Table II bit flip: bools toggle, ints flip in their width, floats flip their integer part only."""
    spec = leaf.spec
    if spec.kind == "bool":
        return not value
    if spec.kind == "int":
        flipped = _flip_bits(value & ((1 << spec.bits) - 1), spec.bits, ctx.rng)
        if spec.signed and flipped >= 1 << (spec.bits - 1):
            flipped -= 1 << spec.bits
        return _wrap(flipped, spec)
    whole = math.trunc(value)
    fraction = value - whole  # exact: no precision is lost in the fractional part
    magnitude = _flip_bits(abs(whole), FLOAT_FLIP_WINDOW, ctx.rng)
    return math.copysign(1.0, value) * float(magnitude) + fraction


def _arithmetic(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> Any:
    """Table II arithmetic: add or subtract ``1..ARITH_MAX`` (ints, wrapping) or a scaled float delta."""
    sign = ctx.rng.choice((-1, 1))
    steps = ctx.rng.randint(1, ARITH_MAX)
    if leaf.spec.kind == "int":
        return _wrap(value + sign * steps, leaf.spec)
    return float(value) + sign * steps * ctx.rng.choice(FLOAT_ARITH_SCALES)


@functools.lru_cache(maxsize=64)
def _interesting_ints(spec: ScalarSpec) -> tuple[int, ...]:
    """AFL's interesting ints and the width's edges that fit ``spec``."""
    edges = (spec.lo, spec.hi, spec.lo + 1, spec.hi - 1)
    return tuple(dict.fromkeys(v for v in (*INTERESTING_INTS, *edges) if spec.lo <= v <= spec.hi))


def _float_pool(values: Sequence[float], spec: ScalarSpec, allow_special: bool) -> list[float]:
    """The values of ``values`` a float leaf of ``spec`` may take."""
    pool = []
    for raw in values:
        try:
            value = float(raw)
        except OverflowError:
            continue
        if not math.isfinite(value):
            if allow_special:
                pool.append(value)
        elif not spec.is_float32 or abs(value) <= FLOAT32_MAX:
            pool.append(value)
    return pool


def _interesting_value(spec: ScalarSpec, ctx: MutationContext) -> Any:
    """An interesting value (Fig. 3 and AFL tables) for a leaf of ``spec``."""
    rng = ctx.rng
    if spec.kind == "bool":
        return rng.choice((False, True))
    if spec.kind == "int":
        return rng.choice(_interesting_ints(spec))
    if spec.kind == "str":
        names = [t for t in ctx.dictionary if isinstance(t, str)]
        return rng.choice([*INTERESTING_STRINGS, *names])
    key = (spec.is_float32, ctx.allow_special)
    if key not in ctx.memo:
        specials = SPECIAL_FLOATS if ctx.allow_special else ()
        ctx.memo[key] = (
            _float_pool(ctx.interesting_floats, spec, ctx.allow_special),
            _float_pool((*INTERESTING_FLOATS, *specials), spec, ctx.allow_special),
        )
    engine, base = ctx.memo[key]
    if engine and rng.random() < ENGINE_INTERESTING_PROBABILITY:
        return rng.choice(engine)
    return rng.choice(base)


def _interesting(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> Any:
    """Table II / Fig. 3: replace the value with an interesting one of the leaf's type."""
    return _interesting_value(leaf.spec, ctx)


def _sign_flip(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> Any:
    """Negate a float (0.0 becomes -0.0)."""
    return -value


def _wrap_2pi(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> Any:
    """Add or subtract 2*pi or pi: the same angle (or its opposite) in another representation."""
    return value + ctx.rng.choice((_TWO_PI, -_TWO_PI, math.pi, -math.pi))


def _nonzero(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> bool:
    """Guard: the value is not already zero."""
    return bool(value != 0)


def _zero(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> Any:
    """Set a number to zero."""
    return 0.0 if leaf.spec.kind == "float" else 0


def _swap_candidates(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> list[str]:
    """Other strings of the same array and of the dictionary, without ``value``."""
    siblings = _get(message, leaf.array) if leaf.array is not None else []
    pool = [s for s in siblings if isinstance(s, str)]
    pool += [t for t in ctx.dictionary if isinstance(t, str)]
    return list(dict.fromkeys(s for s in pool if s != value))


def _can_swap(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> bool:
    return bool(_swap_candidates(value, leaf, message, ctx))


def _string_swap(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> Any:
    """Replace a string by another string of the same array or of the dictionary."""
    return ctx.rng.choice(_swap_candidates(value, leaf, message, ctx))


def _numeric_tokens(tokens: Sequence[str | float]) -> list[int | float]:
    """Numbers of the dictionary: numeric tokens and string tokens that parse as numbers."""
    numbers: list[int | float] = []
    for token in tokens:
        if isinstance(token, bool):
            continue
        if isinstance(token, (int, float)):
            numbers.append(token)
            continue
        for parse in (int, float):
            try:
                numbers.append(parse(token))
                break
            except ValueError:
                continue
    return numbers


def _dictionary_pool(spec: ScalarSpec, ctx: MutationContext) -> tuple[Any, ...]:
    """Dictionary tokens a leaf of ``spec`` may take."""
    return _token_pool(spec, tuple(ctx.dictionary), ctx.allow_special)


@functools.lru_cache(maxsize=256)
def _token_pool(spec: ScalarSpec, tokens: tuple[str | float, ...], allow_special: bool) -> tuple[Any, ...]:
    """Cached body of :func:`_dictionary_pool`."""
    if spec.kind == "str":
        return tuple(
            t[: spec.max_len] if spec.max_len is not None else t for t in tokens if isinstance(t, str)
        )
    numbers = _numeric_tokens(tokens)
    if spec.kind == "float":
        return tuple(_float_pool(numbers, spec, allow_special))
    if spec.kind == "int":
        ints = [n if isinstance(n, int) else int(n) for n in numbers if isinstance(n, int) or _integral(n)]
        return tuple(n for n in ints if spec.lo <= n <= spec.hi)
    return ()


def _integral(number: float) -> bool:
    return math.isfinite(number) and number.is_integer()


def _has_tokens(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> bool:
    """Guard: the dictionary has a token of the leaf's type."""
    return bool(_dictionary_pool(leaf.spec, ctx))


def _dictionary_token(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> Any:
    """Replace the value by a dictionary token of the leaf's type."""
    return ctx.rng.choice(_dictionary_pool(leaf.spec, ctx))


def _has_libfuzzer(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> bool:
    """Guard: a libFuzzer mutate callable is available."""
    return ctx.libfuzzer_mutate is not None


def _libfuzzer_bytes(data: bytes, size: int, ctx: MutationContext) -> bytes:
    """libFuzzer's mutation of ``data``, padded with zeros or truncated to ``size`` bytes."""
    assert ctx.libfuzzer_mutate is not None
    return bytes(ctx.libfuzzer_mutate(data, size))[:size].ljust(size, b"\0")


def _libfuzzer(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> Any:
    """libFuzzer's byte mutator on the IEEE-754 bytes of a float or the UTF-8 bytes of a string."""
    if leaf.spec.kind == "str":
        data = value.encode("utf-8")
        size = max(2 * len(data), len(data) + LIBFUZZER_STRING_SLACK)
        assert ctx.libfuzzer_mutate is not None
        return bytes(ctx.libfuzzer_mutate(data, size))[:size].decode("utf-8", errors="replace")
    fmt, size = ("<f", 4) if leaf.spec.is_float32 else ("<d", 8)
    data = struct.pack(fmt, _to_float32(value) if leaf.spec.is_float32 else value)
    for _ in range(LIBFUZZER_ATTEMPTS):
        result: float = struct.unpack(fmt, _libfuzzer_bytes(data, size, ctx))[0]
        if math.isfinite(result) or ctx.allow_special:
            return result
    raise NotApplicable("libFuzzer produced only NaN/inf")


CROSSING_PROBABILITY: Final = 0.75
""":func:`apply_compared`: chance of writing past a threshold into the leaf a target compared
with it (when the message has one)."""


BETWEEN_PROBABILITY: Final = 0.5
""":func:`apply_compared`: chance, when the leaf's value was compared against two or more
unsolved thresholds, of writing the middle of two of them instead of a value past one."""


def apply_compared(message: Message, ctx: MutationContext) -> Message:
    """The ``compared`` mutator. With probability :data:`CROSSING_PROBABILITY`, Redqueen's
    input-to-state step: a float leaf whose value an unsolved comparison recently saw
    (``ctx.compared.crossing``) gets that comparison's threshold, or a value just past it on the
    far side from the leaf's value (the outcome never seen); or, when the value met two such
    thresholds (a band ``a <= x < b``, a calibration table's entry), the middle of two of them
    (:data:`BETWEEN_PROBABILITY`): inside a narrow band as far from both edges as it can be,
    where the oracle's nudges of the value do not carry it out (an input at a band's very edge
    is judged ill-conditioned). Otherwise, or when no leaf matches, one float leaf gets a
    threshold or a value either side of it (:func:`_compared`)."""
    if ctx.compared is not None and ctx.rng.random() < CROSSING_PROBABILITY:
        found = ctx.compared
        crossing = [
            (leaf, threshold, way)
            for leaf in _eligible_leaves(message, ctx, ("compared",))
            for threshold, way in found.crossings(_get(message, leaf.loc))
        ]
        if crossing:
            leaf, threshold, way = ctx.rng.choice(crossing)
            value = _get(message, leaf.loc)
            others = [t for other, t, _ in crossing if other is leaf and t != threshold]
            if others and ctx.rng.random() < BETWEEN_PROBABILITY:
                new = (threshold + ctx.rng.choice(others)) / 2.0
            else:
                new = _past(threshold, value, ctx.rng, way)
            _set(message, leaf.loc, _coerce(new, leaf.spec, ctx))
            return message
        if _scaled(message, ctx):
            return message
    return _apply_leaf_ops(message, ctx, ("compared",))


def _scaled(message: Message, ctx: MutationContext) -> bool:
    """When no leaf holds a value an unsolved comparison saw: a float leaf (not 0) of the
    message multiplied by ``t' / v``, for ``v`` a value this input compared at an unsolved site
    and ``t'`` its threshold or just past it (``ComparedValues.operands``, ``_past``, which
    never gives a ``v`` of 0: no factor moves it). A value computed from the input in
    proportion to that leaf (a ratio of a scaling factor and a squared one, a distance from
    home) then lands right past the threshold; one that is not, moves toward it. Whether one
    was written.

    The factor is not bounded: an oracle's ``gap > 1e-6`` that saw a rounding error of 2e-16
    scales a leaf by 5e9, a threshold 0 scales one to about 0. Keeping only factors within
    1e-3..1e3 (edc5fe9) lost ``plan_start_band`` in 10 of 10 one-minute trials against 4 of 10
    without (p = 0.035, docs/benchmarks-log.md): such far values are mutations of their own."""
    assert ctx.compared is not None
    operands = ctx.compared.operands()  # never a value of 0, which no factor moves
    if not operands:
        return False
    leaves = [
        leaf for leaf in _eligible_leaves(message, ctx, ("compared",)) if _get(message, leaf.loc) != 0.0
    ]
    if not leaves:
        return False
    threshold, value, way = ctx.rng.choice(operands)
    leaf = ctx.rng.choice(leaves)
    x = _get(message, leaf.loc)
    new = x * (_past(threshold, value, ctx.rng, way) / value)
    if not math.isfinite(new) or new == x:
        return False
    _set(message, leaf.loc, _coerce(new, leaf.spec, ctx))
    return True


_NUMBERS: Final = frozenset({"int", "float"})
_FLOAT: Final = frozenset({"float"})

LEAF_OPS: dict[str, LeafOp] = {
    "bit_flip": LeafOp(frozenset({"bool", "int", "float"}), _bit_flip, _finite),
    "arithmetic": LeafOp(_NUMBERS, _arithmetic, _finite),
    "interesting": LeafOp(frozenset({"bool", "int", "float", "str"}), _interesting),
    "sign_flip": LeafOp(_FLOAT, _sign_flip, _finite),
    "wrap_2pi": LeafOp(_FLOAT, _wrap_2pi, _finite),
    "zero": LeafOp(_NUMBERS, _zero, _nonzero),
    "string_swap": LeafOp(frozenset({"str"}), _string_swap, _can_swap),
    "dictionary": LeafOp(frozenset({"int", "float", "str"}), _dictionary_token, _has_tokens),
    "libfuzzer": LeafOp(frozenset({"float", "str"}), _libfuzzer, _has_libfuzzer),
    "compared": LeafOp(_FLOAT, _compared, _has_thresholds),
}
"""Value-level operations, looked up by name at call time (so they can be instrumented)."""


def _eligible_leaves(message: Message, ctx: MutationContext, op_names: Sequence[str]) -> list[Leaf]:
    """Leaves the first op accepts and whose kind every op handles."""
    first = LEAF_OPS[op_names[0]]
    kinds = functools.reduce(frozenset.intersection, (LEAF_OPS[name].kinds for name in op_names))
    leaves = _inventory(message, ctx).leaves
    return [
        leaf
        for leaf in leaves
        if leaf.spec.kind in kinds and first.eligible(_get(message, leaf.loc), leaf, message, ctx)
    ]


def _apply_leaf_ops(message: Message, ctx: MutationContext, op_names: Sequence[str]) -> Message:
    """Apply ``op_names`` in order to one chosen leaf (later ops are skipped when they cannot apply)."""
    leaf = _choose(_eligible_leaves(message, ctx, op_names), lambda lf: lf.name, ctx)
    value = _get(message, leaf.loc)
    for name in op_names:
        op = LEAF_OPS[name]
        if op.eligible(value, leaf, message, ctx):
            value = _coerce(op.apply(value, leaf, message, ctx), leaf.spec, ctx)
    _set(message, leaf.loc, value)
    return message
