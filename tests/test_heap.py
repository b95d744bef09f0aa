"""A scenario campaign's large blocks go back to the system when freed (``fuzzer.execution.heap``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from fuzzer import campaign
from fuzzer.campaign import CampaignOptions
from fuzzer.execution import heap
from fuzzer.execution.session import RunConfig

ROOT = Path(__file__).resolve().parents[1]

# glibc's mallinfo2: ``hblkhd`` is the bytes held in blocks mapped on their own. A 4-MiB array
# freed raises glibc's dynamic threshold to 4 MiB, so a 1-MiB array made next comes from the heap
# (no new mapping) unless the threshold was fixed first.
PROBE = """
import ctypes, sys
import numpy as np
from fuzzer.execution.heap import give_back_large_blocks

class MallInfo2(ctypes.Structure):
    _fields_ = [(n, ctypes.c_size_t) for n in
                ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks",
                 "fordblks", "keepcost")]

libc = ctypes.CDLL(None)
libc.mallinfo2.restype = MallInfo2
if sys.argv[1] == "fixed":
    assert give_back_large_blocks()
big = np.ones(4 * 2**20 // 8)
del big
before = libc.mallinfo2().hblkhd
block = np.ones(2**20 // 8)
print(libc.mallinfo2().hblkhd - before)
"""


def _mapped_on_its_own(mode: str) -> int:
    run = subprocess.run(
        [sys.executable, "-c", PROBE, mode], capture_output=True, text=True, cwd=ROOT, timeout=60
    )
    assert run.returncode == 0, run.stderr[-2000:]
    return int(run.stdout.split()[-1])


def test_a_fixed_threshold_maps_a_block_that_the_dynamic_one_puts_on_the_heap() -> None:
    if not sys.platform.startswith("linux"):
        pytest.skip("glibc only")
    assert _mapped_on_its_own("dynamic") == 0
    assert _mapped_on_its_own("fixed") >= 2**20


class _Opened(Exception):
    pass


@pytest.mark.parametrize(("op", "fixed"), [("scenario", True), ("fk", False), ("move", False)])
def test_only_a_scenario_campaign_fixes_the_threshold(
    op: str, fixed: bool, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    calls: list[int] = []
    monkeypatch.setattr(heap, "give_back_large_blocks", lambda: calls.append(1) or True)

    def opened(config: RunConfig) -> None:
        raise _Opened  # the campaign stops where its targets would load

    monkeypatch.setattr(campaign.Session, "open", opened)
    monkeypatch.delenv("RROSFUZZ_DEADLINE", raising=False)
    options = CampaignOptions(
        corpus=(tmp_path / "corpus",),
        artifacts=tmp_path / "art",
        libfuzzer_flags=(),
        forwarded=(),
        seeds=None,
        seed=0,
        stop_on_divergence=False,
        progress=False,
        progress_interval=5.0,
        dictionary_file=None,
    )
    with pytest.raises(_Opened):
        campaign.run(RunConfig(op=op), options)
    assert calls == ([1] if fixed else [])
