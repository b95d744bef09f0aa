"""The regression suite: crash files kept under ``tests/regressions/``, replayed by pytest.

``promote`` copies a crash file and its sidecar into the suite and records what
it must do from now on: ``diverge`` (a known divergence that must still
reproduce with the same signature) or ``agree`` (a fixed one that must stay
fixed). The expectation lives in the sidecar's ``regression`` entry.
"""

from __future__ import annotations

import datetime
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fuzzer.artifacts.sidecar import SidecarError, read_sidecar
from fuzzer.artifacts.store import atomic_write, load_sidecar, sidecar_path
from fuzzer.execution.session import ConfigError, RunConfig
from fuzzer.input.testcase import TestCaseError, read_bytes
from fuzzer.triage.replay import Result, replay_file

SUITE = Path(__file__).resolve().parents[2] / "tests" / "regressions"


class PromoteError(ValueError):
    """A file that cannot be promoted as asked."""


@dataclass(frozen=True)
class Promoted:
    path: Path
    expect: str


def promote(crash: Path, fixed: bool, note: str = "", suite: Path = SUITE, trust: bool = False) -> Promoted:
    """Check the file's current verdict against what is asked, then add it to the suite.

    Raises
    ------
    PromoteError
        No sidecar (or a damaged one, or one naming targets that may not be
        imported without ``trust``), or the verdict contradicts the expectation
        (``--fixed`` on a file that still diverges, or a known divergence that no
        longer diverges).
    """
    try:
        sidecar = read_sidecar(crash)
    except SidecarError as exc:
        raise PromoteError(str(exc)) from None
    if sidecar is None:
        raise PromoteError(f"{crash}: no sidecar; only divergence crash files can be promoted")
    try:
        result = replay_file(crash, RunConfig(), {}, trust=trust)
    except ConfigError as exc:
        raise PromoteError(str(exc)) from None
    if result.result is Result.EXPLAINED:
        raise PromoteError(
            f"{crash}: {result.result}; the suite keeps divergences and fixed ones that agree "
            "(test a known limitation beside its rule, in tests/)"
        )
    if fixed and result.result is not Result.AGREES:
        raise PromoteError(f"{crash}: {result.result}; it is not fixed yet (promote it without --fixed)")
    if not fixed and result.result is not Result.SAME:
        raise PromoteError(f"{crash}: {result.result}; promote it with --fixed if it is fixed")
    target = suite / crash.name
    try:
        suite.mkdir(parents=True, exist_ok=True)
        if not (target.exists() and target.samefile(crash)):  # promoted again (--fixed): in place
            # written whole and renamed over the name: a symlink planted there is replaced, not
            # followed (shutil.copyfile wrote the crash file over whatever it pointed at)
            atomic_write(target, read_bytes(crash))
    except OSError as exc:
        raise PromoteError(f"--suite {suite}: cannot hold the crash file ({exc.strerror or exc})") from None
    except TestCaseError as exc:  # replaced since it was replayed
        raise PromoteError(f"{crash}: not a test case: {exc}") from None
    entry: dict[str, Any] = dict(sidecar)
    entry["regression"] = {
        "expect": "agree" if fixed else "diverge",
        "signature": sidecar["signature"]["key"],
        "note": note,
        "promoted": datetime.date.today().isoformat(),
    }
    atomic_write(sidecar_path(target), json.dumps(entry, indent=1, sort_keys=True).encode())
    return Promoted(target, entry["regression"]["expect"])


def suite_files(suite: Path = SUITE) -> list[Path]:
    """Crash files of the suite that carry an expectation."""
    if not suite.is_dir():
        return []
    out = []
    for path in sorted(suite.iterdir()):
        if path.name.endswith(".json") or not path.name.startswith(("crash-", "minimized-")):
            continue
        sidecar = load_sidecar(path)
        if sidecar is not None and "regression" in sidecar:
            out.append(path)
    return out
