"""Settings that travel with files: filling command-line options from a sidecar or a corpus manifest.

The CLI calls these on its parsed options (an :class:`argparse.Namespace`)
before building the run configuration, so what is filled in is also what
libFuzzer's child processes receive (``-fork``, ``-merge``, ``-minimize_crash``).
Options given on the command line always win.

* :func:`adopt_sidecar`: a campaign whose inputs are crash files
  (``fuzz_diff.py -minimize_crash=1 artifacts/crash-X``) runs under the first
  sidecar's configuration.
* :func:`adopt_manifest`: a campaign, ``-merge`` or ``coverage`` over corpus
  folders runs under their manifest's configuration.
* :func:`check_manifests`: refuses a corpus made for another robot or op;
  :func:`record_corpus` (called by the campaign once its configuration has
  opened) writes the manifest of the first corpus folder.
* :func:`prepare_campaign`: the path checks of a campaign (exit 2, no traceback).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import stat
from collections.abc import Sequence
from pathlib import Path

from fuzzer import reporting
from fuzzer.artifacts import manifest
from fuzzer.artifacts.store import MARKERS, sidecar_path
from fuzzer.execution.session import RunConfig
from fuzzer.input.paths import PathError, check_input_file, prepare_folder

OPTIONS = ("op", "robot", "tip_link", "msg_type", "tolerance", "targets")
CHILD_ENV = "RROSFUZZ_CHILD"


def is_child() -> bool:
    """True in libFuzzer's child processes (-fork, -jobs, -merge, -minimize_crash)."""
    return os.environ.get(CHILD_ENV) == "1"


def _given(args: argparse.Namespace) -> set[str]:
    return {name for name in OPTIONS if getattr(args, name, None) is not None}


def _is_default(name: str, value: str, op: str) -> bool:
    from fuzzer.execution.tolerance import Tolerance, default_tolerance
    from fuzzer.input.mapping import DEFAULT_MSG_TYPE
    from robot_api import robots

    if name == "tolerance":
        try:
            return Tolerance.parse(value) == default_tolerance(op)
        except ValueError:
            return False
    defaults = {
        "op": "move",
        "robot": robots.DEFAULT_ROBOT,
        "msg_type": DEFAULT_MSG_TYPE.get(op, ""),
        "targets": "native,python",
    }
    return defaults.get(name) == value


def _apply(args: argparse.Namespace, values: dict[str, str], source: Path) -> None:
    """Set the options; say so when any differs from the default."""
    for name, value in values.items():
        setattr(args, name, value)
    op = getattr(args, "op", None) or "move"
    if any(not _is_default(k, v, op) for k, v in values.items()):
        shown = ", ".join(f"--{k.replace('_', '-')}={v}" for k, v in values.items())
        reporting.info(f"settings from {source}: {shown}")


def adopt_sidecar(args: argparse.Namespace, files: Sequence[Path]) -> bool:
    """Fill options from the sidecar of the first crash file among ``files``; True if one was used.

    Raises
    ------
    fuzzer.artifacts.manifest.SidecarError
        A damaged sidecar, or one naming targets that may not be imported.
    """
    for path in files:
        from fuzzer.artifacts.sidecar import read_sidecar  # a campaign on folders: not needed
        from fuzzer.artifacts.trust import config_from

        sidecar = read_sidecar(path)
        if sidecar is None:
            continue
        given = _given(args)
        trust = bool(getattr(args, "trust_sidecar", False))
        # options given on the command line are not checked here (only their names matter)
        chosen = {k: getattr(args, k) for k in given & {"robot", "targets"}}
        config = config_from(sidecar, sidecar_path(path), chosen, trust)
        values = {
            "op": config.op,
            "robot": config.robot,
            "tip_link": config.tip_link,
            "msg_type": config.message_type,
            "tolerance": f"m={config.tolerance.metres!r},rad={config.tolerance.radians!r}",
            "targets": ",".join(config.targets),
        }
        _apply(
            args,
            {k: v for k, v in values.items() if k not in given and v is not None},
            sidecar_path(path),
        )
        return True
    return False


def adopt_manifest(args: argparse.Namespace, folders: Sequence[Path]) -> None:
    """Fill options from the manifest of the first corpus folder that has one.

    Raises
    ------
    fuzzer.artifacts.manifest.SidecarError
        A damaged manifest, or an unusable robot in it.
    """
    for folder in folders:
        found = manifest.read(folder)
        if found is None:
            continue
        if getattr(args, "op", None) not in (None, found.config.get("op", "move")):
            return  # made for another op: check_manifests refuses it
        trust = bool(getattr(args, "trust_sidecar", False))
        values = manifest.fill(found, _given(args), trust)
        targets: list[str] = found.config.get("targets") or []
        unused = "targets" not in values and getattr(args, "targets", None) is None
        if unused and targets and list(targets) != ["native", "python"]:
            reporting.warn(
                f"{found.path} names targets {','.join(targets)}; not imported from a file "
                "(pass --targets or --trust-sidecar to use them): fuzzing native vs python"
            )
        _apply(args, values, found.path)
        return


def check_manifests(folders: Sequence[Path], config: RunConfig) -> None:
    """Refuse corpus folders made for another robot, op or message type.

    Raises
    ------
    fuzzer.artifacts.manifest.SidecarError
        Saying what the corpus was made for.
    """
    for folder in folders:
        found = manifest.read(folder)
        if found is not None:
            for warning in manifest.check(found, config):
                reporting.warn(warning)


def record_corpus(corpus: Sequence[Path], config: RunConfig) -> None:
    """Write the manifest of the first corpus folder (called once the configuration has opened,
    so a configuration that cannot run is never recorded); a corpus without one is adopted."""
    folders = [p for p in corpus if p.is_dir()]
    if folders:
        try:
            manifest.write(folders[0], config)
        except OSError as exc:
            reporting.warn(f"cannot write the corpus manifest of {folders[0]}: {exc.strerror or exc}")
        except manifest.SidecarError as exc:  # a link made since the manifest was read
            reporting.warn(f"the corpus manifest is not written: {exc}")


def prepare_campaign(corpus: Sequence[Path], artifacts: Path, *, merge: bool = False) -> list[Path]:
    """Check and create a campaign's folders; return the corpus folders.

    ``merge``: a ``-merge=1`` run, whose folders after the first are what it reads: they must
    exist (a mistyped one was created empty, and nothing merged from it, without a word).

    Raises
    ------
    fuzzer.input.paths.PathError
        A corpus entry that is a FIFO or device, a folder that cannot be created,
        listed or written, an artifacts path that is a file, a merge's input that is not there.
    """
    folders: list[Path] = []
    for path in corpus:
        check_input_file(path)
        if path.is_file():
            continue
        if merge and folders and not path.exists():
            raise PathError(f"corpus {path}: no such folder (a merge reads the folders after the first)")
        prepare_folder(path, "corpus", writable=not folders)
        folders.append(path)
    prepare_folder(artifacts, "artifacts", writable=True)
    for folder in folders:
        real = os.path.realpath(folder)
        if os.path.realpath(artifacts) == real or os.path.realpath(artifacts).startswith(real + os.sep):
            raise PathError(
                f"artifacts {artifacts}: inside the corpus folder {folder} (libFuzzer would read the "
                "campaign's logs and crash files as inputs); name another --artifacts"
            )
    check_artifacts(artifacts)
    return folders


def check_artifacts(artifacts: Path) -> None:
    """Refuse an artifacts folder whose entries a campaign writes are not regular files of its own:
    a FIFO named ``stats.jsonl`` or ``divergences.jsonl`` blocked the campaign before its first
    input (past a SIGTERM, which waits for the next input), and a link named ``.signatures`` or
    ``stats.jsonl`` had it read, write and delete files elsewhere.

    Raises
    ------
    fuzzer.input.paths.PathError
        Naming the entry and what it is.
    """
    from fuzzer.artifacts.divlog import DIVERGENCES, STATS
    from fuzzer.input.paths import JOB_LOG, kind_of

    def refuse(path: Path, mode: int) -> None:
        raise PathError(
            f"artifacts {artifacts}: {path.name} is {kind_of(mode)}, where the campaign keeps a "
            f"regular file of its own; remove it or name another --artifacts"
        )

    with os.scandir(artifacts) as entries:
        for entry in entries:
            if entry.name in (DIVERGENCES, STATS) or JOB_LOG.fullmatch(entry.name):
                mode = entry.stat(follow_symlinks=False).st_mode
                if not stat.S_ISREG(mode):
                    refuse(Path(entry.path), mode)
    markers = artifacts / MARKERS
    try:
        mode = markers.lstat().st_mode
    except FileNotFoundError:
        return
    if not stat.S_ISDIR(mode):
        raise PathError(
            f"artifacts {artifacts}: .signatures is {kind_of(mode)}, where the campaign keeps its "
            "folder of signature markers; remove it or name another --artifacts"
        )
    with os.scandir(markers) as entries:
        for entry in entries:
            mode = entry.stat(follow_symlinks=False).st_mode
            if not stat.S_ISREG(mode):
                raise PathError(
                    f"artifacts {artifacts}: .signatures/{entry.name} is {kind_of(mode)}, not a marker "
                    "the campaign wrote (a divergence of that signature would be lost); remove it"
                )


CONFIGURATION = ".rrosfuzz-configuration"
"""The artifacts folder's record of the first campaign's robot and targets (one line)."""


def note_configuration(artifacts: Path, config: RunConfig) -> None:
    """Warn when the artifacts folder holds crash files of a campaign on another robot or pair of
    targets. A signature names a symptom, not the configuration: a symptom already on file there
    gets no crash file of this campaign, and its divergences go into the other's bucket (two zoo
    bugs on two robots made one bucket with the first one's file; the triage probe). The first
    campaign's line is written once and kept."""
    digest = (manifest.robot_digest(config.robot) or "")[:12]
    line = f"robot {config.robot} ({digest}), tip link {config.tip_link}, targets {','.join(config.targets)}"
    path = artifacts / CONFIGURATION
    try:
        info = path.lstat()
    except FileNotFoundError:
        from fuzzer.artifacts.store import atomic_write

        with contextlib.suppress(OSError):  # a folder that cannot be written says so later
            atomic_write(path, (line + "\n").encode(), durable=False)
        return
    except OSError:
        return
    if not stat.S_ISREG(info.st_mode) or info.st_size > 4096:
        return  # not of our making: nothing to compare with
    try:
        first = path.read_bytes().decode("utf-8", "backslashreplace").strip()
    except OSError:
        return
    if first != line:
        reporting.warn(
            f"artifacts {artifacts} holds crash files of a campaign on another configuration "
            f"({first}); this one is {line}. A divergence whose symptom is on file there already "
            "gets no crash file of this campaign: name another --artifacts to keep them apart"
        )
