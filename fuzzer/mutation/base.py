"""The mutators' shared vocabulary: the mutation context, ``NotApplicable`` and the tuning
constants and interesting values (``fuzzer.mutation.mutators`` has the design notes)."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from random import Random
from typing import Any, Final, Protocol, TypeVar

Message = dict[str, Any]
Loc = tuple[str | int, ...]
_T = TypeVar("_T")


class Thresholds(Protocol):
    """Where ``compared`` draws a value (``fuzzer.selection.compared.ComparedValues``): ``pick``
    gives a comparison threshold of the targets, or None before one is known; ``crossings`` the
    thresholds of branches never taken whose comparison recently saw a given value, each with the
    way to that branch (+1.0 up, -1.0 down, 0.0 unknown); ``operands`` the values the input being
    mutated compared at unsolved sites, with their thresholds and ways; ``len`` is how many are
    known."""

    def pick(self, rng: Random) -> float | None: ...

    def crossings(self, value: float) -> list[tuple[float, float]]: ...

    def operands(self) -> list[tuple[float, float, float]]: ...

    def __len__(self) -> int: ...


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
    compared : Thresholds or None
        The targets' float comparison thresholds, learned during the campaign, for
        ``compared``; None: that mutator does not apply.
    """

    rng: Random
    field_types: Mapping[str, str]
    interesting_floats: Sequence[float] = ()
    dictionary: Sequence[str | float] = ()
    allow_special: bool = False
    libfuzzer_mutate: Callable[[bytes, int], bytes] | None = None
    other: dict[str, Any] | None = None
    focus: Sequence[str] = ()
    compared: Thresholds | None = None
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
