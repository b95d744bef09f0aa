"""Crash files: atomic writes, one file per new divergence signature, sidecars.

Every file is written to a hidden temporary name in its final directory and
then renamed, so ``kill -9`` never leaves a half-written artifact. Temporaries
are per process (``.tmp-<name>.<pid>.<token>``); start-up clean-up removes only
those of dead processes (or older than ``STALE_SECONDS``), so ``-fork``/``-jobs``
workers never touch each other's in-flight files.

The first input of each signature wins across processes: a marker under
``.signatures/`` decides. Claiming and writing are atomic together
(:meth:`ArtifactStore.record`): the crash file and sidecar are first written
in full to temporaries, then the marker is created (atomically, holding the
crash file's name), then the temporaries are renamed. A process killed after
claiming leaves complete temporaries, which the next start completes
(:meth:`ArtifactStore.recover`); a marker without crash file and without
temporaries is dropped, so its signature can be written again.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import os
import re
import secrets
import signal
import time
from pathlib import Path
from typing import Any

from fuzzer.artifacts.shorten import MAX_SIDECAR_BYTES, encode_sidecar
from fuzzer.input import untrusted_json

TMP_PREFIX = ".tmp-"
MARKERS = ".signatures"
"""The artifacts folder's sub-folder of signature markers (one file per claimed signature)."""
CRASH_NAME = re.compile(r"crash-[0-9a-f]{40}")
STALE_SECONDS = 600.0
"""A temporary this old is abandoned even if a process with its pid is alive (pid reuse)."""
KILL_HOOK = "RROSFUZZ_TEST_KILL_AT"
"""Test-only: ``<point>:<n>`` makes the process SIGKILL itself at ``point`` ("temp", "claim"
or "sidecar") of its n-th :meth:`ArtifactStore.record`, inside the write window."""


WRITE_FAILED_EXIT = 74
"""A campaign's exit status when its artifacts folder cannot be written (sysexits' EX_IOERR)."""


class ArtifactsUnwritable(Exception):
    """A campaign's artifacts folder could not be written (a full disk, a read-only mount): the
    campaign has said so, with any divergent input it could not save, and stops with
    :data:`WRITE_FAILED_EXIT` rather than go on finding divergences it cannot keep."""


DERIVED_SUFFIXES = (".json", ".jsonl", ".bag")
"""Files made from a crash file, beside it (its sidecar, the logs, ``export-bag``'s default
``CRASH.bag``), never crash files themselves: a bag named ``crash-<sha1>.bag`` was triage's most
severe bucket, "crash without sidecar", and stopped `show`, `minimize` and `report` on the folder."""


def derived(path: Path) -> bool:
    """Whether ``path`` is made from a crash file (:data:`DERIVED_SUFFIXES`), not one."""
    return path.name.endswith(DERIVED_SUFFIXES)


def _temporary(path: Path) -> Path:
    return path.parent / f"{TMP_PREFIX}{path.name}.{os.getpid()}.{secrets.token_hex(4)}"


def _write_temporary(path: Path, data: bytes, durable: bool = True) -> Path:
    """Write ``data`` in full (fsync if ``durable``) to a temporary next to ``path``; return the
    temporary."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temporary(path)
    try:
        with open(tmp, "wb") as handle:
            handle.write(data)
            handle.flush()
            if durable:
                os.fsync(handle.fileno())
    except BaseException as exc:  # a full disk: no empty or short temporary left behind (or renamed)
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError) and exc.filename is None:  # a write's error names no file
            exc.filename = str(path)
        raise
    return tmp


def atomic_write(path: Path, data: bytes, durable: bool = True) -> None:
    """Write ``data`` to ``path`` all at once (per-process temporary file, fsync, rename).

    ``durable=False`` skips the fsync, for files that can be made again (a campaign's generated
    seeds): a reader still sees the old file or the whole new one, and only a power loss can
    leave a short one behind. 64 fsynced seed files took 30-44 ms on this machine with another
    process writing (10-25 ms more than without), and once 0.24 s during a two-job benchmark."""
    tmp = _write_temporary(path, data, durable)
    try:
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)
        raise


def _owner(tmp: Path) -> int | None:
    """The pid in a temporary's name (``.tmp-<name>.<pid>.<token>``), None if it has none."""
    parts = tmp.name.rsplit(".", 2)
    return int(parts[1]) if len(parts) == 3 and parts[1].isdigit() else None


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    return True


def abandoned(tmp: Path, now: float | None = None) -> bool:
    """Whether a temporary belongs to no live writer: its process is gone, or it is stale."""
    pid = _owner(tmp)
    if pid is None or not _alive(pid):
        return True
    try:
        return (now or time.time()) - tmp.stat().st_mtime > STALE_SECONDS
    except FileNotFoundError:
        return False  # renamed meanwhile by its writer


TEMPORARY = re.compile(re.escape(TMP_PREFIX) + r".+\.[0-9]+\.[0-9a-f]{8}")
"""The name :func:`_temporary` gives (a user's ``.tmp-notes.txt`` is not one)."""


def clean_temporaries(directory: Path) -> list[Path]:
    """Remove leftovers of interrupted writes of dead processes; return what was removed."""
    removed = []
    if directory.is_dir():
        for path in directory.glob(f"{TMP_PREFIX}*"):
            if TEMPORARY.fullmatch(path.name) and abandoned(path):
                path.unlink(missing_ok=True)
                removed.append(path)
    return removed


def crash_name(data: bytes) -> str:
    """libFuzzer's naming: ``crash-<sha1 of the input>``."""
    return "crash-" + hashlib.sha1(data).hexdigest()


def oversized(path: Path) -> bool:
    """A file larger than any sidecar a reader accepts (MAX_SIDECAR_BYTES)."""
    try:
        return path.stat().st_size > MAX_SIDECAR_BYTES
    except OSError:
        return False


def sidecar_path(crash: Path) -> Path:
    return crash.with_name(crash.name + ".json")


def _test_kill(point: str, count: int) -> None:
    """The test-only kill hook (see ``KILL_HOOK``)."""
    spec = os.environ.get(KILL_HOOK)
    if spec and spec == f"{point}:{count}":
        os.kill(os.getpid(), signal.SIGKILL)


class ArtifactStore:
    """The artifacts folder of a campaign."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory
        self.markers = directory / MARKERS
        if self.markers.is_symlink():  # its markers read, written and deleted wherever it led
            raise OSError(errno.ELOOP, "a symbolic link, not the artifacts folder's own", str(self.markers))
        self.markers.mkdir(parents=True, exist_ok=True)
        self.recorded = 0
        self.recovered = self.recover()
        clean_temporaries(directory)
        clean_temporaries(self.markers)

    # -- claiming ---------------------------------------------------------------------------

    def _marker_link(self, signature_key: str, crash: str) -> bool:
        """Create the marker with the crash file's name in it, atomically (link of a
        complete temporary); False if it exists."""
        marker = self.markers / signature_key
        tmp = _write_temporary(marker, crash.encode())
        try:
            os.link(tmp, marker)
        except FileExistsError:
            return False
        except OSError:  # no hard links here (some network file systems): O_EXCL, then the name
            try:
                fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                return False
            with os.fdopen(fd, "wb") as handle:  # an empty marker is matched through the sidecars
                handle.write(crash.encode())
        finally:
            tmp.unlink(missing_ok=True)
        return True

    def claim(self, signature_key: str, crash: str = "") -> bool:
        """True for the first caller (in any process) to report this signature."""
        return self._marker_link(signature_key, crash)

    def record(self, signature_key: str, data: bytes, sidecar: dict[str, Any]) -> Path | None:
        """Claim ``signature_key`` and write its crash file and sidecar, atomically together.

        Returns the crash file's path, or None if another process (or an earlier
        run) holds the signature.
        """
        self.recorded += 1
        path = self.directory / crash_name(data)
        side = sidecar_path(path)
        tmp_side = _write_temporary(side, encode_sidecar(sidecar))
        tmp_data: Path | None = None
        claimed = False
        try:
            tmp_data = _write_temporary(path, data)
            _test_kill("temp", self.recorded)
            claimed = self.claim(signature_key, path.name)
        finally:  # not claimed (another process has it, or a full disk): no temporaries left
            if not claimed:
                tmp_side.unlink(missing_ok=True)
                if tmp_data is not None:
                    tmp_data.unlink(missing_ok=True)
        if not claimed:
            return None
        _test_kill("claim", self.recorded)
        os.replace(tmp_side, side)  # the sidecar first: a crash file always has its sidecar
        _test_kill("sidecar", self.recorded)
        if tmp_data is not None:
            os.replace(tmp_data, path)
        return path

    # -- recovery ---------------------------------------------------------------------------

    def _finish(self, final: Path) -> bool:
        """Complete ``final`` from an abandoned temporary if it is missing; whether it exists."""
        if final.is_file():
            return True
        for tmp in sorted(final.parent.glob(f"{TMP_PREFIX}{final.name}.*")):
            if _owner(tmp) is None or not abandoned(tmp):
                continue
            with contextlib.suppress(FileNotFoundError):  # another process completed it first
                os.replace(tmp, final)
            break
        return final.is_file()

    def _writer_alive(self, final: Path) -> bool:
        return any(not abandoned(t) for t in final.parent.glob(f"{TMP_PREFIX}{final.name}.*"))

    def _legacy_names(self) -> dict[str, str]:
        """signature key -> crash file name, from the sidecars and the sidecar temporaries of
        dead writers (markers of older versions, or written without hard links, may be empty)."""
        names: dict[str, str] = {}
        sides = [*self.directory.glob("crash-*.json"), *self.directory.glob(f"{TMP_PREFIX}crash-*.json.*")]
        for side in sides:
            if not side.is_file() or oversized(side):  # never open a FIFO or device planted here
                continue
            name = side.name.removeprefix(TMP_PREFIX).split(".json", 1)[0]
            with contextlib.suppress(OSError, ValueError, AttributeError, TypeError, RecursionError):
                key = untrusted_json.loads(side.read_text(encoding="utf-8"))["signature"]["key"]
                names.setdefault(str(key), name)
        return names

    def recover(self) -> list[str]:
        """Complete claimed signatures whose crash file is missing; drop the markers that
        cannot be completed (so their signature is written again when found again).
        Returns the names of the crash files completed."""
        completed: list[str] = []
        legacy: dict[str, str] | None = None
        for marker in sorted(self.markers.iterdir()):
            if marker.name.startswith(".") or not marker.is_file():
                continue
            try:
                name = marker.read_text(encoding="ascii").strip()
            except (OSError, UnicodeDecodeError):
                continue
            if not name:
                legacy = self._legacy_names() if legacy is None else legacy
                name = legacy.get(marker.name, "")
                if not name:  # its crash file is gone: release it, unless a writer is at work
                    if not any(not abandoned(t) for t in self.directory.glob(f"{TMP_PREFIX}*")):
                        marker.unlink(missing_ok=True)
                    continue
            if not CRASH_NAME.fullmatch(name):  # not written by us: it held the signature with no
                marker.unlink(missing_ok=True)  # crash file, whose divergences were then lost
                continue
            crash = self.directory / name
            if crash.is_file() and sidecar_path(crash).is_file():
                continue
            side_ok = self._finish(sidecar_path(crash))
            data_ok = self._finish(crash)
            if side_ok and data_ok:
                completed.append(name)
            elif not (self._writer_alive(crash) or self._writer_alive(sidecar_path(crash))):
                if crash.is_file() and sidecar_path(crash).is_file():  # its writer just finished
                    continue
                if not crash.is_file():
                    marker.unlink(missing_ok=True)
        return completed

    def crash_files(self) -> list[Path]:
        return sorted(p for p in self.directory.glob("crash-*") if not derived(p))

    # -- writing without claiming (minimize, tests) -------------------------------------------

    def write_sidecar(self, data: bytes, sidecar: dict[str, Any]) -> Path:
        """Write the sidecar of the crash file for ``data``; return the crash file's path."""
        path = self.directory / crash_name(data)
        atomic_write(sidecar_path(path), encode_sidecar(sidecar))
        return path

    def write(self, data: bytes, sidecar: dict[str, Any]) -> Path:
        """Write the input and its sidecar (no claim); return the crash file's path.

        The sidecar goes first: a crash file always has its sidecar.
        """
        path = self.write_sidecar(data, sidecar)
        atomic_write(path, data)
        return path


def load_sidecar(crash: Path) -> dict[str, Any] | None:
    """The sidecar of a crash file, if it has a readable one (native crashes have none); a
    sidecar larger than MAX_SIDECAR_BYTES counts as none, and is not read."""
    path = sidecar_path(crash)
    if not path.is_file() or oversized(path):
        return None
    try:
        data = untrusted_json.loads(path.read_text(encoding="utf-8", errors="replace"))
    except (OSError, ValueError, RecursionError):  # bad JSON, an int past a float's range, nesting
        return None  # a damaged sidecar is treated as none
    return data if isinstance(data, dict) else None
