"""``benchmarks.bench_memory``: a real (short) campaign sampled from ``/proc``, and its table
made again from the file."""

from __future__ import annotations

import json
from pathlib import Path

from benchmarks import bench_memory

ROOT = str(Path(__file__).resolve().parents[1])


def test_a_short_campaign_is_sampled_and_tabulated_again_from_its_file(tmp_path: Path) -> None:
    out = tmp_path / "m.jsonl"
    argv = ["--arm", "here", ROOT, "--op", "fk", "--seconds", "3", "--every", "0.5", "--out", str(out)]
    text = bench_memory.main(argv)
    lines = [json.loads(line) for line in out.read_text(encoding="utf-8").splitlines()]
    header, rows = lines[0], lines[1:]
    assert header["format"] == bench_memory.FORMAT and [a["name"] for a in header["arms"]] == ["here"]
    samples = [r for r in rows if "t" in r]
    assert len(samples) >= 3 and all(0 < r["rss_kb"] <= r["hwm_kb"] for r in samples)
    assert [r["t"] for r in samples] == sorted(r["t"] for r in samples)
    assert rows[-1]["arm"] == "here" and rows[-1]["returncode"] == 0 and rows[-1]["executions"] > 0
    row = next(line for line in text.splitlines() if line.startswith("| here ("))
    assert row.endswith(f"| {rows[-1]['executions']} |")
    assert bench_memory.main(["--from-json", str(out)]) == text
