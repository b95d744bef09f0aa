"""Dedup: group divergences into buckets by signature, most severe first.

A bucket is one signature: what a person would call one problem (op, outcome
pair, kind, field, the kinds of the joints involved, and the target of a
property violation). The size of the difference and its sign are details of the
representative, shown with their unit, not parts of the key; joints are shown by
name. Its count comes from ``divergences.jsonl`` (every divergent
execution), its representative from the crash files (the first input of the
signature, or its minimized form when ``minimize`` has made one). Crash files
without a sidecar (native crashes, timeouts written by libFuzzer) form buckets
of their own.
"""

from __future__ import annotations

import contextlib
import json
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fuzzer.artifacts.divlog import DIVERGENCES, read_lines
from fuzzer.artifacts.store import load_sidecar
from fuzzer.execution.records import Outcome, Signature, describe
from fuzzer.report.steps import ScenarioSteps, scenario_of

SEVERITY = {
    "crash": 0,
    "status": 1,
    "property": 2,
    "value": 3,
    "state_dependent": 4,
    "representation": 5,
    "ill_conditioned": 6,
    "known_limitation": 7,
    "flaky": 8,
}
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
    """The sidecar of the file the bucket shows first (:attr:`best`): the minimized file's when
    there is one, so that its description and step list are that file's."""
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
    def difference(self) -> tuple[float, str]:
        """The headline difference of the file shown first and its unit (0, 'status' when unknown)."""
        sidecar = self.sidecar or {}
        comparison = sidecar.get("comparison") if isinstance(sidecar.get("comparison"), dict) else {}
        assert isinstance(comparison, dict)
        value: Any = sidecar.get("difference", comparison.get("difference", 0.0))
        unit = comparison.get("unit", sidecar.get("unit", "status"))
        ok = isinstance(value, int | float) and not isinstance(value, bool)
        return (float(value) if ok else 0.0), (unit if isinstance(unit, str) else "status")

    @property
    def severity(self) -> tuple[int, float, int, str]:
        return (SEVERITY.get(self.kind, 0), -self.difference[0], -self.count, self.key)

    @property
    def best(self) -> Path:
        """The file to look at first: the minimized one when there is one."""
        return self.minimized or self.representative

    def describe(self) -> str:
        if self.signature is None:
            return f"{self.kind} without sidecar ({self.note or 'native crash or timeout'})"
        s = self.signature
        sidecar = self.sidecar or {}
        comparison = sidecar.get("comparison") if isinstance(sidecar.get("comparison"), dict) else {}
        assert isinstance(comparison, dict)
        joints = comparison.get("joints") or []
        names = sidecar.get("joint_names") or []
        if not (isinstance(joints, list) and all(isinstance(j, int) for j in joints)):
            joints = []
        if not (isinstance(names, list) and all(isinstance(n, str) for n in names)):
            names = []
        difference, unit = self.difference
        raw = comparison.get("raw", 0.0)
        raw = float(raw) if isinstance(raw, int | float) and not isinstance(raw, bool) else 0.0
        text = describe(s.kind, s.field, difference, unit, joints, names, s.target, raw)
        labels = [s.outcome_a, s.outcome_b]
        outcomes = sidecar.get("outcomes")
        if isinstance(outcomes, list) and len(outcomes) == 2:
            # the representative's exact outcomes (the signature's pair may be coarse)
            with contextlib.suppress(KeyError, TypeError, ValueError, AttributeError):
                labels = [Outcome.from_json(o).label for o in outcomes]
        scenario = self.scenario
        step = scenario.divergent_step if scenario is not None else None
        if step is not None:
            # the outcomes that diverge are the step's, not the whole scenario's
            return f"{text}: {step.labels[0]} vs {step.labels[1]} at step {step.index} ({step.topic})"
        return f"{text}: {labels[0]} vs {labels[1]}"

    @property
    def scenario(self) -> ScenarioSteps | None:
        """The step list of the file shown first (``--op scenario``), else None."""
        return scenario_of(self.sidecar)


def _artifacts(directory: Path) -> list[Path]:
    """The artifacts of a folder; symlinks that lead outside it are ignored with a warning."""
    from fuzzer.artifacts.store import derived
    from fuzzer.input.paths import contained
    from fuzzer.reporting import warn

    out = []
    for p in sorted(directory.iterdir()):
        if (
            not derived(p)
            and not p.name.startswith(".")
            and p.name.split("-")[0] in ("crash", "timeout", "oom", "minimized")
            and p.is_file()
        ):
            if contained(directory, p):
                out.append(p)
            else:
                warn(f"ignoring {p}: a link to a file outside {directory}")
    return out


def _sidecar(directory: Path, path: Path) -> tuple[dict[str, Any] | None, str]:
    """The validated sidecar of an artifact (None and why when it has no usable one)."""
    from fuzzer.artifacts.shorten import MAX_SIDECAR_BYTES
    from fuzzer.artifacts.sidecar import SidecarError, of_this_file, validate
    from fuzzer.artifacts.store import oversized, sidecar_path
    from fuzzer.input.paths import contained
    from fuzzer.reporting import warn

    side = sidecar_path(path)
    if side.is_symlink() and not contained(directory, side):
        warn(f"ignoring {side}: a link to a file outside {directory}")
        return None, "its sidecar links outside the folder"
    if oversized(side):
        return None, f"its sidecar is larger than {MAX_SIDECAR_BYTES} bytes: not read"
    sidecar = load_sidecar(path)
    if sidecar is None:
        return None, "no readable sidecar"
    try:
        validate(sidecar, side)
        of_this_file(path, side, sidecar)
    except SidecarError as exc:
        return None, f"damaged sidecar: {exc}"
    return sidecar, ""


def collect(directory: Path, files: list[Path] | None = None) -> list[Bucket]:
    """The buckets of an artifacts folder (or of some of its ``files``), most severe first."""
    counts: Counter[str] = Counter(
        r["sig"] for r in read_lines(directory / DIVERGENCES) if isinstance(r.get("sig"), str)
    )
    representatives: dict[str, tuple[Path, dict[str, Any]]] = {}
    minimized: dict[str, tuple[Path, dict[str, Any]]] = {}
    buckets: list[Bucket] = []
    for path in _artifacts(directory) if files is None else files:
        sidecar, why = _sidecar(directory, path)
        try:
            key = sidecar["signature"]["key"] if sidecar else None
            if sidecar is not None:
                Signature.from_json(sidecar["signature"])
        except (KeyError, TypeError, ValueError):
            key = None
        if sidecar is None or key is None:
            buckets.append(Bucket(path.name, None, 1, path, None, note=why or "no readable sidecar"))
            continue
        if path.name.startswith("minimized-"):
            if key not in minimized or _smaller(path, minimized[key][0]):
                minimized[key] = (path, sidecar)
        elif key not in representatives:
            representatives[key] = (path, sidecar)
    for key in dict.fromkeys([*representatives, *minimized]):
        # what the bucket says (its description, step list, outcomes) is the file it shows first
        path, sidecar = representatives.get(key) or minimized[key]
        best, best_sidecar = minimized.get(key, (None, sidecar))
        signature = Signature.from_json(sidecar["signature"])
        buckets.append(Bucket(key, signature, max(1, counts.get(key, 0)), path, best_sidecar, best))
    return sorted(buckets, key=lambda b: b.severity)


def _smaller(path: Path, other: Path) -> bool:
    """Whether ``path`` is the smaller minimized file (then the first by name): the one a bucket
    shows when ``minimize`` ran more than once."""
    try:
        return (path.stat().st_size, path.name) < (other.stat().st_size, other.name)
    except OSError:
        return False


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
            **({"scenario": b.scenario.to_json()} if b.scenario is not None else {}),
        }
        for b in buckets
    ]


def table(buckets: list[Bucket]) -> list[str]:
    """Plain-text lines listing the buckets (for the terminal; unprintable characters of names
    and sidecar strings escaped, :func:`fuzzer.reporting.shown`)."""
    from fuzzer.reporting import shown

    if not buckets:
        return ["no divergences"]
    total = sum(b.count for b in buckets)
    lines = [f"{len(buckets)} bucket(s), {total} divergent execution(s), most severe first:"]
    for i, b in enumerate(buckets, 1):
        lines.append(f"{i:3d}. [{b.key}] x{b.count}  {b.describe()}")
        lines.append(f"      {b.best}")
        scenario = b.scenario
        if scenario is not None:
            lines += [f"      {line}" for line in scenario.lines()]
    return [shown(line) for line in lines]


def dumps(buckets: list[Bucket]) -> str:
    return json.dumps(as_json(buckets), indent=1)
