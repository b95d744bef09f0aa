"""Redqueen's input-to-state stage, spread over the campaign: new inputs get the ``compared`` mutator.

Redqueen (Aschermann et al., NDSS 2019) and AFL++'s CmpLog run their input-to-state stage on
every new queue entry: the operands that entry compared are tried in its bytes before the
havoc stage. Here the ``compared`` mutator (``seq_compared`` for scenarios) is one arm of the
mutator bandit among a dozen, applied to whatever parent libFuzzer picked. An input that first
reached a comparison (a tutorial script whose profile ratio passes 1) then waits for the one
draw in about a hundred that pairs it with that mutator, and a scaling step that works on it
once in twenty children (``benchmarks.probe_mutator``) is rarely tried on it within a minute.

:class:`I2SQueue` keeps, per unsolved threshold site and in arrival order, the inputs that gave
new coverage and compared a value at that site (``ComparedValues.sites_of``); with probability
:data:`SHARE` a mutation takes the first input of the site whose turn it is as its parent, the
``compared`` arm as its mutator, and that site as its aim (``ComparedValues.select``'s focus),
:data:`ATTEMPTS` times per input; then the next site has its turn. One queue in arrival order
(until 2026-11-28) was flooded: a one-minute scenario campaign offered it about 300 inputs and
it served about 40, so the first input to reach a rare site (``profile_switch_band``'s
``ratio < 1.001``, reached only past the profile switch) waited behind hundreds that compared
at common ones, and its children aimed at whichever of its sites a draw picked. The sites take
turns, so a rare one waits for one input per other site, not for every input before it. At
most :data:`CAPACITY` inputs wait in all (later ones are not queued until there is room);
libFuzzer's own schedule goes on for the rest.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from random import Random
from typing import Final

SHARE: Final = 0.25
"""Share of the mutations that go to the queue's first input (when the queue has one)."""
ATTEMPTS: Final = 8
"""Children made from each queued input with the ``compared`` arm, for each site it waits at."""
CAPACITY: Final = 4096
"""Inputs queued at most, summed over the sites (an input waiting at two sites counts twice)."""


@dataclass
class I2SQueue:
    """Inputs waiting for their input-to-state mutations, per comparison site.

    Attributes
    ----------
    arm : str
        The mutator applied to them (``compared``, or ``seq_compared`` for scenarios).
    live : callable
        Whether a site still wants its inputs (``ComparedValues.is_unsolved``): a site solved
        since loses them when its turn comes.
    """

    arm: str
    live: Callable[[int], bool] = field(default=lambda site: True)
    _waiting: dict[int, deque[bytes]] = field(default_factory=dict)
    """Site -> the inputs waiting at it, in arrival order."""
    _turns: deque[int] = field(default_factory=deque)
    """The sites with inputs waiting, the one whose turn it is first."""
    _size: int = 0
    _left: int = ATTEMPTS
    """Attempts left for the first input of the first site."""

    def offer(self, data: bytes, sites: Iterable[int]) -> None:
        """Queue ``data`` (an input that gave new coverage) at each of ``sites`` (the unsolved
        sites it compared a value at)."""
        for site in sites:
            if self._size >= CAPACITY:
                return
            waiting = self._waiting.get(site)
            if waiting is None:
                waiting = self._waiting[site] = deque()
                self._turns.append(site)
            waiting.append(data)
            self._size += 1

    def take(self, rng: Random) -> tuple[bytes, int] | None:
        """The parent of the next mutation and the site it aims at, with probability
        :data:`SHARE` when an input waits (one of its attempts used), else None."""
        if not self._turns or rng.random() >= SHARE:
            return None
        while not self.live(self._turns[0]):
            self._size -= len(self._waiting.pop(self._turns.popleft()))
            self._left = ATTEMPTS
            if not self._turns:
                return None
        site = self._turns[0]
        waiting = self._waiting[site]
        data = waiting[0]
        self._left -= 1
        if self._left <= 0:  # the next site's turn
            waiting.popleft()
            self._size -= 1
            self._left = ATTEMPTS
            self._turns.popleft()
            if waiting:
                self._turns.append(site)
            else:
                del self._waiting[site]
        return data, site

    def __len__(self) -> int:
        return self._size
