"""What a crash file's sidecar holds when it is written (``fuzzer.campaign``, its dry run's
children, and ``fuzzer.triage.crashfiles`` for a minimized input); ``fuzzer.artifacts.sidecar``
reads them back, as untrusted input."""

from __future__ import annotations

import datetime
import hashlib
from dataclasses import asdict
from typing import Any

from fuzzer.execution.session import Session, outcome_json
from fuzzer.input.testcase import TestCase

__all__ = ["build_sidecar"]


def build_sidecar(
    session: Session, case: TestCase, data: bytes, ev: Any, recorded: dict[str, str], digest: str
) -> dict[str, Any]:
    """Everything needed to understand and replay one divergence."""
    comparison = {
        **asdict(ev.comparison),
        "kind": str(ev.comparison.kind),
        "joints": list(ev.comparison.joints),
    }
    return {
        "rrosfuzz_sidecar": 1,
        "sha1": hashlib.sha1(data).hexdigest(),
        "signature": ev.signature.to_json(),
        "comparison": comparison,
        "difference": ev.difference,
        "config": session.config.to_json(),
        "robot_path": str(session.urdf),
        "robot_sha256": digest,
        "joint_names": list(session.reference.joint_names),
        "testcase": case.to_json(),
        "strategy": case.strategy,
        "lineage": list(case.lineage),
        "call": {"kind": type(ev.call).__name__, **asdict(ev.call)},
        "outcomes": [outcome_json(r, o) for r, o in zip(session.runners, ev.outcomes, strict=True)],
        "versions": dict(recorded),
        "written": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    }
