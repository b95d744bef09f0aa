"""Triage buckets as the page shows them: each bucket's representative, its two targets'
answers and its test case, shortened for the page."""

from __future__ import annotations

import json
import shlex
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from fuzzer.artifacts.store import sidecar_path
from fuzzer.report.records import _int, _number
from fuzzer.triage.pipeline import Bucket

# -- buckets ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class OutcomeView:
    """One target's recorded answer."""

    target: str
    status: str
    error: str
    code: int | None
    message: str
    values: dict[str, tuple[float, ...]]

    @property
    def label(self) -> str:
        if self.error or self.status in ("rejected", "crashed"):
            return f"{self.status}: {self.error} (code {self.code})"
        return self.status

    @classmethod
    def parse(cls, data: Any) -> OutcomeView | None:
        if not isinstance(data, dict):
            return None
        values: dict[str, tuple[float, ...]] = {}
        raw = data.get("values")
        if isinstance(raw, dict):
            for name, vector in raw.items():
                if isinstance(vector, list):
                    values[str(name)] = tuple(float(x) for x in vector if _number(x) is not None)
        code = data.get("code")
        return cls(
            str(data.get("target", "?")),
            str(data.get("status", "?")),
            str(data.get("error") or ""),
            code if isinstance(code, int) else None,
            str(data.get("message") or ""),
            values,
        )


@dataclass(frozen=True)
class BucketView:
    """What the page shows of one bucket."""

    key: str
    kind: str
    description: str
    count: int
    path: str
    """The file to look at (minimized when there is one)."""
    representative: str
    minimized: str | None
    replay: str
    size: int
    signature: dict[str, Any] | None = None
    config: dict[str, Any] | None = None
    outcomes: tuple[OutcomeView, ...] = ()
    joint_names: tuple[str, ...] = ()
    message: str = ""
    msg_type: str = ""
    lineage: tuple[str, ...] = ()
    lineage_length: int = 0
    sequence: int | None = None
    origin: str = ""
    difference: float | None = None
    unit: str = ""
    written: str = ""
    call: dict[str, Any] | None = None
    """The call the sidecar recorded (``kind``: MoveCall, FkCall or IkCall)."""
    preview: str = ""
    """First bytes of a file without sidecar."""
    note: str = ""
    """Why a file that has a sidecar beside it is shown without one (triage's note)."""

    @property
    def has_sidecar(self) -> bool:
        return self.signature is not None


MESSAGE_CHARS = 1500


def compact_json(value: Any, limit: int = MESSAGE_CHARS) -> str:
    """One-line JSON, cut at ``limit`` characters."""
    text = json.dumps(value, separators=(", ", ": "), ensure_ascii=False, allow_nan=True)
    return text if len(text) <= limit else text[:limit] + f" ... ({len(text) - limit} more characters)"


def replay_command(path: Path, sidecar: dict[str, Any] | None) -> str:
    """The command that replays ``path``: with ``--targets`` naming a file's non-builtin
    targets, which a replay never imports on the file's word alone (the reader sees what runs)."""
    from fuzzer.artifacts.trust import foreign_targets

    command = f"python fuzz_diff.py {shlex.quote(str(path.resolve()))}"
    config = sidecar.get("config") if isinstance(sidecar, dict) else None
    targets = config.get("targets") if isinstance(config, dict) else None
    if isinstance(targets, list) and all(isinstance(t, str) for t in targets) and foreign_targets(targets):
        command += f" --targets {shlex.quote(','.join(targets))}"
    return command


def bucket_view(bucket: Bucket) -> BucketView:
    path = bucket.best
    try:
        size = path.stat().st_size
    except OSError:
        size = -1
    common = BucketView(
        key=bucket.key,
        kind=bucket.kind,
        description=bucket.describe(),
        count=bucket.count,
        path=str(path),
        representative=str(bucket.representative),
        minimized=str(bucket.minimized) if bucket.minimized else None,
        replay=replay_command(path, bucket.sidecar),
        size=size,
    )
    sidecar = bucket.sidecar
    if sidecar is None or bucket.signature is None:
        try:
            with open(path, "rb") as handle:
                head = handle.read(240)
        except OSError:
            head = b""
        note = bucket.note if sidecar_path(path).exists() or sidecar_path(path).is_symlink() else ""
        return replace(common, preview=head.decode("utf-8", errors="replace"), note=note)
    testcase = sidecar.get("testcase") if isinstance(sidecar.get("testcase"), dict) else {}
    assert isinstance(testcase, dict)
    outcomes = tuple(o for o in map(OutcomeView.parse, sidecar.get("outcomes") or []) if o is not None)
    lineage = sidecar.get("lineage") or testcase.get("lineage") or []
    difference = _number(sidecar.get("difference"))
    sequence = testcase.get("sequence")
    config, call = sidecar.get("config"), sidecar.get("call")
    return replace(
        common,
        signature=bucket.signature.to_json(),
        config=config if isinstance(config, dict) else None,
        outcomes=outcomes,
        joint_names=tuple(str(n) for n in sidecar.get("joint_names") or []),
        message=compact_json(testcase.get("message", {})),
        msg_type=str(testcase.get("msg_type", "")),
        lineage=tuple(str(s) for s in lineage),
        lineage_length=_int(testcase.get("lineage_length"), len(lineage)),
        sequence=sequence if isinstance(sequence, int) else None,
        origin=str(testcase.get("origin", "")),
        difference=difference,
        unit=bucket.difference[1] if bucket.difference[1] != "status" else "",
        written=str(sidecar.get("written", "")),
        call=call if isinstance(call, dict) else None,
    )
