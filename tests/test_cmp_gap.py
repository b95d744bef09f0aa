"""Comparisons Atheris 3.0.0 leaves untraced, and the pass that traces them (``cmp_gap``)."""

from __future__ import annotations

import dis
import random
import types
from collections.abc import Callable, Iterator
from typing import Any

import atheris
import pytest
from atheris import instrument_bytecode

from fuzzer.selection import cmp_gap
from fuzzer.selection.compared import ComparedValues
from fuzzer.selection.floatcmp import FloatCompareTracer
from fuzzer.selection.guidance import Features
from fuzzer.selection.instrument_cache import instrument_functions


def band_in_condition(x: float) -> int:
    if 0.3 <= x < 0.31:
        return 1
    return 0


def seed_band(seed: list[float] | None) -> int:
    if seed is not None and len(seed) and 0.3 <= float(seed[0]) < 0.31:
        return 1
    return 0


def chain_of_four(a: float, b: float, c: float) -> int:
    if a < b <= c != 4 > 1.5:
        return 1
    return 0


def literals(x: bool) -> int:
    if 1 < 2 and x:
        return 1
    return 0


def band_per_element(values: list[float]) -> tuple[Any, ...]:
    """``wrap_past_pi``'s shape: a band tested per element inside a list comprehension, and the
    other comprehension kinds, one nested in another, and a lambda inside one."""
    wrapped = [v - 6.0 if 4.0 <= v < 4.05 else v for v in values if v != 7.0]
    above = sum(1 for v in values if v > 2.5)
    small = {k: k * 2 for k in values if k < 1.0}
    big = {v for v in values if v >= 9.0}
    nested = [[i for i in range(3) if i < v] for v in values]
    late = list(map(lambda t: [u for u in (t,) if u > 1.5], values))
    return wrapped, above, small, big, nested, late


def _copy(func: Callable[..., Any]) -> types.FunctionType:
    """A fresh function with ``func``'s original code (instrumenting changes it in place)."""
    return types.FunctionType(func.__code__, func.__globals__, func.__name__)


def _raw_comparisons(code: types.CodeType) -> int:
    return sum(1 for i in dis.get_instructions(code) if i.opname == "COMPARE_OP")


def _nested(code: types.CodeType) -> Iterator[types.CodeType]:
    """``code`` and every code object among its constants, recursively."""
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _nested(const)


def _comprehensions(code: types.CodeType) -> list[types.CodeType]:
    return [c for c in _nested(code) if c.co_name in ("<listcomp>", "<genexpr>", "<setcomp>", "<dictcomp>")]


@pytest.fixture
def table() -> Iterator[ComparedValues]:
    """A comparison table fed by the float tracer while the test runs (Atheris' own function
    put back after)."""
    values = ComparedValues()
    tracer = FloatCompareTracer(Features(enabled=False), compared=values)
    tracer.install(budget=0)
    try:
        yield values
    finally:
        atheris._trace_cmp = tracer.inner


@pytest.fixture
def traced() -> Iterator[list[tuple[Any, ...]]]:
    """Every call of ``atheris._trace_cmp`` while the test runs."""
    calls: list[tuple[Any, ...]] = []
    inner = atheris._trace_cmp

    def record(*args: Any) -> Any:
        calls.append(args)
        return inner(*args)

    atheris._trace_cmp = record
    try:
        yield calls
    finally:
        atheris._trace_cmp = inner


def test_atheris_alone_leaves_a_chained_conditions_second_comparison_untraced() -> None:
    """The upstream behaviour this module works around: its straight-line walk takes ``x`` for
    a constant after ``SWAP``/``COPY`` and a jump. If an Atheris upgrade traces it, this fails
    and ``cmp_gap`` can go."""
    cmp_gap.install(atheris)
    own = instrument_bytecode.Instrumentor.trace_data_flow
    original = getattr(own, "__wrapped__", own)
    for func, left in ((band_in_condition, 1), (seed_band, 1), (literals, 1)):
        inst = instrument_bytecode.Instrumentor(func.__code__)
        original(inst)
        assert sum(i.mnemonic == "COMPARE_OP" for i in inst.instructions) == left, func.__name__


def test_atheris_alone_leaves_comprehensions_uninstrumented(monkeypatch: pytest.MonkeyPatch) -> None:
    """Upstream's ``patch_code`` recurses only into nested functions and lambdas. If an Atheris
    upgrade instruments comprehensions itself, this fails and that part of ``cmp_gap`` can go."""
    cmp_gap.install(atheris)
    patch = instrument_bytecode.patch_code
    original = getattr(patch, "__wrapped__", patch)
    monkeypatch.setattr(instrument_bytecode, "patch_code", original)  # its recursion looks it up there
    code = original(_copy(band_per_element).__code__, True, True)
    comprehensions = _comprehensions(code)
    assert len(comprehensions) == 7
    assert sum(_raw_comparisons(c) for c in comprehensions) == 8


def test_comparisons_in_comprehensions_are_traced_without_edge_counters(
    traced: list[tuple[Any, ...]],
) -> None:
    values = [0.5, 4.01, 7.0, 9.5, 2.0, 4.06, 4.0, 4.05]
    expected = band_per_element(values)
    copy = _copy(band_per_element)
    instrument_functions([copy], atheris, None)
    assert sum(_raw_comparisons(c) for c in _nested(copy.__code__)) == 0
    traced.clear()
    assert copy(values) == expected
    assert len({call[3] for call in traced}) == 8
    comprehensions = _comprehensions(copy.__code__)
    assert sum("_trace_cmp" in c.co_names for c in comprehensions) == 6  # all but the one without
    assert not any("_trace_branch" in c.co_names for c in comprehensions)  # data flow only
    # the function itself and the lambda keep Atheris' edge counters
    assert "_trace_branch" in copy.__code__.co_names
    (lam,) = [c for c in _nested(copy.__code__) if c.co_name == "<lambda>"]
    assert "_trace_branch" in lam.co_names


def test_a_band_tested_inside_a_comprehension_becomes_two_thresholds(table: ComparedValues) -> None:
    """``wrap_past_pi``'s ``4.0 <= v < 4.05`` was invisible to the comparison table before."""
    copy = _copy(band_per_element)
    instrument_functions([copy], atheris, None)
    for v in (0.1, 3.0, 5.0, 6.2):
        copy([v])
    assert {4.0, 4.05} <= set(table.thresholds.values())
    assert 4.05 in table.unsolved()  # v < 4.05 only ever reached with v >= 4.05 or v < 4.0


def test_code_atheris_already_instrumented_is_left_as_it_is() -> None:
    copy = _copy(band_per_element)
    instrument_functions([copy], atheris, None)
    once = copy.__code__
    assert cmp_gap.with_comprehensions_traced(once, instrument_bytecode.patch_code) is once
    assert instrument_bytecode.patch_code(once, True, True) is once


@pytest.mark.parametrize(
    ("func", "inputs", "sites"),
    [
        (band_in_condition, [(0.305,), (0.2,), (0.5,), (0.31,), (0.3,)], 2),
        (seed_band, [([0.305],), ([0.2],), ([0.5],), (None,), ([],)], 2),
        (chain_of_four, [(1.0, 2.0, 3.0), (1.0, 2.0, 4.0), (3.0, 2.0, 1.0), (1.0, 2.0, 2.0)], 4),
    ],
)
def test_every_comparison_is_traced_and_every_result_kept(
    func: Callable[..., int], inputs: list[tuple[Any, ...]], sites: int, traced: list[tuple[Any, ...]]
) -> None:
    expected = [func(*args) for args in inputs]
    copy = _copy(func)
    instrument_functions([copy], atheris, None)
    assert _raw_comparisons(copy.__code__) == 0
    traced.clear()
    assert [copy(*args) for args in inputs] == expected
    assert len({call[3] for call in traced}) == sites  # each comparison its own site


def test_two_literals_stay_untraced() -> None:
    copy = _copy(literals)
    instrument_functions([copy], atheris, None)
    assert _raw_comparisons(copy.__code__) == 1
    assert [copy(True), copy(False)] == [1, 0]


def test_the_upper_edge_of_a_band_in_a_condition_becomes_a_threshold(table: ComparedValues) -> None:
    """Without the pass the table only ever learned 0.3 (the ``ik_seed_band`` zoo bug)."""
    copy = _copy(seed_band)
    instrument_functions([copy], atheris, None)
    for x in (0.0, 0.5, 1.0, 2.0, 3.0):  # one input each: 0.3 <= x crossed by four, solved
        table.begin()
        copy([x])
    assert sorted(table.thresholds.values()) == [0.3, 0.31]
    assert table.unsolved() == [0.31]  # x < 0.31 only ever reached with x >= 0.31
    assert table.crossing(2.0) == [0.31] and table.crossing(0.7) == []
    rng = random.Random(0)
    assert table.pick(rng) is not None


def test_install_is_idempotent_and_skips_a_stand_in() -> None:
    assert cmp_gap.install(atheris) and cmp_gap.install(atheris)
    for wrapped in (instrument_bytecode.Instrumentor.trace_data_flow, instrument_bytecode.patch_code):
        mark = "_rrosfuzz_traces_skipped_comparisons"
        assert getattr(wrapped, mark, False)
        assert not getattr(getattr(wrapped, "__wrapped__", None), mark, False)
    assert cmp_gap.install(types.SimpleNamespace()) is False
