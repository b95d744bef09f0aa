"""How a campaign ends on a signal, in each of its processes.

libFuzzer's main loop runs Python only in the test callback and the custom mutator, and
Python raises ``KeyboardInterrupt`` wherever it runs next: in Hypothesis' garbage-collector
callback (where Python ignores it: the Ctrl-C was lost), in the mutator, or in a ``-jobs``
worker's start-up (where it escaped ``atheris.Fuzz``, and the worker died in libFuzzer's
"deadly signal" handler, leaving an empty crash file). Once libFuzzer is about to run (in a
worker, from its start), a SIGINT or SIGTERM is therefore kept for the start of the next input
(``defer_to_next_input``, ``stop_requested``), where a campaign of one process ends as after
Ctrl-C, and a worker with libFuzzer's ``-interrupted_exitcode`` (``INTERRUPTED_EXIT``), on which
a ``-fork`` parent stops its other jobs; a second Ctrl-C, or a second SIGTERM, acts at once.

A ``-jobs``/``-fork`` supervisor runs its jobs through ``system()``, which ignores SIGINT in
the caller while a job runs: only a Ctrl-C to the whole process group (a terminal's, or
``timeout -s INT``'s) reaches the jobs. The supervisor learns of it from its workers' last
snapshots (``interrupted``) and exits 130 (``INT_EXIT``). A SIGTERM to the supervisor is passed
on to its jobs (``forward_term_to_jobs``), and it exits 143 with its summary.
"""

from __future__ import annotations

import os
import select
import signal
import threading

from fuzzer.processes import SUPERVISOR_ENV

INT_EXIT = 128 + signal.SIGINT
"""A campaign ended by SIGINT (Ctrl-C): the shell's status for it, with the summary printed."""
TERM_EXIT = 128 + signal.SIGTERM
"""A campaign ended by SIGTERM: the shell's status for it, with the summary printed."""
INTERRUPTED_EXIT = 72
"""libFuzzer's ``-interrupted_exitcode`` default: a worker ended by a signal exits with it."""

_TERMINATED: list[bool] = []
_PENDING: list[int] = []  # signals kept for the start of the next input
_DEFERRING: list[bool] = []


def on_signal(signum: int, _frame: object) -> None:
    """The handler of SIGTERM in a campaign of one process (``processes.one_campaign``), and of
    SIGINT once libFuzzer is about to run. Before that, a ``KeyboardInterrupt`` where Python
    runs next; after, kept for the next input (``stop_requested``), but a second SIGINT, or a
    second SIGTERM (a service manager's stop, repeated), acts at once (a target that does not
    return). A SIGTERM makes the status ``TERM_EXIT``
    (``terminated``): libFuzzer's own handler (``-handle_term``) ended it with ``_Exit(72)``,
    no summary, no last snapshot."""
    if signum == signal.SIGTERM:
        _TERMINATED.append(True)
    if _DEFERRING and signum not in _PENDING:  # the second of a kind: at once
        _PENDING.append(signum)
        return
    raise KeyboardInterrupt  # Atheris ends the campaign as after Ctrl-C (any other class: a crash)


def defer_to_next_input() -> None:
    """From here on, SIGINT and SIGTERM (where ``on_signal`` handles it) end the campaign at
    the start of the next input. Python's own SIGINT handler is replaced; one set by the
    caller, or SIGINT ignored (a background job), is left as it is."""
    _DEFERRING.append(True)
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, on_signal)


WATCHER = """
import os, select, signal, sys
fd, parent, term = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
for ignored in (signal.SIGINT, signal.SIGTERM):
    signal.signal(ignored, signal.SIG_IGN)

def children():
    for entry in os.listdir("/proc"):
        if entry.isdigit() and int(entry) != os.getpid():
            try:
                with open(f"/proc/{entry}/stat") as handle:
                    if int(handle.read().rsplit(")", 1)[1].split()[1]) == parent:
                        yield int(entry)
            except (OSError, ValueError, IndexError):
                pass

told = None
while True:
    ready, _, _ = select.select([fd], [], [], 0.2 if told is not None else None)
    if ready:
        try:
            data = os.read(fd, 64)
        except InterruptedError:
            continue
        if not data:
            break
        if term in data and told is None:
            told = set()
    if told is not None:
        for pid in set(children()) - told:
            told.add(pid)
            try:
                os.kill(pid, term)
            except OSError:
                pass
"""
"""The supervisor's SIGTERM forwarder (:func:`forward_term_to_jobs`), run as ``python -c``."""


def forward_term_to_jobs() -> None:
    """In a ``-jobs``/``-fork`` supervisor about to enter libFuzzer (run with ``-handle_term=0``):
    a SIGTERM is passed on to its jobs, which end at their next input with their last snapshots
    (``on_signal``), and is kept for the supervisor's end, whose summary then says "terminated"
    (143). libFuzzer's own handler ended the supervisor with ``_Exit`` and no summary, and its
    jobs with ``_Exit(72)`` and no last snapshot (their counts lost).

    The supervisor's main thread stays in libFuzzer with the GIL held, so no Python code of it
    runs there, not even another thread: the interpreter's C-level handler writes the signal's
    number to a wakeup pipe, and a small process started here (:data:`WATCHER`) reads it and
    sends SIGTERM to the supervisor's children, and to each child started after it, once (libFuzzer
    went on starting the jobs waiting for a worker, and a -fork parent its next job after a hung
    one's timeout: they ran to -max_total_time, or for good). It ends when the supervisor does
    (the pipe closes)."""
    import subprocess
    import sys

    read, write = os.pipe()
    os.set_blocking(write, False)
    try:
        subprocess.Popen(
            [sys.executable, "-S", "-c", WATCHER, str(read), str(os.getpid()), str(int(signal.SIGTERM))],
            pass_fds=(read,),
            stdin=subprocess.DEVNULL,
            start_new_session=True,  # a terminal's Ctrl-C, a timeout's group signal: not for it
        )
    except OSError:
        os.close(write)
        return  # no forwarder: libFuzzer's jobs end with the supervisor (end_with_supervisor)
    finally:
        os.close(read)
    signal.set_wakeup_fd(write, warn_on_full_buffer=False)
    _DEFERRING.append(True)  # from here, on_signal keeps a SIGTERM for the supervisor's end


def stop_requested() -> bool:
    """Whether a signal kept by ``on_signal`` is waiting (checked at the start of each input)."""
    return bool(_PENDING)


def terminated() -> bool:
    """Whether this process has had a SIGTERM (``on_signal``)."""
    return bool(_TERMINATED)


def end_with_supervisor() -> None:
    """In a process libFuzzer started (a ``-jobs``/``-fork`` worker, a merge's inner run:
    ``CHILD_ENV``), end (``SIGTERM`` to itself) when the campaign's first process
    (``SUPERVISOR_ENV``) is gone. libFuzzer's supervisor ends on ``SIGTERM`` without ending its
    workers (started through ``system()``, each under a shell of its own): a ``kill PID`` or CI's
    ``timeout`` left them fuzzing with no end. A thread waits on a pidfd of the supervisor (the
    process itself, not a reused pid); without pidfds (not Linux) nothing is watched."""
    try:
        pid = int(os.environ.get(SUPERVISOR_ENV, ""))
    except ValueError:
        return
    try:
        fd = os.pidfd_open(pid)
    except ProcessLookupError:  # gone before this process got here
        os.kill(os.getpid(), signal.SIGTERM)
        return
    except (AttributeError, OSError):
        return

    def watch() -> None:
        select.select([fd], [], [])
        os.kill(os.getpid(), signal.SIGTERM)

    threading.Thread(target=watch, name="rrosfuzz-supervisor", daemon=True).start()
