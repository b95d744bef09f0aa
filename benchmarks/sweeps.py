"""A benchmark's sweep of trials through its journal (``benchmarks.journal``): the trials the
journal does not hold yet, some at a time, each appended as it ends, none started past
``--stop-after``; shared by ``bench_zoo`` and ``bench_deep``.

Each trial running at a time gets a CPU of its own (``cores``), as FuzzBench gives each
trial its own: two trials on two cores otherwise share both, and a trial's second process
(the full engine's dry-run child, which runs beside the campaign when the process sees two
CPUs) takes its time from the other trial.
"""

from __future__ import annotations

import argparse
import os
import queue
import random
import shutil
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from benchmarks import trials
from benchmarks.journal import Journal, JournalError, Sweep, open_sweep
from benchmarks.zoo import Bug

if TYPE_CHECKING:  # bench_zoo imports this module
    from benchmarks.bench_zoo import Run

Job = tuple[Bug, str, int]
"""A trial: (bug, engine, seed)."""

Trial = Callable[[Job, "int | None"], "Run"]
"""Runs a trial pinned to the CPU given (None: not pinned), returns its record."""


def cores(workers: int) -> list[int] | None:
    """The CPUs to pin ``workers`` concurrent trials to, one each (this process's, in order),
    or None when there are fewer than ``workers`` of them or no ``taskset`` to pin with."""
    available = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    if workers > len(available) or shutil.which("taskset") is None:
        return None
    return available[:workers]


def pinned(cmd: list[str], cpu: int | None) -> list[str]:
    """``cmd`` run on CPU ``cpu`` only, it and every process it starts (``taskset``)."""
    return cmd if cpu is None else ["taskset", "--cpu-list", str(cpu), *cmd]


def key_of(job: Job) -> tuple[str, str, str, int]:
    """A trial's identity: (bug, op, engine, seed)."""
    bug, engine, seed = job
    return bug.name, bug.op, engine, seed


def run_key(run: Run) -> tuple[str, str, str, int]:
    """The identity (:func:`key_of`) of a trial's record."""
    return run.bug, run.op, run.engine, run.seed


@dataclass(frozen=True)
class Progress:
    """What a sweep holds after one run of :func:`run_sweep`.

    Attributes
    ----------
    runs : list of Run
        The journal's trials and this run's, in the order of the sweep's jobs.
    total : int
        The sweep's trials.
    pace : float
        Wall seconds per trial of this run (trials at a time included).
    interrupted : bool
        Stopped by Ctrl-C: no trial started after it, those running finished and are in
        ``runs`` (unless a second Ctrl-C killed them: then they are not).
    """

    runs: list[Run]
    total: int
    pace: float
    interrupted: bool = False
    terminated: bool = False
    """Stopped by SIGTERM (``kill``, ``timeout``): the trials running killed and not kept."""

    @property
    def complete(self) -> bool:
        return len(self.runs) == self.total

    def stopped(self, path: Path, minutes: float | None, tabulate: str) -> str:
        """What to say when the sweep stopped with trials left (``--stop-after``); ``tabulate``
        is the tool's option that tabulates a journal so far."""
        # misses cost the whole budget and come in a seeded random order: a rough figure
        left = self.total - len(self.runs)
        why = "interrupted" if self.interrupted or minutes is None else f"stopped after {minutes:g} minutes"
        return (
            f"{why}: {len(self.runs)} of {self.total} trials done, "
            f"in {path}; the same command with --resume goes on (about {left * self.pace / 3600:.1f} "
            f"hours at this run's pace; {tabulate} {path} tabulates them so far)"
        )


def add_arguments(parser: argparse.ArgumentParser, where: str) -> None:
    """A sweep's journal options: ``--resume``, ``--restart``, ``--stop-after`` (``where``: the
    journal's file, as the help names it); :func:`check_arguments` checks them."""
    parser.add_argument(
        "--resume",
        action="store_true",
        help=f"go on with the sweep whose finished trials are in {where} (same options, same "
        "code); only the trials it does not hold run",
    )
    parser.add_argument(
        "--restart",
        action="store_true",
        help=f"start over although {where} holds an unfinished sweep (it is kept as .jsonl.old)",
    )
    parser.add_argument(
        "--stop-after",
        type=float,
        default=None,
        metavar="MINUTES",
        help="start no trial after this many minutes; those running finish, the journal keeps "
        "them all, and --resume goes on later",
    )


def check_arguments(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """The parser's error for journal options (:func:`add_arguments`) that cannot go together."""
    if args.resume and args.restart:
        parser.error("--resume and --restart exclude each other")
    if args.stop_after is not None and not args.stop_after > 0:
        parser.error(f"--stop-after must be a positive number of minutes, not {args.stop_after}")
    if args.jobs < 1:
        parser.error(f"--jobs must be 1 or more, not {args.jobs}")


WAIT_SLICE = 0.5
"""Seconds the main thread waits on a trial before it looks at the signals caught meanwhile."""


class NotStarted(RuntimeError):
    """A trial whose engine ended before it evaluated an input, with a status that is not a
    normal end: a refused command line or a broken build, not a miss."""


def check_started(run: Run) -> None:
    """Raise :class:`NotStarted` for a trial that never began its search (no first input logged)
    and ended with a status other than 0 or the detection's kill (-9): kept, it would count as a
    miss at the budget, and a broken engine would read as one that never finds the bug."""
    if run.first_input is None and run.returncode not in (0, -9):
        raise NotStarted(
            f"{run.engine} did not start on {run.bug} (seed {run.seed}, exit {run.returncode}): "
            "run its command by hand to see why; the trial is not kept"
        )


def run_sweep(
    book: Journal,
    jobs: Sequence[Job],
    done: Sequence[Run],
    trial: Trial,
    workers: int,
    stop_after: float | None = None,
    shuffle: bool = False,
) -> Progress:
    """Run the ``jobs`` that ``done`` (the journal's trials) does not hold, ``workers`` at a
    time, each on a CPU no other running trial has (:func:`cores`; unpinned when there are
    too few), appending each to ``book`` as it ends; start none after ``stop_after`` minutes.

    ``shuffle`` runs them in a seeded random order (as FuzzBench does: a change of machine load
    during the sweep then falls on every engine alike instead of on those that happen to run
    last); the records come back in the jobs' order either way. Closes ``book``.

    Ctrl-C (SIGINT; in the main thread, where SIGINT is not ignored) starts no other trial,
    and the trials running finish and are kept; a second Ctrl-C kills them
    (``trials.stop_all``) and keeps none of them. The trials' processes run in sessions of their
    own (``trials.started``), so the terminal's Ctrl-C reaches them only this way.
    """
    order = {key_of(job): i for i, job in enumerate(jobs)}
    held = {run_key(r): r for r in done if run_key(r) in order}
    todo = list(jobs)
    if shuffle:  # the whole sweep's order, so that a resumed sweep goes on in it
        random.Random(0).shuffle(todo)
    todo = [job for job in todo if key_of(job) not in held]
    began = time.monotonic()
    deadline = None if stop_after is None else began + 60.0 * stop_after

    free: queue.SimpleQueue[int | None] = queue.SimpleQueue()
    width = max(1, workers)
    pinned_to = cores(width)
    pins: list[int | None] = [None] * width if pinned_to is None else [*pinned_to]
    for cpu in pins:
        free.put(cpu)

    interrupted, abandoned, terminated = threading.Event(), threading.Event(), threading.Event()

    def one(job: Job) -> Run | None:
        if interrupted.is_set() or (deadline is not None and time.monotonic() >= deadline):
            return None
        cpu = free.get()  # one per worker: never empty when a worker asks
        try:
            run = trial(job, cpu)
        except Exception:
            if abandoned.is_set():  # killed, or not started, by the second Ctrl-C
                return None
            raise
        finally:
            free.put(cpu)
        if abandoned.is_set():
            return None
        check_started(run)
        book.add(run)
        return run

    def ctrl_c(*_: object) -> None:
        if not interrupted.is_set():  # start no other trial; those running finish and are kept
            interrupted.set()
            print(
                "interrupted: the trials running finish and stay in the journal "
                "(Ctrl-C again stops them now, and keeps none of them)",
                file=sys.stderr,
                flush=True,
            )
        elif not abandoned.is_set():
            abandoned.set()
            killed = trials.stop_all()
            print(f"stopped: {killed} trial(s) running killed, not kept", file=sys.stderr, flush=True)

    def sigterm(*_: object) -> None:
        """As two Ctrl-C: the trials' processes run in sessions of their own, so a SIGTERM that
        ended this process alone left them running, and their folders, behind."""
        terminated.set()
        interrupted.set()
        if not abandoned.is_set():
            abandoned.set()
            killed = trials.stop_all()
            print(f"terminated: {killed} trial(s) running killed, not kept", file=sys.stderr, flush=True)

    trials.allow_starts()
    previous = _handle_sigint(ctrl_c)
    previous_term = _handle_signal(signal.SIGTERM, sigterm)
    pool = ThreadPoolExecutor(max_workers=max(1, workers))
    futures: list[Future[Run | None]] = []
    try:
        futures += (pool.submit(one, job) for job in todo)
        for future in futures:
            # waited for in slices: a signal caught while the main thread is between two waits
            # (a second Ctrl-C during the first one's handler) runs its handler at the next
            # slice, not when the trial ends; a wait it interrupts ends at once either way
            while not future.done():
                wait([future], timeout=WAIT_SLICE)
            future.result()
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
        if previous_term is not None:
            signal.signal(signal.SIGTERM, previous_term)
        book.close()
    ended = [f.result() for f in futures if f.done() and not f.cancelled()]
    new = [run for run in ended if run is not None]
    runs = sorted([*held.values(), *new], key=lambda r: order[run_key(r)])
    pace = (time.monotonic() - began) / max(1, len(new))
    return Progress(runs, len(jobs), pace, interrupted.is_set(), terminated.is_set())


def _handle_sigint(handler: Callable[..., None]) -> Callable[..., object] | int | None:
    """Make ``handler`` SIGINT's and return the handler it replaces; None (nothing set) outside
    the main thread, or where SIGINT is ignored (a shell's background job: Ctrl-C is not ours)."""
    return _handle_signal(signal.SIGINT, handler)


def _handle_signal(
    number: signal.Signals, handler: Callable[..., None]
) -> Callable[..., object] | int | None:
    """Make ``handler`` the signal's and return the handler it replaces; None (nothing set)
    outside the main thread, or where the signal is ignored."""
    if threading.current_thread() is not threading.main_thread():
        return None
    previous = signal.getsignal(number)
    if previous in (signal.SIG_IGN, None):
        return None
    signal.signal(number, handler)
    return previous


PACKAGES = ("fuzzer", "robot_api", "python_impl", "native", "adapters", "benchmarks")
"""The tree's Python packages a trial imports from (``compile_tree``)."""


def compile_tree(root: Path) -> None:
    """Byte-compile the modules of the tree at ``root`` (``PACKAGES``, ``fuzz_diff.py``) before a
    sweep's trials. A trial is a new process importing about 300 of them; where Python writes no
    bytecode (``PYTHONDONTWRITEBYTECODE``, set in this sandbox and in many container images), or
    after an edit, every trial would compile them again: about 0.1 s of its start-up, spent by
    CPython and not by the engine measured, and more for an engine that imports more modules.
    A module is compiled again when its bytecode is missing or ``stale`` as the importer judges
    it (``compileall`` compares the modification second alone, so an edit or a ``git checkout``
    within the second of an earlier compile left bytecode it called fresh and every trial
    compiled the module again: docs/benchmarks-log.md, thirty-ninth session). Files that cannot
    be written are left as they are (Python then compiles in memory)."""
    import contextlib
    import py_compile

    sources = [path for name in PACKAGES for path in sorted((root / name).rglob("*.py"))]
    if (root / "fuzz_diff.py").is_file():
        sources.append(root / "fuzz_diff.py")
    for source in sources:
        if stale(source):  # an unwritable cache folder: the importer compiles in memory
            with contextlib.suppress(OSError):
                py_compile.compile(str(source), doraise=False, quiet=2)


def stale(source: Path) -> bool:
    """Whether the importer would compile ``source`` again rather than load its cached bytecode:
    none, another Python's, or a timestamp header whose source time (whole seconds) or size
    differs from the file's. Hash-checked bytecode (``SOURCE_DATE_EPOCH``) counts as current:
    the importer checks its hash itself."""
    import importlib.util
    import struct

    try:
        with open(importlib.util.cache_from_source(str(source)), "rb") as cached:
            header = cached.read(16)
        status = source.stat()
    except (OSError, ValueError):
        return True
    if len(header) < 16 or header[:4] != importlib.util.MAGIC_NUMBER:
        return True
    flags, mtime, size = struct.unpack("<LLL", header[4:16])
    if flags:
        return False
    return (mtime, size) != (int(status.st_mtime) & 0xFFFF_FFFF, status.st_size & 0xFFFF_FFFF)


def sweep_in_journal(
    parser: argparse.ArgumentParser,
    args: argparse.Namespace,
    path: Path,
    sweep: Sweep,
    root: Path,
    jobs: Sequence[Job],
    trial: Trial,
    tabulate: str,
    shuffle: bool = False,
) -> Progress:
    """A benchmark's sweep through its journal at ``path`` with its command line's ``--resume``,
    ``--restart``, ``--jobs`` and ``--stop-after`` (:func:`open_sweep` on the tree at ``root``,
    :func:`run_sweep`):
    a journal it cannot continue is the parser's error; a sweep that stops with trials left
    says how to go on, and how to tabulate them so far (``tabulate``: the tool's option)."""
    try:
        book, done = open_sweep(path, sweep, root, resume=args.resume, restart=args.restart)
    except JournalError as exc:
        parser.error(str(exc))
    except OSError as exc:
        parser.error(f"{path}: cannot keep the sweep's journal there ({exc.strerror or exc})")
    if done:  # the plan's trials it holds, each once (a line repeated, or of another plan, is not one)
        held = len({run_key(r) for r in done} & {key_of(job) for job in jobs})
        print(f"resuming {path}: {held} of {len(jobs)} trials done")
    compile_tree(root)
    try:
        progress = run_sweep(book, jobs, done, trial, args.jobs, args.stop_after, shuffle)
    except NotStarted as exc:  # the trials ended before it stay in the journal: --resume goes on
        raise SystemExit(f"{exc}; the trials kept so far are in {path}") from None
    if not progress.complete:
        print(progress.stopped(path, args.stop_after, tabulate))
    if progress.terminated:
        raise SystemExit(143)  # as a shell reports a process that SIGTERM ended
    if progress.interrupted:
        raise SystemExit(130)  # as a shell reports a process that SIGINT ended
    return progress
