"""The full engine's dry run: the Hypothesis seeds a fresh campaign generated, then two rounds
of boundary probes, are evaluated once in a child process before libFuzzer gets to them (as
AFL's dry run of its inputs and its deterministic stage).

A campaign's first inputs otherwise wait for what only a libFuzzer-based engine pays: the
space-filling seeds, importing Atheris, the instrumentation, the seed files and libFuzzer's
start (about 60-80 ms on the default robot, BENCHMARKS.md). A divergence that the first seeds
show then comes that much later than from an engine without libFuzzer, for no gain. The dry run
reports it as soon as the seeds exist, as an ordinary crash file (the same ``Harness``:
sidecar, divergence log, signature claim; the campaign's own Harness then finds the signature
claimed and does not file it again).

Why a child (``os.fork``, before Atheris is imported): libFuzzer is what turns a target that
hangs or dies on an input (a deadly signal, an abort) into a timeout or crash file. The child
has no libFuzzer; if a seed kills it, or it outlives ``budget`` seconds (``SIGALRM``, default
action), it ends without a word, and libFuzzer runs every seed next in the campaign process and
reports that input as it reports any. libFuzzer runs every seed anyway, instrumented, for their
coverage: the dry run costs the seeds' evaluation once more (in parallel on a second CPU; on
one, before the rest of the start-up, most of which is importing ``scipy.stats`` for the
space-filling streams), which is why it is kept to the ops whose seeds are cheap enough
(``DRY_RUN_OPS``). An ``ik`` campaign's dry run starts with its orientation probes (``cases``).
"""

from __future__ import annotations

import contextlib
import math
import os
import random
import select
import signal
import sys
import time
from collections.abc import Callable, Sequence
from typing import Any

from fuzzer.artifacts.divlog import CampaignLog
from fuzzer.artifacts.store import ArtifactStore
from fuzzer.execution.evaluate import Evaluator
from fuzzer.execution.session import RunConfig
from fuzzer.harness import Harness
from fuzzer.input.testcase import TestCase
from fuzzer.mutation import mutators
from fuzzer.selection.guidance import Features

DRY_RUN_OPS = frozenset({"fk", "move", "ik"})
"""Ops whose seeds are run twice: ``fk`` and ``move`` seeds cost well under a millisecond each;
an ``ik`` seed about 5 ms, but an IK campaign's start-up imports ``scipy.stats`` (0.55 s, for its
space-filling seed) after the fork, so its dry run reports what the seeds show that much sooner
(BENCHMARKS.md, "Orientation probes, and the baselines' scipy.stats import"). Not ``scenario``:
a scenario seed costs 10 to 100 times more than an ``fk`` one."""

BOUNDARY_ROUNDS = 2
"""Rounds of boundary probes the dry run evaluates after the seeds (``fuzzer.generation.boundary``:
each joint 5e-5 past a limit, inside MoveIt's goal tolerance, then 1.5e-4 past it, beyond; 24
inputs on a 6-joint arm): AFL's deterministic stage, run before the rest of the start-up. The
first round also rides on the space-filling seeds; the campaign's fresh inputs bring both again
later, on space-filling points."""

DEFAULT_BUDGET = 60.0
"""Seconds the child may take when libFuzzer's ``-timeout`` is 0 (off)."""

ENV = "RROSFUZZ_DRY_RUN"
"""``RROSFUZZ_DRY_RUN=0`` turns the dry run off (libFuzzer then runs the seeds first, alone)."""

KILL_GRACE = 2.0
"""Seconds past the child's budget before ``DryRun.wait`` kills a child that outlived its alarm
(one that ignores ``SIGALRM``)."""


def applies(config: RunConfig, mutator: str, several_processes: bool, stop_on_divergence: bool) -> bool:
    """Whether a campaign gets a dry run of its generated seeds.

    Only the full engine (``--mutator rrosfuzz``; the baselines ``libfuzzer`` and ``weights``
    keep libFuzzer's own start), an op of ``DRY_RUN_OPS`` in process (over ROS an input is a
    round trip to nodes that one process owns), a single process (``several_processes``: a
    ``-fork``/``-jobs`` supervisor or worker) and not ``--stop-on-divergence`` (there libFuzzer
    itself writes the crash file and ends the run); ``RROSFUZZ_DRY_RUN=0`` turns it off.
    """
    return (
        os.environ.get(ENV, "1") != "0"
        and mutator == "rrosfuzz"
        and config.op in DRY_RUN_OPS
        and config.transport == "inprocess"
        and not several_processes
        and not stop_on_divergence
        and hasattr(os, "fork")
    )


def harness(
    evaluator: Evaluator,
    store: ArtifactStore,
    log: CampaignLog,
    sidecar: Callable[[TestCase, bytes, Any], dict[str, Any]],
    seeds: Sequence[TestCase],
    joint_names: tuple[str, ...],
) -> Harness:
    """A Harness that evaluates and records, without libFuzzer, coverage or mutation."""
    return Harness(
        evaluator=evaluator,
        store=store,
        features=Features(enabled=False),
        context=mutators.MutationContext(rng=random.Random(0), field_types={}),  # never mutates
        sidecar=sidecar,
        seeds=list(seeds),
        log=log,
        joint_names=joint_names,
    )


def evaluate(h: Harness, cases: Sequence[TestCase]) -> None:
    """Evaluate ``cases`` in order, as libFuzzer hands inputs over (their encoding), then log
    a stats snapshot."""
    for case in cases:
        h.test_one_input(case.encode())
    h.maybe_snapshot(force=True)


def cases(seeds: list[TestCase], probes: list[TestCase], orientation: list[TestCase]) -> list[TestCase]:
    """What the dry run evaluates, in order: a pose campaign's orientation probes (four cheap
    inputs; ``fuzzer.generation.corpus.orientation_cases``), the seeds, then the first
    ``BOUNDARY_ROUNDS`` rounds of joint boundary probes (``probes``; a pose campaign has none)."""
    return orientation + seeds + probes


def launch(make_harness: Callable[[], Harness], seeds: Sequence[TestCase], timeout: int) -> DryRun | None:
    """Start the dry run: a child that makes its Harness and evaluates ``seeds``. ``timeout``
    is libFuzzer's ``-timeout`` (s; 0: off, ``DEFAULT_BUDGET``): the child's whole budget.

    On a single CPU (``os.sched_getaffinity``: a pinned process) the campaign waits for the
    child before it goes on: sharing one CPU would slow both, and the scheduler would let the
    new child wait for a time slice while the campaign starts up, for nothing."""

    def work() -> None:
        evaluate(make_harness(), seeds)

    dry = DryRun.start(work, timeout if timeout > 0 else DEFAULT_BUDGET)
    if dry is not None and _cpus() == 1:
        dry.wait()
    return dry


def _cpus() -> int:
    """The CPUs this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


class DryRun:
    """The child process that evaluates the seeds (``start``), and its end (``wait``)."""

    def __init__(self, pid: int, budget: float) -> None:
        self.pid = pid
        self.deadline = time.monotonic() + budget + KILL_GRACE
        self.status: int | None = None
        """The child's wait status once reaped (``os.waitstatus_to_exitcode`` reads it)."""

    @classmethod
    def start(cls, work: Callable[[], object], budget: float) -> DryRun | None:
        """Fork a child that runs ``work`` and exits (0, or 1 if it raised); None if the system
        cannot fork. The child ends after ``budget`` seconds whatever it is doing (``SIGALRM``,
        whose default action ends a process even inside compiled code)."""
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()  # what is buffered would be written twice
        try:
            pid = os.fork()
        except OSError:
            return None
        if pid:
            return cls(pid, budget)
        code = 1
        try:  # the child: no exit hooks of the campaign, no buffered output of its own to flush
            signal.signal(signal.SIGALRM, signal.SIG_DFL)
            signal.alarm(max(1, math.ceil(budget)))
            work()
            code = 0
        finally:
            os._exit(code)

    def wait(self) -> int | None:
        """Reap the child: wait until it ends or its budget and ``KILL_GRACE`` are spent (then
        kill it). Returns its exit code (negative: the signal that ended it), None if it was
        already reaped."""
        if self.status is not None:
            return None
        while True:
            try:
                pid, status = os.waitpid(self.pid, os.WNOHANG)
            except ChildProcessError:  # reaped elsewhere (a SIGCHLD handler)
                self.status = 0
                return None
            if pid:
                self.status = status
                return os.waitstatus_to_exitcode(status)
            remaining = self.deadline - time.monotonic()
            if remaining <= 0:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(self.pid, signal.SIGKILL)
                self.deadline = remaining = math.inf  # its death is reaped next
            _until_exit(self.pid, min(remaining, 1.0))


def _until_exit(pid: int, seconds: float) -> None:
    """Sleep until process ``pid`` exits or ``seconds`` pass: woken at its exit through a pidfd
    (Linux), else polled every 10 ms."""
    try:
        fd = os.pidfd_open(pid)
    except (AttributeError, OSError):  # not Linux, or already gone (waitpid reaps it next)
        time.sleep(min(seconds, 0.01))
        return
    try:
        select.select([fd], [], [], seconds)
    finally:
        os.close(fd)
