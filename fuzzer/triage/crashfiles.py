"""Minimizing crash files (``fuzz_diff.py minimize``): a crash file and its sidecar in, a
``minimized-<sha1>`` file and sidecar out, under the configuration the sidecar records.

The command line (``fuzzer.cli``) parses the options, walks the files and reports; the steps
are here: :func:`load` (sidecar, configuration, session, test case), :func:`shrink` (the
shrinker of ``fuzzer.triage.minimize``, with the history of a state-dependent divergence),
:func:`minimized_sidecar` (the original sidecar with the minimized input's call, outcomes and
comparison) and :func:`write_minimized`. Files stay data: the sidecar is parsed, never
evaluated (``fuzzer.artifacts.sidecar``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fuzzer.artifacts.sidecar import SidecarError, read_sidecar
from fuzzer.artifacts.store import ArtifactStore, sidecar_path
from fuzzer.artifacts.trust import config_from
from fuzzer.execution.history import history_of
from fuzzer.execution.session import RunConfig, Session
from fuzzer.input.testcase import TestCase, TestCaseError, decode, read_bytes
from fuzzer.triage.minimize import Minimizer, Shrunk, joints_that_matter


@dataclass(frozen=True)
class Loaded:
    """A crash file ready to shrink."""

    path: Path
    raw: bytes
    case: TestCase
    sidecar: dict[str, Any]
    config: RunConfig
    session: Session

    @property
    def history(self) -> Any:
        """The calls before it, for a state-dependent divergence (``[]`` otherwise: fresh targets)."""
        return history_of(self.sidecar)


def load(path: Path, given: dict[str, Any], trust: bool, sessions: dict[RunConfig, Session]) -> Loaded:
    """Read ``path`` and its sidecar, and open (or reuse, from ``sessions``) the session of
    the configuration the sidecar records, with the options ``given`` on the command line.

    Raises
    ------
    ConfigError
        No sidecar, a sidecar or configuration that cannot be used, or a file that is not a
        test case; the message names the file.
    """
    sidecar = read_sidecar(path)
    if sidecar is None:
        raise SidecarError(
            f"{path}: no sidecar ({sidecar_path(path).name}); only divergence crash files "
            "written by RROSFuzz can be minimized (use -minimize_crash=1 for others)"
        )
    config = config_from(sidecar, sidecar_path(path), given, trust)
    from fuzzer.triage.replay import session_for

    session_for(path, config, sessions, "minimize")  # its error names the file and the sidecar
    try:
        raw = read_bytes(path)
        case = decode(raw)
    except (OSError, TestCaseError) as exc:
        raise SidecarError(f"{path}: not a test case: {exc}") from None
    try:
        history_of(sidecar)  # read now: a damaged one is the sidecar's error (exit 2), not a stale file's
    except ValueError as exc:
        raise SidecarError(f"{sidecar_path(path)}: field 'history': {exc}") from None
    return Loaded(path, raw, case, sidecar, config, sessions[config])


def shrink(loaded: Loaded, budget: int) -> Shrunk:
    """The simplest input with the crash file's signature within ``budget`` evaluations.

    Raises
    ------
    ValueError
        The file does not reproduce its signature.
    """
    minimizer = Minimizer(loaded.session, budget, loaded.history)
    return minimizer.minimize(loaded.case, loaded.sidecar["signature"]["key"])


def already_minimal(loaded: Loaded, shrunk: Shrunk) -> bool:
    """True for a ``minimized-`` file that shrinking left as it was (a second ``minimize`` of
    it would write the same message again under a new name, its lineage one step longer)."""
    same = shrunk.case.msg_type == loaded.case.msg_type and shrunk.case.message == loaded.case.message
    return same and loaded.path.name.startswith("minimized-")


def minimized_sidecar(loaded: Loaded, shrunk: Shrunk) -> tuple[bytes, dict[str, Any]]:
    """(the minimized input's bytes, its sidecar): the original sidecar with the configuration,
    the minimized test case, where it came from, the joints that matter and the shrink's
    counts; and the call, outcomes and comparison of the minimized input, not the original's
    (a scenario's step list shrinks, and the sidecar's schema checks they match).

    Raises
    ------
    ValueError
        The minimized input, replayed on fresh targets, has not the file's signature (a
        shrink judged otherwise than a replay judges; never written).
    """
    from fuzzer.artifacts.sidecar_record import build_sidecar

    session = loaded.session
    data = shrunk.case.encode()
    out = dict(
        loaded.sidecar,
        config=loaded.config.to_json(),
        testcase=shrunk.case.to_json(),
        minimized_from=loaded.path.name,
        joints_that_matter=joints_that_matter(shrunk.case, session.reference.joint_names),
        shrink={"evaluations": shrunk.evaluations, "accepted": shrunk.accepted, "complete": shrunk.complete},
    )
    again = session.evaluator().evaluate(shrunk.case, history=loaded.history)
    key = loaded.sidecar["signature"]["key"]
    if again.signature is None or again.signature.key != key:
        now = "does not diverge" if again.signature is None else f"diverges as {again.signature.key[:12]}"
        raise ValueError(f"the minimized input {now} when replayed, not as {key[:12]}: nothing written")
    versions, digest = loaded.sidecar.get("versions", {}), loaded.sidecar.get("robot_sha256", "")
    fresh = build_sidecar(session, shrunk.case, data, again, versions, digest)
    for name in ("sha1", "comparison", "difference", "call", "outcomes", "lineage", "strategy", "written"):
        out[name] = fresh[name]
    return data, out


def write_minimized(folder: Path, data: bytes, sidecar: dict[str, Any]) -> Path:
    """Write ``minimized-<sha1>`` and its sidecar into ``folder``; returns the file's path.

    Raises
    ------
    OSError
        The folder cannot be written.
    """
    written = ArtifactStore(folder).write(data, sidecar)
    minimized = written.with_name("minimized-" + written.name.split("-", 1)[1])
    written.replace(minimized)
    written.with_name(written.name + ".json").replace(minimized.with_name(minimized.name + ".json"))
    return minimized
