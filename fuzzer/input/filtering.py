"""Early input filtering (paper III.E): a message with a non-finite or absurd float is not run."""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

ABSURD = 1e6
"""Early input filtering drops floats larger than this in magnitude (and NaN/inf)."""


def floats_of(value: Any) -> Iterator[float]:
    """Every float leaf of a message."""
    if isinstance(value, float):
        yield value
    elif isinstance(value, dict):
        for item in value.values():
            yield from floats_of(item)
    elif isinstance(value, list):
        for item in value:
            yield from floats_of(item)


def is_reasonable(message: dict[str, Any]) -> bool:
    """Early input filtering: finite floats of sane magnitude only."""
    return all(math.isfinite(x) and abs(x) <= ABSURD for x in floats_of(message))
