"""Atheris' edge callback without pybind11's dispatch (``fuzzer.selection.fastcov``)."""

from __future__ import annotations

import os
import subprocess
import sys
import types
from pathlib import Path

import pytest

from fuzzer.selection import fastcov

ROOT = Path(__file__).resolve().parents[1]

DISABLED = """
import runpy, sys
from fuzzer.selection import fastcov
fastcov.install = lambda atheris=None: "disabled by the test"
sys.argv = ["fuzz_diff.py", *sys.argv[1:]]
runpy.run_path("fuzz_diff.py", run_name="__main__")
"""
"""``fuzz_diff.py`` with Atheris' own edge callback (the test's stand-in, run as ``python -c``)."""


def test_the_module_is_built_and_refuses_what_it_cannot_use() -> None:
    from fuzzer.selection import _fastcov  # type: ignore[attr-defined]

    with pytest.raises(LookupError, match="is not a library this process has loaded"):
        _fastcov.bind("/nonexistent/core.so")  # RTLD_NOLOAD: nothing is loaded from a path
    with pytest.raises(LookupError, match="has no _ZN7atheris13_trace_branchEm"):
        _fastcov.bind(_fastcov.__file__)  # loaded, but not Atheris' core module
    with pytest.raises(TypeError):
        _fastcov.bind(3)
    with pytest.raises(TypeError):
        _fastcov.trace_branch("7")
    with pytest.raises(OverflowError):
        _fastcov.trace_branch(-1)
    with pytest.raises(RuntimeError, match="before bind"):
        _fastcov.trace_branch(7)  # this process never bound it


def test_nothing_is_swapped_before_atheris_fuzzes() -> None:
    """Before ``atheris.Fuzz()``, ``_trace_branch`` is Atheris' pre-fuzzing function (native's,
    counting reserved counters), not a core module's: it stays, and install says why."""
    own = types.SimpleNamespace(_trace_branch=abs)
    assert "atheris.Fuzz() has not started" in str(fastcov.install(own))
    assert own._trace_branch is abs


def _campaign(folder: Path, disabled: bool) -> subprocess.CompletedProcess[str]:
    args = [str(folder / "corpus"), "--op=fk", "-runs=600", "-seed=11", f"--artifacts={folder / 'art'}"]
    command = [sys.executable, "-c", DISABLED] if disabled else [sys.executable, "fuzz_diff.py"]
    return subprocess.run(
        [*command, *args, "--no-progress"],
        cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)), text=True, capture_output=True,
        timeout=300, check=False,
    )  # fmt: skip


def test_a_campaign_keeps_the_same_corpus_with_the_fast_callback(tmp_path: Path) -> None:
    """The fast callback bumps the counters Atheris' own would (the same C++ function), so
    libFuzzer makes the same choices: the same inputs kept for one seed. A callback that bumped
    nothing, or other counters, would keep other inputs."""
    kept = []
    for name, disabled in (("fast", False), ("own", True)):
        run = _campaign(tmp_path / name, disabled)
        assert run.returncode == 0, run.stderr[-2000:]
        assert ("Atheris' own edge callback kept (slower)" in run.stderr) is disabled, run.stderr[-2000:]
        assert ("kept (slower): disabled by the test" in run.stderr) is disabled
        kept.append(sorted(p.name for p in (tmp_path / name / "corpus").iterdir() if p.is_file()))
    assert len(kept[0]) > 100 and kept[0] == kept[1]
