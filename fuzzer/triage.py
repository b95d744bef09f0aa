"""Dedup: group divergences into buckets by signature, most severe first.

A bucket is one signature (op, outcome pair, kind, field, sign flip, magnitude
bucket, joints). Its count comes from ``divergences.jsonl`` (every divergent
execution), its representative from the crash files (the first input of the
signature, or its minimized form when ``minimize`` has made one). Crash files
without a sidecar (native crashes, timeouts written by libFuzzer) form buckets
of their own.
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fuzzer.artifacts import load_sidecar
from fuzzer.divlog import DIVERGENCES, read_lines
from fuzzer.records import Signature

SEVERITY = {"crash": 0, "status": 1, "value": 2, "representation": 3, "ill_conditioned": 4, "flaky": 5}
"""Order of kinds, most severe first: a crash, then a different answer, then a
different number, then a different representation, then the undecidable."""


@dataclass(frozen=True)
class Bucket:
    """One distinct problem."""

    key: str
    signature: Signature | None
    count: int
    representative: Path
    sidecar: dict[str, Any] | None
    minimized: Path | None = None
    note: str = ""

    @property
    def kind(self) -> str:
        if self.signature is not None:
            return self.signature.kind
        return (
            "crash"
            if self.representative.name.startswith("crash-")
            else self.representative.name.split("-")[0]
        )

    @property
    def severity(self) -> tuple[int, int, int]:
        bucket = self.signature.bucket if self.signature else 99
        return (SEVERITY.get(self.kind, 0), -bucket, -self.count)

    @property
    def best(self) -> Path:
        """The file to look at first: the minimized one when there is one."""
        return self.minimized or self.representative

    def describe(self) -> str:
        if self.signature is None:
            return f"{self.kind} without sidecar ({self.note or 'native crash or timeout'})"
        s = self.signature
        where = f" on joints {list(s.joints)}" if s.joints else ""
        size = f", difference ~1e{s.bucket}" if s.bucket > -99 else ""
        flip = ", sign flip" if s.sign_flip else ""
        return f"{s.kind} on {s.field}{where}{size}{flip}: {s.outcome_a} vs {s.outcome_b}"


def _artifacts(directory: Path) -> list[Path]:
    return sorted(
        p
        for p in directory.iterdir()
        if p.is_file()
        and not p.name.endswith(".json")
        and not p.name.startswith(".")
        and p.name.split("-")[0] in ("crash", "timeout", "oom", "minimized")
    )


def collect(directory: Path) -> list[Bucket]:
    """The buckets of an artifacts folder, most severe first."""
    counts: Counter[str] = Counter(r["sig"] for r in read_lines(directory / DIVERGENCES) if "sig" in r)
    representatives: dict[str, tuple[Path, dict[str, Any]]] = {}
    minimized: dict[str, Path] = {}
    buckets: list[Bucket] = []
    for path in _artifacts(directory):
        sidecar = load_sidecar(path)
        try:
            key = sidecar["signature"]["key"] if sidecar else None
            if sidecar is not None:
                Signature.from_json(sidecar["signature"])
        except (KeyError, TypeError, ValueError):
            key = None
        if sidecar is None or key is None:
            buckets.append(Bucket(path.name, None, 1, path, None, note="no readable sidecar"))
            continue
        if path.name.startswith("minimized-"):
            minimized[key] = path
        elif key not in representatives:
            representatives[key] = (path, sidecar)
    for key, (path, sidecar) in representatives.items():
        signature = Signature.from_json(sidecar["signature"])
        buckets.append(Bucket(key, signature, max(1, counts.get(key, 0)), path, sidecar, minimized.get(key)))
    for key, path in minimized.items():
        if key not in representatives:
            sidecar = load_sidecar(path)
            assert sidecar is not None
            buckets.append(
                Bucket(
                    key,
                    Signature.from_json(sidecar["signature"]),
                    max(1, counts.get(key, 0)),
                    path,
                    sidecar,
                    path,
                )
            )
    return sorted(buckets, key=lambda b: b.severity)


def as_json(buckets: list[Bucket]) -> list[dict[str, Any]]:
    return [
        {
            "key": b.key,
            "kind": b.kind,
            "count": b.count,
            "description": b.describe(),
            "representative": str(b.representative),
            "minimized": str(b.minimized) if b.minimized else None,
            "signature": b.signature.to_json() if b.signature else None,
        }
        for b in buckets
    ]


def table(buckets: list[Bucket]) -> list[str]:
    """Plain-text lines listing the buckets (for the terminal)."""
    if not buckets:
        return ["no divergences"]
    total = sum(b.count for b in buckets)
    lines = [f"{len(buckets)} bucket(s), {total} divergent execution(s), most severe first:"]
    for i, b in enumerate(buckets, 1):
        lines.append(f"{i:3d}. [{b.key}] x{b.count}  {b.describe()}")
        lines.append(f"      {b.best}")
    return lines


def dumps(buckets: list[Bucket]) -> str:
    return json.dumps(as_json(buckets), indent=1)
