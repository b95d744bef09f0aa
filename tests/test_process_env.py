"""What importing ``fuzzer`` sets for the process (fuzzer/__init__.py)."""

from __future__ import annotations

import os
import subprocess
import sys

from tests.support import ROOT

PROBE = "import fuzzer, numpy, os; print(os.environ['OPENBLAS_NUM_THREADS'])"


def _probe(**env: str) -> str:
    base = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    done = subprocess.run(
        [sys.executable, "-c", PROBE],
        env={**base, "PYTHONPATH": str(ROOT), **env},
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    return done.stdout.strip()


def test_a_campaign_process_asks_for_one_blas_thread_unless_the_user_set_it() -> None:
    assert _probe() == "1"
    assert _probe(OPENBLAS_NUM_THREADS="2") == "2"
