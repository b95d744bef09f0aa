"""The corpus manifest: which robot, op and message type a corpus folder was made for.

``CORPUS/.rrosfuzz/manifest.json`` is written when a campaign creates or uses a
corpus folder (in a hidden sub-folder, because libFuzzer feeds every file at the
top of a corpus folder to the target, but never enters folders whose name starts
with a dot). It records the run configuration and the robot file's SHA-256.

What it does:

* options not given on the command line are taken from it (op, robot, tip link,
  message type, tolerance, ``max_steps`` of a scenario corpus, and targets when they
  are the builtins, see :mod:`fuzzer.artifacts.sidecar`), for campaigns, ``-merge`` and ``coverage``;
* a corpus made for another op, message type or robot is refused (the robot
  counts as the same when its name or its file's SHA-256 matches; the same name
  with a changed file is a warning);
* a corpus folder without a manifest (made before manifests existed) is adopted:
  the campaign writes one.
"""

from __future__ import annotations

import datetime
import hashlib
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NamedTuple

from fuzzer.artifacts.store import atomic_write
from fuzzer.execution.session import ConfigError, RunConfig
from robot_api import robots
from robot_api.errors import RobotAPIError

MANIFEST = Path(".rrosfuzz") / "manifest.json"
FORMAT = 1


class SidecarError(ConfigError):
    """A sidecar (or manifest) that cannot be used as it is; the message names file and field.

    Defined here, not in :mod:`fuzzer.artifacts.sidecar` (which imports it from here): a campaign
    on a new corpus folder checks for a manifest before its first input, and raising or catching
    this error must not load the sidecar reader (0.45 ms by ``-X importtime``), which only a
    crash file or a manifest that exists needs.
    """


def path_of(corpus: Path) -> Path:
    return corpus / MANIFEST


def _outside(corpus: Path) -> str | None:
    """Where the manifest's folder or file leads out of ``corpus`` (symlinks followed), or None
    when they are inside it or do not exist yet. A ``.rrosfuzz`` symlink made a campaign read
    and write a manifest wherever it pointed."""
    from fuzzer.input.paths import contained

    for path in (corpus / MANIFEST.parent, path_of(corpus)):
        if (path.exists() or path.is_symlink()) and not contained(corpus, path):
            return str(path)
    return None


def _refuse_outside(corpus: Path) -> None:
    where = _outside(corpus)
    if where is not None:
        raise SidecarError(
            f"{where} leads outside the corpus folder {corpus} (symlinks followed); a corpus's "
            "settings are never read or written elsewhere: remove the link"
        )


def robot_digest(spec: str) -> str | None:
    """SHA-256 of the robot file a spec resolves to, or None when it does not resolve."""
    try:
        return hashlib.sha256(robots.resolve(spec).read_bytes()).hexdigest()
    except (OSError, ValueError, RobotAPIError):  # URDFError: neither a file nor a known robot
        return None


class Manifest(NamedTuple):
    """A corpus manifest that was read and validated (a NamedTuple: a campaign on a new corpus
    folder imports this module before its first input, and a frozen dataclass took 0.6 ms to
    define, a tenth of what the full engine's start-up lost to uniform sampling's)."""

    path: Path
    data: dict[str, Any]

    @property
    def config(self) -> dict[str, Any]:
        config: dict[str, Any] = self.data["config"]
        return config

    @property
    def robot_sha256(self) -> str | None:
        digest = self.data.get("robot_sha256")
        return digest if isinstance(digest, str) else None

    def describe(self) -> str:
        c = self.config
        return f"op {c.get('op', 'move')}, robot {c.get('robot', '?')}, {c.get('msg_type', '?')}"


def read(corpus: Path) -> Manifest | None:
    """The manifest of a corpus folder, or None when it has none.

    Raises
    ------
    SidecarError
        A manifest that is damaged or has fields of the wrong type (naming it).
    """
    path = path_of(corpus)
    if not path.exists() and not path.is_symlink():
        _refuse_outside(corpus)  # a dangling or outside .rrosfuzz, written to next
        return None
    _refuse_outside(corpus)
    # imported when there is a manifest to read (as below): a new corpus folder has none
    from fuzzer.artifacts.sidecar import read_json_file, validate_config

    data = read_json_file(path, "corpus manifest")
    if not isinstance(data.get("config"), dict):
        raise SidecarError(f"{path}: field 'config' is missing or not an object (delete the file to adopt)")
    validate_config(data["config"], path)
    return Manifest(path, data)


def check(manifest: Manifest, config: RunConfig) -> list[str]:
    """Refuse a corpus made for another op, message type or robot; return warnings.

    Raises
    ------
    SidecarError
        Saying what the corpus was made for and what was asked.
    """
    corpus = manifest.path.parent.parent
    recorded = manifest.config
    hint = "use another corpus folder, or delete the manifest to reuse the inputs anyway"
    op = recorded.get("op", "move")
    if op != config.op:
        raise SidecarError(f"corpus {corpus} was made for op {op}, not {config.op} ({manifest.path}); {hint}")
    msg_type = recorded.get("msg_type") or ""
    if msg_type and msg_type != config.message_type:
        raise SidecarError(
            f"corpus {corpus} holds {msg_type} inputs, not {config.message_type} ({manifest.path}); {hint}"
        )
    warnings = []
    robot = recorded.get("robot")
    digest = robot_digest(config.robot)
    same_name = robot == config.robot
    same_file = digest is not None and digest == manifest.robot_sha256
    if not same_name and not same_file:
        raise SidecarError(
            f"corpus {corpus} was made for robot {robot}, not {config.robot} ({manifest.path}); {hint}"
        )
    if same_name and not same_file and manifest.robot_sha256:
        warnings.append(f"corpus {corpus}: the file of robot {robot} changed since the corpus was made")
    return warnings


def fill(manifest: Manifest, given: set[str], trust: bool = False) -> dict[str, str]:
    """Options to take from the manifest (command-line spelling), for those not in ``given``.

    Targets are taken only when they are builtins (or with ``trust``); the robot
    only when it is a shipped name or an existing regular file in the corpus folder or the
    working directory (anywhere with ``trust``).
    """
    from fuzzer.artifacts.trust import foreign_targets, safe_robot

    c = manifest.config
    out: dict[str, str] = {}
    if "op" not in given and "op" in c:
        out["op"] = c["op"]
    if "robot" not in given and "robot" in c:
        out["robot"] = safe_robot(c["robot"], manifest.path, trust, folder=manifest.path.parent.parent)
    if "tip_link" not in given and c.get("tip_link"):
        out["tip_link"] = c["tip_link"]
    if "msg_type" not in given and c.get("msg_type"):
        out["msg_type"] = c["msg_type"]
    if "tolerance" not in given and isinstance(c.get("tolerance"), dict):
        tol = c["tolerance"]
        out["tolerance"] = f"m={tol.get('m', 1e-6)!r},rad={tol.get('rad', 1e-6)!r}"
    targets = c.get("targets")
    if "targets" not in given and isinstance(targets, list) and (trust or not foreign_targets(targets)):
        out["targets"] = ",".join(targets)
    return out


def recorded_max_steps(paths: Sequence[Path], op: str | None) -> int | None:
    """The ``max_steps`` a scenario campaign over ``paths`` runs with when ``--max-steps`` is
    not given: the first crash file's sidecar's, else the first corpus manifest's (when it
    was made for op ``scenario`` and ``op`` is that or not given); None otherwise.

    Raises
    ------
    SidecarError
        A damaged sidecar or manifest.
    """
    configs: list[dict[str, Any]] = []
    for path in paths:
        if path.is_file():
            from fuzzer.artifacts.sidecar import read_sidecar

            sidecar = read_sidecar(path)
            if sidecar is not None:
                configs.append(sidecar["config"])
                break
    else:
        found = next((m for m in map(read, (p for p in paths if p.is_dir())) if m is not None), None)
        if found is not None:
            configs.append(found.config)
    for config in configs:
        steps = config.get("max_steps")
        if config.get("op") == "scenario" and op in (None, "scenario") and isinstance(steps, int):
            return steps
    return None


def write(corpus: Path, config: RunConfig) -> Path:
    """Write the manifest of a corpus folder (left alone when it already says the same).

    Raises
    ------
    SidecarError
        The manifest's folder or file leads outside the corpus folder (a symlink).
    OSError
        It cannot be written.
    """
    _refuse_outside(corpus)
    path = path_of(corpus)
    data: dict[str, Any] = {
        "rrosfuzz_corpus": FORMAT,
        "config": config.to_json(),
        "robot_sha256": robot_digest(config.robot),
    }
    try:
        old = read(corpus)
    except SidecarError:
        old = None
    if old is not None and all(old.data.get(k) == v for k, v in data.items()):
        return path
    data["written"] = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    atomic_write(path, (json.dumps(data, indent=1, sort_keys=True) + "\n").encode())
    return path
