"""Native-coverage mode (`make fuzz-native`) runs the engine's own mutators.

Under a preloaded libFuzzer (Atheris' asan_with_fuzzer.so, needed by the clang-instrumented
native module) libFuzzer's weak custom-mutator hooks resolve before Atheris defines them; the
shim in native/coverage/ restores them. Without it, libFuzzer mutates JSON bytes itself and
most inputs are malformed (94% in the report of issue 16). The evidence is the campaign log:
the share of malformed inputs and the mutators that produced the executed inputs.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from fuzzer.mutation import mutators
from fuzzer.selection.state import ALIGNED, SPACEFILL

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="LD_PRELOAD build is Linux-only")


def _last_stats(artifacts: Path) -> dict[str, Any]:
    lines = (artifacts / "stats.jsonl").read_text().splitlines()
    records = [json.loads(line) for line in lines if line.strip()]
    assert records, "the campaign wrote no stats"
    last: dict[str, Any] = records[-1]
    return last


def test_fuzz_native_uses_the_structured_mutators(tmp_path: Path) -> None:
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    shutil.copytree(ROOT / "corpus", corpus)
    # a count of inputs, not a time: 10 s made 1,708 inputs on an idle machine (stop 41's CI) but
    # 62 at the idle class beside a benchmark sweep, and the checks below are about which inputs
    args = f"{corpus} --artifacts={artifacts} -runs=1200 -seed=1 --no-progress"
    env = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
    done = subprocess.run(
        ["make", "-s", "fuzz-native", f"FUZZ_ARGS={args}"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
        check=False,
    )
    log = done.stdout + done.stderr
    assert "Traceback" not in log, log[-3000:]
    assert "Using preloaded libfuzzer" in log, "not the native-coverage setup"
    stats = _last_stats(artifacts)
    execs, malformed = int(stats["execs"]), int(stats["malformed"])
    assert execs > 500, stats
    assert malformed / execs < 0.05, f"{malformed}/{execs} inputs malformed: custom mutator not in use"
    ran = dict(stats["executed_by_strategy"])
    ours = set(ran) & set(mutators.MUTATORS)
    # seeds alone are not evidence: several registered mutators must have produced executed inputs
    assert len(ours) >= 5, f"mutators seen in the campaign log: {sorted(ran)}"
    # the custom mutator's outputs: registered mutators and the fresh inputs it interleaves, the
    # space-filling stream (``spacefill``, ``spacefill:boundary``) and aligned configurations
    # (``aligned``); the source bandit shares the inputs between the three arms as they pay, so
    # only their sum is stable (CI of stop 41: 774 aligned, 277 space-filling, 844 mutated of 1,708)
    made = ours | {name for name in ran if name.partition(":")[0] in (SPACEFILL, ALIGNED)}
    assert sum(ran[name] for name in made) > execs // 2, ran
