"""ROS1 message definitions: ``.msg`` parsing, lookup, validation and message classes.

This is the "input handling" step of RROSFuzz (Section III.A of the paper): a message type
name such as ``sensor_msgs/JointState`` is resolved to its ``.msg`` file, parsed into a
:class:`MessageSpec`, and turned into a runtime "ROS message class".

Message *values* are plain JSON-friendly dicts in field order:

=====================  ===========================================
ROS type               Python value
=====================  ===========================================
bool                   ``bool``
int8 .. uint64         ``int`` (never ``bool``), within the width
float32, float64       ``float`` (nan and inf allowed)
string                 ``str`` (must be encodable as UTF-8)
time, duration         ``{"secs": int, "nsecs": int}``
``T[]``, ``T[N]``      ``list``
nested message         ``dict``
=====================  ===========================================

Definitions are untrusted data: they are parsed with a small hand-written grammar, never
evaluated.
"""

from __future__ import annotations

import dataclasses
import functools
import keyword
import os
import re
import stat
import struct
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = [
    "BUILTIN_TYPES",
    "SHIPPED_MSG_ROOT",
    "ConstantSpec",
    "FieldSpec",
    "MessageRegistry",
    "MessageSpec",
    "MsgError",
    "RosDuration",
    "RosTime",
    "parse_msg",
]

#: Root of the definitions shipped with the fuzzer (``<root>/<pkg>/msg/<Type>.msg``).
SHIPPED_MSG_ROOT = Path(__file__).resolve().parents[1] / "msgs"

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

_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
_FULL_NAME = re.compile(r"(?P<pkg>[A-Za-z][A-Za-z0-9_]*)/(?:msg/)?(?P<type>[A-Za-z][A-Za-z0-9_]*)")
_TYPE_TOKEN = re.compile(
    r"(?:(?P<pkg>[A-Za-z][A-Za-z0-9_]*)/)?(?P<base>[A-Za-z][A-Za-z0-9_]*)(?P<array>\[(?P<length>[0-9]*)\])?"
)
_INT_LITERAL = re.compile(r"[+-]?[0-9]+")
_FLOAT_LITERAL = re.compile(
    r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|inf|infinity|nan)", re.IGNORECASE
)
_BOOL_LITERALS = {"true": True, "1": True, "false": False, "0": False}
_RESERVED_ATTRS = frozenset({"from_dict", "to_dict"})


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


# --------------------------------------------------------------------------- parsing


def _split_full_name(name: str) -> tuple[str, str]:
    """Split ``pkg/Type`` (or ``pkg/msg/Type``) into its parts, or raise :class:`MsgError`."""
    match = _FULL_NAME.fullmatch(name) if isinstance(name, str) else None
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
    package, type_name = _split_full_name(full_name)
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
    if not _NAME.fullmatch(name):
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


# --------------------------------------------------------------------------- registry


class MessageRegistry:
    """Finds, parses, resolves and caches message definitions.

    Parameters
    ----------
    search_paths : sequence of str or Path
        Extra roots laid out as ``<root>/<pkg>/msg/<Type>.msg`` (e.g. ``/usr/share``),
        searched in order after the definitions shipped in ``fuzzer/msgs``. A single
        ``str``/``Path`` is taken as one root.
    """

    def __init__(self, search_paths: Sequence[str | Path] = ()) -> None:
        extra = [search_paths] if isinstance(search_paths, str | Path) else list(search_paths)
        self.roots: tuple[Path, ...] = (SHIPPED_MSG_ROOT, *(Path(p) for p in extra))
        self._specs: dict[str, MessageSpec] = {}
        self._classes: dict[str, type] = {}
        self._fixed_values: dict[str, int] = {}

    # ----------------------------------------------------------------- lookup

    def get(self, name: str) -> MessageSpec:
        """Return the spec of ``name`` after resolving all nested types recursively.

        Parameters
        ----------
        name : str
            ``pkg/Type`` (``pkg/msg/Type`` is accepted too).

        Raises
        ------
        MsgError
            If the type or any nested type is unknown, unreadable, malformed or recursive.
        """
        package, type_name = _split_full_name(name)
        return self._resolve(f"{package}/{type_name}", (), "")

    def _resolve(self, name: str, chain: tuple[str, ...], referrer: str) -> MessageSpec:
        cached = self._specs.get(name)
        if cached is not None:
            return cached
        if name in chain:
            raise MsgError(f"recursive message definition: {' -> '.join((*chain, name))}")
        if len(chain) >= MAX_DEPTH:
            raise MsgError(f"message nesting deeper than {MAX_DEPTH}: {' -> '.join((*chain, name))}")
        spec = self._load(name, referrer)
        total = 0
        for fld in spec.fields:
            per_value = 2 if fld.type in SECS_RANGES else 1
            if not fld.is_builtin:
                where = f"field {fld.name!r} of {name} ({spec.source}:{fld.line})"
                self._resolve(fld.type, (*chain, name), where)
                per_value = self._fixed_values[fld.type]
            count = (fld.length or 0) if fld.is_array else 1
            total += count * per_value
            if total > MAX_FIXED_VALUES:
                raise MsgError(
                    f"{spec.source}:{fld.line}: {name} holds more than {MAX_FIXED_VALUES} values in "
                    f"fixed-size fields (fixed arrays multiply through nested types; field {fld.name!r})"
                )
        self._fixed_values[name] = total
        self._specs[name] = spec
        return spec

    def _find(self, name: str) -> Path | None:
        package, type_name = name.split("/")
        for root in self.roots:
            path = root / package / "msg" / f"{type_name}.msg"
            if path.is_file():
                return path
        return None

    def _load(self, name: str, referrer: str) -> MessageSpec:
        path = self._find(name)
        if path is None:
            by = f" (referenced by {referrer})" if referrer else ""
            roots = ", ".join(str(r) for r in self.roots)
            raise MsgError(f"unknown message type {name!r}{by}; searched {roots}")
        try:
            text = _read_bounded(path).decode("utf-8-sig")
        except (OSError, UnicodeDecodeError) as exc:
            raise MsgError(f"{path}: cannot read message definition: {exc}") from exc
        return parse_msg(text, name, str(path))

    def known(self) -> list[str]:
        """Return every ``pkg/Type`` found on the search path, sorted (not parsed)."""
        names: set[str] = set()
        for root in self.roots:
            try:
                files = list(root.glob("*/msg/*.msg"))
            except OSError:
                continue
            for path in files:
                package, type_name = path.parent.parent.name, path.stem
                if _NAME.fullmatch(package) and _NAME.fullmatch(type_name) and path.is_file():
                    names.add(f"{package}/{type_name}")
        return sorted(names)

    # ----------------------------------------------------------------- values

    def default(self, name: str) -> dict[str, Any]:
        """Return the zero/empty value of ``name`` (fixed arrays are filled with zeros)."""
        return {fld.name: self._default_field(fld) for fld in self.get(name).fields}

    def _default_field(self, fld: FieldSpec) -> Any:
        if fld.is_array:
            return [self._default_scalar(fld.type) for _ in range(fld.length or 0)]
        return self._default_scalar(fld.type)

    def _default_scalar(self, type_: str) -> Any:
        if type_ == "bool":
            return False
        if type_ in INT_RANGES:
            return 0
        if type_ in FLOAT_TYPES:
            return 0.0
        if type_ == "string":
            return ""
        if type_ in SECS_RANGES:
            return {"secs": 0, "nsecs": 0}
        return self.default(type_)

    def validate(self, name: str, value: Any) -> None:
        """Check that ``value`` is a well-formed value of message type ``name``.

        Raises
        ------
        MsgError
            Naming the dotted field path (e.g. ``header.stamp.secs`` or ``position[2]``)
            of the first problem found: missing or unexpected keys, wrong Python types
            (``bool`` is not an int and ints are not floats), integers outside their
            width, wrong fixed-array lengths, or time/duration parts out of range.
        """
        self._check_message(name, self.get(name), value, "")

    def _fail(self, root: str, path: str, problem: str) -> MsgError:
        return MsgError(f"invalid {root} value at {path or '<message>'!r}: {problem}")

    def _check_message(self, root: str, spec: MessageSpec, value: Any, path: str) -> None:
        if not isinstance(value, dict):
            raise self._fail(root, path, f"expected a dict for {spec.full_name}, got {type(value).__name__}")
        names = [fld.name for fld in spec.fields]
        for key in value:
            if key not in names:
                raise self._fail(root, _join(path, str(key)), f"unexpected field in {spec.full_name}")
        for fld in spec.fields:
            sub = _join(path, fld.name)
            if fld.name not in value:
                raise self._fail(root, sub, f"missing field of {spec.full_name}")
            self._check_field(root, fld, value[fld.name], sub)

    def _check_field(self, root: str, fld: FieldSpec, value: Any, path: str) -> None:
        if not fld.is_array:
            self._check_scalar(root, fld.type, value, path)
            return
        if not isinstance(value, list):
            raise self._fail(root, path, f"expected a list, got {type(value).__name__}")
        if fld.length is not None and len(value) != fld.length:
            raise self._fail(root, path, f"expected exactly {fld.length} elements, got {len(value)}")
        for index, item in enumerate(value):
            self._check_scalar(root, fld.type, item, f"{path}[{index}]")

    def _check_scalar(self, root: str, type_: str, value: Any, path: str) -> None:
        if type_ == "bool":
            if not isinstance(value, bool):
                raise self._fail(root, path, f"expected bool, got {type(value).__name__}")
        elif type_ in INT_RANGES:
            self._check_int(root, type_, INT_RANGES[type_], value, path)
        elif type_ in FLOAT_TYPES:
            if not isinstance(value, float):
                raise self._fail(root, path, f"expected float for {type_}, got {type(value).__name__}")
        elif type_ == "string":
            if not isinstance(value, str):
                raise self._fail(root, path, f"expected str, got {type(value).__name__}")
            try:
                value.encode("utf-8")
            except UnicodeEncodeError:
                raise self._fail(root, path, "string is not encodable as UTF-8") from None
        elif type_ in SECS_RANGES:
            if not isinstance(value, dict) or set(value) != {"secs", "nsecs"}:
                shape = "{'secs': int, 'nsecs': int}"
                raise self._fail(root, path, f"expected {type_} as {shape}, got {value!r:.80}")
            self._check_int(root, f"{type_} secs", SECS_RANGES[type_], value["secs"], f"{path}.secs")
            self._check_int(root, f"{type_} nsecs", (0, NSECS_MAX), value["nsecs"], f"{path}.nsecs")
        else:
            self._check_message(root, self.get(type_), value, path)

    def _check_int(self, root: str, what: str, bounds: tuple[int, int], value: Any, path: str) -> None:
        if not isinstance(value, int) or isinstance(value, bool):
            raise self._fail(root, path, f"expected int for {what}, got {type(value).__name__}")
        if not bounds[0] <= value <= bounds[1]:
            raise self._fail(root, path, f"{what} value {value} out of range {bounds[0]}..{bounds[1]}")

    # ----------------------------------------------------------------- classes

    def make_class(self, name: str) -> type:
        """Return the runtime "ROS message class" of ``name`` (cached).

        The class is a frozen dataclass with the fields in definition order, defaulting to
        :meth:`default`; arrays are stored as tuples, ``time``/``duration`` as
        :class:`RosTime`/:class:`RosDuration` and nested messages as instances of their own
        generated class. Constants become class attributes. ``from_dict(d)`` validates and
        converts a message value, ``to_dict()`` converts back. ``_type`` holds ``pkg/Type``.

        Raises
        ------
        MsgError
            If the type does not resolve, or a field/constant name cannot be a Python
            attribute (a keyword, ``from_dict`` or ``to_dict``).
        """
        spec = self.get(name)
        cached = self._classes.get(spec.full_name)
        if cached is not None:
            return cached
        for attr in [fld.name for fld in spec.fields] + [const.name for const in spec.constants]:
            if keyword.iskeyword(attr) or attr in _RESERVED_ATTRS:
                raise MsgError(
                    f"{spec.source}: name {attr!r} of {spec.full_name} cannot be a class attribute"
                )
        columns = [
            (
                fld.name,
                self._annotation(fld),
                field(default_factory=functools.partial(self._default_attr, fld)),
            )
            for fld in spec.fields
        ]
        namespace: dict[str, Any] = {c.name: c.value for c in spec.constants}
        namespace.update(
            _type=spec.full_name,
            _spec=spec,
            from_dict=classmethod(self._from_dict_method(spec.full_name)),
            to_dict=_to_dict_method(spec),
        )
        class_name = spec.full_name.split("/")[1]
        cls = dataclasses.make_dataclass(class_name, columns, namespace=namespace, frozen=True)
        cls.__module__ = __name__
        self._classes[spec.full_name] = cls
        return cls

    def _annotation(self, fld: FieldSpec) -> Any:
        simple: dict[str, Any] = {"bool": bool, "string": str, "time": RosTime, "duration": RosDuration}
        simple.update(dict.fromkeys(INT_RANGES, int))
        simple.update(dict.fromkeys(FLOAT_TYPES, float))
        element = simple.get(fld.type) or self.make_class(fld.type)
        return tuple[element, ...] if fld.is_array else element  # type: ignore[valid-type]

    def _default_attr(self, fld: FieldSpec) -> Any:
        return self._attr(fld, self._default_field(fld))

    def _attr(self, fld: FieldSpec, value: Any) -> Any:
        """Convert a validated field value to its class representation."""
        if fld.is_array:
            return tuple(self._scalar_attr(fld.type, item) for item in value)
        return self._scalar_attr(fld.type, value)

    def _scalar_attr(self, type_: str, value: Any) -> Any:
        if type_ == "time":
            return RosTime(value["secs"], value["nsecs"])
        if type_ == "duration":
            return RosDuration(value["secs"], value["nsecs"])
        if type_ in BUILTIN_TYPES:
            return value
        return self._build(type_, value)

    def _build(self, name: str, value: dict[str, Any]) -> Any:
        spec = self.get(name)
        cls = self.make_class(name)
        return cls(**{fld.name: self._attr(fld, value[fld.name]) for fld in spec.fields})

    def _from_dict_method(self, name: str) -> Callable[[type, Any], Any]:
        def from_dict(cls: type, data: Any) -> Any:
            """Validate the message value ``data`` and build an instance from it."""
            self.validate(name, data)
            return self._build(name, data)

        return from_dict


def _read_bounded(path: Path) -> bytes:
    """Read a regular file of at most ``MAX_MSG_BYTES`` (non-blocking open: a FIFO cannot hang it)."""
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    with os.fdopen(fd, "rb") as handle:
        if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):
            raise OSError(f"{path} is not a regular file")
        data = handle.read(MAX_MSG_BYTES + 1)
    if len(data) > MAX_MSG_BYTES:
        raise OSError(f"larger than {MAX_MSG_BYTES >> 20} MiB")
    return data


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


def _plain(value: Any) -> Any:
    """Convert a class-representation value back to its plain message value."""
    if isinstance(value, tuple):
        return [_plain(item) for item in value]
    if isinstance(value, RosTime | RosDuration):
        return {"secs": value.secs, "nsecs": value.nsecs}
    to_dict = getattr(value, "to_dict", None)
    if callable(to_dict):
        return to_dict()
    return value


def _to_dict_method(spec: MessageSpec) -> Callable[[Any], dict[str, Any]]:
    def to_dict(self: Any) -> dict[str, Any]:
        """Return the plain message value (dict in field order) of this instance."""
        return {fld.name: _plain(getattr(self, fld.name)) for fld in spec.fields}

    return to_dict
