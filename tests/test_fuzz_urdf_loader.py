"""A bounded, seeded fuzz campaign over the native URDF loader (tests/fuzz_urdf_loader.py).

Two flavours, each in a subprocess so that a native crash fails the test instead of
killing pytest:

* ``regular``: the installed module (no sanitizer, no native coverage; the twin's
  Python edges guide the search). Always runs.
* ``asan``: the clang build with AddressSanitizer and libFuzzer's counters
  (``make native-cov``, ``build/coverage/``), under Atheris' ``asan_with_fuzzer.so``.
  The test runs ``make native-cov`` first (a no-op when the build is current; on a
  fresh clone it installs clang and builds), and fails if that fails;
  ``make fuzz-urdf`` runs the same harness for 10 minutes.

A fixed ``-runs`` count and ``-seed`` keep the campaign bounded and repeatable. ``-reload=0``
keeps the count exact: by default libFuzzer re-reads its corpus folder every second and runs
any file there it does not hold in memory (such as one a REDUCE replaced). That reload comes at
the top of its loop, before the ``-runs`` check, so one there can run units past the budget,
depending on the machine's speed (CI once printed ``Done 40002 runs``).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
HARNESS = REPO / "tests" / "fuzz_urdf_loader.py"
RUNS = {"regular": 40_000, "asan": 20_000}


def _asan_env() -> dict[str, str] | None:
    """Environment running the ASan build, or None when there is no fresh one."""
    modules = sorted((REPO / "build" / "coverage").glob("_native*.so"))
    if not modules:
        return None
    sources = [p for p in (REPO / "native" / "src").rglob("*") if p.suffix in (".cpp", ".hpp")]
    if max(p.stat().st_mtime for p in sources) > modules[0].stat().st_mtime:
        return None
    import atheris

    preload = Path(atheris.path()) / "asan_with_fuzzer.so"
    if not preload.is_file():
        return None
    return {
        "LD_PRELOAD": str(preload),
        "ASAN_OPTIONS": "detect_leaks=0",
        "RROSFUZZ_NATIVE_MODULE": str(modules[0]),
    }


@pytest.mark.parametrize("flavour", ["regular", "asan"])
def test_native_loader_survives_fuzzing(tmp_path: Path, flavour: str) -> None:
    env = dict(os.environ)
    env.pop("RROSFUZZ_NATIVE_MODULE", None)
    env["RROSFUZZ_URDF_SCRATCH"] = str(tmp_path / "scratch")  # not a folder left in /tmp per run
    if flavour == "asan":
        build = subprocess.run(
            ["make", "-s", "native-cov"], cwd=REPO, capture_output=True, text=True, timeout=1200, check=False
        )
        assert build.returncode == 0, (build.stdout + build.stderr)[-4000:]
        extra = _asan_env()
        assert extra is not None, "make native-cov left no ASan build newer than native/src"
        env.update(extra)
    cmd = [
        sys.executable, str(HARNESS), f"-runs={RUNS[flavour]}", "-seed=1", "-timeout=30",
        "-reload=0", f"-artifact_prefix={tmp_path}/", str(tmp_path / "corpus"),
    ]  # fmt: skip
    proc = subprocess.run(
        cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=900, check=False
    )
    tail = proc.stderr[-4000:]
    assert proc.returncode == 0, tail
    assert f"Done {RUNS[flavour]} runs" in proc.stderr, tail
    assert not list(tmp_path.glob("crash-*")) and not list(tmp_path.glob("timeout-*")), tail
    assert (tmp_path / "scratch" / "urdf.dict").is_file()  # the harness used the test's folder
