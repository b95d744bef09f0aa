"""Float comparisons of the Python targets as coverage: a distance-to-flip feature per site.

Atheris instruments every ``COMPARE_OP`` of the instrumented modules (the Python targets and
``fuzzer.execution.oracle``: see ``fuzzer.selection.instrument``) with a call
``atheris._trace_cmp(a, b, op, site, is_const)``, looked up on the module at each call.
Atheris turns integer and bytes comparisons into libFuzzer's CMP traces; floats it ignores,
so a branch on a computed float (``if x < 0.1234``, a near-singular wrist, an ``atan2``
quadrant, a calibration band) is invisible to the search until an input happens to flip it.

:class:`FloatCompareTracer` wraps ``_trace_cmp``: for a comparison with a float operand it
adds the feature (site, side, binary exponent of ``|a - b|``), then calls Atheris' own
function. An input that brings a comparison within half the distance of any earlier input
(a new exponent at that site) is new coverage, so libFuzzer keeps it and mutates it further:
the search climbs toward the branch. Exponents are clipped to [-60, 16] (1e-18 .. 65,536); a
difference of exactly 0 is its own bucket. The cost is one Python call per comparison in the
instrumented modules (BENCHMARKS.md has the measured overhead), for the first ``PER_INPUT``
float comparisons of each input; after those the tracer steps aside until the next input.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from fuzzer.selection.guidance import Features

FLOAT_CMP = 11
"""Tag of float-comparison features (guidance's integer feature tuples start with a tag)."""
LOW, HIGH = -60, 16

PER_INPUT = 64
"""Float comparisons traced per input (the first ones it makes); then Atheris' own function
takes over until the next input. A ``move`` through the twin's planner makes about 350, and
tracing them all took a third of the campaign's time (BENCHMARKS.md)."""
_FLOATS = (float, np.float64, np.float32)
_NUMBERS = (*_FLOATS, int, np.int64)


class FloatCompareTracer:
    """Installs itself around ``atheris._trace_cmp`` (again whenever Atheris swaps it).

    Parameters
    ----------
    features : Features
        Where the features go (libFuzzer's extra counters).
    module : object, optional
        The module holding ``_trace_cmp`` (``atheris``; a stand-in in tests).
    """

    def __init__(self, features: Features, module: Any = None) -> None:
        if module is None:
            import atheris

            module = atheris
        self.features = features
        self.module = module
        self.inner: Callable[..., Any] | None = None
        self.sites: set[int] = set()
        """Comparison sites that compared a float at least once."""
        self.traced = 0
        self.remaining = PER_INPUT
        self._keys: set[tuple[int, ...]] = set()

    def install(self, budget: int = PER_INPUT) -> None:
        """Wrap the module's current ``_trace_cmp`` unless it is already this tracer's, for the
        next ``budget`` float comparisons (the harness calls this before every input)."""
        self.remaining = budget
        current = getattr(self.module, "_trace_cmp", None)
        if current is None or current == self.trace:
            return
        self.inner = current
        self.module._trace_cmp = self.trace

    def trace(self, obj1: Any, obj2: Any, opid: int, site: int, is_const: bool) -> Any:
        """The wrapper: record the float distance, then compare as Atheris does."""
        t1, t2 = type(obj1), type(obj2)
        if (t1 in _FLOATS and t2 in _NUMBERS) or (t2 in _FLOATS and t1 in _NUMBERS):
            self._record(float(obj1), float(obj2), site)
            self.remaining -= 1
            if self.remaining <= 0 and self.inner is not None:
                self.module._trace_cmp = self.inner  # the budget is spent: Atheris' own until install()
        inner = self.inner
        if inner is None:  # never installed: compare like COMPARE_OP would
            return _compare(obj1, obj2, opid)
        return inner(obj1, obj2, opid, site, is_const)

    def _record(self, a: float, b: float, site: int) -> None:
        gap = a - b
        if gap != gap or math.isinf(gap):  # NaN or infinite: one bucket per site
            exponent = HIGH + 1
        elif gap == 0.0:
            exponent = LOW - 1
        else:
            exponent = min(HIGH, max(LOW, math.frexp(gap)[1]))
        self.traced += 1
        key = (FLOAT_CMP, site, int(gap > 0.0), exponent)
        if key in self._keys:
            self.features.bump(key)
        else:
            self._keys.add(key)
            self.sites.add(site)
            self.features.hit_ids((key,))


_OPS: dict[int, Callable[[Any, Any], Any]] = {
    0: lambda a, b: a < b,
    1: lambda a, b: a <= b,
    2: lambda a, b: a == b,
    3: lambda a, b: a != b,
    4: lambda a, b: a > b,
    5: lambda a, b: a >= b,
}


def _compare(a: Any, b: Any, opid: int) -> Any:
    return _OPS[opid](a, b)
