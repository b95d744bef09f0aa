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
evaluated (the grammar and the records it makes: :mod:`fuzzer.input.msgparse`, whose public
names this module re-exports).
"""

from __future__ import annotations

import dataclasses
import functools
import keyword
import os
import stat
from collections.abc import Callable, Sequence
from dataclasses import field
from pathlib import Path
from typing import Any

from fuzzer.input.msgparse import (
    BUILTIN_TYPES,
    FLOAT_TYPES,
    INT_RANGES,
    MAX_DEPTH,
    MAX_FIXED_VALUES,
    MAX_MSG_BYTES,
    NAME,
    NSECS_MAX,
    RESERVED_ATTRS,
    SECS_RANGES,
    ConstantSpec,
    FieldSpec,
    MessageSpec,
    MsgError,
    RosDuration,
    RosTime,
    parse_msg,
    split_full_name,
)

__all__ = [
    "BUILTIN_TYPES",
    "INT_RANGES",
    "MAX_FIXED_VALUES",
    "MAX_MSG_BYTES",
    "NSECS_MAX",
    "SECS_RANGES",
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
        package, type_name = split_full_name(name)
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
        """The first root's definition of ``name``.

        Raises
        ------
        MsgError
            That name is taken by something other than a regular file (a FIFO, a folder, a
            dangling link), or by a link out of its root: a root is the folder the user
            pointed at, and nothing outside it is read (a link to /etc/passwd echoed its
            first line in the parse error)."""
        from fuzzer.input.paths import contained, kind_of  # (paths imports the session, which imports this)

        package, type_name = name.split("/")
        for root in self.roots:
            path = root / package / "msg" / f"{type_name}.msg"
            if not (path.is_symlink() or path.exists()):
                continue
            try:
                mode = path.stat().st_mode
            except OSError as exc:  # a dangling link, a loop
                raise MsgError(f"{path}: cannot read message definition: {exc.strerror or exc}") from None
            if not stat.S_ISREG(mode):
                raise MsgError(f"{path}: is {kind_of(mode)}, not a regular file")
            if path.is_symlink() and not contained(root, path):
                raise MsgError(f"{path}: a link out of its message folder {root}; not read")
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
                if NAME.fullmatch(package) and NAME.fullmatch(type_name) and path.is_file():
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
            if keyword.iskeyword(attr) or attr in RESERVED_ATTRS:
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
