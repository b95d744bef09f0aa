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
float comparisons of each input; after those only the guard below runs until the next input.

**Atheris' ``_trace_cmp`` leaks the result of every comparison** (3.0.0, and 3.1.0's source:
``core.cc`` returns the new reference from ``PyObject_RichCompare`` as a ``py::handle``, which
pybind11 increments once more). For ``True``/``False`` that is harmless; for a numpy array
comparison (``t < ta`` over a trajectory) the array is never freed: a ``move`` campaign grew by
about 15 MB/s and libFuzzer stopped it as out-of-memory after about 100 s. Atheris' function
only traces int-int, bytes-bytes and str-str comparisons (libFuzzer's CMP traces) and does a
plain ``PyObject_RichCompare`` for anything else, so the tracer passes exactly those pairs to it
(their result is a bool) and compares everything else itself, with the same operator: the
same result, no leak, and no CMP trace lost. Budget 0 is the guard alone (the baselines).
"""

from __future__ import annotations

import math
import operator
import sys
from collections.abc import Callable
from typing import Any, Final

import numpy as np

from fuzzer.selection.compared import ComparedValues
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
_ATHERIS_TRACES = (int, bytes, str)
"""Operand types Atheris' ``_trace_cmp`` traces (both operands of the same one of these)."""
_OPID_SHIFT = 0 if sys.version_info < (3, 12) else (4 if sys.version_info < (3, 13) else 5)
"""COMPARE_OP's argument holds the operator in its high bits from Python 3.12 (as Atheris reads it)."""


class FloatCompareTracer:
    """Installs itself around ``atheris._trace_cmp`` (again whenever Atheris swaps it).

    Parameters
    ----------
    features : Features
        Where the features go (libFuzzer's extra counters).
    module : object, optional
        The module holding ``_trace_cmp`` (``atheris``; a stand-in in tests).

    ``trace`` is one closure over locals (made with the guard, :meth:`_build`): it records the
    feature, counts the budget down, compares and shows the comparison to ``compared`` in one
    Python call. It was three (``trace``, ``_record``, the guard), with the instance's attributes
    looked up at each: a quarter of the tracing's time, which is a sixth to a quarter of an
    instrumented evaluation (BENCHMARKS.md, "What bounds the single-input rate"). The features,
    the counters bumped and the comparisons ``compared`` sees are the same, in the same order.
    """

    def __init__(
        self,
        features: Features,
        module: Any = None,
        budget: int = PER_INPUT,
        compared: ComparedValues | None = None,
    ) -> None:
        if module is None:
            import atheris

            module = atheris
        self.features = features
        self.module = module
        self.budget = budget
        """Float comparisons traced per input (0: only the leak guard)."""
        self.inner: Callable[..., Any] | None = None
        self.compared = compared
        """Learns the comparison thresholds of every float comparison (the guard feeds it, past
        the budget too), for the ``compared`` mutator; None: not watched (the baselines)."""
        self.sites: set[int] = set()
        """Comparison sites that compared a float at least once."""
        self._counters: dict[tuple[int, ...], int] = {}
        """Each feature key seen so far and its counter (-1 with the features disabled)."""
        self._nearest: dict[int, int] = {}
        """Per site, the smallest exponent of ``|a - b|`` seen so far (either side)."""
        self.nearer: list[int] = []
        """The sites the current input brought nearer their flip than any input before (a
        smaller exponent; reset by :meth:`install`): ``fuzzer.generation.walk`` walks on from it."""
        self._spent = 0
        """Float comparisons traced before the last :meth:`install`."""
        self._given = budget
        self.guard: Callable[..., Any] = make_guard(None, compared)
        """Compares as ``COMPARE_OP`` would; the pairs Atheris traces go through ``inner``."""
        self._build()

    @property
    def traced(self) -> int:
        """Float comparisons traced so far (every input's)."""
        return self._spent + self._given - self._left()

    def install(self, budget: int | None = None) -> None:
        """Wrap the module's current ``_trace_cmp`` unless it is already this tracer's, for the
        next ``budget`` float comparisons (default ``self.budget``; the harness calls this before
        every input, which also catches Atheris swapping its function in when fuzzing starts)."""
        self._spent += self._given - self._left()  # the last input's, before ``trace`` is remade
        current = getattr(self.module, "_trace_cmp", None)
        if current is not None and current != self.trace and current is not self.guard:
            self.inner = current
            self.guard = make_guard(current, self.compared)
            self._build()
        self._given = self.budget if budget is None else budget
        self.nearer.clear()
        self._set_left(self._given)
        if current is not None:
            self.module._trace_cmp = self.trace if self._given > 0 else self.guard

    def _build(self) -> None:
        """Make ``trace`` (and its budget's accessors) around the current guard and ``inner``."""
        features, module, guard, compared = self.features, self.module, self.guard, self.compared
        counters, sites, swap = self._counters, self.sites, self.inner is not None
        nearest, nearer = self._nearest, self.nearer
        floats, numbers, ops, shift, equality = _FLOATS, _NUMBERS, _OPS, _OPID_SHIFT, _EQUALITY
        done = compared.done if compared is not None else None
        watch = compared.watch if compared is not None else None
        frexp, isinf, low, high = math.frexp, math.isinf, LOW, HIGH
        left, branch = self._given, features.brancher()

        def trace(obj1: Any, obj2: Any, opid: int, site: int, is_const: bool) -> Any:
            """The wrapper: record the float distance, then compare (as ``guard`` does)."""
            nonlocal left
            t1, t2 = type(obj1), type(obj2)
            if not ((t1 in floats and t2 in numbers) or (t2 in floats and t1 in numbers)):
                return guard(obj1, obj2, opid, site, is_const)
            gap = float(obj1) - float(obj2)
            if gap != gap or isinf(gap):  # NaN or infinite: one bucket per site
                exponent = high + 1
            elif gap == 0.0:
                exponent = low - 1
            else:
                exponent = min(high, max(low, frexp(gap)[1]))
            key = (FLOAT_CMP, site, int(gap > 0.0), exponent)
            counter = counters.get(key)
            if counter is None:
                counters[key] = features.counter(key) if features.enabled else -1
                sites.add(site)
                features.hit_ids((key,))
                if exponent < nearest.get(site, high + 2):  # only a new key can be nearer
                    nearest[site] = exponent
                    nearer.append(site)
            elif branch is not None:
                branch(counter)
            left -= 1
            if left <= 0 and swap:
                module._trace_cmp = guard  # the budget is spent: the guard until install()
            op = opid >> shift
            result = ops[op](obj1, obj2)
            if done is not None and site not in done:
                watch(site, obj1, obj2, result, op not in equality)  # type: ignore[misc]
            return result

        def get_left() -> int:
            return left

        def set_left(value: int) -> None:
            nonlocal left, branch
            left, branch = value, features.brancher()

        self.trace = trace
        self._left = get_left
        self._set_left = set_left


_OPS: tuple[Callable[[Any, Any], Any], ...] = (
    operator.lt,
    operator.le,
    operator.eq,
    operator.ne,
    operator.gt,
    operator.ge,
)
"""COMPARE_OP's operators in ``dis.cmp_op`` order."""
_EQUALITY: Final = frozenset({2, 3})
"""Indices of ``==`` and ``!=`` in ``_OPS``."""


def make_guard(
    inner: Callable[..., Any] | None, compared: ComparedValues | None = None
) -> Callable[..., Any]:
    """A ``_trace_cmp`` that passes the pairs Atheris traces to ``inner`` (its function) and
    compares the rest itself (a closure over locals: it runs for every comparison); with
    ``compared``, a comparison of two real numbers (one a float) at a site it still watches is
    shown to it (``ComparedValues.watch``)."""
    ops, traced, shift = _OPS, _ATHERIS_TRACES, _OPID_SHIFT

    def guard(obj1: Any, obj2: Any, opid: int, site: int, is_const: bool) -> Any:
        t1 = type(obj1)
        if t1 is type(obj2) and t1 in traced and inner is not None:
            return inner(obj1, obj2, opid, site, is_const)
        return ops[opid >> shift](obj1, obj2)

    if compared is None:
        return guard
    floats, numbers, done, watch, equality = _FLOATS, _NUMBERS, compared.done, compared.watch, _EQUALITY

    def watching(obj1: Any, obj2: Any, opid: int, site: int, is_const: bool) -> Any:
        t1, t2 = type(obj1), type(obj2)
        if t1 is t2 and t1 in traced and inner is not None:
            return inner(obj1, obj2, opid, site, is_const)
        result = ops[opid >> shift](obj1, obj2)
        if site not in done and ((t1 in floats and t2 in numbers) or (t2 in floats and t1 in numbers)):
            watch(site, obj1, obj2, result, opid >> shift not in equality)
        return result

    return watching
