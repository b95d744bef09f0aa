"""Replaying a crash file in a child process, so that one that kills its process is reported.

A crash file a target died on (libFuzzer's, without a sidecar: an abort, a segfault) killed the
``replay`` command with it: exit 134 and no word, not even of the file, and a folder's other files
never replayed. Each file is now replayed in a child forked from the command's process (the
session, its targets loaded, opened there first and shared by the fork); the child sends its
verdict back as JSON through a pipe. A child killed by a signal is a verdict of its own: the file
crashes the replaying process, which is a divergence reproduced (exit 1).

Targets in ROS nodes (``--transport ros``) are replayed in the process itself: a fork would share
rospy's threads and connections.
"""

from __future__ import annotations

import contextlib
import ctypes
import json
import os
import select
import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fuzzer.execution.session import ConfigError, RunConfig, Session
from fuzzer.triage.replay import Replay, config_for, replay_file, session_for

CRASHES = "crashes the replaying process"
"""The verdict of a file whose replay killed its process."""

ENDS = "ends the replaying process"
"""The verdict of a file on which a target ended the process (``exit()``: it was a usage error)."""

HANGS = "hangs the replaying process"
"""The verdict of a file whose replay gave no verdict in :data:`REPLAY_SECONDS`."""

REPLAY_SECONDS = 60.0
"""The longest a file's replay may take (s): a hanging target made ``replay`` wait for good.
Three times libFuzzer's default ``-timeout``, which a campaign's input, oracle included, has."""

CRASH_SIGNALS = {signal.SIGABRT, signal.SIGSEGV, signal.SIGBUS, signal.SIGFPE, signal.SIGILL}
"""Signals a target's own crash raises; any other came from outside (a kill, the OOM killer)."""

try:
    _prctl: Any = ctypes.CDLL(None, use_errno=True).prctl  # resolved here: no dlopen after fork
except (OSError, AttributeError):  # not Linux
    _prctl = None
PR_SET_PDEATHSIG = 1


@dataclass(frozen=True)
class Verdict:
    """What ``replay`` prints of one file (``Replay``'s fields it uses, as the child sent them)."""

    result: str
    detail: str
    steps: tuple[str, ...]
    has_sidecar: bool
    diverges: bool

    @classmethod
    def of(cls, replay: Replay) -> Verdict:
        return cls(str(replay.result), replay.detail, replay.steps, replay.has_sidecar, replay.diverges)


def replay_isolated(
    path: Path, base: RunConfig, given: dict[str, Any], sessions: dict[RunConfig, Session], trust: bool
) -> Verdict:
    """Replay ``path`` as ``replay_file`` does, in a child process.

    Raises
    ------
    ConfigError
        As ``replay_file`` (raised in the child, said again here).
    """
    config, sidecar = config_for(path, base, given, trust)
    if config.transport == "ros":
        return Verdict.of(replay_file(path, base, given, sessions, trust))
    session_for(path, config, sessions)  # here: the next file of this configuration reuses it
    sys.stdout.flush()
    sys.stderr.flush()
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: replay, answer, and end without the parent's exit handlers
        os.close(read)
        if _prctl is not None:  # a replay stopped by a signal left its child spinning at 100% CPU
            _prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        try:
            payload: dict[str, Any] = {
                "verdict": Verdict.of(replay_file(path, base, given, sessions, trust)).__dict__
            }
        except ConfigError as exc:
            payload = {"error": str(exc)}
        except BaseException as exc:  # noqa: BLE001 - said by the parent, as a failed replay
            payload = {"failure": f"{type(exc).__name__}: {exc}"}
        data = json.dumps(payload).encode()
        with open(write, "wb") as pipe:
            pipe.write(data)
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)
    os.close(write)
    data, finished = _read_until(read, time.monotonic() + REPLAY_SECONDS)
    if not finished:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
    _, status = os.waitpid(pid, 0)
    recorded = sidecar is not None
    if not finished:
        return Verdict(HANGS, f"no verdict in {REPLAY_SECONDS:g} s: a target hangs on it", (), recorded, True)
    if os.WIFSIGNALED(status):
        number = os.WTERMSIG(status)
        try:
            name = signal.Signals(number).name
        except ValueError:
            name = str(number)
        crashed = number in {int(s) for s in CRASH_SIGNALS}
        why = "a target crashed on it" if crashed else "a target, or something outside, killed it"
        return Verdict(CRASHES, f"killed by {name}: {why}", (), recorded, True)
    if not data and os.waitstatus_to_exitcode(status) != 0:  # a target's exit(): no answer sent
        return Verdict(
            ENDS, f"exit status {os.waitstatus_to_exitcode(status)}: a target ended it", (), recorded, True
        )
    try:
        payload = json.loads(data) if data else {}
    except ValueError:
        payload = {}
    if "error" in payload:
        raise ConfigError(str(payload["error"]))
    if "verdict" not in payload:
        failure = (
            payload.get("failure") or f"its process ended with status {os.waitstatus_to_exitcode(status)}"
        )
        raise ConfigError(f"{path}: the replay failed: {failure}")
    fields = payload["verdict"]  # (a child that sent one ended normally)
    return Verdict(
        str(fields["result"]),
        str(fields["detail"]),
        tuple(fields["steps"]),
        bool(fields["has_sidecar"]),
        bool(fields["diverges"]),
    )


def _read_until(fd: int, deadline: float) -> tuple[bytes, bool]:
    """What the child sends through ``fd`` until it closes it (True), or until ``deadline``
    (``time.monotonic()``; False)."""
    chunks: list[bytes] = []
    with open(fd, "rb", buffering=0) as pipe:
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([pipe], [], [], left)[0]:
                return b"".join(chunks), False
            chunk = pipe.read(1 << 16)
            if not chunk:
                return b"".join(chunks), True
            chunks.append(chunk)
