"""Redqueen's input-to-state stage, spread over the campaign: new inputs get the ``compared`` mutator.

Redqueen (Aschermann et al., NDSS 2019) and AFL++'s CmpLog run their input-to-state stage on
every new queue entry: the operands that entry compared are tried in its bytes before the
havoc stage. Here the ``compared`` mutator (``seq_compared`` for scenarios) is one arm of the
mutator bandit among a dozen, applied to whatever parent libFuzzer picked. An input that first
reached a comparison (a tutorial script whose profile ratio passes 1) then waits for the one
draw in about a hundred that pairs it with that mutator, and a scaling step that works on it
once in twenty children (``benchmarks.probe_mutator``) is rarely tried on it within a minute.

:class:`I2SQueue` keeps, in arrival order, the inputs that gave new coverage and compared a
value at a still unsolved threshold site (``ComparedValues.operands_of``); with probability
:data:`SHARE` a mutation takes the queue's first input as its parent and the ``compared`` arm as
its mutator, :data:`ATTEMPTS` times per input. The queue holds at most :data:`CAPACITY` inputs
(later ones are not queued until there is room); libFuzzer's own schedule goes on for the rest.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from random import Random
from typing import Final

SHARE: Final = 0.25
"""Share of the mutations that go to the queue's first input (when the queue has one)."""
ATTEMPTS: Final = 8
"""Children made from each queued input with the ``compared`` arm."""
CAPACITY: Final = 4096
"""Inputs queued at most."""


@dataclass
class I2SQueue:
    """Inputs waiting for their input-to-state mutations.

    Attributes
    ----------
    arm : str
        The mutator applied to them (``compared``, or ``seq_compared`` for scenarios).
    """

    arm: str
    _queue: deque[bytes] = field(default_factory=deque)
    _left: int = ATTEMPTS
    """Attempts left for the queue's first input."""

    def offer(self, data: bytes) -> None:
        """Queue ``data`` (an input that gave new coverage and compared at an unsolved site)."""
        if len(self._queue) < CAPACITY:
            self._queue.append(data)

    def take(self, rng: Random) -> bytes | None:
        """The parent of the next mutation, with probability :data:`SHARE` when the queue has
        one (one of its attempts used), else None."""
        if not self._queue or rng.random() >= SHARE:
            return None
        data = self._queue[0]
        self._left -= 1
        if self._left <= 0:
            self._queue.popleft()
            self._left = ATTEMPTS
        return data

    def __len__(self) -> int:
        return len(self._queue)
