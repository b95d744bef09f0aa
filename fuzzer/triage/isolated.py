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

import json
import os
import signal
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fuzzer.execution.session import ConfigError, RunConfig, Session
from fuzzer.triage.replay import Replay, config_for, replay_file, session_for

CRASHES = "crashes the replaying process"
"""The verdict of a file whose replay killed its process."""


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
    with open(read, "rb") as pipe:
        data = pipe.read()
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        number = os.WTERMSIG(status)
        name = signal.Signals(number).name if number in signal.Signals._value2member_map_ else str(number)
        detail = f"killed by {name}: a target crashed on it"
        return Verdict(CRASHES, detail, (), sidecar is not None, True)
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
    fields = payload["verdict"]
    return Verdict(
        str(fields["result"]),
        str(fields["detail"]),
        tuple(fields["steps"]),
        bool(fields["has_sidecar"]),
        bool(fields["diverges"]),
    )
