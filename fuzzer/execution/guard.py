"""One input evaluated in the campaign's own process before libFuzzer starts, under the guards a
child process or libFuzzer would give it: the dry run's first input (``fuzzer.dry_run``).

The dry run evaluates its inputs in children (``fuzzer.processes.DryRun``), so that an input
that kills or hangs the targets cannot take the campaign with it. For the first input that
isolation costs what a one-call bug's detection is decided by: the fork, the child's set-up and
its copy-on-write faults, 5-7 ms (BENCHMARKS.md, "Paired A/B"). ``guarded`` evaluates that one
input in the campaign's process instead, as libFuzzer evaluates its own seeds, with:

* **the input written ahead**: before the evaluation, into the campaign's first corpus folder as
  ``first-input-<sha1>``, removed once the evaluation returns (or raises). If the process dies
  meanwhile (a deadly signal, or the hang guard's last resort), the file stays: a rerun of the
  same command finds it among the seeds (and says so, ``leftovers``), libFuzzer runs it and
  reports it as it reports any crash or timeout, and no input is evaluated in process while
  such a file is there; a campaign that then ends normally renames it to its SHA-1 (``settle``):
  it ran as a seed without a crash;
* **a hang guard**: ``SIGALRM`` after ``budget`` seconds (libFuzzer's ``-timeout``) writes the
  input as ``timeout-<sha1>`` to the artifacts folder, as libFuzzer does, says so, and ends the
  campaign with libFuzzer's timeout exit code; a target that never returns to the interpreter
  (a loop in compiled code holding the GIL) is ended ``GRACE`` seconds later by
  ``faulthandler``'s watchdog thread, which needs no GIL (it prints where each thread was),
  leaving the written-ahead file.

The guard costs about 0.2 ms (a file written and removed, a timer and the watchdog thread
started and stopped).
"""

from __future__ import annotations

import contextlib
import errno
import faulthandler
import hashlib
import os
import signal
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from fuzzer import reporting
from fuzzer.artifacts.store import atomic_write

PENDING = "first-input-"
"""Name prefix of a written-ahead input in a corpus folder."""

GRACE = 1.0
"""Seconds after ``budget`` at which the watchdog ends a process the ``SIGALRM`` handler could not
(the interpreter never regained control)."""


def leftovers(folders: Sequence[Path]) -> list[Path]:
    """Written-ahead inputs (``PENDING``) left in ``folders`` by a campaign that died while it
    evaluated them, as absolute paths: a ``-jobs`` supervisor changes into the artifacts folder
    before ``settle``, where a relative corpus path led nowhere and the file was never renamed."""
    found: list[Path] = []
    for folder in folders:
        with contextlib.suppress(OSError):
            found += sorted(
                p.absolute() for p in folder.iterdir() if p.name.startswith(PENDING) and p.is_file()
            )
    return found


def settle(left: Sequence[Path]) -> list[Path]:
    """Written-ahead inputs a campaign found (``leftovers``) and libFuzzer then ran as seeds, the
    campaign ending normally (statuses 0 and 1): kept in the corpus under libFuzzer's own name,
    the SHA-1 of their bytes, so that the next campaign evaluates its first input in process
    again (a leftover stayed for good, and with it the warning). Returns the files kept."""
    kept: list[Path] = []
    for path in left:
        with contextlib.suppress(OSError):
            target = path.with_name(path.name.removeprefix(PENDING))
            if target.exists():
                path.unlink()
            else:
                path.rename(target)
            kept.append(target)
    return kept


def write_ahead(corpus: Path, data: bytes) -> Path:
    """Write ``data`` into the corpus folder ``corpus`` as ``first-input-<sha1>`` (``PENDING``),
    before it is evaluated; returns the file (``guarded`` removes it).

    Raises
    ------
    OSError
        It could not be written.
    """
    if not corpus.is_dir():  # gone (atomic_write would make it again)
        raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), str(corpus))
    pending = corpus / f"{PENDING}{hashlib.sha1(data).hexdigest()}"
    # written whole and renamed over the name (no fsync: it is made again if lost): a link or
    # FIFO planted under that predictable name is replaced, never followed or opened
    atomic_write(pending, data, durable=False)
    return pending


@contextlib.contextmanager
def guarded(pending: Path, data: bytes, artifacts: Path, budget: float, timeout_code: int) -> Iterator[None]:
    """Run the ``with`` block (the evaluation of ``data``) in this process under the hang guard,
    and remove ``pending`` (``write_ahead``'s file) when it ends (see the module docstring).
    The main thread only (``signal``).

    Parameters
    ----------
    pending : Path
        ``write_ahead(corpus, data)``.
    data : bytes
        The input's encoding, as libFuzzer would hand it over.
    artifacts : Path
        Where the ``timeout-`` file goes.
    budget : float
        Seconds (> 0) before the input counts as a hang: libFuzzer's ``-timeout``.
    timeout_code : int
        The exit code of a hang (``-timeout_exitcode``).
    """
    digest = hashlib.sha1(data).hexdigest()

    def on_alarm(signum: int, frame: Any) -> None:
        target = artifacts / f"timeout-{digest}"
        with contextlib.suppress(OSError):
            target.write_bytes(data)
        reporting.warn(
            f"timeout: the dry run's first input ran past {budget:g} s (-timeout) in the campaign's "
            f"process; written to {target}"
        )
        with contextlib.suppress(OSError):
            pending.unlink()
        os._exit(timeout_code)

    previous = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, budget)
    faulthandler.dump_traceback_later(budget + GRACE, exit=True)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous if previous is not None else signal.SIG_DFL)
        with contextlib.suppress(OSError):
            pending.unlink()
