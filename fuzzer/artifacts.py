"""Crash files: atomic writes, one file per new divergence signature, sidecars.

Every file is written to a hidden temporary name in its final directory and
then renamed, so ``kill -9`` can leave a stray ``.tmp-*`` (removed at the next
start) but never a half-written artifact. The first input of each signature
wins across processes (``-fork``/``-jobs``): a marker created with O_EXCL
under ``.signatures/`` decides.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

TMP_PREFIX = ".tmp-"


def atomic_write(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` all at once (temporary file, fsync, rename)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.parent / f"{TMP_PREFIX}{path.name}-{os.getpid()}"
    with open(tmp, "wb") as handle:
        handle.write(data)
        handle.flush()
        os.fsync(handle.fileno())
    os.replace(tmp, path)


def clean_temporaries(directory: Path) -> list[Path]:
    """Remove leftovers of interrupted writes; return what was removed."""
    removed = []
    if directory.is_dir():
        for path in directory.glob(f"{TMP_PREFIX}*"):
            path.unlink(missing_ok=True)
            removed.append(path)
    return removed


def crash_name(data: bytes) -> str:
    """libFuzzer's naming: ``crash-<sha1 of the input>``."""
    return "crash-" + hashlib.sha1(data).hexdigest()


def sidecar_path(crash: Path) -> Path:
    return crash.with_name(crash.name + ".json")


class ArtifactStore:
    """The artifacts folder of a campaign."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory
        self.markers = directory / ".signatures"
        self.markers.mkdir(parents=True, exist_ok=True)
        clean_temporaries(directory)
        clean_temporaries(self.markers)

    def claim(self, signature_key: str) -> bool:
        """True for the first caller (in any process) to report this signature."""
        try:
            fd = os.open(self.markers / signature_key, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            return False
        os.close(fd)
        return True

    def write_sidecar(self, data: bytes, sidecar: dict[str, Any]) -> Path:
        """Write the sidecar of the crash file for ``data``; return the crash file's path."""
        path = self.directory / crash_name(data)
        atomic_write(sidecar_path(path), json.dumps(sidecar, indent=1, sort_keys=True).encode())
        return path

    def write(self, data: bytes, sidecar: dict[str, Any]) -> Path:
        """Write the input and its sidecar; return the crash file's path.

        The sidecar goes first: a crash file always has its sidecar.
        """
        path = self.write_sidecar(data, sidecar)
        atomic_write(path, data)
        return path

    def crash_files(self) -> list[Path]:
        return sorted(p for p in self.directory.glob("crash-*") if not p.name.endswith(".json"))


def load_sidecar(crash: Path) -> dict[str, Any] | None:
    """The sidecar of a crash file, if it has a readable one (native crashes have none)."""
    path = sidecar_path(crash)
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8", errors="replace"))
    except (OSError, json.JSONDecodeError):
        return None  # a damaged sidecar is treated as none
    return data if isinstance(data, dict) else None
