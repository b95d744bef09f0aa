"""A function with branches on computed floats (tests/test_floatcmp.py instruments it)."""


def branch(x: float, y: float) -> int:
    if x * 2.0 < 0.1234:
        return 1
    if y > 3:
        return 2
    return 0
