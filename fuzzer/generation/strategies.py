"""Hypothesis strategies for ROS message values (Table I of the RROSFuzz paper).

Algorithm 1 maps each ``(name, type)`` pair of a message class to a strategy and combines
them; here the message class is a :class:`~fuzzer.input.msgdef.MessageSpec` and the combination
is :func:`hypothesis.strategies.fixed_dictionaries` (with its key order restored), so a
drawn value is a plain message dict (see :mod:`fuzzer.input.msgdef`) in field order.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Any

from hypothesis import strategies as st
from hypothesis.strategies import SearchStrategy

from fuzzer.input.msgdef import INT_RANGES, NSECS_MAX, SECS_RANGES, MessageRegistry, MessageSpec, MsgError

__all__ = ["strategy_for", "strategy_table"]

_TABLE = {
    "string": "string(): st.text",
    "time": "time(): Time, {secs: st.integers(0, 2**32-1), nsecs: st.integers(0, 10**9-1)}",
    "duration": "time(): Time, {secs: st.integers(-2**31, 2**31-1), nsecs: st.integers(0, 10**9-1)}",
    "array": "array(): st.lists (exact size for T[N], at most max_array elements for T[])",
    "complex": "ros type to dict(): combination strategy, st.fixed_dictionaries over the fields",
    "bool": "st.booleans",
    "int8..uint64": "st.integers within the width",
    "float64": "st.floats(allow_nan=allow_infinity=allow_special_floats)",
    "float32": "st.floats(width=32, allow_nan=allow_infinity=allow_special_floats)",
}


def strategy_table() -> dict[str, str]:
    """Describe the generation strategies (Table I): type family -> strategy."""
    return dict(_TABLE)


def strategy_for(
    registry: MessageRegistry,
    msg_type: str,
    *,
    hints: Mapping[str, SearchStrategy[Any]] | None = None,
    allow_special_floats: bool = False,
    max_array: int = 8,
) -> SearchStrategy[dict[str, Any]]:
    """Build a strategy drawing valid values of ``msg_type``.

    Parameters
    ----------
    registry : MessageRegistry
        Where ``msg_type`` and its nested types are looked up.
    msg_type : str
        ``pkg/Type``.
    hints : mapping of str to SearchStrategy, optional
        Dotted field path -> strategy that replaces the strategy of that field, e.g.
        ``'name'``, ``'header.frame_id'``, ``'pose.position.x'``, ``'header.stamp.secs'``.
        A path through an array of messages applies to every element
        (``'layout.dim.label'``). Hinted strategies are used as given, not validated.
    allow_special_floats : bool
        Whether float fields may be nan or +-inf.
    max_array : int
        Largest size of variable-length arrays.

    Returns
    -------
    SearchStrategy
        Strategy of message dicts in field order.

    Raises
    ------
    MsgError
        If the type does not resolve, a hint path names no field, a hint is shadowed by a
        hint on an enclosing field, or a hint is not a strategy.
    ValueError
        If ``max_array`` is negative.
    """
    if max_array < 0:
        raise ValueError(f"max_array must be >= 0, got {max_array}")
    spec = registry.get(msg_type)
    chosen = dict(hints or {})
    _check_hints(registry, spec, chosen)
    return _Builder(registry, chosen, allow_special_floats, max_array).message(spec, "")


def _paths(registry: MessageRegistry, spec: MessageSpec, prefix: str) -> Iterator[str]:
    """Yield every hintable dotted path below ``prefix``."""
    for fld in spec.fields:
        path = f"{prefix}{fld.name}"
        yield path
        if fld.type in SECS_RANGES:
            yield f"{path}.secs"
            yield f"{path}.nsecs"
        elif not fld.is_builtin:
            yield from _paths(registry, registry.get(fld.type), f"{path}.")


def _check_hints(registry: MessageRegistry, spec: MessageSpec, hints: Mapping[str, Any]) -> None:
    valid = set(_paths(registry, spec, ""))
    for path, strategy in hints.items():
        if path not in valid:
            sample = ", ".join(sorted(valid)[:12])
            raise MsgError(f"unknown hint path {path!r} for {spec.full_name} (valid paths include: {sample})")
        if not isinstance(strategy, SearchStrategy):
            raise MsgError(f"hint {path!r} must be a hypothesis strategy, got {type(strategy).__name__}")
        parts = path.split(".")
        for cut in range(1, len(parts)):
            outer = ".".join(parts[:cut])
            if outer in hints:
                raise MsgError(f"hint {path!r} is shadowed by the hint on {outer!r}")


class _Builder:
    """Recursive mapping from field types to strategies (Algorithm 1, lines 3-10)."""

    def __init__(
        self,
        registry: MessageRegistry,
        hints: Mapping[str, SearchStrategy[Any]],
        allow_special_floats: bool,
        max_array: int,
    ) -> None:
        self.registry = registry
        self.hints = hints
        self.special = allow_special_floats
        self.max_array = max_array

    def message(self, spec: MessageSpec, path: str) -> SearchStrategy[dict[str, Any]]:
        """Combination strategy of a (nested) message at ``path``."""
        parts: dict[str, SearchStrategy[Any]] = {}
        for fld in spec.fields:
            sub = f"{path}.{fld.name}" if path else fld.name
            if sub in self.hints:
                parts[fld.name] = self.hints[sub]
                continue
            element = self.scalar(fld.type, sub)
            if not fld.is_array:
                parts[fld.name] = element
            elif fld.length is not None:
                parts[fld.name] = st.lists(element, min_size=fld.length, max_size=fld.length)
            else:
                parts[fld.name] = st.lists(element, max_size=self.max_array)
        return _ordered(parts)

    def scalar(self, type_: str, path: str) -> SearchStrategy[Any]:
        """Strategy of one element of type ``type_`` at ``path``."""
        if type_ == "bool":
            return st.booleans()
        if type_ in INT_RANGES:
            lo, hi = INT_RANGES[type_]
            return st.integers(lo, hi)
        if type_ == "float64":
            return st.floats(allow_nan=self.special, allow_infinity=self.special)
        if type_ == "float32":
            return st.floats(width=32, allow_nan=self.special, allow_infinity=self.special)
        if type_ == "string":
            return st.text()
        if type_ in SECS_RANGES:
            return self.time(type_, path)
        return self.message(self.registry.get(type_), path)

    def time(self, type_: str, path: str) -> SearchStrategy[dict[str, int]]:
        """The Time strategy: ``{'secs': ..., 'nsecs': ...}`` within range."""
        lo, hi = SECS_RANGES[type_]
        secs = self.hints.get(f"{path}.secs", st.integers(lo, hi))
        nsecs = self.hints.get(f"{path}.nsecs", st.integers(0, NSECS_MAX))
        return _ordered({"secs": secs, "nsecs": nsecs})


def _ordered(parts: dict[str, SearchStrategy[Any]]) -> SearchStrategy[dict[str, Any]]:
    """``st.fixed_dictionaries`` whose values keep the key order of ``parts``.

    Hypothesis shuffles the iteration order of fixed dictionaries on purpose; message
    values must list their fields in definition order, so the order is restored.
    """
    keys = tuple(parts)
    return st.fixed_dictionaries(parts).map(lambda drawn: {key: drawn[key] for key in keys})
