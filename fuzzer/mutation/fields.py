"""What a mutator may touch and how a value stays valid: ROS field types, the inventory of a
message's leaves and arrays, and the one coercion step every new value goes through."""

from __future__ import annotations

import copy
import functools
import math
import re
import struct
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Final

from fuzzer.mutation.base import (
    _T,
    FLOAT32_MAX,
    FOCUS_PROBABILITY,
    MAX_ARRAY_LEN,
    NSECS_PER_SEC,
    Loc,
    Message,
    MutationContext,
    NotApplicable,
)

if TYPE_CHECKING:
    from fuzzer.input.msgdef import MessageRegistry

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


def field_types(
    registry: MessageRegistry, msg_type: str, prefix: str = "", message_arrays: bool = False
) -> dict[str, str]:
    """Dotted path -> ROS type (``float64``, ``uint8[]``, ``geometry_msgs/Pose[]``) of every field
    of ``msg_type`` a mutator may touch: its builtin leaves, through nested messages. An array of
    messages is left out, unless ``message_arrays``: then it is a field itself and its elements'
    fields are typed under its name (``poses.position.x``), so that a ``/cartesian_path``
    step's waypoints can be mutated, inserted and removed."""
    out: dict[str, str] = {}
    for f in registry.get(msg_type).fields:
        path = f"{prefix}{f.name}"
        suffix = "" if not f.is_array else ("[]" if f.length is None else f"[{f.length}]")
        if f.is_builtin or (message_arrays and f.is_array):
            out[path] = f.type + suffix
        if not f.is_builtin and (message_arrays or not f.is_array):
            out.update(field_types(registry, f.type, path + ".", message_arrays))
    return out


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


def clone(value: _T) -> _T:
    """Deep copy of JSON-like data (dicts, lists, immutable scalars); other objects via ``copy.deepcopy``."""
    if isinstance(value, dict):
        return {key: clone(item) for key, item in value.items()}  # type: ignore[return-value]
    if isinstance(value, list):
        return [clone(item) for item in value]  # type: ignore[return-value]
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
