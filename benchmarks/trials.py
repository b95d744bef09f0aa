"""Running one benchmark trial and reading what it found (``bench_zoo.run_one``).

Every process a trial starts (its campaign, its replay) runs in a session of its own: a
terminal's Ctrl-C goes to the sweep, which decides what becomes of the trials running
(``benchmarks.sweeps``), and never cuts a trial short behind its back (a trial stopped at 3 s of
its 10 would be kept as a 10-s trial). ``stop_all`` kills them all (a second Ctrl-C).

``run_to_end`` runs a trial for its whole budget. ``run_until_detection`` runs it until its
first detection (``stop_at_detection``): the trial's process group is killed once its logs show
a detection and the snapshot that records its first input. The time to first detection is the
engine's own timestamp in its divergence log, so stopping, and how long the kill takes, do not
change it. ``found_fields`` sums up its logged divergences; ``replay_fidelity`` replays its
crash files in a new process."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks.zoo import Bug
from fuzzer.artifacts.divlog import DIVERGENCES, STATS

NOT_DETECTIONS = {"ill_conditioned", "known_limitation", "flaky"}
"""Divergence kinds that do not count as detecting a bug."""

POLL_SECONDS = 0.05
"""How often a trial that stops at its first detection reads its logs."""


@dataclass(frozen=True)
class Progress:
    """What the logs of a running trial have shown so far (``stop_at_detection``)."""

    detected: bool = False
    """A divergence that counts as a detection (its kind is not in ``NOT_DETECTIONS``) is logged."""
    started: bool = False
    """A stats snapshot with a ``first_input`` is logged (the start-up is measured)."""
    divergences_offset: int = 0
    stats_offset: int = 0

    @property
    def done(self) -> bool:
        """Whether the trial has shown all that ``run_one`` measures when stopping early."""
        return self.detected and self.started


def read_new(path: Path, offset: int) -> tuple[list[dict[str, Any]], int]:
    """The records of a JSON Lines file past byte ``offset``, and the offset to read from next.

    Parameters
    ----------
    path
        The file (it may not exist yet: no records).
    offset
        The byte offset where the previous read stopped.

    Returns
    -------
    tuple[list[dict[str, Any]], int]
        The complete lines past ``offset`` that parse as JSON objects (others are skipped), and
        the offset after the last complete line: a trailing partial line is read again next time.
    """
    try:
        with open(path, "rb") as handle:
            handle.seek(offset)
            data = handle.read()
    except FileNotFoundError:
        return [], offset
    complete = data[: data.rfind(b"\n") + 1]
    records = []
    for line in complete.splitlines():
        try:
            record = json.loads(line)
        except ValueError:  # JSONDecodeError or UnicodeDecodeError
            continue
        if isinstance(record, dict):
            records.append(record)
    return records, offset + len(complete)


def watch(progress: Progress, artifacts: Path) -> Progress:
    """``progress`` after the lines logged in ``artifacts`` since it was taken."""
    hits, divergences_offset = read_new(artifacts / DIVERGENCES, progress.divergences_offset)
    snapshots, stats_offset = read_new(artifacts / STATS, progress.stats_offset)
    return Progress(
        progress.detected or any(r.get("kind") not in NOT_DETECTIONS for r in hits),
        progress.started or any(r.get("first_input") is not None for r in snapshots),
        divergences_offset,
        stats_offset,
    )


def _kill_group(process: subprocess.Popen[Any]) -> None:
    """SIGKILL the process group of ``process`` (a session leader not yet reaped)."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGKILL)


class Stopped(Exception):
    """A trial asked to start a process after ``stop_all``."""


_RUNNING: set[subprocess.Popen[Any]] = set()
"""The processes ``started`` has started and not yet reaped."""
_LOCK = threading.Lock()
_STOPPING = threading.Event()
"""Set by ``stop_all``: ``started`` starts nothing more until ``allow_starts``."""


def stop_all() -> int:
    """Kill every process group a trial has running (``started``), and start no other until
    ``allow_starts``: a sweep's second Ctrl-C. Returns how many were killed."""
    _STOPPING.set()
    with _LOCK:
        running = [p for p in _RUNNING if p.returncode is None]
        for process in running:
            _kill_group(process)
    return len(running)


def allow_starts() -> None:
    """Let trials start processes again (a new sweep, after ``stop_all``)."""
    _STOPPING.clear()


@contextlib.contextmanager
def started(cmd: list[str], cwd: Path, **streams: Any) -> Iterator[subprocess.Popen[Any]]:
    """``cmd`` started in a session of its own, in ``cwd`` (also its ``PYTHONPATH``), with
    ``streams`` (``stdout``, ``stderr``, ``text``: as ``subprocess.Popen``'s; default: none
    kept); its whole process group is killed if it still runs when the block ends (a time-out,
    an exception). ``stop_all`` can kill it meanwhile; after ``stop_all``, raises ``Stopped``."""
    options: dict[str, Any] = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, **streams}
    with _LOCK:
        if _STOPPING.is_set():
            raise Stopped(f"the sweep is stopping: {cmd[0]} not started")
        process = subprocess.Popen(
            cmd,
            cwd=cwd,
            env=dict(os.environ, PYTHONPATH=str(cwd)),
            stdin=subprocess.DEVNULL,
            start_new_session=True,
            **options,
        )
        _RUNNING.add(process)
    try:
        yield process
    finally:
        if process.returncode is None:  # timed out, interrupted, or its reader failed
            _kill_group(process)
            if options["stdout"] == subprocess.PIPE:
                process.communicate()  # its pipes drained: wait() could block on a full one
            else:
                process.wait()
        with _LOCK:
            _RUNNING.discard(process)


def run_to_end(cmd: list[str], timeout: float, cwd: Path) -> int:
    """Run ``cmd`` (``started``) until it exits; past ``timeout`` seconds its process group is
    killed and ``subprocess.TimeoutExpired`` raised. Returns its exit status."""
    with started(cmd, cwd) as process:
        return process.wait(timeout=timeout)


def run_until_detection(cmd: list[str], artifacts: Path, timeout: float, cwd: Path) -> int:
    """Run ``cmd`` (``started``) until it exits or logs a detection in ``artifacts``.

    Parameters
    ----------
    cmd
        The trial's command (``command``).
    artifacts
        Its artifacts folder, whose logs are read about every ``POLL_SECONDS``.
    timeout
        Seconds before the trial is killed and ``subprocess.TimeoutExpired`` raised.
    cwd
        Its working folder (also its ``PYTHONPATH``).

    Returns
    -------
    int
        The exit status: the process's own, or ``-SIGKILL`` when it was stopped because its
        logs showed a detection and a stats snapshot with its first input (``Progress.done``);
        its whole process group is killed then.
    """
    deadline, progress = time.monotonic() + timeout, Progress()
    with started(cmd, cwd) as process:
        while True:
            try:
                return process.wait(timeout=POLL_SECONDS)
            except subprocess.TimeoutExpired:
                pass
            progress = watch(progress, artifacts)
            if progress.done:
                _kill_group(process)
                return process.wait()
            if time.monotonic() > deadline:
                raise subprocess.TimeoutExpired(cmd, timeout)


def found_fields(hits: list[dict[str, Any]]) -> tuple[str, ...]:
    """``kind field: largest difference unit`` per (kind, field) of the logged divergences."""
    largest: dict[tuple[str, str], tuple[float, str]] = {}
    for r in hits:
        key = (str(r.get("kind")), str(r.get("field")))
        diff = float(r.get("difference") or 0.0)
        if key not in largest or diff > largest[key][0]:
            largest[key] = (diff, str(r.get("unit") or ""))
    return tuple(f"{k} {f}: {d:.2g} {u}".rstrip() for (k, f), (d, u) in sorted(largest.items()))


def replay_fidelity(bug: Bug, artifacts: Path, root: Path) -> tuple[int, int, tuple[str, ...]]:
    """Replay every crash file of a run in one new process, in the tree at ``root``: (files,
    same signature, misses)."""
    crashes = sorted(
        p for p in artifacts.glob("crash-*") if p.suffix != ".json" and Path(f"{p}.json").is_file()
    )
    if not crashes:
        return 0, 0, ()
    cmd = [sys.executable, str(root / "fuzz_diff.py"), *map(str, crashes), f"--targets=native,{bug.target}"]
    with started(cmd, root, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) as process:
        stdout, stderr = process.communicate(timeout=600)
    same, misses = 0, []
    for path in crashes:
        line = next(
            (ln for ln in stdout.splitlines() if ln.startswith(f"{path}:")),
            f"no verdict (exit {process.returncode}: {stderr.strip()[-300:]})",
        )
        if "still diverges (same signature)" in line:
            same += 1
        else:
            kind = json.loads(path.with_name(path.name + ".json").read_text())["signature"]["kind"]
            misses.append(f"{kind}: {line.removeprefix(f'{path}: ')}")
    return len(crashes), same, tuple(misses)
