"""The libFuzzer side of a campaign: TestOneInput, the custom mutator and crossover.

Per input (``test_one_input``): decode the test case, evaluate it on both
targets, feed its behaviour to libFuzzer as coverage features, keep
high-difference inputs as preferred parents (Algorithm 3), and record the first
input of every new divergence signature as a crash file with a sidecar. By
default the campaign goes on past divergences. With ``stop_on_divergence`` the
first one raises, libFuzzer writes ``crash-<sha1>`` and exits.

The mutator (``mutate``) decodes, picks a parent (usually libFuzzer's, sometimes
a high-difference one), applies one registered mutator (``fuzzer.mutators``)
with an RNG seeded by libFuzzer, records it in the lineage, and encodes. It
never raises: an exception there would hang Atheris.
"""

from __future__ import annotations

import bisect
import hashlib
import math
import random
import time
from collections import Counter, OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from fuzzer import mutators
from fuzzer.artifacts import ArtifactStore
from fuzzer.divlog import CampaignLog, closer_to_command, near_zero_count
from fuzzer.evaluate import Evaluation, Evaluator, Verdict
from fuzzer.guidance import Features, input_features
from fuzzer.mapping import FkCall, MoveCall
from fuzzer.testcase import TestCase, TestCaseError, decode

SNAPSHOT_SECONDS = 5.0
POOL_SIZE = 64
POOL_PARENT_CHANCE = 0.2
DECODE_CACHE = 4096


class DivergenceFound(Exception):
    """Raised from TestOneInput with --stop-on-divergence: libFuzzer turns it into a crash."""


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


@dataclass
class Harness:
    """Glue between libFuzzer and the evaluator."""

    evaluator: Evaluator
    store: ArtifactStore
    features: Features
    context: mutators.MutationContext
    """Reused for every mutation; its ``rng`` is replaced each time."""
    sidecar: Callable[[TestCase, bytes, Evaluation], dict[str, Any]]
    seeds: list[TestCase]
    lower: tuple[float, ...] = ()
    upper: tuple[float, ...] = ()
    stop_on_divergence: bool = False
    on_exec: Callable[[], None] = lambda: None
    log: CampaignLog | None = None
    joint_names: tuple[str, ...] = ()
    stats: Stats = field(default_factory=Stats)
    pool: Pool = field(default_factory=Pool)
    _last: tuple[bytes, TestCase] | None = None
    _decoded: OrderedDict[bytes, TestCase] = field(default_factory=OrderedDict)
    _next_snapshot: float = 0.0

    # -- TestOneInput ------------------------------------------------------------------------

    def test_one_input(self, data: bytes) -> None:
        self.stats.execs += 1
        case, trusted = self._decode(data)
        if case is None:
            self.stats.malformed += 1
            self.on_exec()
            return
        evaluation = self.evaluator.evaluate(case, validated=trusted)
        if evaluation.verdict != Verdict.MALFORMED:
            self._remember(data, case)
        if evaluation.verdict == Verdict.FILTERED:
            self.stats.filtered += 1
        elif evaluation.verdict == Verdict.MALFORMED:
            self.stats.malformed += 1
        else:
            self._record(case, data, evaluation)
        if self.log is not None and not self.stats.execs & 255:
            self.maybe_snapshot()
        self.on_exec()

    def maybe_snapshot(self, force: bool = False) -> None:
        """Append this process's counters to stats.jsonl (at most every SNAPSHOT_SECONDS)."""
        now = time.monotonic()
        if self.log is not None and (force or now >= self._next_snapshot):
            self._next_snapshot = now + SNAPSHOT_SECONDS
            self.log.snapshot(self.stats.to_json())

    def _decode(self, data: bytes) -> tuple[TestCase | None, bool]:
        """(test case or None, whether it is known valid). Parents repeat: recent ones are cached."""
        if self._last is not None and self._last[0] == data:
            return self._last[1], True  # made by our mutator: valid by construction
        cached = self._decoded.get(data)
        if cached is not None:
            self._decoded.move_to_end(data)
            return cached, True
        try:
            case = decode(data)
        except TestCaseError:
            return None, False
        if case.msg_type != self.seeds[0].msg_type:
            return None, False
        return case, False

    def _remember(self, data: bytes, case: TestCase) -> None:
        """Cache a test case that passed validation."""
        self._decoded[data] = case
        if len(self._decoded) > DECODE_CACHE:
            self._decoded.popitem(last=False)

    def _record(self, case: TestCase, data: bytes, ev: Evaluation) -> None:
        stats = self.stats
        stats.executed_by_strategy[case.strategy] += 1
        a, b = ev.outcomes
        cmp = ev.comparison
        if cmp.kind == "value" and math.isfinite(ev.difference) and ev.difference > stats.max_difference:
            stats.max_difference, stats.max_difference_unit = ev.difference, cmp.unit
        self.features.hit(f"o:{a.label}|{b.label}")
        self.features.hit(f"d:{cmp.kind}:{cmp.field}:{cmp.bucket}:{int(cmp.sign_flip)}")
        if cmp.joints:
            self.features.hit(f"j:{cmp.kind}:{cmp.field}:{','.join(map(str, cmp.joints))}")
        values: tuple[float, ...] = ()
        if isinstance(ev.call, MoveCall | FkCall):
            values = ev.call.positions if isinstance(ev.call, MoveCall) else ev.call.joint_values
            self.features.hit_ids(input_features(values, self.lower, self.upper))
            stats.near_zero[near_zero_count(values)] += 1
        self.pool.offer(cmp.largest, data)  # Algorithm 3: the paper's difference information
        if not cmp.divergent or ev.signature is None:
            return
        stats.divergent[str(cmp.kind)] += 1
        stats.by_strategy[case.strategy] += 1
        key = ev.signature.key
        if self.log is not None:
            self._log_divergence(case, data, ev, values)
        if key not in stats.signatures:
            # claim and write together (the store's record); None: another process has it.
            # With stop_on_divergence libFuzzer writes crash-<sha1> itself when this raises.
            written = self.store.record(
                key, data, self._sidecar(case, data, ev), with_input=not self.stop_on_divergence
            )
            stats.signatures[key] = str(written or "")
        if self.stop_on_divergence:
            # every divergence is a crash here (libFuzzer's -minimize_crash relies on it)
            raise DivergenceFound(f"{cmp.headline(self.joint_names)}: signature {key}")

    def _log_divergence(self, case: TestCase, data: bytes, ev: Evaluation, values: tuple[float, ...]) -> None:
        a, b = ev.outcomes
        command = None
        if isinstance(ev.call, MoveCall) and (ev.call.names is None or ev.call.names == self.joint_names):
            command = ev.call.positions
        cmp = ev.comparison
        assert self.log is not None and ev.signature is not None
        self.log.divergence(
            {
                "sig": ev.signature.key,
                "kind": str(cmp.kind),
                "field": cmp.field,
                "bucket": cmp.bucket,
                "sign_flip": cmp.sign_flip,
                "difference": cmp.difference,
                "unit": cmp.unit,
                "raw": cmp.raw,
                "joints": list(cmp.joints),
                "joint_names": [self.joint_names[j] for j in cmp.joints if j < len(self.joint_names)],
                "target": cmp.target,
                "outcome_a": a.label,
                "outcome_b": b.label,
                "strategy": case.strategy,
                "near_zero": near_zero_count(values) if values else None,
                "closer": closer_to_command(
                    command, a.values.get("joint_values", ()), b.values.get("joint_values", ())
                ),
                "sha1": hashlib.sha1(data).hexdigest(),
            }
        )

    def _sidecar(self, case: TestCase, data: bytes, ev: Evaluation) -> dict[str, Any]:
        """The sidecar, with the call history of a ``state_dependent`` divergence (replay
        makes those calls on fresh targets before the input)."""
        sidecar = self.sidecar(case, data, ev)
        if ev.history:
            sidecar["history"] = list(ev.history)
        sidecar.setdefault("unit", ev.comparison.unit)
        return sidecar

    # -- custom mutator / crossover ------------------------------------------------------------

    def mutate(self, data: bytes, max_size: int, seed: int) -> bytes:
        try:
            rng = random.Random(seed)
            parent = self._parent(data, rng)
            ctx = self.context
            ctx.rng = rng
            message, name = mutators.mutate(parent.message, ctx)
            return self._emit(parent.child(message, name), parent, max_size, data)
        except Exception:  # noqa: BLE001 - must never raise into libFuzzer
            return data[:max_size]

    def crossover(self, data1: bytes, data2: bytes, max_size: int, seed: int) -> bytes:
        try:
            rng = random.Random(seed)
            a, b = self._parent(data1, rng, pool=False), self._parent(data2, rng, pool=False)
            ctx = self.context
            ctx.rng = rng
            message = mutators.crossover(a.message, b.message, ctx)
            return self._emit(a.child(message, "splice"), a, max_size, data1)
        except Exception:  # noqa: BLE001 - must never raise into libFuzzer
            return data1[:max_size]

    def _parent(self, data: bytes, rng: random.Random, pool: bool = True) -> TestCase:
        if pool and rng.random() < POOL_PARENT_CHANCE:
            preferred = self.pool.pick(rng)
            if preferred is not None:
                data = preferred
        case, _ = self._decode(data)
        if case is None:
            # not a test case (a foreign or damaged file): restart from a generated seed
            base = rng.choice(self.seeds)
            return TestCase(base.msg_type, base.message, base.sequence, "repair", ("repair",), 1)
        return case

    def _emit(self, case: TestCase, parent: TestCase, max_size: int, fallback: bytes) -> bytes:
        """The child's bytes; if too large, the (valid) parent's; if still too large, the input cut."""
        for candidate in (case, parent):
            out = candidate.encode()
            if len(out) <= max_size:
                self._last = (out, candidate)
                return out
        return fallback[:max_size]
