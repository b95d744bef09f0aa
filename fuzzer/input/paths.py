"""Paths given on the command line: checked before use, so bad ones give a message, not a traceback.

* :func:`crash_inputs` expands what triage commands receive (files, folders, a shell
  glob such as ``artifacts/crash-*`` that also matches the ``.json`` sidecars):
  sidecars are skipped silently, a path that does not exist is an error.
* :func:`prepare_folder` makes sure a corpus or artifacts folder exists, is a
  folder, can be listed and (when asked) written: by trying it, which also works
  as root, where permission bits do not apply.
* :func:`contained` tells whether a path inside a folder really stays inside it
  (symlinks resolved), for the report, which must never read outside.
* :func:`given_path` is every path option's argparse type: an empty one is an error, not
  the current folder.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import stat
import tempfile
from collections.abc import Iterable
from pathlib import Path

from fuzzer.artifacts.store import derived
from fuzzer.execution.session import ConfigError


class PathError(ConfigError):
    """A path that cannot be used; the message names it and the problem."""


class FolderUnwritable(PathError):
    """A folder that cannot be created or written into (a read-only mount, a full disk): the
    command exits 74, as for any write that fails (docs/engine.md, "Progress, summary and exit
    status"); ``report`` said 2."""


WRITE_FAILURES = frozenset({errno.EROFS, errno.EACCES, errno.EPERM, errno.ENOSPC, errno.EDQUOT, errno.EFBIG})
"""The ``errno`` values of a folder that takes no file (read-only, not ours, full, over a
quota or a file size limit): :class:`FolderUnwritable`'s, exit 74, rather than a bad path."""


ARTIFACT_PREFIXES = ("crash-", "timeout-", "oom-", "leak-", "slow-unit-", "minimized-")


JOB_LOG = re.compile(r"fuzz-[0-9]+\.log")
"""The log libFuzzer's ``-jobs`` writes per worker into the artifacts folder."""


def given_path(text: str) -> Path:
    """argparse's ``type`` for a path option: ``Path(text)``, but an empty one is the parser's
    error. ``Path("")`` is the current folder, so an unset shell variable (``--artifacts=$OUT``)
    silently wrote seeds, crash files or a bag there."""
    if not text:
        import argparse

        raise argparse.ArgumentTypeError("an empty path (an unset shell variable?); '.' names this folder")
    return Path(text)


def kind_of(mode: int) -> str:
    """What a file of ``mode`` is, for messages ("a FIFO", "a symbolic link", ...)."""
    if stat.S_ISLNK(mode):
        return "a symbolic link"
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISDIR(mode):
        return "a folder"
    return "a file"


def file_problem(path: Path) -> str | None:
    """Why ``path`` is not a regular file to read (``no such file``, ``is a folder, not a regular
    file``...), or None when it is one."""
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        return "no such file"
    except OSError as exc:
        return str(exc.strerror or exc)
    return None if stat.S_ISREG(mode) else f"is {kind_of(mode)}, not a regular file"


def is_sidecar(path: Path) -> bool:
    """``X.json`` next to an existing file ``X`` (the sidecar of a crash file)."""
    return path.name.endswith(".json") and path.with_name(path.name[: -len(".json")]).is_file()


def _beside_crash_files(path: Path) -> bool:
    """A sidecar, a campaign's log (``.jsonl``) or an exported bag of a crash file beside it
    (``crash-X.bag``), which a glob such as ``art/crash-*`` also matches."""
    exported = path.name.endswith(".bag") and path.with_name(path.name[: -len(".bag")]).is_file()
    return is_sidecar(path) or path.name.endswith(".jsonl") or exported


def crash_inputs(paths: Iterable[Path], *, folders: bool = True) -> list[Path]:
    """Files to work on: files as given, folders expanded to their files; sidecars skipped, and a
    folder's symlinks that lead outside it (``show FOLDER`` printed what a link to a file
    elsewhere held; a file given by name is read wherever it is).

    Raises
    ------
    PathError
        A path that does not exist, is not a regular file or folder, or a folder
        where ``folders`` is False; or nothing left to work on.
    """
    out: list[Path] = []
    given = list(paths)
    for path in given:
        try:
            mode = path.stat().st_mode
        except FileNotFoundError:
            raise PathError(f"{path}: no such file") from None
        except OSError as exc:
            raise PathError(f"{path}: {exc.strerror or exc}") from None
        if stat.S_ISDIR(mode):
            if not folders:
                raise PathError(f"{path}: is a folder; give crash files")
            try:
                entries = sorted(path.iterdir())
            except OSError as exc:
                raise PathError(f"{path}: cannot list the folder: {exc.strerror or exc}") from None
            out.extend(
                f
                for f in entries
                if f.is_file()
                and not derived(f)
                and not f.name.startswith(".")
                and not JOB_LOG.fullmatch(f.name)  # a -jobs worker's log, never a test case
                and (not f.is_symlink() or contained(path, f))  # a folder's link out of it: not read
            )
        elif not stat.S_ISREG(mode):
            raise PathError(f"{path}: is {kind_of(mode)}, not a regular file")
        elif not _beside_crash_files(path):
            out.append(path)
    if not out:
        if given and all(_beside_crash_files(p) for p in given):
            raise PathError(
                "only sidecars (.json) or campaign logs (.jsonl) given: give the crash files they describe"
            )
        raise PathError("no files to work on")
    return list(dict.fromkeys(out))


def prepare_folder(path: Path, role: str, *, writable: bool) -> None:
    """Create ``path`` if needed and check it is a folder that can be listed (and written).

    Raises
    ------
    PathError
        ``"<role> <path>: <problem>"``.
    """
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        mode = None
    except NotADirectoryError:
        blocker = next((p for p in path.parents if p.is_file()), path.parent)
        raise PathError(f"{role} {path}: cannot be a folder, {blocker} is a file") from None
    except OSError as exc:
        raise PathError(f"{role} {path}: {exc.strerror or exc}") from None
    if mode is not None and not stat.S_ISDIR(mode):
        raise PathError(f"{role} {path}: is {kind_of(mode)}, not a folder")
    if mode is None:
        try:
            path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise FolderUnwritable(
                f"{role} {path}: cannot create the folder: {exc.strerror or exc}"
            ) from None
    try:
        os.listdir(path)
    except OSError as exc:
        raise PathError(f"{role} {path}: cannot read the folder: {exc.strerror or exc}") from None
    if writable:
        try:
            fd, probe = tempfile.mkstemp(prefix=".tmp-probe-", dir=path)
        except OSError as exc:
            raise FolderUnwritable(
                f"{role} {path}: cannot write into the folder: {exc.strerror or exc}"
            ) from None
        os.close(fd)
        os.unlink(probe)


def check_output_file(output: Path, crash: Path, option: str) -> None:
    """Refuse an output file a crash file's command may not write: a folder, a FIFO or device
    (opening it blocked or wrote into it), a missing folder, or the crash file or its sidecar
    themselves (``view --screenshot CRASH.json`` wrote the screen over the sidecar).

    Raises
    ------
    PathError
        Naming ``option`` and the problem.
    """
    try:
        mode = output.stat().st_mode
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        raise PathError(f"{option} {output}: {exc.strerror or exc}") from None
    if mode is not None and not stat.S_ISREG(mode):
        raise PathError(f"{option} {output}: is {kind_of(mode)}, not a regular file")
    if not output.parent.is_dir():
        raise PathError(f"{option} {output}: its folder {output.parent} does not exist")
    if mode is not None:
        for own in (crash, crash.with_name(crash.name + ".json")):
            with contextlib.suppress(OSError):
                if own.exists() and os.path.samefile(output, own):
                    raise PathError(f"{option} {output}: the crash file's own data; name another file")


def check_input_file(path: Path) -> None:
    """A positional corpus entry that exists but is not a folder must be a regular file.

    Raises
    ------
    PathError
        For a FIFO, socket or device (reading it would hang or never end).
    """
    try:
        mode = path.stat().st_mode
    except OSError:
        return
    if not (stat.S_ISDIR(mode) or stat.S_ISREG(mode)):
        raise PathError(f"corpus {path}: is {kind_of(mode)}, not a folder or a regular file")


def contained(directory: Path, path: Path) -> bool:
    """True when ``path`` (symlinks resolved) lies inside ``directory`` (resolved)."""
    try:
        root = directory.resolve(strict=True)
        real = path.resolve(strict=True)
    except (OSError, RuntimeError):
        return False
    return real == root or root in real.parents


def looks_like_artifact(path: Path) -> bool:
    """A name libFuzzer or RROSFuzz gives to artifacts (crash-, timeout-, minimized-...)."""
    return path.name.startswith(ARTIFACT_PREFIXES)
