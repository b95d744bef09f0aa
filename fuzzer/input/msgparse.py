"""ROS1 message definitions, the grammar: ``.msg`` text to a :class:`MessageSpec`.

The records of a parsed definition (fields, constants), the builtin types and their ranges,
and the limits every definition is held to. Definitions are untrusted data: they are parsed
with a small hand-written grammar, never evaluated. Finding definitions by name, checking
values and building message classes is :mod:`fuzzer.input.msgdef`'s part.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass, field

__all__ = [
    "BUILTIN_TYPES",
    "FLOAT_TYPES",
    "INT_RANGES",
    "MAX_DEPTH",
    "MAX_FIXED_VALUES",
    "MAX_MSG_BYTES",
    "NAME",
    "NSECS_MAX",
    "RESERVED_ATTRS",
    "SECS_RANGES",
    "ConstantSpec",
    "FieldSpec",
    "MessageSpec",
    "MsgError",
    "RosDuration",
    "RosTime",
    "parse_msg",
    "split_full_name",
]

INT_RANGES: dict[str, tuple[int, int]] = {
    "int8": (-(2**7), 2**7 - 1),
    "uint8": (0, 2**8 - 1),
    "int16": (-(2**15), 2**15 - 1),
    "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
}
FLOAT_TYPES = frozenset({"float32", "float64"})
#: Range of ``secs`` for the two time-like builtins; ``nsecs`` is always ``0..NSECS_MAX``.
SECS_RANGES: dict[str, tuple[int, int]] = {"time": INT_RANGES["uint32"], "duration": INT_RANGES["int32"]}
NSECS_MAX = 999_999_999
BUILTIN_TYPES = frozenset({"bool", "string", *INT_RANGES, *FLOAT_TYPES, *SECS_RANGES})
#: Builtins a constant may have (ROS1 has no time/duration constants).
CONSTANT_TYPES = BUILTIN_TYPES - set(SECS_RANGES)
#: Deprecated ROS1 aliases.
TYPE_ALIASES = {"byte": "int8", "char": "uint8"}
#: Largest fixed array length accepted (``type[N]``); real definitions use at most 36.
MAX_FIXED_LENGTH = 1024
#: Deepest nesting of message types accepted.
MAX_DEPTH = 32
#: Most values a message's fixed part may hold (fixed arrays multiply through nesting);
#: a default value is built eagerly, so ``T[1024]`` nested three deep would need 1e9.
MAX_FIXED_VALUES = 1 << 16
#: Largest ``.msg`` file read, in bytes; real definitions are under 10 KiB.
MAX_MSG_BYTES = 1 << 20
#: Most digits in an integer literal (array length or constant): uint64 needs 20.
_MAX_INT_DIGITS = 20

#: A field, constant, package or type name.
NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
_FULLNAME = re.compile(r"(?P<pkg>[A-Za-z][A-Za-z0-9_]*)/(?:msg/)?(?P<type>[A-Za-z][A-Za-z0-9_]*)")
_TYPE_TOKEN = re.compile(
    r"(?:(?P<pkg>[A-Za-z][A-Za-z0-9_]*)/)?(?P<base>[A-Za-z][A-Za-z0-9_]*)(?P<array>\[(?P<length>[0-9]*)\])?"
)
_INT_LITERAL = re.compile(r"[+-]?[0-9]+")
_FLOAT_LITERAL = re.compile(
    r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|inf|infinity|nan)", re.IGNORECASE
)
_BOOL_LITERALS = {"true": True, "1": True, "false": False, "0": False}
#: Attribute names a generated message class keeps for itself.
RESERVED_ATTRS = frozenset({"from_dict", "to_dict"})


class MsgError(ValueError):
    """Any problem parsing, finding, validating or instantiating a ROS message."""


@dataclass(frozen=True)
class FieldSpec:
    """One field of a message definition.

    Attributes
    ----------
    name : str
        Field name.
    type : str
        Builtin type name (aliases already resolved) or a full message name ``pkg/Type``.
    is_array : bool
        Whether the field is an array.
    length : int or None
        Length of a fixed array; ``None`` for variable arrays and scalars.
    line : int
        Line of the definition (0 when unknown); ignored by comparisons.
    """

    name: str
    type: str
    is_array: bool
    length: int | None
    line: int = field(default=0, compare=False, repr=False)

    @property
    def is_builtin(self) -> bool:
        """Whether the element type is a builtin (not a nested message)."""
        return self.type in BUILTIN_TYPES


@dataclass(frozen=True)
class ConstantSpec:
    """A constant declared in a message definition (``type NAME=value``)."""

    name: str
    type: str
    value: bool | int | float | str


@dataclass(frozen=True)
class MessageSpec:
    """A parsed message definition.

    Attributes
    ----------
    full_name : str
        ``pkg/Type``.
    fields : tuple of FieldSpec
        Fields in definition order.
    constants : tuple of ConstantSpec
        Constants in definition order.
    source : str
        Path of the definition, or ``'<string>'``.
    """

    full_name: str
    fields: tuple[FieldSpec, ...]
    constants: tuple[ConstantSpec, ...]
    source: str


@dataclass(frozen=True)
class RosTime:
    """Value of a ``time`` field inside a generated message class."""

    secs: int = 0
    nsecs: int = 0


@dataclass(frozen=True)
class RosDuration:
    """Value of a ``duration`` field inside a generated message class."""

    secs: int = 0
    nsecs: int = 0


def split_full_name(name: str) -> tuple[str, str]:
    """Split ``pkg/Type`` (or ``pkg/msg/Type``) into its parts, or raise :class:`MsgError`."""
    match = _FULLNAME.fullmatch(name) if isinstance(name, str) else None
    if match is None:
        raise MsgError(f"invalid message type name {name!r}: expected 'package/Type'")
    return match["pkg"], match["type"]


def parse_msg(text: str, full_name: str, source: str = "<string>") -> MessageSpec:
    """Parse the text of a ROS1 ``.msg`` definition.

    Parameters
    ----------
    text : str
        Content of the definition.
    full_name : str
        Name of the message, ``pkg/Type``; unqualified nested types resolve to ``pkg``.
    source : str
        Where the text came from, used in error messages.

    Returns
    -------
    MessageSpec
        Fields and constants in definition order. Nested types are not looked up here.

    Raises
    ------
    MsgError
        On any syntax error, naming ``source`` and the line.
    """
    package, type_name = split_full_name(full_name)
    full_name = f"{package}/{type_name}"
    fields: list[FieldSpec] = []
    constants: list[ConstantSpec] = []
    seen: dict[str, int] = {}
    for lineno, raw in enumerate(text.split("\n"), start=1):
        line = raw.removesuffix("\r")
        code = line.split("#", 1)[0].strip()
        if not code:
            continue
        where = f"{source}:{lineno}"
        item: FieldSpec | ConstantSpec
        if "=" in code:
            item = _parse_constant(line, code, where)
            constants.append(item)
        else:
            item = _parse_field(code, package, where, lineno)
            fields.append(item)
        if item.name in seen:
            first = seen[item.name]
            raise MsgError(f"{where}: duplicate name {item.name!r} in {full_name} (first on line {first})")
        seen[item.name] = lineno
    return MessageSpec(full_name, tuple(fields), tuple(constants), source)


def _check_name(name: str, what: str, where: str) -> None:
    if not NAME.fullmatch(name):
        rule = "letters, digits and '_', starting with a letter"
        raise MsgError(f"{where}: invalid {what} name {name!r} ({rule})")


def _parse_type(token: str, package: str, where: str) -> tuple[str, bool, int | None]:
    """Resolve a type token to ``(type, is_array, length)``."""
    match = _TYPE_TOKEN.fullmatch(token)
    if match is None:
        raise MsgError(f"{where}: invalid type {token!r}")
    base, pkg = match["base"], match["pkg"]
    if pkg is not None:
        resolved = f"{pkg}/{base}"
    elif base in TYPE_ALIASES:
        resolved = TYPE_ALIASES[base]
    elif base in BUILTIN_TYPES:
        resolved = base
    elif base == "Header":
        resolved = "std_msgs/Header"
    else:
        resolved = f"{package}/{base}"
    if match["array"] is None:
        return resolved, False, None
    if not match["length"]:
        return resolved, True, None
    digits = match["length"].lstrip("0") or "0"
    length = int(digits) if len(digits) <= _MAX_INT_DIGITS else MAX_FIXED_LENGTH + 1
    if not 1 <= length <= MAX_FIXED_LENGTH:
        raise MsgError(f"{where}: fixed array length must be 1..{MAX_FIXED_LENGTH}, got {token!r:.80}")
    return resolved, True, length


def _parse_field(code: str, package: str, where: str, lineno: int) -> FieldSpec:
    tokens = code.split()
    if len(tokens) != 2:
        raise MsgError(f"{where}: expected 'type name' or 'type NAME=value', got {code!r}")
    type_token, name = tokens
    _check_name(name, "field", where)
    resolved, is_array, length = _parse_type(type_token, package, where)
    return FieldSpec(name, resolved, is_array, length, lineno)


def _parse_constant(line: str, code: str, where: str) -> ConstantSpec:
    parts = code.split(None, 1)
    if len(parts) != 2 or "=" in parts[0]:
        raise MsgError(f"{where}: expected 'type NAME=value', got {code!r}")
    type_token, rest = parts
    ctype = TYPE_ALIASES.get(type_token, type_token)
    if ctype not in CONSTANT_TYPES:
        rule = "a builtin scalar other than time/duration"
        raise MsgError(f"{where}: constant type must be {rule}, got {type_token!r}")
    name = rest.partition("=")[0].strip()
    _check_name(name, "constant", where)
    if ctype == "string":
        # String constants take the rest of the line verbatim ('#' included), trimmed like ROS1 does.
        return ConstantSpec(name, ctype, line[line.index("=") + 1 :].strip())
    text = rest.partition("=")[2].strip()
    return ConstantSpec(name, ctype, _constant_value(ctype, text, where))


def _constant_value(ctype: str, text: str, where: str) -> bool | int | float:
    """Convert the literal ``text`` of a non-string constant of type ``ctype``."""
    if ctype == "bool":
        if text.lower() not in _BOOL_LITERALS:
            raise MsgError(f"{where}: invalid bool constant {text!r} (true/false/1/0)")
        return _BOOL_LITERALS[text.lower()]
    if ctype in INT_RANGES:
        lo, hi = INT_RANGES[ctype]
        if not _INT_LITERAL.fullmatch(text):
            raise MsgError(f"{where}: invalid {ctype} constant {text!r:.80}")
        sign, digits = ("-" if text[0] == "-" else ""), text.lstrip("+-").lstrip("0") or "0"
        if len(digits) > _MAX_INT_DIGITS:  # int() refuses more than 4300 digits; the range check needs <= 20
            raise MsgError(f"{where}: {ctype} constant {text:.40}... out of range {lo}..{hi}")
        value = int(sign + digits)
        if not lo <= value <= hi:
            raise MsgError(f"{where}: {ctype} constant {value} out of range {lo}..{hi}")
        return value
    if not _FLOAT_LITERAL.fullmatch(text):
        raise MsgError(f"{where}: invalid {ctype} constant {text!r}")
    number = float(text)
    if ctype == "float32":
        try:
            struct.pack("<f", number)
        except OverflowError:
            raise MsgError(f"{where}: float32 constant {text!r} out of range") from None
    return number
