"""ROS processes started by the engine: a master and nodes, none outliving it.

Every process is started in its own process group (``start_new_session``) with
``PR_SET_PDEATHSIG`` = SIGKILL, so it dies with the engine however the engine
ends (libFuzzer's C ``exit``, ``_Exit``, a signal); :func:`shutdown_all` (run by
``atexit`` at a normal Python exit) terminates each group, then kills it.
``PR_SET_PDEATHSIG`` follows the thread that started the process: processes are
started from the main thread. Only
loopback is used: a master listens on a free port of 127.0.0.1.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import threading
import time
import xmlrpc.client
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fuzzer import reporting
from fuzzer.ros import env

PR_SET_PDEATHSIG = 1
MASTER_START_SECONDS = 20.0
"""How long a new master may take to answer (a loaded 2-core machine is slow to start Python)."""
TERM_GRACE_SECONDS = 3.0

_lock = threading.Lock()
_live: list[Process] = []
_hook_installed = False


_prctl = ctypes.CDLL(None, use_errno=True).prctl  # resolved here: no dlopen after fork
SETPRIV = shutil.which("setpriv")
"""util-linux's ``setpriv --pdeathsig``: sets the death signal in the child without running
Python between fork and exec (a fork of a process with threads, rospy's, must not)."""


def _die_with_parent() -> None:  # fallback without setpriv: runs in the child between fork and exec
    _prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)


@dataclass
class Process:
    """A ROS process in its own process group."""

    name: str
    popen: subprocess.Popen[bytes]
    log: Path
    _closed: bool = field(default=False, repr=False)

    @property
    def pid(self) -> int:
        return self.popen.pid

    def alive(self) -> bool:
        return self.popen.poll() is None

    def log_tail(self, lines: int = 15) -> str:
        """The last lines of the process's output (for error messages)."""
        try:
            text = self.log.read_text(errors="replace")
        except OSError:
            return ""
        return "\n".join(text.splitlines()[-lines:])

    def stop(self) -> None:
        """SIGTERM to the process group, SIGKILL after a grace period; reaps the process."""
        if self._closed:
            return
        self._closed = True
        for sig in (signal.SIGTERM, signal.SIGKILL):
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.popen.pid, sig)
            try:
                self.popen.wait(TERM_GRACE_SECONDS)
                break
            except subprocess.TimeoutExpired:
                continue
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.popen.pid, signal.SIGKILL)  # whatever the group's leader left behind
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.popen.wait(TERM_GRACE_SECONDS)
        with _lock:
            if self in _live:
                _live.remove(self)


def spawn(name: str, argv: Sequence[str], environment: dict[str, str], log_dir: str | Path) -> Process:
    """Start ``argv`` as a process group that dies with this process; output goes to a log file."""
    _install_hook()
    log = Path(log_dir) / f"{name}.log"
    with open(log, "ab") as out:
        command = [SETPRIV, "--pdeathsig", "KILL", "--", *argv] if SETPRIV else list(argv)
        popen = subprocess.Popen(
            command,
            stdin=subprocess.DEVNULL,
            stdout=out,
            stderr=subprocess.STDOUT,
            env={**os.environ, **environment},
            start_new_session=True,
            preexec_fn=None if SETPRIV else _die_with_parent,
            close_fds=True,
        )
    process = Process(name, popen, log)
    with _lock:
        _live.append(process)
    return process


def live() -> list[Process]:
    """The processes started here and not stopped yet."""
    with _lock:
        return list(_live)


def shutdown_all() -> None:
    """Stop every process started here (newest first: nodes before their master)."""
    for process in reversed(live()):
        process.stop()


def _install_hook() -> None:
    global _hook_installed
    if _hook_installed:
        return
    _hook_installed = True
    atexit.register(shutdown_all)


def free_port() -> int:
    """A TCP port of 127.0.0.1 free right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def master_answers(uri: str, timeout: float = 2.0) -> bool:
    """Whether a ROS master answers ``getPid`` at ``uri``."""
    transport = _TimeoutTransport(timeout)
    try:
        answer: Any = xmlrpc.client.ServerProxy(uri, transport=transport).getPid("/rrosfuzz")
    except (OSError, ValueError, xmlrpc.client.Error):  # ValueError: not a URI ("http://[::1")
        return False
    return isinstance(answer, list) and len(answer) == 3 and answer[0] == 1


class _TimeoutTransport(xmlrpc.client.Transport):
    def __init__(self, timeout: float) -> None:
        super().__init__()
        self._timeout = timeout

    def make_connection(self, host):  # type: ignore[no-untyped-def]
        connection = super().make_connection(host)
        connection.timeout = self._timeout
        return connection


@dataclass
class Master:
    """A ROS master: started here on a free loopback port, or joined (``ROS_MASTER_URI``)."""

    uri: str
    log_dir: str
    process: Process | None = None

    @property
    def environment(self) -> dict[str, str]:
        return env.loopback_environment(self.uri, self.log_dir)

    def stop(self) -> None:
        if self.process is not None:
            self.process.stop()


def log_folder(given: str | None = None, prefix: str = "rrosfuzz-ros-") -> str:
    """Where ROS processes log: ``given``, else ``ROS_LOG_DIR`` (ROS's own variable), else a new
    temporary folder named ``prefix``..."""
    return given or os.environ.get("ROS_LOG_DIR") or tempfile.mkdtemp(prefix=prefix)


def start_master(log_dir: str | None = None, attempts: int = 3) -> Master:
    """Start ``rosmaster --core`` on a free port of 127.0.0.1 and wait until it answers.

    Raises
    ------
    RosUnavailableError
        ROS is not installed, or the master does not come up (its log's tail says why).
    """
    env.require()
    log_dir = log_folder(log_dir)
    last = ""
    for _ in range(attempts):  # the port may be taken between free_port() and the bind
        port = free_port()
        uri = f"http://127.0.0.1:{port}/"
        environment = env.loopback_environment(uri, log_dir)
        process = spawn(
            f"rosmaster-{port}", ["rosmaster", "--core", "-p", str(port), "-w", "2"], environment, log_dir
        )
        deadline = time.monotonic() + MASTER_START_SECONDS
        while time.monotonic() < deadline and process.alive():
            if master_answers(uri):
                return Master(uri, log_dir, process)
            time.sleep(0.05)
        last = process.log_tail()
        process.stop()
    raise env.RosUnavailableError(f"the ROS master did not start; its log ends with:\n{last}")


def join_or_start_master(log_dir: str | None = None) -> Master:
    """The master of ``ROS_MASTER_URI`` when one answers there, else a new one on a free port."""
    uri = os.environ.get("ROS_MASTER_URI", "")
    log_dir = log_folder(log_dir)
    if uri and master_answers(uri):
        return Master(uri if uri.endswith("/") else uri + "/", log_dir)
    master = start_master(log_dir)
    if uri:  # someone who meant to join their master (to watch, to record) should know
        reporting.warn(
            f"ROS_MASTER_URI={uri!r}: no ROS master answers there, so the campaign runs on a master "
            f"of its own at {master.uri} (nodes on yours will not see it)"
        )
    return master
