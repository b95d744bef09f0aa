"""Running one benchmark trial and reading what it found (``bench_zoo.run_one``).

``run_until_detection`` runs it until its first detection (``stop_at_detection``): the trial's
process group is killed once its logs show a detection and the snapshot that records its first
input. The time to first detection is the engine's own timestamp in its divergence log, so
stopping, and how long the kill takes, do not change it. ``found_fields`` sums up its logged
divergences; ``replay_fidelity`` replays its crash files in a new process."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
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


def _kill_group(process: subprocess.Popen[bytes]) -> None:
    """SIGKILL the process group of ``process`` (a session leader not yet reaped)."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGKILL)


def run_until_detection(cmd: list[str], artifacts: Path, timeout: float, cwd: Path) -> int:
    """Run ``cmd`` in a new session until it exits or logs a detection in ``artifacts``.

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
    process = subprocess.Popen(
        cmd,
        cwd=cwd,
        env=dict(os.environ, PYTHONPATH=str(cwd)),
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    deadline, progress = time.monotonic() + timeout, Progress()
    try:
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
    finally:
        if process.returncode is None:  # timed out, or interrupted
            _kill_group(process)
            process.wait()


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
    done = subprocess.run(
        [sys.executable, str(root / "fuzz_diff.py"), *map(str, crashes), f"--targets=native,{bug.target}"],
        cwd=root,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
        env=dict(os.environ, PYTHONPATH=str(root)),
    )
    same, misses = 0, []
    for path in crashes:
        line = next(
            (ln for ln in done.stdout.splitlines() if ln.startswith(f"{path}:")),
            f"no verdict (exit {done.returncode}: {done.stderr.strip()[-300:]})",
        )
        if "still diverges (same signature)" in line:
            same += 1
        else:
            kind = json.loads(path.with_name(path.name + ".json").read_text())["signature"]["kind"]
            misses.append(f"{kind}: {line.removeprefix(f'{path}: ')}")
    return len(crashes), same, tuple(misses)
