"""The targets' float comparison thresholds are learned while they run (``compared``)."""

from __future__ import annotations

import math
import random
import types

import atheris
import pytest

from fuzzer.selection import compared as cv
from fuzzer.selection.compared import ComparedValues
from fuzzer.selection.floatcmp import FloatCompareTracer
from fuzzer.selection.guidance import Features
from tests.test_floatcmp import _instrumented


def solve(table: ComparedValues, site: int, a: float, b: float, result: bool, key: bytes = b"solver") -> None:
    """``SOLVED_AFTER`` inputs (the last one ``key``) each compare ``a`` with ``b`` at ``site``."""
    for i in range(cv.SOLVED_AFTER):
        table.begin()
        table.watch(site, a, b, result)
        table.end(key if i == cv.SOLVED_AFTER - 1 else b"solver %d" % i)


def test_a_fixed_operand_against_a_varying_one_is_a_threshold() -> None:
    table = ComparedValues()
    table.watch(1, 0.5, 0.3, False)  # one observation: nothing known yet
    assert len(table) == 0 and table.pick(random.Random(0)) is None
    table.watch(1, 0.7, 0.3, False)
    assert table.thresholds == {1: 0.3} and table.unsolved() == [0.3]
    assert 1 not in table.done  # one outcome only: still watched
    solve(table, 1, 0.1, 0.3, True)  # the other branch, often enough: solved, no longer watched
    assert table.thresholds == {1: 0.3} and table.unsolved() == [] and 1 in table.done


def test_a_site_is_solved_once_enough_inputs_took_the_other_branch() -> None:
    """The first input into a band may not show what lies behind it (a ``/go`` into the band,
    then no ``/plan``): the site stays unsolved until ``SOLVED_AFTER`` inputs gave the outcome
    its first comparison did not, each counted once however often it compared there."""
    table = ComparedValues()
    for x in (0.9, 1.2):
        table.watch(3, x, 0.735, x < 0.735)
    for i in range(cv.SOLVED_AFTER - 1):
        table.begin()
        for x in (0.734, 0.7341, 0.7342):  # one input, three comparisons in the band
            table.watch(3, x, 0.735, x < 0.735)
        table.end(b"into the band %d" % i)
        assert table.unsolved() == [0.735] and 3 not in table.done
        assert table.crossings(0.9) == [(0.735, 0.0)]  # values on both sides: away from the leaf's
    assert table.operands_of(b"into the band 0") == [(0.735, 0.734, 1.0)]
    table.begin()
    table.watch(3, 0.2, 0.735, True)
    table.end(b"the last one")
    assert table.unsolved() == [] and 3 in table.done and table.crossings(0.9) == []


def test_inputs_that_cross_an_ordering_threshold_only_at_its_edge_do_not_solve_it() -> None:
    """``ik_seed_band``'s ``seed[0] < 0.31`` crossed by 0.30999999999999994 (the next float) or
    by 1e-6: the scenario oracle judges a divergence there ill-conditioned (a nudge of the state
    carries it out of the band), so such inputs show nothing behind the branch and the site
    stays unsolved until inputs clear of the edge (``EDGE``) take it."""
    table = ComparedValues()
    for x in (0.9, 1.2):
        table.watch(6, x, 0.31, x < 0.31)
    edge = (math.nextafter(0.31, 0.0), 0.31 - 1e-6, 0.31 - 0.5 * cv.EDGE)
    for i in range(2 * cv.SOLVED_AFTER):
        table.begin()
        x = edge[i % len(edge)]
        table.watch(6, x, 0.31, x < 0.31)
        table.end(b"at the edge %d" % i)
    assert table.unsolved() == [0.31] and 6 not in table.done
    for i in range(cv.SOLVED_AFTER):
        table.begin()
        table.watch(6, 0.305, 0.31, True)
        table.end(b"inside %d" % i)
    assert table.unsolved() == [] and 6 in table.done


def test_past_an_edge_the_way_still_leads_deeper_into_the_new_side() -> None:
    """Values within ``EDGE`` of the threshold count on neither side: after crossings by a float,
    input-to-state still writes values past ``x < 0.31`` going down, from the edge value too
    (before, it went up from there, back out of the band), and the scaled crossing of an input
    that compared the edge value goes down too."""
    table = ComparedValues()
    at_edge = math.nextafter(0.31, 0.0)
    for x in (0.9, 1.2):
        table.watch(6, x, 0.31, x < 0.31)
    table.begin()
    table.watch(6, at_edge, 0.31, True)
    table.end(b"at the edge")
    assert table.crossings(0.9) == [(0.31, -1.0)]
    assert table.crossings(at_edge) == [(0.31, -1.0)]
    table.select(b"at the edge")
    assert table.operands() == [(0.31, at_edge, -1.0)]
    table.begin()
    table.watch(6, 0.305, 0.31, True)  # clear of the edge: both sides seen
    table.end(b"inside")
    assert table.crossings(0.9) == [(0.31, 0.0)]
    table.select(b"inside")
    assert table.operands() == [(0.31, 0.305, 1.0)]


def test_an_equality_is_solved_by_inputs_on_its_threshold() -> None:
    """``==`` and ``!=`` give their other outcome only on the threshold: no edge to clear."""
    table = ComparedValues()
    for x in (0.9, 1.2):
        table.watch(7, x, 0.25, x == 0.25, ordered=False)
    for i in range(cv.SOLVED_AFTER):
        table.begin()
        table.watch(7, 0.25, 0.25, True, ordered=False)
        table.end(b"equal %d" % i)
    assert table.unsolved() == [] and 7 in table.done


def test_the_guard_tells_orderings_from_equalities() -> None:
    module = _instrumented()
    table = ComparedValues()
    tracer = FloatCompareTracer(Features(enabled=False), compared=table)
    tracer.install(budget=0)
    try:
        for x in (0.0, 0.5, 1.0, 0.6, 0.7):  # 0.3 <= x solved; x < 0.31 reached with x >= 0.31
            table.begin()
            module.band(x)
            module.exactly(x)
        for _ in range(cv.SOLVED_AFTER):
            table.begin()
            assert module.band(math.nextafter(0.31, 0.0)) is True  # at the edge: no count
            assert module.exactly(0.25) is True  # an equality's other outcome: counts
        assert table.unsolved() == [0.31]
    finally:
        atheris._trace_cmp = tracer.inner


def test_two_varying_operands_or_none_make_no_threshold() -> None:
    table = ComparedValues()
    for x in (0.1, 0.2):
        table.watch(2, x, 2 * x, True)
    assert len(table) == 0 and 2 in table.done
    for _ in range(cv.PATIENCE):
        table.watch(3, 1.5, 2.5, True)  # the input never reaches it: nothing to learn
    assert len(table) == 0 and 3 in table.done


def test_a_non_finite_fixed_operand_is_no_threshold() -> None:
    table = ComparedValues()
    for x in (0.1, 0.2):
        table.watch(4, x, float("inf"), True)
    assert len(table) == 0


def test_pick_prefers_the_unsolved_sites() -> None:
    table = ComparedValues()
    for x in (0.0, 1.0):
        table.watch(1, x, 0.5, x < 0.5)
        table.watch(2, x, 4.05, x < 4.05)  # unsolved
    solve(table, 1, 0.7, 0.5, False)  # solved
    rng = random.Random(5)
    picks = [table.pick(rng) for _ in range(4000)]
    share = picks.count(4.05) / len(picks)
    expected = cv.UNSOLVED_PROBABILITY + (1 - cv.UNSOLVED_PROBABILITY) / 2
    assert set(picks) == {0.5, 4.05} and abs(share - expected) < 0.03


def test_the_guard_learns_a_chained_comparison_past_the_budget() -> None:
    module = _instrumented()
    table = ComparedValues()
    tracer = FloatCompareTracer(Features(enabled=False), compared=table)
    tracer.install(budget=0)  # the guard alone, as after an input's first comparisons
    try:
        for x in (0.0, 0.5, 1.0, 0.6, 0.7):  # 0.3 <= x crossed by four inputs: solved
            table.begin()
            assert module.band(x) is False
        assert tracer.traced == 0  # no feature: the guard only
        assert sorted(table.thresholds.values()) == [0.3, 0.31]
        assert table.unsolved() == [0.31]  # x < 0.31 was only ever reached with x >= 0.31
        for _ in range(cv.SOLVED_AFTER):
            table.begin()
            assert module.band(0.305) is True
        assert table.unsolved() == []
    finally:
        atheris._trace_cmp = tracer.inner


def test_the_baselines_guard_watches_nothing() -> None:
    calls: list[object] = []
    fake = types.SimpleNamespace(_trace_cmp=lambda *args: calls.append(args))
    tracer = FloatCompareTracer(Features(enabled=False), fake, budget=0)
    tracer.install()
    assert tracer.compared is None
    assert fake._trace_cmp(0.5, 0.3, 0, 1, False) is False and calls == []


@pytest.mark.parametrize("operand", [[0.1, 0.2], "text", None])
def test_the_guard_shows_only_real_numbers(operand: object) -> None:
    table = ComparedValues()
    fake = types.SimpleNamespace(_trace_cmp=lambda *args: False)
    tracer = FloatCompareTracer(Features(enabled=False), fake, budget=0, compared=table)
    tracer.install()
    for x in (0.1, 0.2):
        fake._trace_cmp(x, operand, 2, 9, False)  # ==: defined for any pair
    assert len(table) == 0 and 9 not in table.done


def test_an_unsolved_site_names_the_values_its_varying_operand_took() -> None:
    table = ComparedValues()
    for x in (0.5, 1.2, 2.0):
        table.watch(7, x, 0.31, x < 0.31)  # x < 0.31 never true: unsolved
    assert table.crossing(0.5) == [0.31]  # the first value counts too
    assert table.crossing(2.0) == [0.31] and table.crossing(0.7) == []
    table.watch(8, 0.0, 4.05, True)
    table.watch(8, 1.0, 4.05, True)
    assert table.crossing(1.0) == [4.05] and table.crossing(0.0) == []  # 0.0 matches by coincidence
    solve(table, 7, 0.305, 0.31, True)  # solved: nothing left to cross
    assert table.crossing(2.0) == [] and 7 in table.done


def test_the_way_to_cross_is_the_side_the_site_never_compared_a_value_on() -> None:
    """``x < 0.735`` seen false with x = 1.5 and with x = 0.735 itself: from 0.735 the branch
    not taken lies below, which the value alone cannot tell (a campaign that wrote the threshold
    into a leaf then only ever wrote values above it)."""
    table = ComparedValues()
    for x in (1.5, 0.735):
        table.watch(4, x, 0.735, x < 0.735)
    assert table.crossings(0.735) == [(0.735, -1.0)] and table.crossings(1.5) == [(0.735, -1.0)]
    for x in (0.2, 0.3):
        table.watch(5, 0.6, x, x >= 0.6)  # never true: the values lie below, cross up
    assert table.crossings(0.3) == [(0.6, 1.0)]
    table.watch(6, 1.0, 2.0, False)
    table.watch(6, 2.0, 2.0, False)  # x > 2.0, false at 1.0 and at 2.0: up from 2.0
    assert table.crossings(2.0) == [(2.0, 1.0)]
    table.watch(7, 1.0, 9.5, True)
    table.watch(7, 12.0, 9.5, True)  # x != 9.5 on both sides: no side to prefer
    assert table.crossings(12.0) == [(9.5, 0.0)]


def test_each_input_s_own_compared_values_are_remembered_for_when_it_is_mutated() -> None:
    """``ratio < 1.001`` seen false with ratios 2.0 (input b"a") and 3.0 (b"b"), computed from
    the input, held by no leaf: mutating b"a" gives (1.001, 2.0, down), b"b" (1.001, 3.0, down)."""
    table = ComparedValues()
    table.watch(9, 4.0, 1.001, False)  # a site's first comparison only opens its record
    for key, ratio in ((b"a", 2.0), (b"b", 3.0), (b"c", 2.5)):
        table.begin()
        table.watch(9, ratio, 1.001, False)
        table.watch(9, ratio * 7, 1.001, False)  # only the first value of an input is its own
        table.end(key)
    table.select(b"a")
    assert table.operands() == [(1.001, 2.0, -1.0)]
    table.select(b"b")
    assert table.operands() == [(1.001, 3.0, -1.0)]
    table.select(b"unknown")
    assert table.operands() == []
    solve(table, 9, 1.0005, 1.001, True, b"d")  # solved: nothing left to cross
    table.select(b"a")
    assert table.operands() == []


def test_the_first_input_to_reach_a_site_has_its_operand_there_too() -> None:
    """The seed that first makes a ratio pass 1 is the first to compare it with 1.001: the
    site's threshold is known only when a second input compares another ratio there, and the
    first input's own value must still be remembered for it (it was not, before 2026-11-27)."""
    table = ComparedValues()
    for key, ratio in ((b"first", 6.2), (b"second", 6.2), (b"third", 1.7)):
        table.begin()
        table.watch(9, ratio, 1.001, False)
        table.end(key)
    for key, ratio in ((b"first", 6.2), (b"second", 6.2), (b"third", 1.7)):
        table.select(key)
        assert table.operands() == [(1.001, ratio, -1.0)], key
    solve(table, 9, 1.0005, 1.001, True, b"fourth")  # solved: no operand left, and nothing kept for it
    table.select(b"first")
    assert table.operands() == []
    table.select(b"fourth")
    assert table.operands() == []


def test_the_memory_keeps_the_newest_inputs() -> None:
    table = ComparedValues()
    table.watch(1, 5.0, 0.5, False)
    for i in range(cv.MEMORY + 1):
        table.begin()
        table.watch(1, 6.0 + i, 0.5, False)
        table.end(str(i).encode())
    table.select(b"0")
    assert table.operands() == []  # the oldest went
    table.select(b"1")
    assert table.operands() == [(0.5, 7.0, -1.0)]


def test_a_site_remembers_only_its_newest_operand_values() -> None:
    table = ComparedValues()
    values = [1.0 + i for i in range(cv.RECENT + 2)]
    for x in values:
        table.watch(3, x, 0.5, False)
    assert table.crossing(values[0]) == [] and table.crossing(values[1]) == []
    assert table.crossing(values[2]) == [0.5] and table.crossing(values[-1]) == [0.5]


def test_a_value_of_0_is_no_operand() -> None:
    """A leaf at its default 0 compared at an unsolved site: no factor scales 0 past the
    threshold, so the input has no operand there, and the input-to-state stage does not queue it
    for that site (two 10-trial runs per arm, docs/benchmarks-log.md: ``plan_start_band`` 10/20 -> 15/20
    one-minute trials, p = 0.015)."""
    table = ComparedValues()
    table.watch(4, 3.0, 0.25, False)
    for key, value in ((b"zero", 0.0), (b"other", 0.5)):
        table.begin()
        table.watch(4, value, 0.25, False)
        table.end(key)
    assert table.operands_of(b"zero") == []
    assert table.operands_of(b"other") == [(0.25, 0.5, -1.0)]


def test_a_focus_aims_a_mutation_at_one_site() -> None:
    """The input-to-state stage hands an input over with the site it waits at: operands,
    crossings and picks then name that site alone, until the next selection."""
    table = ComparedValues()
    for i, x in enumerate((0.6, 1.3)):  # two inputs, each comparing x at two unsolved sites
        table.begin()
        table.watch(1, x, 0.31, x < 0.31)  # ``x < 0.31``
        table.watch(2, 2 * x, 1.001, 2 * x < 1.001)  # ``ratio < 1.001``, the ratio computed from x
        table.end(b"input %d" % i)
    assert table.sites_of(b"input 1") == [1, 2]
    table.select(b"input 1")
    assert table.operands() == [(0.31, 1.3, -1.0), (1.001, 2.6, -1.0)]
    assert [t for t, _ in table.crossings(1.3)] == [0.31] and [t for t, _ in table.crossings(2.6)] == [1.001]
    table.select(b"input 1", focus=2)
    assert table.operands() == [(1.001, 2.6, -1.0)]
    assert table.crossings(1.3) == [] and [t for t, _ in table.crossings(2.6)] == [1.001]
    assert {table.pick(random.Random(s)) for s in range(50)} == {1.001}
    assert table.operands_of(b"input 1") == [(0.31, 1.3, -1.0), (1.001, 2.6, -1.0)]  # whatever the focus
    table.select(b"input 0")  # the next selection has none
    assert table.operands() == [(0.31, 0.6, -1.0), (1.001, 1.2, -1.0)]
    solve(table, 2, 1.0005, 1.001, True)
    assert not table.is_unsolved(2) and table.is_unsolved(1) and not table.is_unsolved(99)
    table.select(b"input 1", focus=2)  # solved since: picks go back to the unsolved sites
    assert table.operands() == [] and {table.pick(random.Random(s)) for s in range(50)} <= {0.31, 1.001}
