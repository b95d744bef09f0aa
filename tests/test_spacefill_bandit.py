"""Space-filling inputs (fuzzer.generation.spacefill) and the source bandit (fuzzer.selection.bandit)."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from fuzzer.generation.spacefill import SpaceFill, configuration_message
from fuzzer.selection.bandit import Bandit

LOWER = (-2.9, -1.5, 0.0, float("-inf"))
UPPER = (2.9, 1.2, 0.35, float("inf"))


def test_same_seed_same_stream_other_seed_other_stream() -> None:
    a, b, c = (
        SpaceFill(LOWER, UPPER, seed=7),
        SpaceFill(LOWER, UPPER, seed=7),
        SpaceFill(LOWER, UPPER, seed=8),
    )
    first = [a.next() for _ in range(300)]
    assert first == [b.next() for _ in range(300)]
    assert first != [c.next() for _ in range(300)]
    assert a.drawn == 300


def test_points_inside_the_limits_continuous_joints_in_pi_box() -> None:
    s = SpaceFill(LOWER, UPPER, seed=1)
    pts = np.array([s.next() for _ in range(2048)])
    lo = np.array([-2.9, -1.5, 0.0, -math.pi])
    hi = np.array([2.9, 1.2, 0.35, math.pi])
    assert np.all(pts >= lo) and np.all(pts <= hi)


def test_every_joint_range_is_stratified() -> None:
    """The first 256 points put exactly one point in each 1/256 slice of every joint's range
    (a property of scrambled Sobol nets; uniform random sampling leaves about 37% of the slices
    empty)."""
    s = SpaceFill(LOWER, UPPER, seed=3)
    pts = np.array([s.next() for _ in range(256)])
    lo = np.array([-2.9, -1.5, 0.0, -math.pi])
    hi = np.array([2.9, 1.2, 0.35, math.pi])
    bins = np.floor((pts - lo) / (hi - lo) * 256).astype(int)
    for j in range(len(LOWER)):
        assert sorted(bins[:, j]) == list(range(256))


def test_a_narrow_band_away_from_round_values_is_visited() -> None:
    """A band 0.1% wide of one joint's range is hit at least 3 times in 4096 points (4.1 expected)."""
    s = SpaceFill(LOWER, UPPER, seed=11)
    start = -2.9 + 0.6173 * 5.8
    width = 0.001 * 5.8
    hits = sum(start <= s.next()[0] < start + width for _ in range(4096))
    assert hits >= 3


def test_fixed_joint_and_bad_limits() -> None:
    s = SpaceFill((0.5, -1.0), (0.5, 1.0), seed=0)
    assert all(s.next()[0] == 0.5 for _ in range(10))
    with pytest.raises(ValueError, match="same non-zero length"):
        SpaceFill((), ())
    with pytest.raises(ValueError, match="same non-zero length"):
        SpaceFill((0.0,), (1.0, 2.0))


def test_configuration_messages() -> None:
    js = {"header": {"frame_id": ""}, "name": ["x"], "position": [0.0], "velocity": [], "effort": []}
    out = configuration_message("sensor_msgs/JointState", js, (0.1, 0.2), ("j1", "j2"))
    assert out is not None and out["position"] == [0.1, 0.2] and out["name"] == ["j1", "j2"]
    assert js["position"] == [0.0]  # the base is not modified
    arr = configuration_message("std_msgs/Float64MultiArray", {"layout": {}, "data": []}, (0.3,), ("j1",))
    assert arr is not None and arr["data"] == [0.3]

    def fk(q: tuple[float, ...]) -> tuple[tuple[float, ...], tuple[float, ...]]:
        return (q[0], 0.0, 1.0), (0.0, 0.0, 0.0, 1.0)

    stamped = {"header": {"frame_id": ""}, "pose": {}}
    pose = configuration_message("geometry_msgs/PoseStamped", stamped, (0.25,), ("j1",), fk)
    assert pose is not None and pose["pose"]["position"] == {"x": 0.25, "y": 0.0, "z": 1.0}
    assert configuration_message("geometry_msgs/PoseStamped", stamped, (0.25,), ("j1",)) is None
    assert configuration_message("std_msgs/String", {"data": ""}, (0.25,), ("j1",)) is None


def test_bandit_prefers_the_arm_that_pays_and_never_starves_one() -> None:
    rng = random.Random(5)
    bandit = Bandit(("mutate", "spacefill"))
    for _ in range(3000):
        arm = bandit.choose(rng)
        chance = 0.5 if arm == "spacefill" else 0.05
        bandit.reward(arm, paid=rng.random() < chance)
    arms = bandit.arms
    assert arms["spacefill"].pulls > 4 * arms["mutate"].pulls
    assert arms["mutate"].pulls >= 20  # the floor keeps trying it
    assert set(bandit.to_json()) == {"mutate", "spacefill"}


def test_bandit_follows_a_change_of_payoff() -> None:
    rng = random.Random(9)
    bandit = Bandit(("a", "b"))
    for step in range(6000):
        arm = bandit.choose(rng)
        good = "a" if step < 3000 else "b"
        bandit.reward(arm, paid=arm == good and rng.random() < 0.3)
    picks = [bandit.choose(random.Random(i)) for i in range(200)]
    assert picks.count("b") > 150


def test_bandit_is_deterministic_and_checks_names() -> None:
    def run(seed: int) -> list[str]:
        rng, bandit, out = random.Random(seed), Bandit(("x", "y", "z")), []
        for _ in range(200):
            arm = bandit.choose(rng)
            bandit.reward(arm, paid=arm == "y")
            out.append(arm)
        return out

    assert run(1) == run(1)
    with pytest.raises(ValueError, match="distinct"):
        Bandit(("a", "a"))
    with pytest.raises(ValueError, match="distinct"):
        Bandit(())
    Bandit(("a",)).reward("unknown", True)  # ignored
