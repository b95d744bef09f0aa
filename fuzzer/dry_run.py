"""The full engine's dry run: inputs that need no libFuzzer, evaluated in child processes before
libFuzzer starts (as AFL's dry run of its inputs and its deterministic stage), in two stages
(``Stages``): before the Hypothesis seeds exist, a pose campaign's orientation and reach probes,
uniform random sweeps (``fk``) or configurations (``move``), aligned configurations and the
boundary probes, or a scenario campaign's tutorial scripts and uniform scripts; once they exist,
the seeds and the rest of the uniform work (not for ``scenario``).

A campaign's first inputs otherwise wait for what only a libFuzzer-based engine pays: the
space-filling seeds, importing ``scipy.stats`` for them (0.55 s on one CPU) and Atheris, the
instrumentation, the seed files and libFuzzer's start. A divergence those inputs show would
come that much later than from an engine without libFuzzer. The dry run reports it as an
ordinary crash file (the same ``Harness``: sidecar, divergence log, signature claim; the
campaign's own Harness then finds the signature claimed and does not file it again). Its
uniform rows come from Python's Mersenne Twister, not Sobol's sequence: neither ``scipy.stats``
nor ``numpy.random`` is imported yet (``fuzzer.generation.spacefill.Uniform``, the sweeps'
source ``uniform``).

Why children (``os.fork``, before Atheris is imported): libFuzzer is what turns a target that
hangs or dies on an input (a deadly signal, an abort) into a timeout or crash file. A child
has no libFuzzer; if an input kills it, or it outlives ``budget`` seconds (``SIGALRM``, default
action), it ends without a word, and libFuzzer runs every seed next in the campaign process and
reports that input as it reports any. libFuzzer runs every seed anyway, instrumented, for their
coverage: the dry run costs the seeds' evaluation once more (in parallel on a second CPU; on
one, before the rest of the start-up), which is why it is kept to the ops whose inputs are cheap
enough (``DRY_RUN_OPS``).

But the first (``IN_PROCESS_FIRST`` ops): the first stage's first input is evaluated in the
campaign's process before the fork, under ``fuzzer.execution.guard`` (written ahead into the
corpus, a hang guard), and the child goes on from the second. A child's fork, set-up and
copy-on-write faults put 5-7 ms before its first evaluation, and a bug that nearly every input
shows is decided by that input (BENCHMARKS.md, "Paired A/B"). It runs on the campaign's own
targets, as every input libFuzzer runs later: for a stateful target it is one call more before
libFuzzer's first, in the evaluator's history like any (a ``state_dependent`` crash file lists
and replays it), and the child inherits the targets after it, as its own first evaluation left
them before.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

from fuzzer import reporting
from fuzzer.dry_harness import MakeHarness, evaluate, sweep
from fuzzer.execution import guard
from fuzzer.execution.session import RunConfig, Session
from fuzzer.generation.corpus import (
    aligned_cases,
    boundary_cases,
    literal_cases,
    literal_scripts,
    orientation_cases,
    reach_cases,
    space_filling_count,
    tutorial_seeds,
    uniform_cases,
    uniform_scripts,
)
from fuzzer.generation.dry_run_plan import (
    ALIGNED,
    BOUNDARY_ROUNDS,
    DRY_RUN_OPS,
    EARLY,
    FIRST_ROWS,
    HEAD,
    IN_PROCESS_FIRST,
    LATE,
    LEAD,
    LEADING_SWEEP_OPS,
    LITERALS,
    SCRIPTS,
    SECOND_STAGE_OPS,
    SWEEP_SEED,
    TOTAL_SWEEPS,
    UNIFORM,
)
from fuzzer.generation.sweep import Sweep
from fuzzer.harness import Harness
from fuzzer.input.testcase import TestCase
from fuzzer.processes import TIMEOUT_EXIT, DryRun, launch
from fuzzer.scenario.fresh import GO
from fuzzer.selection.state import SPACEFILL

DEFAULT_BUDGET = 60.0
"""Seconds the child may take when libFuzzer's ``-timeout`` is 0 (off)."""

ENV = "RROSFUZZ_DRY_RUN"
"""``RROSFUZZ_DRY_RUN=0`` turns the dry run off (libFuzzer then runs the seeds first, alone);
``RROSFUZZ_DRY_RUN=children`` (``CHILDREN``) keeps every dry-run input out of the campaign's
process, the first one included (``IN_PROCESS_FIRST``): for targets known to crash or hang, at
5-7 ms of the first detection."""

CHILDREN = "children"


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


Parts = Iterator[tuple[str, list[TestCase]]]
"""The first stage's parts still to come (``Stages._first_parts``)."""

Here = tuple[Sweep | None, Harness, Parts, list[TestCase]]
"""What the first stage's child goes on with after its first input was evaluated before the
fork (``Stages._first_here``): the sweep, the Harness, the parts still to come, the rest of
the first input's part."""

TUTORIAL_PART, UNIFORM_PART, PROBE_PART, LITERAL_PART = "tutorial", "uniform", "probe", "literal"
"""Names of the first stage's parts (``Stages._first_parts``): MoveIt's tutorial scripts; uniform
configurations or scripts; orientation, reach, aligned and boundary probes; the literal
configurations."""


@dataclass
class Stages:
    """A campaign's dry run in two children, one per stage (``first``, ``second``).

    The first starts before the Hypothesis seeds exist (making 32 costs the campaign 75-95 ms):
    a pose campaign's orientation and reach probes, the first ``EARLY`` uniform sweeps (``fk``)
    or ``LEAD`` configurations (``move``; ``LITERALS`` configurations at the targets' compared
    numbers after the first ``HEAD`` of them), ``ALIGNED`` aligned configurations, the boundary
    probes (then the literal configurations of the other ops), then the rest of ``EARLY``'s
    configurations (``fk`` and ``move``: ``LATE`` more sweeps); a scenario's: the tutorial scripts, then
    ``SCRIPTS`` uniform scripts, the first ``LITERALS`` of them from literal configurations. The
    second starts once they exist: the seeds, then the rest of the uniform work (``TOTAL_SWEEPS``,
    ``UNIFORM``); a scenario has none (``SECOND_STAGE_OPS``). On one CPU the campaign waits
    for each child before it goes on (``launch``); on two, the children run while the campaign
    starts up.

    Parameters
    ----------
    session : Session
        The campaign's.
    mutator : str
        ``--mutator`` (only ``rrosfuzz`` sweeps).
    seed : int
        ``-seed``: with ``SWEEP_SEED`` (first stage) and ``SWEEP_SEED + 1`` (second), the
        uniform rows' and configurations' seed.
    wanted : int
        Seeds the campaign makes: the probes are numbered after them.
    timeout : int
        libFuzzer's ``-timeout`` (s; 0: off): each child's budget, and the first input's.
    make_harness : MakeHarness
    corpus : Path, optional
        The campaign's first corpus folder, where the first input is written ahead
        (``fuzzer.execution.guard``); None: no input is evaluated in the campaign's process.
    artifacts : Path, optional
        Where the first input goes as a ``timeout-`` file if it hangs (None: as ``corpus``).
    timeout_code : int
        ``-timeout_exitcode``.
    close_fd_mask : int
        libFuzzer's ``-close_fd_mask``: the target's stdout (1) and stderr (2) closed here too.
    """

    session: Session
    mutator: str
    seed: int
    wanted: int
    timeout: int
    make_harness: MakeHarness
    corpus: Path | None = None
    artifacts: Path | None = None
    timeout_code: int = TIMEOUT_EXIT
    close_fd_mask: int = 0
    children: list[DryRun] = field(default_factory=list)
    _first_count: int = 0
    _literal_at: int = 0

    def _base(self) -> list[TestCase]:
        """The Harness's seed: the message a sweep's rows go into, the zero message of the
        campaign's type (a scenario's: one ``/go``; a scenario has no registry type of its own)."""
        msg_type = self.session.config.message_type
        if self.session.config.op == "scenario":
            return [TestCase(msg_type, {"steps": [dict(GO)]}, 0, SPACEFILL)]
        return [TestCase(msg_type, self.session.registry.default(msg_type), 0, SPACEFILL)]

    def _first_parts(self, literals: bool = False) -> Iterator[tuple[str, list[TestCase]]]:
        """The first stage's inputs (besides its sweeps) in the order they are evaluated, in
        parts named by what they hold, each made when its turn comes: the child evaluates its
        first input while the rest are still to be made (making all of ``move``'s took 2-3 ms
        before it). A pose campaign's orientation and reach probes; the first uniform
        configuration, then the rest of the first ``HEAD``; the ``LITERAL_PART``; the rest of
        the first ``LEAD``; the aligned ones and the boundary probes; the ``LITERAL_PART`` of an
        op without uniform configurations; the rest of the ``EARLY`` uniform configurations. A
        scenario's: the tutorial scripts, then the uniform ones, in the ``LITERAL_PART`` the
        first of them from literal configurations (``literal_scripts``, with ``literals``). The
        ``LITERAL_PART`` holds ``literal_cases``' configurations with ``literals``, else nothing
        (it marks where they go: ``first_cases``)."""
        session, wanted = self.session, self.wanted
        op = session.config.op
        seed = self.seed + SWEEP_SEED
        if op == "scenario":
            tutorials = tutorial_seeds(session, self.seed, wanted)
            yield TUTORIAL_PART, tutorials
            scripts = uniform_scripts(session, SCRIPTS, seed, wanted + len(tutorials))
            started = literal_scripts(session, scripts, LITERALS, seed + 1) if literals else []
            yield LITERAL_PART, started
            yield UNIFORM_PART, scripts[len(started) :]
            return
        orientation = orientation_cases(session, wanted + space_filling_count(op, wanted))
        probes = [] if orientation else boundary_cases(session, BOUNDARY_ROUNDS, wanted)
        count = min(EARLY.get(op, 0), UNIFORM.get(op, 0))
        at = wanted + len(probes)  # the uniform configurations' first number, after the probes'
        # reach_cases' numbers follow the aligned configurations', which are none for a pose,
        # the only message type reach_cases makes inputs for
        reach = reach_cases(session, seed, at + count)
        yield PROBE_PART, orientation + reach
        lead = min(LEAD, count)
        head = min(HEAD, lead)
        yield UNIFORM_PART, uniform_cases(session, count, seed, at, stop=min(1, lead))
        yield UNIFORM_PART, uniform_cases(session, count, seed, at, start=min(1, lead), stop=head)
        aligned = aligned_cases(session, ALIGNED.get(op, 0), seed, at + count)
        # numbered after the second stage's inputs, as literal_cases
        made = len(orientation) + len(reach) + count + len(aligned) + len(probes)
        after = wanted + made + self._later_uniform()
        if count:
            yield LITERAL_PART, literal_cases(session, LITERALS, after) if literals else []
        yield UNIFORM_PART, uniform_cases(session, count, seed, at, start=head, stop=lead)
        yield PROBE_PART, aligned + probes
        if not count:  # made only now: reading the source would hold up the probes
            yield LITERAL_PART, literal_cases(session, LITERALS, after) if literals else []
        yield UNIFORM_PART, uniform_cases(session, count, seed, at, start=lead)

    def first_cases(self) -> list[TestCase]:
        """The first stage's inputs (besides its sweeps, and but for ``literal_cases``), all
        made (``_first_parts``): orientation and reach probes, the uniform configurations, the
        aligned ones, the boundary probes. Sets where ``literal_cases`` go among them
        (``_literal_at``), and how many they are (which numbers the second stage's inputs)."""
        cases: list[TestCase] = []
        for name, part in self._first_parts():
            if name == LITERAL_PART:
                self._literal_at = len(cases)
            cases += part
        self._first_count = len(cases)
        return cases

    def _later_uniform(self) -> int:
        """Uniform configurations the second stage evaluates (``UNIFORM`` less ``EARLY``)."""
        op = self.session.config.op
        return UNIFORM.get(op, 0) - min(EARLY.get(op, 0), UNIFORM.get(op, 0))

    def literal_cases(self) -> list[TestCase]:
        """The first ``LITERALS`` configurations with joints at the numbers the Python targets
        compare against (``corpus.literal_cases``), numbered after the second stage's inputs.
        The first stage makes them in its child when their turn comes (``_first_parts``): reading
        the targets' source takes 5-16 ms, which the campaign's start-up would otherwise wait for."""
        first = self.wanted + self._first_count + self._later_uniform()  # after second_cases' numbers
        return literal_cases(self.session, LITERALS, first)

    def second_cases(self, seeds: list[TestCase]) -> list[TestCase]:
        """The second stage's inputs (besides its sweeps): the seeds, then the rest of the
        uniform configurations."""
        count = self._later_uniform()
        first = self.wanted + self._first_count  # numbered after the first stage's (first_cases)
        return seeds + uniform_cases(self.session, count, self.seed + SWEEP_SEED + 1, first)

    def _first_sweeps(self) -> tuple[int, int]:
        """The first stage's sweeps of ``ROWS``: before its probes (``EARLY``, ``fk``) and after
        them (``LATE``), together at most the op's ``TOTAL_SWEEPS``."""
        op = self.session.config.op
        total = TOTAL_SWEEPS.get(op, 0)
        early = min(EARLY.get(op, 0), total) if op in LEADING_SWEEP_OPS else 0
        return early, min(LATE.get(op, 0), total - early)

    def _first_rows(self) -> int:
        """Rows of the first stage's first sweep: ``FIRST_ROWS`` where it leads the stage, else
        a full sweep's (0)."""
        return FIRST_ROWS if self.session.config.op in LEADING_SWEEP_OPS else 0

    def first(self) -> None:
        """Start the first stage. Its child makes its inputs (6-7 ms for ``fk``): its sweeps
        come first, and the campaign's start-up would otherwise wait for them; the campaign
        makes them again after the fork, for the second stage's numbering only (an op with a
        second stage, ``SECOND_STAGE_OPS``)."""
        early, late = self._first_sweeps()
        here = self._first_here()

        def work() -> None:
            if here is None:
                made = sweep(self.session, self.mutator, self.seed + SWEEP_SEED, self._first_rows())
                harness = self.make_harness(self._base(), made)
                parts: Parts = self._first_parts(literals=True)
                rest: list[TestCase] = []
            else:  # the first input was evaluated before the fork
                made, harness, parts, rest = here
                harness.maybe_snapshot(force=True)  # this process's first snapshot, which counts it
            leading = made is not None and self.session.config.op in LEADING_SWEEP_OPS
            for _ in range(early + 1 if leading else 0):  # FIRST_ROWS rows, then early sweeps
                harness.run_sweep()
            evaluate(harness, rest, snapshot=False)  # the rest of the first input's part
            for _, part in parts:  # the literals made here: off the start-up
                evaluate(harness, part, snapshot=False)
            for _ in range(late if made is not None else 0):  # the late sweeps, after the probes
                harness.run_sweep()
            harness.maybe_snapshot(force=True)

        self._launch(work)
        if self.session.config.op in SECOND_STAGE_OPS:
            self.first_cases()  # sets _first_count, which numbers the second stage's inputs

    def _first_here(self) -> Here | None:
        """Evaluate the first stage's first input in this process, before the fork, under
        ``fuzzer.execution.guard`` (an ``IN_PROCESS_FIRST`` op with a ``corpus`` folder); returns
        what the child goes on with (the sweep, the Harness, the parts still to come, the rest
        of the first input's part), or None (the child makes and evaluates everything).

        The first input is the first uniform configuration: for ``move`` its stream's first
        (the child goes on from the second); ``fk`` sweeps its uniform rows and has no
        single-call configurations, so it gets one more, on the single-call path, before the
        child's stream (a sweep of ``FIRST_ROWS`` first costs about 0.8 ms, and what a bug
        needs a joint away from zero for, its aligned configurations may not show). An input
        that cannot be written ahead is left to the child (``fk``: not evaluated)."""
        session = self.session
        op = session.config.op
        if op not in IN_PROCESS_FIRST or self.corpus is None or os.environ.get(ENV) == CHILDREN:
            return None
        if threading.current_thread() is not threading.main_thread():
            return None  # the hang guard needs signals, which only the main thread may set
        made = sweep(session, self.mutator, self.seed + SWEEP_SEED, self._first_rows())
        harness = self.make_harness(self._base(), made)
        harness.hold_snapshots()  # the child logs the first (a snapshot names its process)
        parts = self._first_parts(literals=True)
        part: list[TestCase] = []
        if UNIFORM.get(op, 0):
            for _, part in parts:
                if part:
                    break
            first, rest = (part[0], part[1:]) if part else (None, [])
        else:
            extra = uniform_cases(session, 1, self.seed + SWEEP_SEED, self.wanted)
            first, rest = (extra[0] if extra else None), []
        if first is None:
            return made, harness, parts, rest
        data = first.encode()
        try:
            pending = guard.write_ahead(self.corpus, data)
        except OSError:
            return made, harness, parts, part
        with (
            guard.guarded(pending, data, self.artifacts or self.corpus, self.budget, self.timeout_code),
            reporting.target_output_closed(self.close_fd_mask),
        ):
            harness.test_one_input(data)
        return made, harness, parts, rest

    def second(self, seeds: list[TestCase]) -> None:
        """Start the second stage, with the campaign's generated ``seeds`` (none for an op
        outside ``SECOND_STAGE_OPS``)."""
        if self.session.config.op not in SECOND_STAGE_OPS:
            return
        rest = TOTAL_SWEEPS.get(self.session.config.op, 0) - sum(self._first_sweeps())

        def work() -> None:
            made = sweep(self.session, self.mutator, self.seed + SWEEP_SEED + 1)
            evaluate(self.make_harness(self._base(), made), self.second_cases(seeds), after=rest)

        self._launch(work)

    @property
    def budget(self) -> float:
        """Seconds a child, or the first input in this process, may take: libFuzzer's
        ``-timeout``, ``DEFAULT_BUDGET`` if 0."""
        return self.timeout if self.timeout > 0 else DEFAULT_BUDGET

    def _launch(self, work: Callable[[], None]) -> None:
        def closed() -> None:
            with reporting.target_output_closed(self.close_fd_mask):
                work()

        child = launch(closed, self.budget)
        if child is not None:
            self.children.append(child)

    @property
    def pids(self) -> list[int]:
        return [child.pid for child in self.children]

    def wait(self) -> None:
        """Reap every child (``DryRun.wait``)."""
        for child in self.children:
            child.wait()

    def stop(self) -> None:
        """End and reap every child now (``DryRun.stop``): the campaign did not start."""
        for child in self.children:
            child.stop()
