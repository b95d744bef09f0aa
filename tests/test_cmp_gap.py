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


def _copy(func: Callable[..., Any]) -> types.FunctionType:
    """A fresh function with ``func``'s original code (instrumenting changes it in place)."""
    return types.FunctionType(func.__code__, func.__globals__, func.__name__)


def _raw_comparisons(code: types.CodeType) -> int:
    return sum(1 for i in dis.get_instructions(code) if i.opname == "COMPARE_OP")


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


def test_the_upper_edge_of_a_band_in_a_condition_becomes_a_threshold() -> None:
    """Without the pass the table only ever learned 0.3 (the ``ik_seed_band`` zoo bug)."""
    copy = _copy(seed_band)
    instrument_functions([copy], atheris, None)
    table = ComparedValues()
    tracer = FloatCompareTracer(Features(enabled=False), compared=table)
    tracer.install(budget=0)
    try:
        for x in (0.0, 0.5, 1.0, 2.0):
            copy([x])
        assert sorted(table.thresholds.values()) == [0.3, 0.31]
        assert table.unsolved() == [0.31]  # x < 0.31 only ever reached with x >= 0.31
        assert table.crossing(2.0) == [0.31] and table.crossing(0.7) == []
        rng = random.Random(0)
        assert table.pick(rng) is not None
    finally:
        atheris._trace_cmp = tracer.inner


def test_install_is_idempotent_and_skips_a_stand_in() -> None:
    assert cmp_gap.install(atheris) and cmp_gap.install(atheris)
    wrapped = instrument_bytecode.Instrumentor.trace_data_flow
    assert not getattr(getattr(wrapped, "__wrapped__", None), "_rrosfuzz_traces_skipped_comparisons", False)
    assert cmp_gap.install(types.SimpleNamespace()) is False
