"""The input-to-state queue: new inputs that compared at an unsolved site get the compared arm."""

from __future__ import annotations

import random
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from fuzzer.input.testcase import decode
from fuzzer.selection import i2s
from fuzzer.selection.compared import SOLVED_AFTER, ComparedValues
from fuzzer.selection.floatcmp import FloatCompareTracer
from fuzzer.selection.i2s import I2SQueue
from tests.test_harness import make_harness


def test_the_queue_gives_each_input_its_attempts_in_arrival_order() -> None:
    queue = I2SQueue("compared")
    rng = random.Random(0)
    assert queue.take(rng) is None  # empty
    queue.offer(b"first", [5])
    queue.offer(b"second", [5])
    taken = [queue.take(rng) for _ in range(4000)]
    given = [t for t in taken if t is not None]
    assert given == [(b"first", 5)] * i2s.ATTEMPTS + [(b"second", 5)] * i2s.ATTEMPTS
    assert len(queue) == 0
    first_uses = [i for i, t in enumerate(taken) if t is not None]
    assert first_uses[-1] < 400  # about SHARE of the draws while it holds inputs


def test_the_sites_take_turns_so_a_rare_site_does_not_wait_behind_a_common_one() -> None:
    """Three inputs compared at a common site, then one at a rare site (a ratio past a profile
    switch): the rare one is second, not last, and an input waiting at two sites gets a stage
    for each, aimed at that site."""
    queue = I2SQueue("compared")
    rng = random.Random(2)
    for name in (b"common1", b"common2", b"common3"):
        queue.offer(name, [1])
    queue.offer(b"both", [1, 2])
    queue.offer(b"rare", [3])
    assert len(queue) == 6
    given = [t for t in (queue.take(rng) for _ in range(4000)) if t is not None]
    order = [given[i] for i in range(0, len(given), i2s.ATTEMPTS)]
    expected = [(b"common1", 1), (b"both", 2), (b"rare", 3), (b"common2", 1), (b"common3", 1), (b"both", 1)]
    assert order == expected
    assert len(given) == 6 * i2s.ATTEMPTS and len(queue) == 0


def test_a_site_solved_since_loses_its_inputs() -> None:
    solved: set[int] = set()
    queue = I2SQueue("compared", lambda site: site not in solved)
    rng = random.Random(3)
    queue.offer(b"a", [1])
    queue.offer(b"b", [1])
    queue.offer(b"c", [2])
    solved.add(1)
    given = [t for t in (queue.take(rng) for _ in range(4000)) if t is not None]
    assert given == [(b"c", 2)] * i2s.ATTEMPTS
    assert len(queue) == 0


def test_the_queue_takes_a_share_of_the_mutations() -> None:
    queue = I2SQueue("compared")
    rng = random.Random(1)
    for i in range(i2s.CAPACITY + 10):
        queue.offer(str(i).encode(), [i % 7])
    assert len(queue) == i2s.CAPACITY  # later ones wait for room
    share = sum(queue.take(rng) is not None for _ in range(4000)) / 4000
    assert share == pytest.approx(i2s.SHARE, abs=0.03)


def _harness_with_table(tmp_path: Path) -> tuple[Any, ComparedValues]:
    harness = make_harness(tmp_path)
    table = ComparedValues()
    harness.float_tracer = FloatCompareTracer(harness.features, SimpleNamespace(), compared=table)
    harness.context.compared = table  # as fuzzer.campaign wires them
    harness.i2s = I2SQueue("compared")
    return harness, table


def test_a_new_input_that_compared_at_an_unsolved_site_is_queued(tmp_path: Path) -> None:
    harness, table = _harness_with_table(tmp_path)
    table.watch(5, 0.9, 0.31, False)  # ``x < 0.31``, unsolved
    evaluate = harness.evaluator.evaluate

    def comparing(case: Any, **kw: Any) -> Any:
        table.watch(5, 0.7 + len(harness.i2s), 0.31, False)  # what a target compares while it runs
        return evaluate(case, **kw)

    harness.evaluator.evaluate = comparing  # type: ignore[method-assign]
    first = harness.seeds[0].encode()
    harness.test_one_input(first)  # new coverage (its first features) and an operand: queued
    assert len(harness.i2s) == 1
    harness.test_one_input(first)  # nothing new: not queued again
    assert len(harness.i2s) == 1
    for _ in range(SOLVED_AFTER):  # solved: no operand left
        table.begin()
        table.watch(5, 0.2, 0.31, True)
    harness.test_one_input(harness.seeds[1].encode())
    assert len(harness.i2s) == 1


def test_a_queued_input_is_mutated_with_the_compared_arm(tmp_path: Path) -> None:
    harness, table = _harness_with_table(tmp_path)
    table.watch(5, 0.9, 0.31, False)
    table.watch(5, 0.7, 0.31, False)
    queued = harness.seeds[2].child(harness.seeds[2].message, "queued")  # a lineage to tell its children by
    harness.i2s.offer(queued.encode(), [5])
    other = harness.seeds[0].encode()
    select, foci = table.select, []

    def selecting(key: bytes, focus: int | None = None) -> None:
        foci.append(focus)
        select(key, focus)

    table.select = selecting  # type: ignore[method-assign]
    children = [decode(harness.mutate(other, 4096, seed)) for seed in range(200)]
    assert foci.count(5) == i2s.ATTEMPTS and set(foci) == {None, 5}  # the stage's children aim at site 5
    staged = [c for c in children if c.lineage[:-1] == queued.lineage]
    assert all(c.lineage[-2:-1] != ("queued",) for c in children if c not in staged)
    assert len(staged) == i2s.ATTEMPTS and all(c.lineage[-1] == "compared" for c in staged)
    assert len(harness.i2s) == 0
