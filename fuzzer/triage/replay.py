"""Replaying crash files: does the divergence still reproduce, with the same signature?

A crash file is replayed under the configuration its sidecar records (op,
robot, targets, tolerance, message type), unless the command line overrides
it. The sidecar is untrusted data (:mod:`fuzzer.artifacts.sidecar`): it is validated
strictly, and targets other than the builtins are imported only when the
command line passes ``--targets`` or ``--trust-sidecar``.

A file without a sidecar (a native crash or a timeout written by libFuzzer
itself, or a corpus input) replays like libFuzzer replays an input: under the
configuration of its folder's corpus manifest when there is one
(:mod:`fuzzer.artifacts.manifest`), else under the command line's (the defaults when none
is given). Nothing is recorded to compare with, so the verdict says so instead
of "now agrees", and the configuration used is named.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fuzzer.artifacts import manifest
from fuzzer.artifacts.sidecar import BUILTIN_TARGETS, SidecarError, read_sidecar
from fuzzer.artifacts.store import sidecar_path
from fuzzer.artifacts.trust import config_from, describe
from fuzzer.execution.evaluate import Evaluation, Verdict
from fuzzer.execution.records import UNCOUNTED
from fuzzer.execution.session import ConfigError, RunConfig, Session
from fuzzer.input.paths import PathError, crash_inputs
from fuzzer.input.testcase import TestCase, TestCaseError, read_case
from fuzzer.report.steps import SCENARIO_TYPE, scenario_steps


class Result(enum.StrEnum):
    SAME = "still diverges (same signature)"
    DIFFERENT = "diverges differently"
    AGREES = "now agrees"
    EXPLAINED = "now explained (not a finding)"
    """Another signature than the sidecar's, of a kind the oracle explains (``known_limitation``,
    ``ill_conditioned``: ``records.UNCOUNTED``), which a campaign writes for triage but does not
    count: a divergence an older engine reported that a documented rule now covers."""
    NEW = "diverges (no sidecar to compare with)"
    UNRECORDED_AGREES = "the targets agree (no sidecar to compare with)"
    SKIPPED = "skipped"


@dataclass(frozen=True)
class Replay:
    path: Path
    result: Result
    evaluation: Evaluation | None
    expected: str | None
    detail: str = ""
    config: RunConfig | None = None
    has_sidecar: bool = True
    source: str = "sidecar"
    """Where the configuration came from: sidecar, a corpus manifest's path, or command line."""
    steps: tuple[str, ...] = ()
    """For a scenario that diverges: the first divergent step, then one line per step
    (:meth:`fuzzer.report.steps.ScenarioSteps.lines`); the first ends ``detail``, the
    others are printed under the verdict."""

    @property
    def diverges(self) -> bool:
        return self.result in (Result.SAME, Result.DIFFERENT, Result.NEW)


def config_for(
    path: Path, base: RunConfig, overrides: dict[str, Any], trust: bool = False
) -> tuple[RunConfig, dict[str, Any] | None]:
    """The configuration to replay ``path`` under, and its validated sidecar (None without one).

    ``base`` is the command line's configuration (``overrides`` applied), used as is
    for a file without a sidecar.

    Raises
    ------
    fuzzer.artifacts.sidecar.SidecarError
        A damaged sidecar, or one naming targets that may not be imported.
    """
    sidecar = read_sidecar(path)
    if sidecar is None:
        found = manifest.read(path.parent)
        if found is None:
            return base, None
        return config_from(found.data, found.path, overrides, trust), None
    return config_from(sidecar, sidecar_path(path), overrides, trust), sidecar


def _phrase(source: str) -> str:
    return {"sidecar": "its sidecar", "command line": "the command line"}.get(source, source)


def source_of(path: Path) -> str:
    """Where :func:`config_for` takes the configuration of ``path`` from (for messages)."""
    if sidecar_path(path).exists():
        return "sidecar"
    found = manifest.path_of(path.parent)
    return str(found) if found.exists() else "command line"


def session_for(
    path: Path, config: RunConfig, cache: dict[RunConfig, Session], verb: str = "replay"
) -> Session:
    """The session of ``config`` from ``cache``, opened (and kept there) if need be.

    Raises
    ------
    ConfigError
        It cannot be opened; the message names ``path`` and where its configuration came from.
    """
    if config not in cache:
        try:
            cache[config] = Session.open(config)
        except ConfigError as exc:
            raise ConfigError(
                f"{path}: cannot {verb} under the configuration from {_phrase(source_of(path))}: {exc}"
            ) from None
    return cache[config]


def replay_file(
    path: Path,
    base: RunConfig,
    overrides: dict[str, Any],
    sessions: dict[RunConfig, Session] | None = None,
    trust: bool = False,
) -> Replay:
    """Replay one file; ``sessions`` caches targets between files of one configuration.

    Raises
    ------
    fuzzer.execution.session.ConfigError
        The sidecar cannot be used, or its configuration cannot be opened.
    """
    config, sidecar = config_for(path, base, overrides, trust)
    unrecorded = sidecar is None
    try:
        case = read_case(path)
    except OSError as exc:  # unreadable: an error (exit 2), not a file that is no test case (exit 0)
        raise PathError(f"{path}: cannot be read: {exc.strerror or exc}") from None
    except TestCaseError as exc:
        return Replay(path, Result.SKIPPED, None, None, f"not a test case: {exc}", config, not unrecorded)
    cache = sessions if sessions is not None else {}
    session = session_for(path, config, cache)
    if case.msg_type != config.message_type:
        return Replay(
            path,
            Result.SKIPPED,
            None,
            None,
            f"message type {case.msg_type} is not {config.message_type}",
            config,
            not unrecorded,
        )
    from fuzzer.execution.history import history_of

    try:
        history = history_of(sidecar)
    except ValueError as exc:  # a damaged sidecar, as a field of the wrong type is (exit 2)
        raise SidecarError(f"{sidecar_path(path)}: field 'history': {exc}") from None
    # fresh targets for every file, and a state_dependent divergence's recorded calls first
    evaluation = session.evaluator().evaluate(case, history=history)
    expected = sidecar["signature"]["key"] if sidecar else None
    if evaluation.verdict != Verdict.EVALUATED:
        return Replay(
            path,
            Result.SKIPPED,
            evaluation,
            expected,
            f"{evaluation.verdict}: {evaluation.reason}",
            config,
            not unrecorded,
        )
    got = evaluation.signature.key if evaluation.signature else None
    if got is None:
        result = Result.UNRECORDED_AGREES if unrecorded else Result.AGREES
    elif expected is None:
        result = Result.NEW
    elif got == expected:
        result = Result.SAME
    else:
        result = Result.EXPLAINED if evaluation.comparison.kind in UNCOUNTED else Result.DIFFERENT
    detail = ""
    steps: tuple[str, ...] = ()
    if evaluation.signature is not None:
        cmp = evaluation.comparison
        detail = f"signature {got}: {cmp.headline(tuple(session.reference.joint_names))}"
        steps = scenario_lines(case, evaluation, tuple(r.name for r in session.runners))
    if unrecorded:
        detail = "; ".join(filter(None, [detail, f"replayed under {describe(config)}"]))
    else:
        changed = settings_changed(config, sidecar)
        if changed:  # "now agrees" under other targets read as a fix
            detail = "; ".join(filter(None, [detail, f"replayed with {changed}"]))
        if robot_changed(session, sidecar):
            detail = "; ".join(filter(None, [detail, ROBOT_CHANGED]))
    if steps:
        detail = f"{detail}; {steps[0]}"  # the step list follows the verdict line (cli_tools.replay_main)
    return Replay(path, result, evaluation, expected, detail, config, not unrecorded, steps=steps)


ROBOT_CHANGED = (
    "the robot file is not the campaign's (its SHA-256 differs from the sidecar's robot_sha256): "
    "the verdict is on today's file"
)


def robot_changed(session: Session, sidecar: dict[str, Any] | None) -> bool:
    """Whether the robot file replayed on is not the one the sidecar's campaign ran on (a verdict
    of "now agrees" would otherwise read as a fix)."""
    digest = sidecar.get("robot_sha256") if sidecar is not None else None
    if not isinstance(digest, str) or not digest:
        return False
    try:
        return session.robot_digest() != digest
    except OSError:
        return True  # the file is gone or unreadable now: not the campaign's, as far as we know


def settings_changed(config: RunConfig, sidecar: dict[str, Any] | None) -> str:
    """The settings ``config`` (the command line's options on the sidecar's) replays with that
    are not the campaign's, each with the campaign's value: "" when none is. A verdict of "now
    agrees" under ``--targets native,native2``, or in process for a file found over ROS, read as
    a fix without a word."""
    recorded = sidecar.get("config") if sidecar is not None else None
    if not isinstance(recorded, dict):
        return ""
    out = []
    targets = recorded.get("targets", list(BUILTIN_TARGETS))
    if isinstance(targets, list) and tuple(targets) != config.targets:
        out.append(f"targets {','.join(config.targets)} (the campaign's: {','.join(map(str, targets))})")
    for name, label in (
        ("op", "op"),
        ("transport", "transport"),
        ("tip_link", "tip link"),
        ("max_steps", "max steps"),
    ):
        was = recorded.get(name, RunConfig.__dataclass_fields__[name].default)
        now = getattr(config, name)
        if isinstance(was, str | int | type(None)) and not isinstance(was, bool) and was != now:
            out.append(
                f"{label} {_or_default(now)} (the campaign's: {_or_default(was)})"
            )  # another tip: another chain
    msg_type = recorded.get("msg_type")
    if isinstance(msg_type, str) and msg_type and msg_type != config.message_type:
        out.append(f"message type {config.message_type} (the campaign's: {msg_type})")
    tolerance = recorded.get("tolerance")
    if isinstance(tolerance, dict):
        was_m, was_rad = tolerance.get("m"), tolerance.get("rad")
        if (was_m, was_rad) != (config.tolerance.metres, config.tolerance.radians):
            out.append(
                f"tolerance {config.tolerance.metres:g} m / {config.tolerance.radians:g} rad "
                f"(the campaign's: {was_m:g} m / {was_rad:g} rad)"
                if isinstance(was_m, int | float) and isinstance(was_rad, int | float)
                else f"tolerance {config.tolerance.metres:g} m / {config.tolerance.radians:g} rad"
            )
    filtering = recorded.get("filtering")
    if isinstance(filtering, bool) and filtering != config.filtering:
        out.append("--no-filter" if not config.filtering else "the filter on (the campaign's: --no-filter)")
    return ", ".join(out)


def _or_default(value: object) -> str:
    return "the default" if value is None else str(value)


def scenario_lines(case: TestCase, evaluation: Evaluation, targets: tuple[str, ...]) -> tuple[str, ...]:
    """The step list of a divergent scenario as replayed (``()`` for any other test case):
    the first divergent step with both targets' outcome labels there, then one line per step."""
    message = case.message.get("steps") if case.msg_type == SCENARIO_TYPE else None
    if not isinstance(message, list):
        return ()
    cmp = evaluation.comparison
    found = scenario_steps(message, evaluation.outcomes, cmp.step, cmp.step_kind, cmp.field, targets)
    return tuple(found.lines())


def expand(paths: Iterable[Path]) -> list[Path]:
    """Files and the test files inside folders; sidecars skipped (:func:`fuzzer.input.paths.crash_inputs`)."""
    return crash_inputs(paths)
