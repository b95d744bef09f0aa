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

import copy
import functools
import math
import re
import struct
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from random import Random
from typing import Any, Final, TypeVar

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

Message = dict[str, Any]
Loc = tuple[str | int, ...]
_T = TypeVar("_T")


@dataclass
class MutationContext:
    """Everything a mutator may use besides the message itself.

    Attributes
    ----------
    rng : random.Random
        The only source of randomness: a given seed gives a given mutation.
    field_types : Mapping[str, str]
        Dotted field path -> ROS builtin type (``'float64'``, ``'float64[]'``, ``'float64[9]'``,
        ``'string[]'``, ``'time'``, ``'uint32'``...).  Fields of messages inside arrays use the array's path
        (``'points.x'``).
    interesting_floats : Sequence[float]
        Extra interesting values from the engine (joint limits +- epsilon...).
    dictionary : Sequence[str | float]
        Tokens: user dictionary entries, joint and link names, numbers.
    allow_special : bool
        Whether NaN, inf and -inf may be produced.
    libfuzzer_mutate : Callable[[bytes, int], bytes] or None
        ``atheris.Mutate`` when running under libFuzzer.
    other : dict or None
        A second message of the same type, for ``splice``.
    focus : Sequence[str]
        Dotted paths to prefer (``['position']``); empty means any field.
    """

    rng: Random
    field_types: Mapping[str, str]
    interesting_floats: Sequence[float] = ()
    dictionary: Sequence[str | float] = ()
    allow_special: bool = False
    libfuzzer_mutate: Callable[[bytes, int], bytes] | None = None
    other: dict[str, Any] | None = None
    focus: Sequence[str] = ()
    memo: dict[Any, Any] = field(default_factory=dict, repr=False, compare=False)
    """Derived tables (float pools), valid while the fields above do not change."""


Mutator = Callable[[dict[str, Any], MutationContext], dict[str, Any]]


class NotApplicable(Exception):
    """Raised by a mutator that cannot apply to this message (no suitable field, no ``ctx.other``...)."""


# ----------------------------------------------------------------------------------------------------------
# Tuning constants
# ----------------------------------------------------------------------------------------------------------

PAPER_STRATEGIES: Final = ("bit_flip", "arithmetic", "interesting", "comb1", "comb2", "comb3", "comb4")
FUTURE_WORK: Final = ("dictionary", "havoc", "splice")
NOOP: Final = "noop"
"""Name reported by :func:`mutate` when no mutator applies (the message is returned unchanged)."""

ARITH_MAX: Final = 35
"""Largest arithmetic step, as AFL's ``ARITH_MAX``."""
FLOAT_ARITH_SCALES: Final = (1e-9, 1e-6, 1e-4, 1e-2, 0.1, 1.0)
"""A float delta is ``scale * k * sign`` with ``k`` in ``1..ARITH_MAX``: ``|delta| <= ARITH_MAX``."""
FLIP_AMOUNTS: Final = (1, 2, 4)
FLOAT_FLIP_WINDOW: Final = 8
"""Bits 0..7 of the integer part of a float may be flipped."""
HAVOC_MIN_STACK: Final = 2
HAVOC_MAX_STACK: Final = 16
HAVOC_EXCLUDED: Final = frozenset({"havoc", "splice"})
FOCUS_PROBABILITY: Final = 0.9
"""Probability of choosing among the focused fields when ``ctx.focus`` matches some."""
ENGINE_INTERESTING_PROBABILITY: Final = 0.5
"""Probability that ``interesting`` draws a float from ``ctx.interesting_floats`` (when not empty)."""
DICTIONARY_INSERT_PROBABILITY: Final = 0.25
MAX_ARRAY_LEN: Final = 4096
"""Variable-length arrays never grow beyond this (bounded arrays: their bound)."""
LONG_STRING_LEN: Final = 4096
LIBFUZZER_ATTEMPTS: Final = 4
LIBFUZZER_STRING_SLACK: Final = 16
SPLICE_ATTEMPTS: Final = 8
NSECS_PER_SEC: Final = 1_000_000_000

FLOAT32_MAX: Final = 3.4028234663852886e38
_TWO_PI: Final = 2.0 * math.pi

INTERESTING_INTS: Final[tuple[int, ...]] = (
    # AFL's INTERESTING_8 / _16 / _32, then wider limits; filtered by each field's width.
    -128, -1, 0, 1, 16, 32, 64, 100, 127,
    -32768, -129, 128, 255, 256, 512, 1000, 1024, 4096, 32767,
    -2147483648, -100663046, -32769, 32768, 65535, 65536, 100663045, 2147483647,
    2**32 - 1, 2**32, 999_999_999, NSECS_PER_SEC, -(2**63), 2**63 - 1, 2**64 - 1,
)  # fmt: skip

INTERESTING_FLOATS: Final[tuple[float, ...]] = (
    # Fig. 3: values that may overflow or hit angle-normalisation boundaries, and more.
    0.0, -0.0, 1.0, -1.0, 0.5, -0.5, 1e-9, -1e-9, 2.220446049250313e-16,
    math.pi, -math.pi, math.pi / 2, -math.pi / 2, _TWO_PI, -_TWO_PI, 3 * math.pi, -3 * math.pi,
    math.pi + 1e-9, math.pi - 1e-9, -(math.pi + 1e-9), -(math.pi - 1e-9),
    _TWO_PI + 1e-9, -(_TWO_PI + 1e-9),
    5e-324, -5e-324, 2.2250738585072014e-308, 1e-300, 1e300, -1e300,
    1.7976931348623157e308, -1.7976931348623157e308,
    2.0**31, -(2.0**31), 2.0**31 - 1, 2.0**32, 2.0**53, 2.0**63, -(2.0**63), 2.0**64,
    FLOAT32_MAX, -FLOAT32_MAX, 1.1754943508222875e-38, 1.401298464324817e-45, 1e6, 1e9,
)  # fmt: skip

SPECIAL_FLOATS: Final[tuple[float, ...]] = (math.nan, math.inf, -math.inf)

INTERESTING_STRINGS: Final[tuple[str, ...]] = (
    "",
    "A" * LONG_STRING_LEN,
    "j\u00f6int_\u00f1_\u540d\u524d_\U0001f916",
    "%s%n%s%n",
    "\x00",
    " ",
    "\t\n",
    "nan",
    "-1",
)

# ----------------------------------------------------------------------------------------------------------
# Types
# ----------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ScalarSpec:
    """What a leaf may hold: ``kind`` is ``'bool'``, ``'int'``, ``'float'`` or ``'str'``.

    ``lo``/``hi``/``bits``/``signed`` describe ints; ``max_len`` bounds strings (``string<=N``).
    """

    kind: str
    name: str
    lo: int = 0
    hi: int = 0
    bits: int = 0
    signed: bool = False
    max_len: int | None = None

    @property
    def is_float32(self) -> bool:
        """Whether values must be representable as IEEE-754 binary32."""
        return self.name == "float32"


def _int_spec(name: str, bits: int, signed: bool) -> ScalarSpec:
    """Spec of a two's complement (``signed``) or unsigned int of ``bits`` bits."""
    lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
    return ScalarSpec("int", name, lo, hi, bits, signed)


_SCALARS: Final[dict[str, ScalarSpec]] = {
    "bool": ScalarSpec("bool", "bool"),
    "float32": ScalarSpec("float", "float32"),
    "float64": ScalarSpec("float", "float64"),
    "string": ScalarSpec("str", "string"),
    "wstring": ScalarSpec("str", "wstring"),
    "int8": _int_spec("int8", 8, True),
    "uint8": _int_spec("uint8", 8, False),
    "int16": _int_spec("int16", 16, True),
    "uint16": _int_spec("uint16", 16, False),
    "int32": _int_spec("int32", 32, True),
    "uint32": _int_spec("uint32", 32, False),
    "int64": _int_spec("int64", 64, True),
    "uint64": _int_spec("uint64", 64, False),
    "byte": _int_spec("int8", 8, True),  # ROS 1: deprecated alias of int8
    "char": _int_spec("uint8", 8, False),  # ROS 1: deprecated alias of uint8
    "octet": _int_spec("uint8", 8, False),
}
_TIME_SECS: Final[dict[str, ScalarSpec]] = {
    "time": _int_spec("uint32", 32, False),
    "duration": _int_spec("int32", 32, True),
}
NSECS_SPEC: Final = ScalarSpec("int", "nsecs", 0, NSECS_PER_SEC - 1, 30, False)
_TYPE_RE: Final = re.compile(r"^(?P<base>[^\[\]]+?)\s*(?:\[(?P<bound><=)?(?P<size>\d*)\])?$")
_BOUNDED_STRING_RE: Final = re.compile(r"^(?P<base>w?string)<=(?P<max>\d+)$")


@dataclass(frozen=True)
class FieldType:
    """A parsed field type: ``base`` plus array shape (``fixed`` length or ``bound``)."""

    base: str
    is_array: bool = False
    fixed: int | None = None
    bound: int | None = None


@functools.lru_cache(maxsize=1024)
def _parse_type(text: str) -> FieldType:
    """Parse ``'float64[9]'``, ``'string[]'``, ``'int32[<=4]'``, ``'time'``... into a :class:`FieldType`."""
    match = _TYPE_RE.match(text.strip())
    if match is None:
        return FieldType(text.strip())
    base = match["base"]
    if text.rstrip().endswith("]"):
        size = int(match["size"]) if match["size"] else None
        if match["bound"]:
            return FieldType(base, is_array=True, bound=size)
        return FieldType(base, is_array=True, fixed=size)
    return FieldType(base)


@functools.lru_cache(maxsize=1024)
def _scalar_spec(base: str) -> ScalarSpec | None:
    """The scalar spec of a builtin base type, ``None`` for time/duration and message types."""
    if base in _SCALARS:
        return _SCALARS[base]
    bounded = _BOUNDED_STRING_RE.match(base)
    if bounded is not None:
        return ScalarSpec("str", bounded["base"], max_len=int(bounded["max"]))
    return None


# ----------------------------------------------------------------------------------------------------------
# Walking a message
# ----------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Leaf:
    """One mutable scalar: its location in the message, dotted name and spec.

    ``array`` is the location of the enclosing scalar array (for siblings), ``None`` otherwise.
    """

    loc: Loc
    name: str
    spec: ScalarSpec
    array: Loc | None = None


@dataclass(frozen=True)
class ArrayRef:
    """One array field: location, dotted name and parsed type."""

    loc: Loc
    name: str
    ftype: FieldType

    @property
    def capacity(self) -> int:
        """Largest length the array may take."""
        if self.ftype.fixed is not None:
            return self.ftype.fixed
        return self.ftype.bound if self.ftype.bound is not None else MAX_ARRAY_LEN


@dataclass
class _Inventory:
    leaves: list[Leaf]
    arrays: list[ArrayRef]


def _fits(value: Any, spec: ScalarSpec) -> bool:
    """Whether ``value`` has the Python type a leaf of ``spec`` holds (ints accepted for floats)."""
    if spec.kind == "bool":
        return isinstance(value, bool)
    if isinstance(value, bool):
        return False
    if spec.kind == "int":
        return isinstance(value, int)
    if spec.kind == "float":
        return isinstance(value, (int, float))
    return isinstance(value, str)


def _is_time(value: Any) -> bool:
    """Whether ``value`` looks like a ``{"secs": int, "nsecs": int}`` dict."""
    return (
        isinstance(value, dict) and isinstance(value.get("secs"), int) and isinstance(value.get("nsecs"), int)
    )


INVENTORY_CACHE: Final = 512


def _inventory(message: Message, ctx: MutationContext) -> _Inventory:
    """All mutable leaves (array elements individually, time as secs + nsecs) and all arrays.

    Leaves are locations, so they depend only on the message's structure. A registered
    mutator works on a clone of its input (``ctx.memo["_source"]`` = (clone, input)), and
    the inventory of a clone is that of its input: cached by the input's identity. Each
    cache entry keeps its message alive, so an id cannot be reused while cached.
    """
    source = ctx.memo.get("_source")
    cache: OrderedDict[int, tuple[Message, Mapping[str, str], _Inventory]] = ctx.memo.setdefault(
        "_inventories", OrderedDict()
    )
    if source is not None and source[0] is message:
        entry = cache.get(id(source[1]))
        if entry is not None and entry[0] is source[1] and entry[1] is ctx.field_types:
            cache.move_to_end(id(source[1]))
            return entry[2]
    inv = _Inventory([], [])
    _walk_dict(message, (), "", ctx.field_types, inv)
    if source is not None and source[0] is message:
        cache[id(source[1])] = (source[1], ctx.field_types, inv)
        if len(cache) > INVENTORY_CACHE:
            cache.popitem(last=False)
    return inv


@functools.lru_cache(maxsize=4096)
def _dotted(prefix: str, key: Any) -> str:
    return f"{prefix}.{key}" if prefix else str(key)


def _walk_dict(node: Message, loc: Loc, prefix: str, types: Mapping[str, str], inv: _Inventory) -> None:
    """Collect the leaves and arrays of the fields of ``node`` into ``inv``."""
    for key, value in node.items():
        name = _dotted(prefix, key)
        sub = (*loc, key)
        text = types.get(name)
        if text is None:
            if isinstance(value, dict):
                _walk_dict(value, sub, name, types, inv)
            continue
        ftype = _parse_type(text)
        if not ftype.is_array:
            _walk_value(value, sub, name, ftype.base, None, types, inv)
        elif isinstance(value, list):
            inv.arrays.append(ArrayRef(sub, name, ftype))
            for index, item in enumerate(value):
                _walk_value(item, (*sub, index), name, ftype.base, sub, types, inv)


def _walk_value(
    value: Any, loc: Loc, name: str, base: str, array: Loc | None, types: Mapping[str, str], inv: _Inventory
) -> None:
    """Collect ``value`` (a field or an array element of type ``base``) into ``inv``."""
    if base in _TIME_SECS:
        if _is_time(value):
            inv.leaves.append(Leaf((*loc, "secs"), f"{name}.secs", _TIME_SECS[base]))
            inv.leaves.append(Leaf((*loc, "nsecs"), f"{name}.nsecs", NSECS_SPEC))
        return
    spec = _scalar_spec(base)
    if spec is not None:
        if _fits(value, spec):
            inv.leaves.append(Leaf(loc, name, spec, array))
    elif isinstance(value, dict):
        _walk_dict(value, loc, name, types, inv)


def _clone(value: _T) -> _T:
    """Deep copy of JSON-like data (dicts, lists, immutable scalars); other objects via ``copy.deepcopy``."""
    if isinstance(value, dict):
        return {key: _clone(item) for key, item in value.items()}  # type: ignore[return-value]
    if isinstance(value, list):
        return [_clone(item) for item in value]  # type: ignore[return-value]
    if value is None or isinstance(value, (str, int, float)):
        return value
    return copy.deepcopy(value)


def _get(message: Message, loc: Loc) -> Any:
    """The value at ``loc`` (keys and list indices)."""
    node: Any = message
    for step in loc:
        node = node[step]
    return node


def _set(message: Message, loc: Loc, value: Any) -> None:
    """Store ``value`` at ``loc``."""
    _get(message, loc[:-1])[loc[-1]] = value


def _in_focus(name: str, focus: Sequence[str]) -> bool:
    """Whether the dotted ``name`` is one of ``focus`` or inside one of them."""
    return any(name == f or name.startswith(f + ".") for f in focus)


def _choose(items: Sequence[_T], names: Callable[[_T], str], ctx: MutationContext) -> _T:
    """Uniform choice, preferring items in ``ctx.focus`` with probability :data:`FOCUS_PROBABILITY`."""
    if not items:
        raise NotApplicable("nothing to mutate")
    if ctx.focus:
        focused = [item for item in items if _in_focus(names(item), ctx.focus)]
        if focused and ctx.rng.random() < FOCUS_PROBABILITY:
            return ctx.rng.choice(focused)
    return ctx.rng.choice(items)


# ----------------------------------------------------------------------------------------------------------
# Coercion: the single gate every new value passes
# ----------------------------------------------------------------------------------------------------------


def _wrap(value: int, spec: ScalarSpec) -> int:
    """Wrap an int into ``[lo, hi]`` (two's complement per width; modulo 10**9 for nsecs)."""
    if spec.lo <= value <= spec.hi:
        return value
    return (value - spec.lo) % (spec.hi - spec.lo + 1) + spec.lo


def _to_float32(value: float) -> float:
    """Round to the nearest float32, clamping finite values beyond the float32 range."""
    if not math.isfinite(value):
        return value
    clamped = max(-FLOAT32_MAX, min(FLOAT32_MAX, value))
    result: float = struct.unpack("<f", struct.pack("<f", clamped))[0]
    return result


def _coerce(value: Any, spec: ScalarSpec, ctx: MutationContext) -> Any:
    """Bring a candidate value into the leaf's type, or raise :class:`NotApplicable`."""
    if not _fits(value, spec):
        raise NotApplicable(f"{value!r} cannot be a {spec.name}")
    if spec.kind == "int":
        return _wrap(value, spec)
    if spec.kind == "float":
        try:
            number = float(value)
        except OverflowError as exc:
            raise NotApplicable(str(exc)) from exc
        if not math.isfinite(number) and not ctx.allow_special:
            raise NotApplicable("NaN/inf not allowed")
        return _to_float32(number) if spec.is_float32 else number
    if spec.kind == "str" and spec.max_len is not None:
        return value[: spec.max_len]
    return value


def _valid(value: Any, spec: ScalarSpec, ctx: MutationContext) -> bool:
    """Whether ``value`` may be stored as is in a leaf of ``spec``."""
    try:
        coerced = _coerce(value, spec, ctx)
    except NotApplicable:
        return False
    same = coerced == value or (isinstance(value, float) and math.isnan(value))
    return same and type(coerced) is type(value)


def _valid_time(value: Any, base: str, ctx: MutationContext) -> bool:
    """Whether ``value`` is a ``{"secs", "nsecs"}`` dict within the ranges of ``base`` (time/duration)."""
    return (
        _is_time(value)
        and len(value) == 2
        and _valid(value["secs"], _TIME_SECS[base], ctx)
        and _valid(value["nsecs"], NSECS_SPEC, ctx)
    )


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
            clone = _clone(message)
            outer = ctx.memo.get("_source")
            ctx.memo["_source"] = (clone, message)  # lets _inventory reuse the input's inventory
            try:
                return fn(clone, ctx)
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


def _valid_element(item: Any, base: str, ctx: MutationContext) -> bool:
    """Whether ``item`` may be an element of an array of ``base`` (message elements: any dict)."""
    if base in _TIME_SECS:
        return _valid_time(item, base, ctx)
    spec = _scalar_spec(base)
    return _valid(item, spec, ctx) if spec is not None else isinstance(item, dict)


def _splice_array(a: list[Any], b: Any, ftype: FieldType, ctx: MutationContext) -> list[Any]:
    """Prefix of one parent + suffix of the other, cut at one aligned index (fixed lengths kept)."""
    if not isinstance(b, list) or (ftype.fixed is not None and len(b) != len(a)):
        return _clone(a)
    if len(b) > max(len(a), ftype.bound or MAX_ARRAY_LEN):
        return _clone(a)
    if not all(_valid_element(item, ftype.base, ctx) for item in b):
        return _clone(a)
    first, second = (a, b) if ctx.rng.random() < 0.5 else (b, a)
    cut = ctx.rng.randint(0, len(first))  # cut <= len(first): element i always comes from a[i] or b[i]
    return _clone(first[:cut] + second[cut:])


def _splice_scalar(a: Any, b: Any, base: str, ctx: MutationContext) -> Any:
    """``a`` or ``b`` (coin flip) when ``b`` is a valid value of the same type, else ``a``."""
    spec = _scalar_spec(base)
    valid = _valid(b, spec, ctx) if spec is not None else base in _TIME_SECS and _valid_time(b, base, ctx)
    return _clone(b if valid and ctx.rng.random() < 0.5 else a)


def _splice_dict(a: Message, b: Any, prefix: str, ctx: MutationContext) -> Message:
    """Field-by-field splice of ``a`` with ``b`` (shape and order of ``a``)."""
    out: Message = {}
    for key, value in a.items():
        name = f"{prefix}.{key}" if prefix else str(key)
        other = b.get(key) if isinstance(b, dict) else None
        text = ctx.field_types.get(name)
        ftype = _parse_type(text) if text is not None else None
        if other is None:
            out[key] = _clone(value)
        elif ftype is not None and ftype.is_array and isinstance(value, list):
            out[key] = _splice_array(value, other, ftype, ctx)
        elif isinstance(value, dict) and (ftype is None or ftype.base not in _TIME_SECS):
            out[key] = _splice_dict(value, other, name, ctx)
        elif ftype is not None:
            out[key] = _splice_scalar(value, other, ftype.base, ctx)
        else:
            out[key] = _clone(value)
    return out


def _splice_both(a: Message, b: Message, ctx: MutationContext) -> Message:
    """Splice ``a`` and ``b``, retrying (up to :data:`SPLICE_ATTEMPTS`) while one parent is reproduced."""
    child = _splice_dict(a, b, "", ctx)
    for _ in range(SPLICE_ATTEMPTS - 1):
        if a == b or (child != a and child != b):
            break
        child = _splice_dict(a, b, "", ctx)
    return child


@register("splice", weight=0.5)
def splice(message: Message, ctx: MutationContext) -> Message:
    """Join the message with ``ctx.other`` (AFL splice): arrays prefix + suffix, scalars from either.

    Not applicable without ``ctx.other``.  The shape and field order of ``message`` are kept.
    """
    if ctx.other is None:
        raise NotApplicable("splice needs ctx.other")
    return _splice_both(message, ctx.other, ctx)


# --- libFuzzer ---------------------------------------------------------------------------------------------


@register("libfuzzer", weight=1.0)
def libfuzzer(message: Message, ctx: MutationContext) -> Message:
    """Mutate the bytes of one float (``'<d'``; ``'<f'`` for float32) or string with libFuzzer's mutator.

    ``ctx.libfuzzer_mutate(data, size)`` (``atheris.Mutate``) brings libFuzzer's dictionaries and CMP
    tables; its output is padded/truncated to ``size`` bytes (8, or 4 for float32) and decoded; strings
    are UTF-8 encoded and decoded with ``errors='replace'``.  Not applicable without the callable.
    """
    return _apply_leaf_ops(message, ctx, ("libfuzzer",))


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


def _choose_array(
    message: Message, ctx: MutationContext, keep: Callable[[ArrayRef, list[Any]], bool]
) -> ArrayRef:
    """An array of ``message`` that ``keep`` accepts (focus honoured), or :class:`NotApplicable`."""
    refs = [ref for ref in _inventory(message, ctx).arrays if keep(ref, _get(message, ref.loc))]
    return _choose(refs, lambda ref: ref.name, ctx)


def _new_element(ref: ArrayRef, array: list[Any], ctx: MutationContext) -> Any:
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
    return _clone(ctx.rng.choice(array))


def _growable(ref: ArrayRef, array: list[Any]) -> bool:
    """Whether ``array`` is variable-length and below its capacity."""
    return ref.ftype.fixed is None and len(array) < ref.capacity


@register("array_insert", weight=0.5)
def array_insert(message: Message, ctx: MutationContext) -> Message:
    """Insert an element (interesting value) into a variable-length array; parallel arrays may mismatch."""

    def keep(ref: ArrayRef, array: list[Any]) -> bool:
        is_message = ref.ftype.base not in _TIME_SECS and _scalar_spec(ref.ftype.base) is None
        return _growable(ref, array) and not (is_message and not array)

    ref = _choose_array(message, ctx, keep)
    array = _get(message, ref.loc)
    array.insert(ctx.rng.randint(0, len(array)), _new_element(ref, array, ctx))
    return message


@register("array_delete", weight=0.5)
def array_delete(message: Message, ctx: MutationContext) -> Message:
    """Delete one element of a non-empty variable-length array; parallel arrays may mismatch."""
    ref = _choose_array(message, ctx, lambda ref, array: ref.ftype.fixed is None and bool(array))
    array = _get(message, ref.loc)
    del array[ctx.rng.randrange(len(array))]
    return message


@register("array_duplicate", weight=0.5)
def array_duplicate(message: Message, ctx: MutationContext) -> Message:
    """Duplicate an array element next to itself; in fixed-length arrays, copy it over another one."""

    def keep(ref: ArrayRef, array: list[Any]) -> bool:
        if ref.ftype.fixed is None:
            return bool(array) and _growable(ref, array)
        return len(array) >= 2

    ref = _choose_array(message, ctx, keep)
    array = _get(message, ref.loc)
    source = ctx.rng.randrange(len(array))
    if ref.ftype.fixed is None:
        array.insert(source + 1, _clone(array[source]))
    else:
        target = ctx.rng.choice([i for i in range(len(array)) if i != source])
        array[target] = _clone(array[source])
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
        return _clone(message), NOOP


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
    return _splice_both(a, b, ctx)
