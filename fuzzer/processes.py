"""libFuzzer's child processes and the end of a campaign.

``-fork``/``-jobs``/``-merge`` re-run ``fuzz_diff.py`` in child processes. This
module holds what the parent and its children agree on: the time budget of a
``-fork`` campaign (its children stop at the parent's deadline, since libFuzzer
checks ``-max_total_time`` only between jobs and merges), the paths a ``-jobs``
campaign makes absolute before it moves into its artifacts folder, and the
campaign's exit status from what it wrote; and a forked child with a time budget
(``DryRun``, the dry run's, ``fuzzer.dry_run``).
"""

from __future__ import annotations

import contextlib
import math
import os
import select
import signal
import sys
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from fuzzer.artifacts.store import derived, oversized, sidecar_path
from fuzzer.execution.records import UNCOUNTED
from fuzzer.input import untrusted_json

CHILD_ENV = "RROSFUZZ_CHILD"
DEADLINE_ENV = "RROSFUZZ_DEADLINE"
"""Set by a -fork campaign for its children: the epoch second at which -max_total_time ends."""
SUPERVISOR_ENV = "RROSFUZZ_SUPERVISOR"
"""Set by a campaign's first process for the processes libFuzzer starts: its pid."""
TIMEOUT_EXIT = 70
"""libFuzzer's -timeout_exitcode default."""
OOM_EXIT = 71
"""libFuzzer's status after an out-of-memory (``-rss_limit_mb``; no flag sets it)."""
ERROR_EXIT = 77
"""libFuzzer's -error_exitcode default: a deadly signal, or ``--stop-on-divergence``."""
PATH_FLAGS = (
    "-dict",
    "-exact_artifact_path",
    "-artifact_prefix",
    "-merge_control_file",
    "-features_dir",
    "-stop_file",
    "-data_flow_trace",
)
"""libFuzzer flags naming a path: made absolute when -jobs moves the campaign into its artifacts."""


def deadline() -> float | None:
    """The end of a -fork campaign's time budget, in a child process (None elsewhere)."""
    if os.environ.get(CHILD_ENV) != "1":
        return None
    try:
        value = float(os.environ.get(DEADLINE_ENV, ""))
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def one_campaign(flags: tuple[str, ...]) -> bool:
    """Whether this process runs the campaign itself: not a ``-jobs``/``-fork`` supervisor (its
    main thread stays in libFuzzer, where no Python signal handler runs), not their worker,
    not a merge or a crash's minimization (``SINGLE_RUN_FLAGS``)."""
    return (
        not supervises(flags)
        and os.environ.get(CHILD_ENV) != "1"
        and not any(int_flag(flags, name, 0) != 0 for name in SINGLE_RUN_FLAGS)
    )


def supervises(flags: tuple[str, ...]) -> bool:
    """Whether libFuzzer runs this campaign in child processes (-fork, -jobs)."""
    return any(int_flag(flags, name, 0) > 0 for name in ("-fork", "-jobs"))


SINGLE_RUN_FLAGS = ("-merge", "-set_cover_merge", "-minimize_crash", "-cleanse_crash", "-minimize_corpus")
"""libFuzzer flags that run no campaign of random choices (a merge, a crash's minimization)."""


def drawn_seed(flags: tuple[str, ...], corpus: tuple[Path, ...]) -> tuple[tuple[str, ...], int | None]:
    """``flags`` with a ``-seed`` drawn from the OS for a campaign of one process given none, or
    ``-seed=0`` (libFuzzer's "draw one from the clock"), and the seed drawn (None when none was).

    libFuzzer draws such a seed itself, and ``-verbosity=0`` hides it: the campaign could not be
    repeated. Drawn here, it is printed and passed on; the harness's own seed (``--seed``, else
    the ``-seed`` given, else 0) stays as it was, so ``-seed=N --seed=S`` repeats the campaign's
    choices (docs/engine.md, "Reproducing a campaign"). Left to libFuzzer: ``-jobs`` and
    ``-fork`` (one ``-seed`` for every job would run the same choices in each), their workers
    (``CHILD_ENV``), merges and a crash's minimization (``SINGLE_RUN_FLAGS``), and files among
    the corpus (libFuzzer runs them).
    """
    given = flag_value(flags, "-seed")
    if given is not None and (not given.isdigit() or int(given) != 0):
        return flags, None
    if supervises(flags) or os.environ.get(CHILD_ENV) == "1" or any(p.is_file() for p in corpus):
        return flags, None
    if any(int_flag(flags, name, 0) != 0 for name in SINGLE_RUN_FLAGS):
        return flags, None
    seed = 1 + int.from_bytes(os.urandom(4), "little") % (2**31 - 1)
    return (*(f for f in flags if f.partition("=")[0] != "-seed"), f"-seed={seed}"), seed


def libfuzzer_seed(flags: tuple[str, ...]) -> int | None:
    """libFuzzer's ``-seed`` among ``flags`` (``drawn_seed`` has put one there for a campaign of
    one process), None when libFuzzer draws its own (absent, 0 or not a number: a ``-jobs``
    campaign, say; a ``-fork`` job gets its own from its parent)."""
    value = flag_value(flags, "-seed")
    return int(value) if value is not None and value.isdigit() and int(value) > 0 else None


def is_number(text: str) -> bool:
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def int_flag(flags: tuple[str, ...], name: str, default: int) -> int:
    value = flag_value(flags, name)
    return int(value) if value is not None and value.lstrip("-").isdigit() else default


@dataclass(frozen=True)
class Found:
    """Files written into the artifacts folder since a campaign started."""

    divergences: list[Path]
    """Crash files with a sidecar: divergences (not the kinds in ``NOT_FINDINGS``)."""
    crashes: list[Path]
    """libFuzzer's crash-/oom-/leak- files without a sidecar: the targets crashed."""
    timeouts: list[Path]
    explained: list[Path] = field(default_factory=list)
    """Crash files with a sidecar of a kind in ``NOT_FINDINGS``: written for triage, not findings."""

    def explained_kinds(self) -> Counter[str]:
        """How many of ``explained`` each kind has."""
        return Counter(_sidecar_kind(sidecar_path(path)) or "unreadable" for path in self.explained)

    def with_recovered(self, recovered: list[Path]) -> Found:
        """With crash files an interrupted run had claimed (completed by this one: new to the
        user), each sorted by its sidecar's kind like the others."""
        explained = [p for p in recovered if _sidecar_kind(sidecar_path(p)) in NOT_FINDINGS]
        findings = [p for p in recovered if p not in explained]
        return Found(
            sorted({*self.divergences, *findings}),
            self.crashes,
            self.timeouts,
            sorted({*self.explained, *explained}),
        )


NOT_FINDINGS = frozenset(str(kind) for kind in UNCOUNTED)
"""Kinds that are written as crash files for triage but do not make a campaign fail: a
documented limitation of a target, and IK seeds where the answer is chaotic (docs/engine.md)."""


def _sidecar_kind(path: Path) -> str | None:
    """The divergence kind a sidecar records (None when it cannot be read: counted as a finding)."""
    if oversized(path):
        return None  # no reader accepts it
    try:
        data = untrusted_json.loads(path.read_bytes())
    except (OSError, ValueError, RecursionError):
        return None
    signature = data.get("signature") if isinstance(data, dict) else None
    kind = signature.get("kind") if isinstance(signature, dict) else None
    return kind if isinstance(kind, str) else None


def new_artifacts(directory: Path, since: float) -> Found:
    divergences, crashes, timeouts, explained = [], [], [], []
    for path in sorted(directory.iterdir()) if directory.is_dir() else ():
        name = path.name
        if derived(path) or not path.is_file():  # a sidecar, an exported bag
            continue
        try:
            if path.stat().st_mtime < since:
                continue
        except OSError:
            continue
        if name.startswith("timeout-"):
            timeouts.append(path)
        elif name.startswith("crash-") and sidecar_path(path).is_file():
            if _sidecar_kind(sidecar_path(path)) in NOT_FINDINGS:
                explained.append(path)
            else:
                divergences.append(path)
        elif name.startswith(("crash-", "oom-", "leak-")):
            crashes.append(path)
    return Found(divergences, crashes, timeouts, explained)


def exit_status(
    status: int | None,
    found: Found,
    supervisor: bool,
    timeout_code: int = TIMEOUT_EXIT,
    error_code: int = ERROR_EXIT,
) -> int:
    """The campaign's exit status, given the one libFuzzer exits with.

    libFuzzer's own non-zero status (a crash, a timeout, a -fork job's status) is kept.
    Otherwise: for a -fork/-jobs supervisor whose workers left crash, oom or timeout files
    (libFuzzer's fork mode ignores timeouts and out-of-memories by default, and crashes with
    ``-ignore_crashes=1``), what one process would have exited with (:func:`failed_job_status`:
    a campaign of 12 crash files exited 0, "no new divergence"); 1 if new divergences were
    written, else 0.
    """
    if status:
        return status
    if supervisor and (found.crashes or found.timeouts):
        return failed_job_status(found, False, timeout_code, error_code)
    return 1 if found.divergences else 0


def failed_job_status(found: Found, stop_on_divergence: bool, timeout_code: int, error_code: int) -> int:
    """What a ``-jobs`` supervisor's status 1 (libFuzzer's: some job ended non-zero) stands for,
    from what the jobs left in the artifacts folder, as one process would have ended: a target
    that died (a crash- or leak- file without a sidecar), or a divergence under
    ``--stop-on-divergence``: ``error_code``; an out-of-memory (an oom- file): :data:`OOM_EXIT`;
    a timeout: ``timeout_code``; none of these (a job's usage error, an out-of-memory before its
    first input, a job killed): 1, which the summary explains."""
    died = any(not path.name.startswith("oom-") for path in found.crashes)
    if died or (stop_on_divergence and found.divergences):
        return error_code
    if found.crashes:
        return OOM_EXIT
    if found.timeouts:
        return timeout_code
    return 1


def flag_value(flags: tuple[str, ...], name: str) -> str | None:
    """The value of libFuzzer flag ``name`` among ``flags``: its last occurrence, the one libFuzzer
    keeps (each ``-name=value`` it parses overwrites the one before); None when absent."""
    for flag in reversed(flags):
        key, _, value = flag.partition("=")
        if key == name:
            return value
    return None


def absolute_flag(flag: str) -> str:
    name, sep, value = flag.partition("=")
    if sep and value and name in PATH_FLAGS:
        slash = "/" if value.endswith("/") else ""
        return f"{name}={os.path.abspath(value)}{slash}"
    if sep and value and name == "-seed_inputs" and not value.startswith("@"):
        return f"{name}={','.join(os.path.abspath(v) for v in value.split(','))}"
    if sep and value.startswith("@") and name == "-seed_inputs":
        return f"{name}=@{os.path.abspath(value[1:])}"
    return flag


def absolute_option(option: str) -> str:
    """--robot=<file> and --msg-path=<folder> made absolute (a robot name stays a name)."""
    name, sep, value = option.partition("=")
    if sep and name in ("--robot", "--msg-path") and os.path.exists(value):
        return f"{name}={os.path.abspath(value)}"
    return option


KILL_GRACE = 2.0
"""Seconds past the child's budget before ``DryRun.wait`` kills a child that outlived its alarm
(one that ignores ``SIGALRM``)."""


class DryRun:
    """A child process that evaluates a stage's inputs (``start``), and its end (``wait``)."""

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
            if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:  # not the campaign's deferral:
                signal.signal(signal.SIGINT, signal.default_int_handler)  # a Ctrl-C ends it at once
            signal.alarm(max(1, math.ceil(budget)))
            work()
            code = 0
        finally:
            os._exit(code)

    def stop(self) -> None:
        """End the child now (``SIGKILL``) and reap it: the campaign stopped before libFuzzer
        started (a usage error after the fork), and the child's inputs are nobody's any more."""
        if self.status is not None:
            return
        with contextlib.suppress(ProcessLookupError):
            os.kill(self.pid, signal.SIGKILL)
        try:
            _, self.status = os.waitpid(self.pid, 0)
        except ChildProcessError:  # reaped elsewhere (a SIGCHLD handler)
            self.status = 0

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


def launch(work: Callable[[], object], budget: float) -> DryRun | None:
    """Start a dry-run child that runs ``work`` within ``budget`` seconds (``DryRun.start``).

    On a single CPU (``os.sched_getaffinity``: a pinned process) the campaign waits for the
    child before it goes on: sharing one CPU would slow both, and the scheduler would let the
    new child wait for a time slice while the campaign starts up, for nothing."""
    dry = DryRun.start(work, budget)
    if dry is not None and _cpus() == 1:
        dry.wait()
    return dry


def _cpus() -> int:
    """The CPUs this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1
