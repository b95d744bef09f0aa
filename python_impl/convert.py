"""Argument checking at the twin's boundary (docs/api.md, "Arguments").

A real number is an ``int`` (not ``bool``), a ``float``, or any object whose type
defines ``__float__`` and is not ``str``/``bytes``/``bytearray`` (``Decimal``, ``Fraction``);
a numpy scalar or 0-d array only of an integer or float dtype (not bool, complex or object);
whatever its ``__float__`` raises is INVALID_ARGUMENT. A joint
vector is a ``list``/``tuple`` of real numbers, read once as ``tuple()`` reads it before its items
are converted, or a 1-D integer/float ndarray (a masked array with masked entries is refused).
Anything else is INVALID_ARGUMENT.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from robot_api.constants import QUATERNION_NORM_EPS
from robot_api.errors import ErrorCode, InvalidInputError

_REAL_KINDS = ("f", "i", "u")


def bad(what: str, why: str) -> InvalidInputError:
    return InvalidInputError(f"{what}: {why}", ErrorCode.INVALID_ARGUMENT)


def is_real(value: Any) -> bool:
    t = type(value)
    if t is float or t is int:
        return True
    if isinstance(value, bool | str | bytes | bytearray):
        return False
    if isinstance(value, np.generic):  # a numpy scalar is real by its dtype, as an array is
        return value.dtype.kind in _REAL_KINDS
    if isinstance(value, np.ndarray):  # a 0-d array is a number of its dtype; others are not numbers
        return value.ndim == 0 and value.dtype.kind in _REAL_KINDS
    return isinstance(value, int | float) or hasattr(t, "__float__")


def to_real(value: Any, what: str) -> float:
    if type(value) is float:
        return value
    if not is_real(value):
        raise bad(what, f"expected a real number, got {type(value).__name__}")
    try:
        return float(value)
    except Exception:  # noqa: BLE001 - any error of a __float__ is the argument's (docs/api.md)
        raise bad(what, f"cannot convert {type(value).__name__} to a float") from None


def is_sequence(value: Any) -> bool:
    return isinstance(value, list | tuple | np.ndarray)


def items(values: list[Any] | tuple[Any, ...], what: str) -> tuple[Any, ...]:
    """The items of a list or tuple, read once (as native reads them: ``PySequence_Tuple``), so
    that converting them cannot change what is read."""
    try:
        return tuple(values)
    except Exception:  # noqa: BLE001 - a subclass's __iter__ failing is the argument's
        raise bad(what, f"cannot read the {type(values).__name__}") from None


def refuse_masked(array: np.ndarray, what: str, code: ErrorCode = ErrorCode.INVALID_ARGUMENT) -> None:
    """A masked array (``numpy.ma``) with masked entries: they have no value to use."""
    if isinstance(array, np.ma.MaskedArray) and np.ma.is_masked(array):
        raise InvalidInputError(f"{what}: a masked array with masked entries (they have no value)", code)


def to_vector(values: Any, what: str) -> list[float]:
    """A joint vector as a list of floats (no length or finiteness check)."""
    if isinstance(values, list | tuple):
        return [to_real(v, what) for v in items(values, what)]
    if isinstance(values, np.ndarray):
        if values.ndim != 1:
            raise bad(what, f"expected a 1-D array, got {values.ndim}-D")
        if values.dtype.kind not in _REAL_KINDS:
            raise bad(what, f"array of kind '{values.dtype.kind}' is not real")
        refuse_masked(values, what)
        return as_float64(values, what).tolist()  # type: ignore[no-any-return]
    raise bad(what, f"expected a list, tuple or 1-D array of numbers, got {type(values).__name__}")


def as_float64(values: np.ndarray, what: str, code: ErrorCode = ErrorCode.INVALID_ARGUMENT) -> np.ndarray:
    """A real array as a C-ordered float64 one; one whose copy cannot be made (no memory: a
    broadcast view of 10**10 values takes 8 bytes) is the argument's, as in native."""
    try:
        return np.ascontiguousarray(values, dtype=np.float64)
    except MemoryError:
        raise InvalidInputError(f"{what}: cannot convert the array to float64", code) from None


def to_string(value: Any, what: str) -> str:
    if not isinstance(value, str):
        raise bad(what, f"expected a str, got {type(value).__name__}")
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        raise bad(what, "string is not valid UTF-8") from None
    return value


def to_optional_string(value: Any, what: str) -> str | None:
    return None if value is None else to_string(value, what)


def to_strings(values: Any, what: str) -> list[str]:
    if not isinstance(values, list | tuple):
        raise bad(what, f"expected a list or tuple of names, got {type(values).__name__}")
    return [to_string(v, what) for v in items(values, what)]


def to_pose(pose: Any) -> tuple[list[float], list[float]]:
    """Position (3,) and unit quaternion (x, y, z, w) of a Pose or (position, orientation) pair."""
    if not isinstance(pose, tuple | list):
        raise bad(
            "pose", f"expected a robot_api.Pose or a (position, orientation) pair, got {type(pose).__name__}"
        )
    pose = items(pose, "pose")
    if len(pose) != 2:
        raise bad("pose", "expected a (position, orientation) pair")
    p = to_vector(pose[0], "pose position")
    q = to_vector(pose[1], "pose orientation")
    if len(p) != 3:
        raise bad("pose position", f"expected 3 values, got {len(p)}")
    if len(q) != 4:
        raise bad("pose orientation", f"expected 4 values (x, y, z, w), got {len(q)}")
    if not all(math.isfinite(v) for v in p):
        raise InvalidInputError("pose position is not finite", ErrorCode.NON_FINITE)
    if not all(math.isfinite(v) for v in q):
        raise InvalidInputError("pose orientation is not finite", ErrorCode.NON_FINITE)
    scale = max(abs(v) for v in q)  # scaled first: squaring 1e154 would overflow the norm to inf
    scaled = [v / scale for v in q] if scale > 0.0 else [0.0] * 4
    unit = math.sqrt(
        scaled[0] * scaled[0] + scaled[1] * scaled[1] + scaled[2] * scaled[2] + scaled[3] * scaled[3]
    )
    if not scale * unit >= QUATERNION_NORM_EPS:
        raise bad("pose orientation", "quaternion has (near) zero norm")
    return p, [v / unit for v in scaled]
