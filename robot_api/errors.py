"""The error vocabulary both implementations raise.

Every error an implementation raises on bad input is a :class:`RobotAPIError`
subclass carrying an :class:`ErrorCode`. Two implementations "fail the same way"
when they raise the same class with the same code; the message is free text for
people and is never compared.

The numeric codes are part of the contract: the C++ side throws them and its
binding turns each into the class given by :func:`error_class`.
"""

from __future__ import annotations

import enum


class ErrorCode(enum.IntEnum):
    """Why a call was rejected. Values are stable (used across the C++ boundary)."""

    URDF_INVALID = 1
    """The URDF is not readable or not well formed, or breaks a URDF rule."""
    URDF_UNSUPPORTED = 2
    """The URDF is valid but uses something the API does not support."""
    WRONG_LENGTH = 10
    """A joint vector or a names/values pair has the wrong number of entries."""
    NON_FINITE = 11
    """A value is NaN or infinite."""
    INVALID_ARGUMENT = 12
    """An argument has the wrong type or a value outside its domain."""
    DUPLICATE_NAME = 13
    """The same joint name is given twice."""
    INVALID_TRAJECTORY = 14
    """A trajectory passed to ``execute`` does not fit the group or its state."""
    UNSUPPORTED_OPERATION = 15
    """The operation is not defined for this model (e.g. IK through a mimic joint)."""
    UNKNOWN_JOINT = 20
    UNKNOWN_LINK = 21
    UNKNOWN_NAMED_TARGET = 22
    OUT_OF_BOUNDS = 30
    """A joint target lies beyond its limits by more than the goal tolerance."""
    PLANNING_FAILED = 40
    """No trajectory within the contract's limits (it would last too long)."""


class RobotAPIError(Exception):
    """Base class of every error of the API.

    Parameters
    ----------
    code : ErrorCode
        Why the call was rejected.
    message : str
        A human readable explanation naming the offending item.
    """

    default_code: ErrorCode = ErrorCode.INVALID_ARGUMENT

    def __init__(self, message: str, code: ErrorCode | int | None = None) -> None:
        super().__init__(message)
        self.code = ErrorCode(code) if code is not None else self.default_code

    def __reduce__(self) -> tuple[object, ...]:  # keep code through copy/multiprocessing
        return (type(self), (str(self), int(self.code)))


class URDFError(RobotAPIError):
    """A URDF could not be loaded: unreadable, malformed or unsupported."""

    default_code = ErrorCode.URDF_INVALID


class InvalidInputError(RobotAPIError, ValueError):
    """An argument is malformed: wrong length, type, non-finite value, duplicate name."""

    default_code = ErrorCode.INVALID_ARGUMENT


class UnknownNameError(RobotAPIError, LookupError):
    """A joint, link or named target does not exist in the model."""

    default_code = ErrorCode.UNKNOWN_JOINT


class OutOfBoundsError(RobotAPIError, ValueError):
    """A joint target is beyond its limits by more than the goal tolerance."""

    default_code = ErrorCode.OUT_OF_BOUNDS


class PlanningError(RobotAPIError):
    """``plan()`` found no acceptable trajectory (``go()`` returns False instead)."""

    default_code = ErrorCode.PLANNING_FAILED


_CLASS_OF_CODE: dict[ErrorCode, type[RobotAPIError]] = {
    ErrorCode.URDF_INVALID: URDFError,
    ErrorCode.URDF_UNSUPPORTED: URDFError,
    ErrorCode.WRONG_LENGTH: InvalidInputError,
    ErrorCode.NON_FINITE: InvalidInputError,
    ErrorCode.INVALID_ARGUMENT: InvalidInputError,
    ErrorCode.DUPLICATE_NAME: InvalidInputError,
    ErrorCode.INVALID_TRAJECTORY: InvalidInputError,
    ErrorCode.UNSUPPORTED_OPERATION: InvalidInputError,
    ErrorCode.UNKNOWN_JOINT: UnknownNameError,
    ErrorCode.UNKNOWN_LINK: UnknownNameError,
    ErrorCode.UNKNOWN_NAMED_TARGET: UnknownNameError,
    ErrorCode.OUT_OF_BOUNDS: OutOfBoundsError,
    ErrorCode.PLANNING_FAILED: PlanningError,
}


def error_class(code: ErrorCode | int) -> type[RobotAPIError]:
    """Return the exception class the contract assigns to ``code``."""
    return _CLASS_OF_CODE[ErrorCode(code)]


def make_error(code: ErrorCode | int, message: str) -> RobotAPIError:
    """Build the exception the contract assigns to ``code``."""
    return error_class(code)(message, code)
