"""Behaviour features reach libFuzzer as coverage; input features describe boundaries."""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys
from pathlib import Path

from fuzzer.selection.guidance import INPUT, INSIDE, NEAR_PI, OUTSIDE, Features, input_features

ROOT = Path(__file__).resolve().parents[1]
PROBE = ROOT / "tests" / "plugins" / "guidance_probe.py"


def corpus_size(mode: str, tmp_path: Path) -> int:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    run = subprocess.run(
        [sys.executable, str(PROBE), mode, "-runs=20000", "-seed=1", "-max_len=16"],
        cwd=tmp_path,
        env=env,
        text=True,
        capture_output=True,
        timeout=120,
        check=False,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    return int(re.findall(r"DONE .*corp: (\d+)/", run.stderr)[-1])


def test_features_grow_libfuzzers_corpus(tmp_path: Path) -> None:
    off, on = corpus_size("off", tmp_path), corpus_size("on", tmp_path)
    assert off == 1  # nothing else can make an input interesting
    assert on >= 32  # the probe has 64 features


def test_disabled_features_still_record_names() -> None:
    f = Features(enabled=False)
    f.hit("o:ok|ok")
    f.hit_ids([(1, 2)])
    assert f.seen == {"o:ok|ok", "(1, 2)"}


def test_input_features_locate_values_near_limits_and_pi() -> None:
    got = input_features([3.1416 - 2e-7, 2.5, math.nan], (-3.1416, -1.0, -1.0), (3.1416, 1.0, 1.0))
    assert (INPUT, 0, INSIDE, -7) in got and (INPUT, 0, NEAR_PI, -6) in got
    assert (INPUT, 1, OUTSIDE, 0) in got
    assert (INPUT, 2, 0) in got  # non-finite
    # the same value gives the same features (stable keys, usable across processes)
    assert got == input_features([3.1416 - 2e-7, 2.5, math.nan], (-3.1416, -1.0, -1.0), (3.1416, 1.0, 1.0))
