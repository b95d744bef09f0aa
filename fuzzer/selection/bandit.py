"""A bandit over input sources and mutators, rewarded by new behaviour.

Each *arm* is a way to make the next input: mutating a corpus input (libFuzzer's parent or a
high-difference one), or a fresh space-filling sample or aligned configuration
(``fuzzer.generation.spacefill``). After the input runs, the harness tells the arm that made it whether
it paid off: a new coverage feature name or a new divergence signature in this process.
:class:`Bandit` is discounted Thompson sampling on Bernoulli rewards (a Beta posterior per
arm whose counts decay by ``DISCOUNT`` per update, so an arm that stops paying off is tried
less, and one that starts again is noticed): the standard choice for non-stationary rewards,
and fuzzers' (e.g. MOPT's and Thompson-sampling mutator schedulers') setting. Every draw
takes the caller's RNG, so a campaign with the same seeds makes the same choices.
"""

from __future__ import annotations

import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

DISCOUNT = 0.999
"""Per-update decay of every arm's counts (an effective memory of about 1,000 inputs)."""
PRIOR_LOSSES = 4.0
"""Pseudo-losses of every arm when a prior is given (so a weight of 1 starts at mean 2/7)."""
FLOOR = 0.02
"""Each arm is chosen at least this share of the time (uniformly), so none starves."""


@dataclass
class Arm:
    """One arm: its discounted pseudo-counts, and plain counts of the inputs credited to it
    (``pulls``) and of those that paid off (``rewards``). An input is credited to the arm that
    made it, which is not always the one chosen (a mutator that does not apply hands over to
    another), so both counts are kept where the reward arrives."""

    name: str
    wins: float = 0.0
    losses: float = 0.0
    pulls: int = 0
    rewards: int = 0

    def to_json(self) -> dict[str, Any]:
        return {"pulls": self.pulls, "rewards": self.rewards, "posterior_mean": self.mean}

    @property
    def mean(self) -> float:
        return (self.wins + 1.0) / (self.wins + self.losses + 2.0)


@dataclass
class Bandit:
    """Discounted Thompson sampling over named arms.

    Parameters
    ----------
    names : sequence of str
        The arms, e.g. ``("spacefill", "arithmetic", ...)``.
    prior : mapping of str to float, optional
        Pseudo-wins per arm at the start (e.g. the mutators' registry weights), against
        ``PRIOR_LOSSES`` pseudo-losses each; they fade with the discount like real counts.
    """

    names: Sequence[str]
    prior: Mapping[str, float] | None = None
    discount: float = DISCOUNT
    floor: float = FLOOR
    arms: dict[str, Arm] = field(init=False)

    def __post_init__(self) -> None:
        if not self.names or len(set(self.names)) != len(self.names):
            raise ValueError("a bandit needs distinct arm names")
        prior = self.prior or {}
        self.arms = {
            name: Arm(name, max(0.0, float(prior.get(name, 0.0))), PRIOR_LOSSES if prior else 0.0)
            for name in self.names
        }

    def choose(self, rng: random.Random) -> str:
        """The arm to pull next."""
        if rng.random() < self.floor:
            return rng.choice(list(self.names))
        arms = self.arms
        return max(self.names, key=lambda n: rng.betavariate(arms[n].wins + 1.0, arms[n].losses + 1.0))

    def reward(self, name: str, paid: bool) -> None:
        """Tell arm ``name`` whether its input paid off (unknown names are ignored)."""
        arm = self.arms.get(name)
        if arm is None:
            return
        for other in self.arms.values():
            other.wins *= self.discount
            other.losses *= self.discount
        arm.pulls += 1
        if paid:
            arm.wins += 1.0
            arm.rewards += 1
        else:
            arm.losses += 1.0

    def to_json(self) -> dict[str, Any]:
        return {name: arm.to_json() for name, arm in self.arms.items()}
