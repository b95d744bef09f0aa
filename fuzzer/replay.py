"""Replaying crash files: does the divergence still reproduce, with the same signature?

A crash file is replayed under the configuration its sidecar records (op,
robot, targets, tolerance, message type), unless the command line overrides
it. A crash file without a sidecar (a native crash or a timeout written by
libFuzzer itself) replays under the command line's configuration.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from fuzzer.artifacts import load_sidecar
from fuzzer.evaluate import Evaluation, Verdict
from fuzzer.session import RunConfig, Session
from fuzzer.testcase import TestCaseError, decode


class Result(enum.StrEnum):
    SAME = "still diverges (same signature)"
    DIFFERENT = "diverges differently"
    AGREES = "now agrees"
    NEW = "diverges"  # no sidecar to compare with
    SKIPPED = "skipped"


@dataclass(frozen=True)
class Replay:
    path: Path
    result: Result
    evaluation: Evaluation | None
    expected: str | None
    detail: str = ""

    @property
    def diverges(self) -> bool:
        return self.result in (Result.SAME, Result.DIFFERENT, Result.NEW)


def config_for(
    path: Path, base: RunConfig, overrides: dict[str, Any]
) -> tuple[RunConfig, dict[str, Any] | None]:
    sidecar = load_sidecar(path)
    config = RunConfig.from_json(sidecar["config"]) if sidecar else base
    return (replace(config, **overrides) if overrides else config), sidecar


def replay_file(
    path: Path, base: RunConfig, overrides: dict[str, Any], sessions: dict[RunConfig, Session] | None = None
) -> Replay:
    """Replay one file; ``sessions`` caches targets between files of one configuration."""
    config, sidecar = config_for(path, base, overrides)
    try:
        case = decode(path.read_bytes())
    except (OSError, TestCaseError) as exc:
        return Replay(path, Result.SKIPPED, None, None, f"not a test case: {exc}")
    cache = sessions if sessions is not None else {}
    if config not in cache:
        cache[config] = Session.open(config)
    session = cache[config]
    if case.msg_type != config.message_type:
        return Replay(
            path, Result.SKIPPED, None, None, f"message type {case.msg_type} is not {config.message_type}"
        )
    evaluation = session.evaluator().evaluate(case)
    expected = sidecar["signature"]["key"] if sidecar else None
    if evaluation.verdict != Verdict.EVALUATED:
        return Replay(
            path, Result.SKIPPED, evaluation, expected, f"{evaluation.verdict}: {evaluation.reason}"
        )
    got = evaluation.signature.key if evaluation.signature else None
    if got is None:
        result = Result.AGREES
    elif expected is None:
        result = Result.NEW
    else:
        result = Result.SAME if got == expected else Result.DIFFERENT
    detail = ""
    if evaluation.signature is not None:
        cmp = evaluation.comparison
        detail = f"signature {got}: {cmp.kind} on {cmp.field or 'status'}, difference {cmp.difference:.3g}"
    return Replay(path, result, evaluation, expected, detail)


def expand(paths: Iterable[Path]) -> list[Path]:
    """Files and the crash/test files inside folders (sidecars excluded)."""
    out: list[Path] = []
    for p in paths:
        if p.is_dir():
            out.extend(
                sorted(
                    f
                    for f in p.iterdir()
                    if f.is_file() and not f.name.endswith(".json") and not f.name.startswith(".")
                )
            )
        else:
            out.append(p)
    return out
