"""What a campaign process keeps between inputs: its counters (``Stats``), the inputs of
highest difference (``Pool``, the paper's Algorithm 3) and the bandits over input sources and
mutators (``Sources``, issue 11). Used by ``fuzzer.harness``."""

from __future__ import annotations

import bisect
import random
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from fuzzer.selection.bandit import Bandit

if TYPE_CHECKING:
    from fuzzer.generation.walk import Walk
    from fuzzer.input.testcase import TestCase

POOL_SIZE = 64

SPACEFILL = "spacefill"
"""The arm (and lineage name) of a fresh space-filling input (``fuzzer.generation.spacefill``)."""

BOUNDARY = f"{SPACEFILL}:boundary"
"""The lineage name of a space-filling input carrying a boundary probe (``fuzzer.generation.boundary``);
the ``spacefill`` arm made it."""

UNIFORM = f"{SPACEFILL}:uniform"
"""The lineage name of a dry run's uniform random configuration (``corpus.uniform_cases``) or
script (``corpus.uniform_scripts``)."""

LITERAL = f"{SPACEFILL}:literal"
"""The lineage name of a dry run's configuration with a joint at a number a target compares
against (``corpus.literal_cases``)."""


ALIGNED = "aligned"
"""The arm (and lineage name) of a fresh aligned configuration: every joint at a multiple of
pi/2 or at a limit (``fuzzer.generation.spacefill.Aligned``), where joint axes line up."""

MUTATE = "mutate"
"""The arm of a mutated (or crossed-over) corpus input."""

WALK = "walk"
"""The arm (and lineage name) of an IK goal moved through joint space (``fuzzer.generation.walk``)."""

Made = tuple[dict[str, Any], str] | None
"""A fresh input's message and lineage name, or None (the source does not apply)."""
Maker = Callable[[dict[str, Any], random.Random], Made]
"""What makes a fresh input from a parent message (``Sources.fresh``, ``Sources.aligned``)."""


@dataclass
class Sources:
    """Where the next input comes from (issue 11), chosen by two bandits rewarded by new
    coverage features or new divergence signatures (``fuzzer.selection.bandit``): ``source``
    between a fresh space-filling input (``spacefill``: the next configuration of the Sobol
    stream put into the parent by ``fresh``), a fresh aligned configuration (``aligned``, by
    ``aligned``), for ``--op ik`` the parent's goal moved through joint space (``walk``, by
    ``walk``) and a mutated corpus input (``mutate``); then, for a mutation, ``mutators`` over
    the registered mutators by name.

    Attributes
    ----------
    source : Bandit
        Arms ``spacefill``, ``mutate`` and (with ``aligned``) ``aligned``; it also decides
        libFuzzer's crossovers.
    mutators : Bandit
        One arm per registered mutator.
    fresh : callable (message, rng) -> (message, lineage name) or None
        A copy of the parent carrying the next space-filling configuration, named ``spacefill``
        or ``spacefill:boundary`` (None: not applicable to this message; the harness then
        mutates).
    aligned : callable like ``fresh``, optional
        A copy of the parent carrying the next aligned configuration, named ``aligned``.
    walk : Walk, optional
        ``--op ik``: the parent with its goal moved through joint space, named ``walk`` (None
        when the parent's configuration is not known); it learns configurations from each run.
    """

    source: Bandit
    mutators: Bandit
    fresh: Maker
    aligned: Maker | None = None
    walk: Walk | None = None

    def make(self, arm: str, message: dict[str, Any], rng: random.Random) -> Made:
        """A fresh input from the source ``arm`` (None for ``mutate``, or when not applicable)."""
        if arm == SPACEFILL:
            return self.fresh(message, rng)
        if arm == ALIGNED and self.aligned is not None:
            return self.aligned(message, rng)
        if arm == WALK and self.walk is not None:
            return self.walk.make(message, rng)
        return None

    def parent(self, arm: str, case: TestCase, rng: random.Random) -> TestCase:
        """The parent source ``arm`` makes its input from: ``case`` (libFuzzer's), or for
        ``walk`` sometimes the input nearest a float comparison's flip."""
        return self.walk.parent(case, rng) if arm == WALK and self.walk is not None else case

    def learn(self, call: Any, outcomes: Any) -> None:
        """After an input ran: what its outcomes tell the sources (the walk's configurations)."""
        if self.walk is not None:
            self.walk.learn(call, outcomes)

    def offer(self, site: int, case: TestCase) -> None:
        """An input that came nearer the flip of float comparison ``site`` than any before
        (the walk's preferred parents)."""
        if self.walk is not None:
            self.walk.offer(site, case)

    def reward(self, strategy: str, paid: bool) -> None:
        """Credit the arms that made an input whose last step was ``strategy``."""
        source = strategy.partition(":")[0]
        if source in (SPACEFILL, ALIGNED, WALK):
            self.source.reward(source, paid)
            return
        self.source.reward(MUTATE, paid)
        self.mutators.reward(strategy.partition(":")[0], paid)

    def to_json(self) -> dict[str, Any]:
        return {"source": self.source.to_json(), "mutators": self.mutators.to_json()}


@dataclass
class Stats:
    """Counts of a campaign (one process)."""

    started: float = field(default_factory=time.monotonic)
    execs: int = 0
    filtered: int = 0
    malformed: int = 0
    divergent: Counter[str] = field(default_factory=Counter)
    by_strategy: Counter[str] = field(default_factory=Counter)
    executed_by_strategy: Counter[str] = field(default_factory=Counter)
    signatures: dict[str, str] = field(default_factory=dict)
    max_difference: float = 0.0
    """The largest headline difference of a value divergence (never a representation)."""
    max_difference_unit: str = ""
    """Its unit (m or rad); '' when no value divergence was seen."""
    near_zero: Counter[int] = field(default_factory=Counter)
    """Fig. 7: evaluated test cases by how many joint values are close to zero."""
    first_input: float | None = None
    """Wall-clock time (``time.time()``) the first test case was evaluated: what start-up cost
    (imports, seeds, instrumentation) ends at; ``benchmarks.bench_deep`` measures from it too."""

    def to_json(self) -> dict[str, Any]:
        return {
            "elapsed": self.elapsed,
            "execs": self.execs,
            "filtered": self.filtered,
            "malformed": self.malformed,
            "divergent": dict(self.divergent),
            "by_strategy": dict(self.by_strategy),
            "executed_by_strategy": dict(self.executed_by_strategy),
            "signatures": len(self.signatures),
            "max_difference": self.max_difference,
            "max_difference_unit": self.max_difference_unit,
            "near_zero": {str(k): v for k, v in sorted(self.near_zero.items())},
            "first_input": self.first_input,
        }

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self.started

    @property
    def divergences(self) -> int:
        return sum(self.divergent.values())


@dataclass
class Pool:
    """Candidate seeds sorted by difference priority (Algorithm 3)."""

    size: int = POOL_SIZE
    entries: list[tuple[float, bytes]] = field(default_factory=list)

    def offer(self, difference: float, data: bytes) -> None:
        if difference <= 0.0 or (len(self.entries) >= self.size and difference <= self.entries[0][0]):
            return
        bisect.insort(self.entries, (difference, data))
        del self.entries[: max(0, len(self.entries) - self.size)]

    def pick(self, rng: random.Random) -> bytes | None:
        """Higher difference, higher chance (rank-weighted)."""
        if not self.entries:
            return None
        weights = range(1, len(self.entries) + 1)
        return rng.choices(self.entries, weights=weights)[0][1]
