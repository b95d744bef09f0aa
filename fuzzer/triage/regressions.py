"""The regression suite: crash files kept under ``tests/regressions/``, replayed by pytest.

``promote`` copies a crash file and its sidecar into the suite and records what
it must do from now on: ``diverge`` (a known divergence that must still
reproduce with the same signature) or ``agree`` (a fixed one that must stay
fixed). The expectation lives in the sidecar's ``regression`` entry.

A crash file found on a robot *file* (not a shipped robot) names it relative to the campaign's
working folder, which the suite is not replayed from; so ``promote`` copies the URDF into the
suite's ``urdfs/`` folder (named by its stem and SHA-256) and the promoted sidecar names the
copy: relative to the repository for the default suite (``tests/regressions/urdfs/...``, which
``tests/test_regressions.py`` replays from the repository's root), by its absolute path for a
``--suite`` elsewhere. The sidecar's first name for it is kept as ``regression.robot_from``.
"""

from __future__ import annotations

import datetime
import hashlib
import json
import os
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fuzzer.artifacts.sidecar import SidecarError, read_sidecar
from fuzzer.artifacts.store import atomic_write, load_sidecar, sidecar_path
from fuzzer.execution.session import ConfigError, RunConfig
from fuzzer.input.paths import WRITE_FAILURES, FolderUnwritable
from fuzzer.input.testcase import TestCaseError, read_bytes
from fuzzer.triage.replay import ROBOT_CHANGED, Replay, Result, replay_file
from robot_api import robots
from robot_api.errors import URDFError

ROOT = Path(__file__).resolve().parents[2]
SUITE = ROOT / "tests" / "regressions"


class PromoteError(ValueError):
    """A file that cannot be promoted as asked."""


@dataclass(frozen=True)
class Promoted:
    path: Path
    expect: str


def promote(
    crash: Path,
    fixed: bool,
    note: str = "",
    suite: Path = SUITE,
    trust: bool = False,
    robot: str | None = None,
) -> Promoted:
    """Check the file's current verdict against what is asked, then add it to the suite.

    ``robot`` (``--robot``) replaces the sidecar's robot, for a file whose robot path was
    relative to another working folder; it must be the campaign's file (its SHA-256), and is
    kept in the suite as any robot file is.

    Raises
    ------
    PromoteError
        No sidecar (or a damaged one, or one naming targets that may not be
        imported without ``trust``), or the verdict contradicts the expectation
        (``--fixed`` on a file that still diverges, or a known divergence that no
        longer diverges).
    """
    try:
        sidecar = read_sidecar(crash)
    except SidecarError as exc:
        raise PromoteError(str(exc)) from None
    if sidecar is None:
        raise PromoteError(f"{crash}: no sidecar; only divergence crash files can be promoted")
    try:
        result = replay_file(crash, RunConfig(), {"robot": robot} if robot else {}, trust=trust)
    except ConfigError as exc:
        raise PromoteError(str(exc)) from None
    if ROBOT_CHANGED in result.detail:  # first: every verdict below is on another robot
        raise PromoteError(f"{crash}: {ROBOT_CHANGED}; the suite keeps what the campaign ran on")
    if result.result is Result.EXPLAINED:
        raise PromoteError(
            f"{crash}: {result.result}; the suite keeps divergences and fixed ones that agree "
            "(test a known limitation beside its rule, in tests/)"
        )
    if result.result is Result.DIFFERENT:  # neither --fixed nor not: each pointed at the other
        raise PromoteError(
            f"{crash}: {result.result} (signature {_short(result)}, the file's {str(result.expected)[:12]}); "
            "the suite keeps a divergence that reproduces its own signature, or a fixed one that "
            "agrees: replay it, and promote a crash file of the signature it has now"
        )
    if result.result is Result.SKIPPED:  # neither fixed nor a divergence: each pointed at the other
        said = f"{crash}: {result.result} ({result.detail})"
        raise PromoteError(f"{said}; only a test case that runs can be kept")
    if fixed and result.result is not Result.AGREES:
        raise PromoteError(f"{crash}: {result.result}; it is not fixed yet (promote it without --fixed)")
    if not fixed and result.result is not Result.SAME:
        raise PromoteError(f"{crash}: {result.result}; promote it with --fixed if it is fixed")
    robot = result.config.robot if result.config is not None else robots.DEFAULT_ROBOT
    target = suite / crash.name
    try:
        suite.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _cannot_hold(suite, exc) from None
    try:
        kept = None if robot in robots.known_robots() else _keep_robot(robot, suite)
    except OSError as exc:
        if exc.errno in WRITE_FAILURES:
            raise _cannot_hold(suite, exc) from None
        raise PromoteError(f"{crash}: its robot file cannot be kept in --suite {suite} ({exc})") from None
    try:
        copied = not (target.exists() and target.samefile(crash))
        if copied:  # not promoted again (--fixed) in place
            # written whole and renamed over the name: a symlink planted there is replaced, not
            # followed (shutil.copyfile wrote the crash file over whatever it pointed at)
            atomic_write(target, read_bytes(crash))
    except OSError as exc:
        raise _cannot_hold(suite, exc) from None
    except TestCaseError as exc:  # replaced since it was replayed
        raise PromoteError(f"{crash}: not a test case: {exc}") from None
    entry: dict[str, Any] = dict(sidecar)
    entry["regression"] = {
        "expect": "agree" if fixed else "diverge",
        "signature": sidecar["signature"]["key"],
        "note": note,
        "promoted": datetime.date.today().isoformat(),
    }
    if kept is not None:
        entry["config"] = {**sidecar["config"], "robot": _suite_name(kept, suite)}
        entry["robot_path"] = str(kept)
        entry["regression"]["robot_from"] = robot
    elif robot != sidecar["config"].get("robot", robots.DEFAULT_ROBOT):  # --robot NAME, the same file:
        entry["config"] = {**sidecar["config"], "robot": robot}  # the name replays from anywhere
        entry["robot_path"] = str(robots.resolve(robot))  # (it kept a path relative to another folder)
        entry["regression"]["robot_from"] = sidecar["config"].get("robot")
    try:
        atomic_write(sidecar_path(target), json.dumps(entry, indent=1, sort_keys=True).encode())
    except OSError as exc:
        if copied:  # no crash file without its sidecar in the suite (its test would fail)
            target.unlink(missing_ok=True)
        raise _cannot_hold(suite, exc) from None
    return Promoted(target, entry["regression"]["expect"])


def _cannot_hold(suite: Path, exc: OSError) -> PromoteError | FolderUnwritable:
    """The error for a suite folder that took no file: a read-only, full or foreign one exits 74
    for every file, as any folder that takes no file does (it exited 1, "not promoted"); a bad
    path (through a file) is this file's "not promoted"."""
    message = f"--suite {suite}: cannot hold the crash file and its sidecar ({exc.strerror or exc})"
    return FolderUnwritable(message) if exc.errno in WRITE_FAILURES else PromoteError(message)


def _short(result: Replay) -> str:
    """The first 12 hex digits of the signature a replay found ("none" when it agrees)."""
    signature = result.evaluation.signature if result.evaluation is not None else None
    return signature.key[:12] if signature is not None else "none"


def _keep_robot(robot: str, suite: Path) -> Path:
    """Copy the robot file a crash file was replayed on into ``suite/urdfs/`` (once per content),
    and return the copy's path.

    Raises
    ------
    OSError
        The robot file cannot be read again, or the suite cannot hold the copy.
    """
    try:
        path = robots.resolve(robot)
    except URDFError as exc:  # gone or replaced by a FIFO since the replay
        raise OSError(f"robot {robot!r}: {exc}") from None
    if os.path.realpath(path.parent) == os.path.realpath(suite / "urdfs"):
        return path  # kept already (promoted again, --fixed)
    data = path.read_bytes()
    digest = hashlib.sha256(data).hexdigest()
    kept = suite / "urdfs" / f"{Path(robot).stem}-{digest[:12]}.urdf"
    kept.parent.mkdir(exist_ok=True)
    try:  # a copy there already (a regular file, never a link or FIFO followed) is kept
        same = stat.S_ISREG(kept.lstat().st_mode) and kept.read_bytes() == data
    except OSError:
        same = False
    if not same:
        atomic_write(kept, data)
    return kept


def _suite_name(kept: Path, suite: Path) -> str:
    """How the promoted sidecar names the kept robot: relative to the repository for the default
    suite (replayed from its root), else the absolute path."""
    if os.path.realpath(suite) == os.path.realpath(SUITE):
        return kept.resolve().relative_to(ROOT.resolve()).as_posix()
    return str(kept.resolve())


def suite_files(suite: Path = SUITE) -> list[Path]:
    """Crash files of the suite that carry an expectation."""
    if not suite.is_dir():
        return []
    out = []
    for path in sorted(suite.iterdir()):
        if path.name.endswith(".json") or not path.name.startswith(("crash-", "minimized-")):
            continue
        sidecar = load_sidecar(path)
        if sidecar is not None and "regression" in sidecar:
            out.append(path)
    return out
