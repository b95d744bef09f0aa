"""Boundary probes (issue 11): AFL's deterministic interesting-value stage on space-filling points."""

from __future__ import annotations

import math
import random

import pytest

from fuzzer.execution.session import RunConfig, Session
from fuzzer.generation.boundary import CONTINUOUS, OFFSETS, Boundary, probes
from fuzzer.generation.spacefill import SpaceFill, fresh_inputs
from fuzzer.selection.bandit import Bandit
from fuzzer.selection.state import BOUNDARY, MUTATE, SPACEFILL, Sources

INF = math.inf


def test_probes_go_round_by_round_over_every_joint_and_side() -> None:
    lower, upper = (-1.0, 0.0, -INF), (2.0, 0.5, INF)
    items = probes(lower, upper)
    per_round = 2 + 2 + 1  # two finite joints (both sides) and one continuous joint
    assert len(items) == per_round * len(OFFSETS)
    first = items[:per_round]
    assert first == [(0, 2.0 + 5e-5), (0, -1.0 - 5e-5), (1, 0.5 + 5e-5), (1, 0.0 - 5e-5), (2, math.pi)]
    second = items[per_round : 2 * per_round]
    assert [j for j, _ in second] == [0, 0, 1, 1, 2] and second[-1] == (2, -math.pi)
    assert second[0][1] == 2.0 + 1.5e-4 and second[3][1] == -1.5e-4
    # exactly on the limits in the third round; the continuous joint's values in CONTINUOUS order
    assert items[2 * per_round : 2 * per_round + 2] == [(0, 2.0), (0, -1.0)]
    assert [v for j, v in items if j == 2] == list(CONTINUOUS)


def test_a_joint_with_one_limit_gets_that_side_only() -> None:
    items = probes((0.0,), (INF,))
    assert items == [(0, -off) for off in OFFSETS]
    with pytest.raises(ValueError, match="same length"):
        probes((0.0,), (1.0, 2.0))


def test_boundary_hands_out_each_probe_once_from_its_start() -> None:
    b = Boundary((-1.0,), (1.0,), start=10)
    out = [b.apply((0.25,)) for _ in range(4)]
    assert out[:2] == [((1.0 + 1e-9,), True), ((-1.0 - 1e-9,), True)]
    assert out[2:] == [((0.25,), False), ((0.25,), False)]  # run out: values unchanged
    b = Boundary((-1.0, -2.0), (1.0, 2.0))
    assert b.apply((0.1, 0.2)) == ((1.0 + 5e-5, 0.2), True)
    assert b.apply((0.1, 0.2)) == ((-1.0 - 5e-5, 0.2), True)


def test_fresh_inputs_alternate_plain_points_and_probes_on_them() -> None:
    session = Session.open(RunConfig())
    facts = session.facts()
    boundary = Boundary(facts.lower, facts.upper, start=5)
    stream = SpaceFill(facts.lower, facts.upper, seed=4)
    plain = SpaceFill(facts.lower, facts.upper, seed=4)
    fresh = fresh_inputs(
        "move", "sensor_msgs/JointState", stream, facts.joint_names, facts.reachable, 16, boundary
    )
    base = session.registry.default("sensor_msgs/JointState")
    expected = probes(facts.lower, facts.upper)[5:]
    names, point = [], ()
    for i in range(2 * len(expected) + 3):
        made = fresh(base, random.Random(i))
        assert made is not None
        message, name = made
        names.append(name)
        if name == SPACEFILL:
            point = plain.next()  # a probe does not use up a point of the sequence
            assert message["position"] == list(point)
        else:
            j, value = expected[(i - 1) // 2]
            assert message["position"] == [value if k == j else v for k, v in enumerate(point)]
    assert names == [SPACEFILL, BOUNDARY] * len(expected) + [SPACEFILL] * 3
    assert stream.drawn == len(expected) + 3 and boundary.left == 0


def test_the_seeds_take_one_round() -> None:
    b = Boundary((-1.0, -INF), (1.0, INF), rounds=1)
    assert b.left == 3 and b.items == [(0, 1.0 + 5e-5), (0, -1.0 - 5e-5), (1, math.pi)]
    assert Boundary((-1.0,), (1.0,), rounds=0).left == 0


def test_a_boundary_input_credits_the_space_filling_arm() -> None:
    sources = Sources(Bandit((MUTATE, SPACEFILL)), Bandit(("zero",)), lambda m, r: None)
    sources.reward(BOUNDARY, True)
    sources.reward("zero", False)
    assert sources.source.arms[SPACEFILL].rewards == 1 and sources.source.arms[SPACEFILL].pulls == 1
    assert sources.source.arms[MUTATE].rewards == 0 and sources.mutators.arms["zero"].losses > 0
