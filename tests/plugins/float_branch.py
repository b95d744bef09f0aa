"""A function with branches on computed floats (tests/test_floatcmp.py instruments it)."""


def branch(x: float, y: float) -> int:
    if x * 2.0 < 0.1234:
        return 1
    if y > 3:
        return 2
    return 0


def band(x: float) -> bool:
    """A chained comparison (Atheris does not mark its constants ``is_const``)."""
    return 0.3 <= x < 0.31


def exactly(x: float) -> bool:
    """An equality (its other outcome lies only on the threshold)."""
    return x == 0.25
