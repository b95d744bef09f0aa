"""Aligned configurations (fuzzer.generation.spacefill.Aligned): the ``aligned`` input source."""

from __future__ import annotations

import math
import random
from pathlib import Path

import numpy as np
import pytest

from fuzzer.execution.session import RunConfig, Session
from fuzzer.execution.tolerance import default_tolerance
from fuzzer.generation.spacefill import Aligned, SpaceFill, configuration_message, fresh_inputs
from fuzzer.input.testcase import TestCase, decode
from fuzzer.mutation import mutators
from fuzzer.selection.bandit import Bandit
from fuzzer.selection.state import ALIGNED, MUTATE, SPACEFILL, Sources
from tests.test_harness import make_harness

QUARTER = math.pi / 2


def test_each_joint_takes_a_multiple_of_a_quarter_turn_inside_its_limits_or_a_limit() -> None:
    lower, upper = [-3.2, -0.7, 0.0, -math.inf, -0.05], [3.2, 3.84, 0.0, math.inf, 0.05]
    stream = Aligned(lower, upper, seed=4)
    assert stream.choices[0] == (-3.2, -math.pi, -QUARTER, 0.0, QUARTER, math.pi, 3.2)
    assert stream.choices[1] == (-0.7, 0.0, QUARTER, math.pi, 3.84)
    assert stream.choices[2] == (0.0,)  # a fixed joint
    assert stream.choices[3] == (-math.pi, -QUARTER, 0.0, QUARTER, math.pi)  # continuous
    assert stream.choices[4] == (-0.05, 0.0, 0.05)  # a small (prismatic) range: 0 and the limits
    points = [stream.next() for _ in range(400)]
    assert stream.drawn == 400
    for j, values in enumerate(stream.choices):
        assert {p[j] for p in points} == set(values)  # every value comes, nothing else
    again = Aligned(lower, upper, seed=4)
    assert [again.next() for _ in range(400)] == points
    other = Aligned(lower, upper, seed=5)
    assert [other.next() for _ in range(400)] != points
    with pytest.raises(ValueError, match="same non-zero length"):
        Aligned([0.0], [1.0, 2.0])


def test_aligned_configurations_reach_a_gimbal_lock_that_space_filling_ones_miss() -> None:
    """The zoo's rpy_gimbal_band (a roll-pitch-yaw conversion that branches on a 1e-6 band
    around pitch +-pi/2): aligned configurations of the default arm often point the tip straight
    up or down; a Sobol point essentially never does."""
    config = RunConfig(
        op="fk", tolerance=default_tolerance("fk"), targets=("native", "benchmarks.zoo.bugs:rpy_gimbal_band")
    )
    session = Session.open(config)
    evaluator, facts = session.evaluator(), session.facts()
    base = session.registry.default(config.message_type)

    def divergent(stream: Aligned | SpaceFill) -> int:
        found = 0
        for _ in range(200):
            message = configuration_message(config.message_type, base, stream.next(), facts.joint_names)
            assert message is not None
            found += evaluator.evaluate(TestCase(config.message_type, message, 0, "t")).divergent
        return found

    assert divergent(Aligned(facts.lower, facts.upper, seed=0)) >= 5
    assert divergent(SpaceFill(facts.lower, facts.upper, seed=0)) == 0


def _forced_source(tmp_path: Path, arm: str) -> Sources:
    h = make_harness(tmp_path)
    facts = Session.open(RunConfig()).facts()
    joint_state = "sensor_msgs/JointState"
    fresh = fresh_inputs("move", joint_state, SpaceFill(facts.lower, facts.upper), facts.joint_names)
    stream = Aligned(facts.lower, facts.upper)
    aligned = fresh_inputs("move", joint_state, stream, facts.joint_names, name=ALIGNED)
    source = Bandit((MUTATE, SPACEFILL, ALIGNED), {arm: 1e9}, floor=0.0)
    h.sources = Sources(source, Bandit(tuple(mutators.WEIGHTS), mutators.WEIGHTS), fresh, aligned)
    children = []
    for s in range(30):  # each run as libFuzzer runs it, right after the step that made it
        made = h.mutate(h.seeds[0].encode(), 4096, s)
        children.append(decode(made))
        h.test_one_input(made)
    assert {c.strategy for c in children} == {arm}
    choices = Aligned(facts.lower, facts.upper).choices
    for child in children:
        values = child.message["position"]
        assert all(v in c for v, c in zip(values, choices, strict=True)) == (arm == ALIGNED)
    return h.sources


def test_the_source_bandit_makes_and_credits_aligned_inputs(tmp_path: Path) -> None:
    sources = _forced_source(tmp_path / "a", ALIGNED)
    arms = sources.source.arms
    assert arms[ALIGNED].pulls == 30 and arms[SPACEFILL].pulls == arms[MUTATE].pulls == 0
    assert arms[ALIGNED].rewards > 0  # new behaviour features early on
    spacefill = _forced_source(tmp_path / "b", SPACEFILL).source.arms
    assert spacefill[SPACEFILL].pulls == 30 and spacefill[ALIGNED].pulls == 0


def test_without_an_aligned_source_that_arm_mutates() -> None:
    made = Sources(Bandit((MUTATE, ALIGNED)), Bandit(("zero",)), lambda m, r: ({}, SPACEFILL))
    assert made.make(ALIGNED, {}, random.Random(0)) is None
    assert made.make(MUTATE, {}, random.Random(0)) is None
    assert made.make(SPACEFILL, {}, random.Random(0)) == ({}, SPACEFILL)


def test_wide_limits_give_a_bounded_stream_and_finite_samples() -> None:
    # a URDF's "unbounded" written as +-1e7 listed 13 million multiples per joint (1.4 GB), and
    # +-1e308 overflowed the span: every space-filling sample was inf
    from fuzzer.generation.spacefill import ALIGNED_TURNS, Uniform

    wide = Aligned([-1e7, -1e308, -1.0], [1e7, 1e308, 1.0], seed=3)
    assert len(wide.choices[0]) == len(wide.choices[1]) == 8 * ALIGNED_TURNS + 1 + 2
    assert wide.choices[0][0] == -1e7 and wide.choices[0][-1] == 1e7  # its limits stay among them
    assert wide.choices[2] == (-1.0, 0.0, 1.0)
    points = Uniform([-1e308, -1.0], [1e308, 1.0], seed=1).block(64)
    assert np.isfinite(points).all()
