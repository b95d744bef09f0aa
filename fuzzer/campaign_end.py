"""How a campaign ends: its exit status and its summary, made once, however the process ends.

``fuzzer.campaign.run`` hands a :class:`CampaignEnd` to ``fuzzer.exit_hook.on_exit``, which
calls it with libFuzzer's status (``-max_total_time``, ``-runs``, the end of ``-fork``), with the
status the campaign chose itself (an unwritable artifacts folder, an interrupted worker, a
``-jobs`` supervisor's ``SystemExit``), or with None where Python ends the process (Atheris after
an exception of a target, Ctrl-C). It answers the status the process should end with
(``processes.exit_status``; docs/engine.md, "Exit status").
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fuzzer import dry_run, reporting
from fuzzer.artifacts.divlog import worker_totals
from fuzzer.artifacts.store import WRITE_FAILED_EXIT, ArtifactStore, ArtifactsUnwritable
from fuzzer.execution import guard
from fuzzer.processes import ERROR_EXIT, Found, exit_status, failed_job_status, int_flag, new_artifacts
from fuzzer.signals import INT_EXIT, TERM_EXIT, stop_requested, terminated

if TYPE_CHECKING:
    from fuzzer.campaign import CampaignOptions
    from fuzzer.harness import Harness
    from fuzzer.selection.guidance import Features

USAGE_EXIT = 2
"""A usage error's status (``fuzzer.cli``)."""
LIBFUZZER_ERROR = "libFuzzer stopped with an error: its message above says which"
"""What a campaign's status 2 means when libFuzzer itself ended it with its status 1 (an
``-artifact_prefix`` folder that is not there, a merge's control file it cannot write,
``-minimize_crash`` on an input that does not crash): the status a campaign gives new divergences,
which it had found none of."""
JOB_FAILED = "a job failed: its fuzz-N.log in the artifacts folder says why"
"""What a ``-jobs`` supervisor's status 1 means when no file its jobs left explains it
(``processes.failed_job_status``: libFuzzer's 1 for a job that ended with a non-zero status)."""


CORPUS_GONE = "a corpus folder is gone: the inputs libFuzzer added to it were lost"

PROBE_BYTES = 4096
"""What a supervisor writes (and removes) to see whether its artifacts folder still takes files."""


@dataclass
class CampaignEnd:
    """The state a campaign's end reads, and the call that ends it.

    The two flags are set by the campaign's input callback: ``in_callback`` while an input is
    being evaluated (an end from there is Atheris reporting a target's exception), ``unwritable``
    once the artifacts folder could not be written (said once, when it happened).
    """

    options: CampaignOptions
    harness: Harness
    features: Features
    progress: reporting.Progress
    store: ArtifactStore
    artifacts: Path
    """The artifacts folder, resolved (a ``-jobs`` supervisor changes its working folder)."""
    started: float
    """When the campaign started (s since the epoch): crash files since then are this run's."""
    child: bool
    supervisor: bool
    timeout_code: int
    interrupted: int
    """libFuzzer's ``-interrupted_exitcode``: a worker's status after Ctrl-C."""
    single_run: bool = False
    """A merge or a crash's minimization (``processes.SINGLE_RUN_FLAGS``): its inner processes ran
    the inputs, and the summary adds up their counts as a supervisor's (it said "executions: 0"
    beside new crash files)."""
    dry: dry_run.Stages | None = None
    leftovers: list[Path] = field(default_factory=list)
    """Written-ahead inputs found at the start (``guard.leftovers``), settled by a normal end."""
    in_callback: bool = False
    unwritable: bool = False
    reason: str | None = None
    """What ended the campaign, when not libFuzzer nor a signal (the summary's exit line says it)."""
    corpus: tuple[Path, ...] = field(init=False)
    """The corpus folders, resolved when the campaign's end is set up (before a ``-jobs``
    supervisor changes its working folder): one gone at the end (removed or renamed meanwhile)
    took the inputs libFuzzer added with it, its writes failing without a word."""

    def __post_init__(self) -> None:
        self.corpus = tuple(p.resolve() for p in self.options.corpus if p.is_dir())

    def __call__(self, status: int | None) -> int | None:
        """End the campaign: the last snapshot, the dry run's children, the summary; returns the
        status the process should end with (None: keep libFuzzer's or Atheris')."""
        self.progress.close()
        if self.harness.stats.execs and not self.unwritable:
            try:
                self.harness.maybe_snapshot(force=True)
            except ArtifactsUnwritable:  # said; the crash files written before are this run's
                self.unwritable = True
        status = self._signalled(WRITE_FAILED_EXIT if self.unwritable and not status else status)
        found = self._found()
        spawned = self.supervisor or self.single_run
        totals = worker_totals(self.artifacts, self.started, os.getpid()) if spawned else None
        dry = None if self.dry is None else worker_totals(self.artifacts, self.started, pids=self.dry.pids)
        stopped = status == self.interrupted or (totals or {}).get("interrupted")
        job_failed = refused = False
        if status == 1 and not self.supervisor and not (found.divergences or found.crashes or found.timeouts):
            status, refused = USAGE_EXIT, True  # libFuzzer's own error (exit(1)): no divergence of ours
        elif self.supervisor and not terminated() and stopped:
            status = INT_EXIT  # libFuzzer's is 1 for -jobs (a job's status), 72 for -fork
        error_code = int_flag(self.options.libfuzzer_flags, "-error_exitcode", ERROR_EXIT)
        if not refused and self._jobs() and status == 1:  # a job ended non-zero: as one process would
            status = failed_job_status(found, self.options.stop_on_divergence, self.timeout_code, error_code)
            job_failed = True
        code: int | None = exit_status(status, found, self.supervisor, self.timeout_code, error_code)
        if status is None and (self.in_callback or found.crashes or found.timeouts):
            # Atheris ending the process: an exception in the target (libFuzzer reports it as a
            # crash next), or a -jobs run whose failed job set libFuzzer's status
            code = None
        if self.child:
            return None  # a worker's status is libFuzzer's business (its parent reads it)
        gone = False
        for folder in self.corpus:
            if not folder.is_dir():
                reporting.error(
                    f"corpus folder {folder} is gone (removed or renamed during the campaign): the "
                    "inputs libFuzzer added to it this run are lost"
                )
                gone = True
                if code in (0, 1):
                    code = WRITE_FAILED_EXIT
        full = None
        if self.supervisor and code in (1, WRITE_FAILED_EXIT) and not self.unwritable:
            full = self._artifacts_problem()  # a job's write failed there: the supervisor said "1"
            if full is not None:
                code = WRITE_FAILED_EXIT
        if code in (0, 1) and self.leftovers:  # libFuzzer ran them as seeds, and they did no harm
            for path in guard.settle(self.leftovers):
                reporting.info(f"{path}: the input a campaign died on ran as a seed, harmless now; kept")
        meaning = self._job_meaning(code, found) if job_failed else (LIBFUZZER_ERROR if refused else None)
        meaning = self.reason or meaning
        if full is not None:
            meaning = (
                f"the artifacts folder {self.options.artifacts} cannot be written ({full}): a job's "
                "divergences may be lost (its log says which)"
            )
        elif code == WRITE_FAILED_EXIT and not self.unwritable and (meaning is None or job_failed):
            meaning = CORPUS_GONE if gone else "a folder could not be written, in a job: its log says which"
        shown = code
        if code is None and status is None and self.in_callback:
            shown = error_code  # libFuzzer's status for the exception it reports next (--stop-on-divergence)
        self._summary(found, totals, shown, meaning, dry)
        return code

    def _artifacts_problem(self) -> str | None:
        """Why the artifacts folder takes no file now (a full disk, a read-only mount), or None:
        what a supervisor, which learns only that a job ended non-zero, can see of a job's
        failed write (a full disk ended both -jobs jobs with 74, and the campaign with 1)."""
        try:
            with tempfile.NamedTemporaryFile(dir=self.artifacts, prefix=".tmp-probe-") as handle:
                handle.write(bytes(PROBE_BYTES))
                handle.flush()
                os.fsync(handle.fileno())
        except OSError as exc:
            return exc.strerror or str(exc)
        return None

    def _jobs(self) -> bool:
        """Whether this process is a ``-jobs`` supervisor."""
        return self.supervisor and int_flag(self.options.libfuzzer_flags, "-jobs", 0) > 0

    @staticmethod
    def _signalled(status: int | None) -> int | None:
        """``status``, or the status of a SIGTERM or a Ctrl-C the campaign kept (fuzzer.signals)."""
        if terminated():
            return TERM_EXIT  # Atheris ends it as after Ctrl-C (130)
        if stop_requested():
            return INT_EXIT  # a Ctrl-C kept for an input's start: Atheris ends it, status unknown here
        return status

    def _found(self) -> Found:
        """This run's crash, timeout and divergence files, the dry run's and recovered ones included."""
        if self.dry is not None:
            self.dry.wait()
        if self.dry is not None or self.supervisor:
            # the dry run's crash files are this run's, even one it died writing; so are those of
            # a -jobs worker killed in its write window (its signature's marker hid the finding)
            self.store.recovered = [*self.store.recovered, *self.store.recover()]
        found = new_artifacts(self.artifacts, self.started)
        if self.store.recovered:  # completed for a killed run that never reported them: new to the user
            found = found.with_recovered([self.artifacts / name for name in self.store.recovered])
        return found

    @staticmethod
    def _job_meaning(code: int | None, found: Found) -> str | None:
        """What a ``-jobs`` supervisor's status says when one of its jobs ended non-zero."""
        if code is None:
            return None
        if code == 1:  # libFuzzer's 1, which nothing the jobs left explains
            return f"new divergences found; {JOB_FAILED}" if found.divergences else JOB_FAILED
        return f"{reporting.meaning_of(code)}, in a job: its fuzz-N.log in the artifacts folder says more"

    def _summary(
        self,
        found: Found,
        totals: dict[str, Any] | None,
        code: int | None,
        meaning: str | None,
        dry: dict[str, Any] | None = None,
    ) -> None:
        """The end-of-campaign report, files named as the user named the artifacts folder."""

        def shown(path: Path) -> str:
            return str(self.options.artifacts / path.name)

        reporting.summary(
            self.harness.stats,
            len(self.features.seen),
            str(self.options.artifacts),
            [str(c) for c in self.options.corpus],
            [shown(p) for p in found.divergences],
            totals=totals,
            timeouts=[shown(p) for p in found.timeouts],
            crashes=[shown(p) for p in found.crashes],
            explained=found.explained_kinds(),
            exit_code=code,
            exit_meaning=meaning,
            dry_run=dry,
        )
