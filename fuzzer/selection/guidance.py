"""Divergence-guided fuzzing: outcome classes as libFuzzer coverage features.

Edge coverage barely moves in branch-free kinematics, so the harness also tells
libFuzzer about *behaviour*. Each feature is a named event: an outcome pair, a
divergence kind with its field and log-magnitude bucket (NEZHA's
delta-diversity), and, in input space, how close each joint value sits to its
limits and to multiples of pi; for scenarios, each pair of consecutive steps
as (step kind, step status label) bigrams. A feature maps (by CRC-32, stable across
processes) onto one of ``COUNTERS`` 8-bit counters reserved from Atheris before
fuzzing starts. An input that bumps a counter libFuzzer has not seen (or in a
new hit-count bucket) counts as new coverage and joins the corpus.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Callable, Iterable, Sequence

COUNTERS = 4096


class Features:
    """A block of Atheris counters addressed by feature name.

    Must be created before ``atheris.Fuzz()``: counters reserved then are
    registered with libFuzzer when fuzzing starts. Atheris' pre-Fuzz
    ``_reserve_counter`` returns ``1..N`` while the counters it registers are
    ``0..N-1``, hence the ``- 1``.
    """

    def __init__(self, count: int = COUNTERS, enabled: bool = True) -> None:
        self.count = count
        self.enabled = enabled
        self.seen: set[str] = set()
        self._ids: list[int] = []
        if enabled:
            import atheris

            self._atheris = atheris
            self._ids = [atheris._reserve_counter() - 1 for _ in range(count)]

    def hit(self, name: str) -> None:
        """Record feature ``name`` for the current input."""
        self.seen.add(name)
        if self.enabled:
            # look the function up at call time: Fuzz() swaps in the real one
            self._atheris._trace_branch(self._ids[zlib.crc32(name.encode()) % self.count])

    def counter(self, key: tuple[int, ...]) -> int:
        """The counter of a feature named by an integer tuple (the one :meth:`hit_ids` bumps)."""
        return self._ids[hash(key) % self.count]

    def brancher(self) -> Callable[[int], None] | None:
        """The function that bumps a counter (Atheris' ``_trace_branch`` as it is now: ``Fuzz()``
        swaps the real one in, so ask again per input), or None with the features disabled. The
        hot path of float-comparison tracing bumps a feature it has recorded with it."""
        return self._atheris._trace_branch if self.enabled else None

    def hit_ids(self, keys: Iterable[tuple[int, ...]]) -> None:
        """Record features named by integer tuples (cheaper than strings; ``hash`` of an int
        tuple is the same in every process, unlike the hash of a str)."""
        for key in keys:
            self.seen.add(str(key))
            if self.enabled:
                self._atheris._trace_branch(self._ids[hash(key) % self.count])


def _decade(x: float) -> int:
    if x <= 0.0:
        return -99
    return max(-12, min(1, math.floor(math.log10(x))))


INPUT, NONFINITE, INSIDE, OUTSIDE, NEAR_PI = 7, 0, 1, 2, 3


def input_features(
    values: Iterable[float], lower: tuple[float, ...], upper: tuple[float, ...]
) -> list[tuple[int, ...]]:
    """Where each joint value sits: decade of its distance to the nearest limit
    (inside or outside the limits) and to the nearest multiple of pi."""
    out: list[tuple[int, ...]] = []
    for j, v in enumerate(values):
        if not math.isfinite(v):
            out.append((INPUT, j, NONFINITE))
            continue
        if j < len(lower):
            lo, hi = lower[j], upper[j]
            if math.isfinite(lo) and math.isfinite(hi):
                gap = min(abs(v - lo), abs(v - hi))
                out.append((INPUT, j, INSIDE if lo <= v <= hi else OUTSIDE, _decade(gap)))
        out.append((INPUT, j, NEAR_PI, _decade(abs(v - math.pi * round(v / math.pi)))))
    return out


START = "^"
"""The token before a scenario's first step (so a scenario's first call is a bigram too)."""


def step_bigrams(kinds: Sequence[str], labels: Sequence[str]) -> list[str]:
    """Bigrams of consecutive scenario steps as feature names.

    Parameters
    ----------
    kinds : sequence of str, shape (N,)
        Step kinds in order (``go``, ``plan``...).
    labels : sequence of str, shape (M,)
        The step outcomes' labels on one target (``ok``, ``rejected:OutOfBoundsError:30``);
        M < N when a step crashed and ended the scenario.

    Returns
    -------
    list of str, shape (min(N, M),)
        ``"<prev kind>:<prev label>><kind>:<label>"`` for each executed step, the first one
        after :data:`START`: ``"^>joint_target:ok"``, ``"joint_target:ok>go:failed"``...
    """
    tokens = [f"{kind}:{label}" for kind, label in zip(kinds, labels, strict=False)]
    return [f"{before}>{after}" for before, after in zip([START, *tokens], tokens, strict=False)]
