"""The libFuzzer side of a campaign: TestOneInput, the custom mutator and crossover.

Per input (``test_one_input``): decode the test case, evaluate it on both
targets, feed its behaviour to libFuzzer as coverage features, keep
high-difference inputs as preferred parents (Algorithm 3), and record the first
input of every new divergence signature as a crash file with a sidecar. By
default the campaign goes on past divergences. With ``stop_on_divergence`` the
first one raises (its crash file and sidecar written first), libFuzzer writes
``crash-<sha1>`` again (the same bytes) and exits.

The custom mutator and crossover (``mutate``, ``crossover``) are its other half,
``fuzzer.mutation.step.MutationStep``. Scenario outcomes also feed bigrams of
consecutive (step kind, step status) to libFuzzer (``guidance.step_bigrams``).
"""

from __future__ import annotations

import math
import sys
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from fuzzer import reporting
from fuzzer.artifacts.divlog import CampaignLog, divergence_record, near_zero_count
from fuzzer.artifacts.store import ArtifactStore, ArtifactsUnwritable
from fuzzer.execution.evaluate import Evaluation, Evaluator, Verdict
from fuzzer.generation.spacefill import configuration_message
from fuzzer.generation.sweep import CENTRES, Sweep
from fuzzer.input.mapping import FkCall, MoveCall
from fuzzer.input.testcase import TestCase, TestCaseError, decode
from fuzzer.mutation import mutators
from fuzzer.mutation.step import MessageCrossover, MessageMutator, MutationStep, digest
from fuzzer.selection.floatcmp import FloatCompareTracer
from fuzzer.selection.guidance import Features, input_features, step_bigrams
from fuzzer.selection.i2s import I2SQueue
from fuzzer.selection.state import Pool, Sources, Stats

SNAPSHOT_SECONDS = 5.0
DECODE_CACHE = 4096
"""Decoded test cases kept (libFuzzer's parents repeat), the most recently used ones..."""
DECODE_BYTES = 4 << 20
"""...while their encoded sizes add up to no more than this: a decoded scenario takes about 6
times its JSON, and 4,096 of them held 45-47 MB in a 10-minute campaign, where the count alone
bounds ``fk`` and ``move`` (about 1.5 MB of inputs; BENCHMARKS.md, "Memory")."""


class DivergenceFound(Exception):
    """Raised from TestOneInput with --stop-on-divergence: libFuzzer turns it into a crash."""


@dataclass
class Harness(MutationStep):
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
    campaign_seeds: tuple[int | None, int] | None = None
    """libFuzzer's ``-seed`` (None: libFuzzer drew its own, as with ``-jobs``) and the harness's
    own seed, recorded in every ``stats.jsonl`` snapshot as ``seed`` (the dry run's processes
    record their campaign's; None: not recorded)."""
    mutate_message: MessageMutator = mutators.mutate
    """The mutator of one message (``fuzzer.scenario.dispatch.for_registry`` for scenarios). One
    with a true ``uses_other`` attribute gets a second parent as ``context.other``."""
    crossover_message: MessageCrossover = mutators.crossover
    """The crossover of two messages; its ``lineage_name`` (default ``splice``) goes in the lineage."""
    sources: Sources | None = None
    """The bandit over input sources and mutators (None: libFuzzer's parent, one mutator by weight)."""
    float_tracer: FloatCompareTracer | None = None
    """Float comparisons of the Python targets as features (``fuzzer.selection.floatcmp``)."""
    i2s: I2SQueue | None = None
    """New inputs waiting for the ``compared`` arm (``fuzzer.selection.i2s``)."""
    sweep: Sweep | None = None
    """Batched FK sweeps for ``--op fk`` (``fuzzer.generation.sweep``)."""
    stats: Stats = field(default_factory=Stats)
    interrupted: bool = False
    """Ended by a signal (a ``-jobs``/``-fork`` worker): said in its last snapshot."""
    pool: Pool = field(default_factory=Pool)
    _last: tuple[bytes, TestCase] | None = None
    _credit: bytes | None = None
    _decoded: OrderedDict[bytes, TestCase] = field(default_factory=OrderedDict)
    _decoded_bytes: int = 0
    _next_snapshot: float = 0.0

    # -- TestOneInput ------------------------------------------------------------------------

    def test_one_input(self, data: bytes) -> None:
        self.stats.execs += 1
        case, trusted = self._decode(data)
        if case is None:
            self.stats.malformed += 1
            self.on_exec()
            return
        seen, signatures = len(self.features.seen), len(self.stats.signatures)
        first = self.stats.first_input is None
        self._execute(case, data, trusted)
        if self.sources is not None and self._credit is not None and self._credit == data:
            # only what the last step made: a corpus file a campaign resumes on names the arms
            # that made it in another run, and was credited again (83% "paid", every feature new)
            self._credit = None
            paid = len(self.features.seen) > seen or len(self.stats.signatures) > signatures
            self.sources.reward(case.strategy, paid)
        compared = self.float_tracer.compared if self.float_tracer is not None else None
        new = len(self.features.seen) > seen
        if self.sources is not None and self.float_tracer is not None:
            for site in self.float_tracer.nearer:  # where it came nearest a flip: walked on from
                self.sources.offer(site, case)
        if self.i2s is not None and compared is not None and new:
            self.i2s.offer(data, compared.sites_of(digest(data)))  # input-to-state (fuzzer.selection.i2s)
        if self.sweep is not None and self.sweep.due():
            self.run_sweep()
        if self.log is not None and (first or not self.stats.execs & 255):
            self.maybe_snapshot()  # the first right away: stats.jsonl then says when the search began
        self.on_exec()

    def _execute(self, case: TestCase, data: bytes, trusted: bool) -> Evaluation:
        """Evaluate a decoded test case and record what it showed."""
        if self.stats.first_input is None:
            self.stats.first_input = time.time()
        compared = self.float_tracer.compared if self.float_tracer is not None else None
        if self.float_tracer is not None:
            self.float_tracer.install()  # a fresh budget; again if Atheris swapped its _trace_cmp in
        if compared is not None:
            compared.begin()
        evaluation = self.evaluator.evaluate(case, validated=trusted)
        if compared is not None:
            compared.end(digest(data))  # what this input compared, for when it is mutated
        if self.sources is not None:
            self.sources.learn(evaluation.call, evaluation.outcomes)  # the walk's configurations
        if evaluation.verdict != Verdict.MALFORMED:
            self._remember(data, case)
        if evaluation.verdict == Verdict.FILTERED:
            self.stats.filtered += 1
        elif evaluation.verdict == Verdict.MALFORMED:
            self.stats.malformed += 1
        else:
            self._record(case, data, evaluation)
        return evaluation

    def run_sweep(self) -> None:
        """A batched FK sweep (``fuzzer.generation.sweep``): its flagged rows are evaluated as
        ordinary test cases; neighbours that raised the difference become preferred parents."""
        assert self.sweep is not None
        if self.stats.first_input is None:  # a sweep evaluates inputs: the search has begun
            self.stats.first_input = time.time()
        centres = []
        for difference, data in reversed(self.pool.entries[-CENTRES:]):
            call = self._call_of(data)
            if isinstance(call, FkCall):
                centres.append((call.joint_values, difference))
        result = self.sweep.run([r.model for r in self.evaluator.runners], centres)
        base = self.seeds[0]
        for row in result.flagged:
            case = self._row_case(base, row)
            if case is None:
                continue
            self.stats.execs += 1
            if not self._execute(case, case.encode(), trusted=True).divergent:
                self.sweep.unconfirmed += 1
        for row in result.improved:
            case = self._row_case(base, row)
            if case is not None:
                self.pool.offer(row.difference, case.encode())

    def _call_of(self, data: bytes) -> Any:
        case = self._decode(data)[0]
        try:
            return None if case is None else self.evaluator.mapping(case.message)
        except ValueError:
            return None

    def _row_case(self, base: TestCase, row: Any) -> TestCase | None:
        message = configuration_message(base.msg_type, base.message, row.values, self.joint_names)
        if message is None:
            return None
        if isinstance(message.get("header"), dict):  # the sweep's link (a JointState's frame_id)
            message["header"]["frame_id"] = (self.sweep.link if self.sweep is not None else None) or ""
        if self.evaluator.op == "move" and "velocity" in message:  # MoveIt's default scaling
            message["velocity"], message["effort"] = [], []  # (a seed's may make a 60,000-point plan)
        return base.child(message, row.label)

    def hold_snapshots(self) -> None:
        """Log no snapshot until ``maybe_snapshot(force=True)`` (the first input's right-away
        one included): the dry run evaluates its first input before it forks, and the child
        logs the snapshot that counts it (``fuzzer.dry_run``)."""
        self._next_snapshot = math.inf

    def maybe_snapshot(self, force: bool = False) -> None:
        """Append this process's counters to stats.jsonl (at most every SNAPSHOT_SECONDS).

        It runs inside an input's evaluation, at a point the clock decides, so it must not run
        code of the instrumented modules (the targets', the oracle's): their coverage would
        then depend on the time, and with it libFuzzer's corpus and choices (``-seed`` would
        no longer repeat a campaign). It reads plain attributes only."""
        now = time.monotonic()
        if self.log is not None and (force or now >= self._next_snapshot):
            self._next_snapshot = now + SNAPSHOT_SECONDS
            data = self.stats.to_json()
            if self.campaign_seeds is not None:
                data["seed"] = {"libfuzzer": self.campaign_seeds[0], "harness": self.campaign_seeds[1]}
            if self.sources is not None:
                data["bandit"] = self.sources.to_json()
            if self.sweep is not None:
                data["sweep"] = self.sweep.to_json()
            if self.interrupted:
                data["interrupted"] = True
            if self.float_tracer is not None:
                data["float_compares"] = {
                    "traced": self.float_tracer.traced,
                    "sites": len(self.float_tracer.sites),
                }
            twin = sys.modules.get("python_impl.kinematics")  # loaded by a target; never imported here
            if twin is not None:
                memo = twin.IK_MEMO
                data["ik_memo"] = {"hits": memo.hits, "misses": memo.misses, "kept": memo.kept}
            try:
                self.log.snapshot(data)
            except OSError as exc:
                raise self._unwritable(exc) from None

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
        """Cache a test case that passed validation (``DECODE_CACHE``, ``DECODE_BYTES``)."""
        cache = self._decoded
        if data not in cache:
            self._decoded_bytes += len(data)
        cache[data] = case
        while len(cache) > 1 and (len(cache) > DECODE_CACHE or self._decoded_bytes > DECODE_BYTES):
            self._decoded_bytes -= len(cache.popitem(last=False)[0])

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
        if a.steps or b.steps:
            self._step_features(ev)
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
        try:
            if self.log is not None:
                command = None  # the paper's Table IV: a move naming every joint, in order
                names = ev.call.names if isinstance(ev.call, MoveCall) else ()
                if isinstance(ev.call, MoveCall) and (names is None or names == self.joint_names):
                    command = ev.call.positions
                record = divergence_record(ev, case.strategy, data, values, self.joint_names, command)
                self.log.divergence(record)
            if key not in stats.signatures:
                # claim and write together (the store's record); None: another process has it.
                # With stop_on_divergence libFuzzer writes crash-<sha1> too when this raises, the
                # same bytes under the same name: left to it alone, the pair was split by an
                # -exact_artifact_path (a folder: the input lost) and the summary, made first,
                # counted no new file
                written = self.store.record(key, data, self._sidecar(case, data, ev))
                stats.signatures[key] = str(written or "")
        except OSError as exc:
            raise self._unwritable(exc, data if key not in stats.signatures else None, key) from None
        if self.stop_on_divergence:
            # every divergence is a crash here (libFuzzer's -minimize_crash relies on it)
            raise DivergenceFound(f"{cmp.headline(self.joint_names)}: signature {key}")

    def _unwritable(self, exc: OSError, lost: bytes | None = None, key: str = "") -> ArtifactsUnwritable:
        """Say that the artifacts folder cannot be written (with the divergent input ``lost``, of
        signature ``key``, that could not be saved: printed whole, so it is not lost), and return
        the exception that ends the campaign (``fuzzer.campaign``) or the dry run's child."""
        where = exc.filename or self.store.directory
        text = f"cannot write to the artifacts folder ({where}: {exc.strerror or exc}); the campaign stops"
        if lost is not None:
            text += (
                f". The first input of the new divergence signature {key} could not be saved; "
                "its test case, to save as a file and replay, is the next line"
            )
        reporting.error(text)
        if lost is not None:  # whole and on a line of its own: an error line is bounded and indented
            reporting.terminal().write(reporting.shown(lost.decode("utf-8", "backslashreplace")) + "\n")
            reporting.terminal().flush()
        return ArtifactsUnwritable(text)

    def _step_features(self, ev: Evaluation) -> None:
        """Scenarios: bigrams of (step kind, step status label) of consecutive steps, per target
        (a new order of calls, or a call ending otherwise after another, is a new behaviour)."""
        kinds = [str(getattr(step, "kind", "?")) for step in getattr(ev.call, "steps", ())]
        for side, outcome in zip(("a", "b"), ev.outcomes, strict=False):
            labels = [step.label for step in outcome.steps]
            for name in step_bigrams(kinds[: len(labels)], labels):
                self.features.hit(f"q:{side}:{name}")

    def _sidecar(self, case: TestCase, data: bytes, ev: Evaluation) -> dict[str, Any]:
        """The sidecar, with the call history of a ``state_dependent`` divergence (replay
        makes those calls on fresh targets before the input)."""
        sidecar = self.sidecar(case, data, ev)
        if ev.history:
            sidecar["history"] = list(ev.history)
        sidecar.setdefault("unit", ev.comparison.unit)
        return sidecar
