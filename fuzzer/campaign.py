"""Running a campaign under libFuzzer (Atheris).

Order matters: the Python targets and the oracle are instrumented
(``fuzzer.selection.instrument``) before the session loads them, the feature
counters are reserved before ``atheris.Fuzz()``, and the argv handed to Atheris
carries our options as ``--name=value`` tokens, which libFuzzer ignores but
copies to the child processes of ``-fork``/``-jobs``/``-merge``.
"""

from __future__ import annotations

import atexit
import os
import random
import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

from fuzzer import dry_harness, dry_run, reporting
from fuzzer.artifacts.divlog import CampaignLog
from fuzzer.artifacts.sidecar_record import build_sidecar
from fuzzer.artifacts.store import WRITE_FAILED_EXIT, ArtifactStore, ArtifactsUnwritable
from fuzzer.campaign_end import USAGE_EXIT, CampaignEnd
from fuzzer.execution import guard
from fuzzer.execution.session import RunConfig, Session, tip_hint, versions
from fuzzer.generation.corpus import prescan, write_bag_seeds
from fuzzer.generation.initial import initial_seeds
from fuzzer.input.libfuzzer_flags import DEFAULT_FLAGS, cut_seeds, libfuzzer_argv
from fuzzer.input.testcase import TestCase
from fuzzer.mutation.dictionary import parse_dictionary
from fuzzer.mutation.session_values import field_types, interesting_values
from fuzzer.processes import (
    CHILD_ENV,
    DEADLINE_ENV,
    SINGLE_RUN_FLAGS,
    SUPERVISOR_ENV,
    TIMEOUT_EXIT,
    flag_value,
    int_flag,
    is_number,
    libfuzzer_seed,
    one_campaign,
    supervises,
)
from fuzzer.processes import deadline as child_deadline
from fuzzer.selection import fastcov
from fuzzer.selection.instrument import instrument
from fuzzer.selection.search import search_parts
from fuzzer.signals import (
    INTERRUPTED_EXIT,
    defer_to_next_input,
    end_with_supervisor,
    forward_term_to_jobs,
    on_signal,
    stop_requested,
)

if TYPE_CHECKING:
    from fuzzer.harness import Harness
    from fuzzer.selection.guidance import Features


@dataclass(frozen=True)
class CampaignOptions:
    """What the CLI hands over (beyond the run configuration)."""

    corpus: tuple[Path, ...]
    artifacts: Path
    libfuzzer_flags: tuple[str, ...]
    forwarded: tuple[str, ...]
    seeds: int | None
    seed: int
    stop_on_divergence: bool
    progress: bool
    progress_interval: float
    dictionary_file: str | None
    mutator: str = "rrosfuzz"
    verbose: bool = False
    seeds_from_bag: Path | None = None
    """``--seeds-from-bag``: a bag whose messages of the campaign's type become seeds."""
    max_len: int = int(DEFAULT_FLAGS["-max_len"])
    """The ``-max_len`` libFuzzer gets unless given (``libfuzzer_flags.default_max_len``)."""
    drawn_note: str = ""
    """What to say of a ``-seed`` drawn for this campaign, once its targets have loaded (not before
    an error that ends it)."""


def libfuzzer_mutate(data: bytes, max_size: int) -> bytes:
    """libFuzzer's own mutator. Looked up at each call: Atheris replaces ``Mutate`` when
    ``Fuzz()`` starts, and the version bound before that exits the process."""
    import atheris

    return atheris.Mutate(data, max_size)  # type: ignore[no-any-return]


def run(config: RunConfig, options: CampaignOptions) -> int:
    """Run a campaign; returns only if libFuzzer does (it usually exits the process, and the
    exit hook then sets the status: see ``exit_status``)."""
    deadline = child_deadline()
    if deadline is not None and time.time() >= deadline:
        os._exit(0)  # a -fork job or merge started after the budget: nothing left to do
    started = time.time()  # crash files since then are this run's (the dry run's included)
    # the targets load before Atheris (for fuzzer.dry_run); ``instrument`` rewrites them in place
    session = Session.open(config)
    if options.drawn_note:
        reporting.info(options.drawn_note)
    child = os.environ.get(CHILD_ENV) == "1"
    if not session.reference.dof and not child:
        reporting.warn(f"{session.urdf.name}: no joint moves its tip link; {tip_hint(session.urdf)}")
    if child:
        defer_to_next_input()  # a worker's SIGINT, in its start-up too, ends it at an input's start
        end_with_supervisor()  # a -jobs worker outlived a supervisor killed alone
    else:
        os.environ[SUPERVISOR_ENV] = str(os.getpid())  # for the processes libFuzzer starts
    if one_campaign(options.libfuzzer_flags) or child or supervises(options.libfuzzer_flags):
        # SIGTERM ends it with its summary, a worker at its next input with its last snapshot
        # (-handle_term=0; a supervisor passes it on to its jobs: signals.forward_term_to_jobs)
        signal.signal(signal.SIGTERM, on_signal)
    supervisor = not child and supervises(options.libfuzzer_flags)
    options.artifacts.mkdir(parents=True, exist_ok=True)
    artifacts = options.artifacts.resolve()  # -jobs changes the working folder
    folders = tuple(p for p in options.corpus if not p.is_file())
    for directory in folders:
        directory.mkdir(parents=True, exist_ok=True)
    store = ArtifactStore(artifacts)
    if store.recovered and not child:
        reporting.info(
            f"completed {len(store.recovered)} crash file(s) that an interrupted run had claimed: "
            + ", ".join(store.recovered[:5])
            + (" ..." if len(store.recovered) > 5 else "")
        )

    digest = session.robot_digest()

    def sidecar(case: TestCase, data: bytes, ev: Any) -> dict[str, Any]:
        # versions(): looked up when the first sidecar is written, not before the first input
        return build_sidecar(session, case, data, ev, versions(), digest)

    evaluator = session.evaluator()
    timeout = int_flag(options.libfuzzer_flags, "-timeout", int(DEFAULT_FLAGS["-timeout"]))
    evaluator.check_seconds = check_seconds(timeout)
    if config.transport == "ros" and timeout > 0:
        from fuzzer.ros.transport import fit_request_timeout

        fit_request_timeout(timeout)
    dry: dry_run.Stages | None = None
    dry_ok = dry_run.applies(config, options.mutator, child or supervisor, options.stop_on_divergence)
    timeout_code = int_flag(options.libfuzzer_flags, "-timeout_exitcode", TIMEOUT_EXIT)
    left = guard.leftovers(folders) if not child else []
    for path in left:  # fuzzer/execution/guard.py
        reporting.warn(
            f"{path}: a campaign ended while it evaluated this input in its own process (a crash, "
            "a hang or a kill); libFuzzer runs it as a seed, and no input is evaluated in the "
            "campaign's process while it is there"
        )
    usable, seeds = prescan(session, folders) if not child else (1, [])
    if options.seeds_from_bag is not None and not child and folders:
        from_bag = write_bag_seeds(session, options.seeds_from_bag, folders[0])
        seeds, usable = from_bag + seeds, usable + len(from_bag)
    wanted = (
        options.seeds
        if options.seeds is not None
        else (0 if usable or len(folders) < len(options.corpus) else 32)
    )
    seeds_of_campaign = (libfuzzer_seed(options.libfuzzer_flags), options.seed)  # in stats.jsonl
    if wanted and not child and folders and dry_ok:
        # fuzzer.dry_run: children evaluate probes, uniform inputs, seeds while libFuzzer starts
        joints = tuple(session.reference.joint_names)
        dry = dry_run.Stages(
            session,
            options.mutator,
            options.seed,
            wanted,
            timeout,
            lambda base, sweep: dry_harness.harness(
                evaluator, store, CampaignLog(artifacts), sidecar, base, joints, sweep, seeds_of_campaign
            ),
            corpus=None if left else folders[0],
            artifacts=artifacts,
            timeout_code=timeout_code,
            close_fd_mask=int_flag(options.libfuzzer_flags, "-close_fd_mask", 0),
        )
        dry.first()  # before the seeds exist
        # until libFuzzer runs, an exit (a usage error such as seeds Hypothesis cannot draw, a full
        # disk, Ctrl-C) ends the children too: they ran on for up to -timeout after the error
        atexit.register(dry.stop)
    if one_campaign(options.libfuzzer_flags):
        # from here a signal ends the campaign at an input's start (once the seeds are made, below):
        # Hypothesis' gc callback and scipy's Sobol set-up swallow a KeyboardInterrupt raised in
        # them (2 Ctrl-Cs of 110 were lost, the campaign fuzzing on)
        defer_to_next_input()
    seeds, filling = initial_seeds(
        session, wanted if not child else 0, options.seed, options.mutator, folders, seeds, dry
    )
    if stop_requested() and not child:
        raise KeyboardInterrupt  # fuzzer.cli: "interrupted" (or "terminated"), 130 (143)
    given_len = flag_value(options.libfuzzer_flags, "-max_len") is not None
    if not child and (given_len or options.seeds_from_bag is not None):
        # a given -max_len, or ours for a bag's seeds (a 20 kB JointState was cut short, unsaid);
        # generated seeds fit ours, and encoding them all cost the start-up up to 1.8 ms
        limits = (f"-max_len={options.max_len}", *options.libfuzzer_flags)  # the last one given wins
        cut = cut_seeds(limits, [len(case.encode()) for case in (*seeds, *filling)])
        if cut is not None:
            reporting.warn(cut)
    if not child:  # the seeds made: record the configuration in the corpus manifest
        from fuzzer.artifacts.travel import record_corpus  # (fuzzer/artifacts/manifest.py)

        record_corpus(options.corpus, config)  # after the dry run's fork: its fsync took 1-4 ms
    if dry is not None:
        pids = ", ".join(map(str, dry.pids))
        what = (
            "MoveIt's tutorial scripts and uniform scripts"
            if config.op == "scenario"
            else "probes, uniform inputs and the seeds"
        )
        reporting.info(f"dry run: processes {pids} evaluate {what} before libFuzzer")

    import atheris

    instrument(config)
    harness, features = _harness(
        session,
        options,
        evaluator,
        store,
        sidecar,
        seeds,
        len(filling),
        CampaignLog(artifacts),
        seeds_of_campaign,
    )
    total = flag_value(options.libfuzzer_flags, "-max_total_time")
    progress = reporting.Progress(
        harness.stats,
        features,
        options.progress_interval,
        float(total) if total and is_number(total) else None,
        enabled=options.progress and not supervisor,
    )
    harness.on_exec = progress.tick

    from fuzzer.exit_hook import flush_all, on_exit

    interrupted = int_flag(options.libfuzzer_flags, "-interrupted_exitcode", INTERRUPTED_EXIT)
    end = CampaignEnd(
        options,
        harness,
        features,
        progress,
        store,
        artifacts,
        started,
        child=child,
        supervisor=supervisor,
        single_run=not child and any(int_flag(options.libfuzzer_flags, n, 0) != 0 for n in SINGLE_RUN_FLAGS),
        timeout_code=timeout_code,
        interrupted=interrupted,
        dry=dry,
        leftovers=left,
    )
    once = on_exit(end)
    if dry is not None:
        atexit.unregister(dry.stop)  # from here the campaign's end waits for them (CampaignEnd)
    edge_callback: list[str | None] = []  # fastcov.install's answer, asked at the first call
    lost_reason: Any = None
    if config.transport == "ros":
        from fuzzer.ros.transport import lost_reason

    def end_now(status: int) -> NoReturn:
        """End this process with ``status`` from inside an input, its exit hook run first."""
        once(status)
        flush_all()
        os._exit(status)

    def test_one_input(data: bytes) -> None:
        if stop_requested():  # a SIGINT or SIGTERM since the last input (fuzzer.signals)
            if not child:
                raise KeyboardInterrupt  # Atheris ends it with its summary, as after Ctrl-C
            harness.interrupted = True  # in its last snapshot, for the supervisor's status
            end_now(interrupted)  # a worker: libFuzzer's status for an interrupted job
        if not edge_callback:  # atheris.Fuzz() has put its core module's _trace_branch in place
            edge_callback.append(fastcov.install(atheris))
            if edge_callback[0] is not None:
                reporting.info(f"Atheris' own edge callback kept (slower): {edge_callback[0]}")
        if not data:
            return  # libFuzzer always runs the empty input first: not a test case, not counted
        if deadline is not None and time.time() >= deadline:
            end_now(0)  # the -fork budget is spent: end this job as if its own time were up
        end.in_callback = True
        try:
            harness.test_one_input(data)
        except ArtifactsUnwritable:  # said, with the input it could not save: not a crash of a target
            end.unwritable = True
            end_now(WRITE_FAILED_EXIT)
        end.in_callback = False
        lost = lost_reason(session.runners) if lost_reason is not None else None
        if lost is not None:  # a node that died and cannot start again: the transport, not a target
            reporting.error(f"--transport ros: {lost}; the campaign stops (its findings so far are kept)")
            end.reason = "a target's ROS node could not be started again: the error above says why"
            end_now(USAGE_EXIT)

    reporting.info(
        f"fuzzing {config.op} on {session.urdf.name} ({session.reference.dof} joints): "
        f"{config.targets[0]} vs {config.targets[1]}{_transport_note(config)}, "
        f"{config.message_type}, tolerance "
        f"{config.tolerance.metres:g} m / {config.tolerance.radians:g} rad, artifacts in {options.artifacts}"
    )
    argv = libfuzzer_argv(options)  # a signal already waits for an input's start (before the seeds)
    os.environ[CHILD_ENV] = "1"
    os.environ["PATH"] = os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", "")
    if not child and total and is_number(total) and supervisor:
        # -fork and -jobs: a job that starts after it exits at once, one that reaches it ends
        # (-jobs=3 -workers=1 -max_total_time=10 ran 35 s: libFuzzer gives each job the time)
        os.environ[DEADLINE_ENV] = repr(time.time() + float(total))
    if not child and int_flag(options.libfuzzer_flags, "-jobs", 0) > 0:
        if os.environ.get("PYTHONPATH"):  # the jobs import plugin targets from it
            entries = os.environ["PYTHONPATH"].split(os.pathsep)
            os.environ["PYTHONPATH"] = os.pathsep.join(os.path.abspath(e) if e else e for e in entries)
        os.chdir(artifacts)  # libFuzzer writes fuzz-<job>.log into the working folder
    if int_flag(options.libfuzzer_flags, "-close_fd_mask", 0) & 2:
        reporting.keep_terminal()  # libFuzzer silences the target's stderr, not the engine's lines
    if options.mutator == "libfuzzer":  # baseline: libFuzzer's own byte-level mutations of the JSON
        atheris.Setup(argv, test_one_input)
    else:
        atheris.Setup(argv, test_one_input, custom_mutator=harness.mutate, custom_crossover=harness.crossover)
    if supervisor:
        forward_term_to_jobs()
    try:
        atheris.Fuzz()
    except SystemExit as exc:  # how Atheris ends a -jobs supervisor: with libFuzzer's status
        if not supervisor or not isinstance(exc.code, int):
            raise  # elsewhere (an exception of a target, Ctrl-C) the exit hooks end it
        code = once(exc.code)
        final = exc.code if code is None else code
        if final:  # as the exit hook does (Python would end a run it saw interrupted by SIGINT)
            flush_all()
            os._exit(final)
    return once(0) or 0


def _harness(
    session: Session,
    options: CampaignOptions,
    evaluator: Any,
    store: ArtifactStore,
    sidecar: Any,
    seeds: list[TestCase],
    seeded: int,
    log: CampaignLog,
    campaign_seeds: tuple[int | None, int],
) -> tuple[Harness, Features]:
    """The campaign's Harness (mutators, crossover, search parts, evaluator) and its feature
    counters, built after ``instrument``: their modules import the instrumented ones.
    ``seeded``: space-filling seeds already written (the Sobol sequence goes on after them)."""
    from fuzzer.harness import Harness
    from fuzzer.input.mapping import FOCUS
    from fuzzer.mutation import mutators
    from fuzzer.selection.guidance import Features

    config = session.config
    limits = session.reference.joint_limits
    # a scenario's steps have their own types (the scenario mutators know them)
    types = {} if config.op == "scenario" else field_types(session, config.message_type)
    dictionary: list[str | float] = [*session.reference.joint_names, *session.reference.link_names]
    if options.dictionary_file:
        dictionary += parse_dictionary(options.dictionary_file)
    context = mutators.MutationContext(
        rng=random.Random(options.seed),
        field_types=types,
        interesting_floats=tuple(interesting_values(session)),
        dictionary=tuple(dictionary),
        allow_special=not config.filtering,
        libfuzzer_mutate=libfuzzer_mutate,
        focus=FOCUS.get(config.message_type, ()),
    )
    features = Features()
    search = search_parts(session, options.mutator, options.seed, features, seeded=seeded)
    context.compared = search["float_tracer"].compared  # what the targets compare floats against
    harness = Harness(
        **_scenario_mutators(session),
        **search,
        evaluator=evaluator,
        store=store,
        features=features,
        context=context,
        sidecar=sidecar,
        seeds=seeds,
        lower=tuple(lim.lower for lim in limits),
        upper=tuple(lim.upper for lim in limits),
        stop_on_divergence=options.stop_on_divergence,
        log=log,
        joint_names=tuple(session.reference.joint_names),
        campaign_seeds=campaign_seeds,
    )
    return harness, features


def check_seconds(timeout: int) -> float | None:
    """One input's time budget for the oracle's re-runs (``Evaluator.check_seconds``): half of
    libFuzzer's ``-timeout`` (s), so that checking a divergence never makes it a timeout; None
    (no budget) for ``-timeout=0``, which has none either."""
    return timeout / 2.0 if timeout > 0 else None


def _scenario_mutators(session: Session) -> dict[str, Any]:
    """For ``--op scenario``: the Harness's sequence mutator and crossover
    (``fuzzer.scenario.dispatch.for_registry``); {} for the other ops."""
    if session.config.op != "scenario":
        return {}
    from fuzzer.generation.spacefill import finite_box
    from fuzzer.scenario import dispatch

    facts = session.facts()
    box = finite_box(facts.lower, facts.upper)
    mutate_message, crossover_message = dispatch.for_registry(
        session.registry, session.config.max_steps, box, facts.reachable, facts.joint_names
    )
    return {"mutate_message": mutate_message, "crossover_message": crossover_message}


def _transport_note(config: RunConfig) -> str:
    """`` as ROS nodes (master ...)`` for ``--transport ros`` (``rosnode list`` shows them there)."""
    if config.transport != "ros":
        return ""
    return f" as ROS nodes (master {os.environ.get('ROS_MASTER_URI', '?')})"
