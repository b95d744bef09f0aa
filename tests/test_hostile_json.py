"""JSON from anywhere (corpus files, sidecars, a campaign's logs) with what Python's parser
raises besides ``JSONDecodeError``: an integer past 4,300 digits (``ValueError``), nesting past
the recursion limit (``RecursionError``). Each reader names it, skips it or treats it as damaged,
as it does bad JSON; a helper's probe found each one ending in a traceback (2026-12-05)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from fuzzer.artifacts.divlog import read_lines
from fuzzer.artifacts.sidecar import SidecarError, read_sidecar
from fuzzer.artifacts.store import load_sidecar
from fuzzer.input.testcase import TestCase, TestCaseError, decode
from fuzzer.report.records import read_records

BIG = "1" + "0" * 5000
"""An integer literal past CPython's 4,300-digit limit of int(str)."""
FLOATLESS = "1" + "0" * 400
"""An integer literal ``json`` parses and no float can hold: ``float()`` of it raised OverflowError."""
DEEP = "[" * 100_000 + "]" * 100_000

CRASH = "crash-0123456789abcdef0123456789abcdef01234567"


def _case_with(value: str) -> bytes:
    good = TestCase("std_msgs/Float64MultiArray", {"data": [0.5]}).encode().decode()
    return good.replace("0.5", value, 1).encode()


@pytest.mark.parametrize("value", [BIG, DEEP])
def test_a_test_case_is_not_json_not_a_traceback(value: str) -> None:
    with pytest.raises(TestCaseError, match="not JSON"):
        decode(_case_with(value))


@pytest.mark.parametrize(
    "text",
    ['{"signature": {"key": ' + BIG + "}}", DEEP, '{"config": {"tolerance": {"m": ' + FLOATLESS + "}}}"],
)
def test_a_sidecar_is_damaged_not_a_traceback(tmp_path: Path, text: str) -> None:
    crash = tmp_path / CRASH
    crash.write_bytes(b"{}")
    crash.with_name(CRASH + ".json").write_text(text)
    with pytest.raises(SidecarError, match="not valid JSON"):
        read_sidecar(crash)
    assert load_sidecar(crash) is None  # triage and report: a damaged sidecar counts as none


def test_log_lines_past_the_parser_are_skipped(tmp_path: Path) -> None:
    log = tmp_path / "divergences.jsonl"
    lines = ['{"sig": "a"}', '{"n": ' + BIG + "}", DEEP, '{"t": ' + FLOATLESS + "}", '{"sig": "b"}']
    log.write_text("\n".join(lines) + "\n")
    assert [r["sig"] for r in read_lines(log)] == ["a", "b"]
    records, skipped = read_records(log)
    assert [r["sig"] for r in records] == ["a", "b"] and skipped == 3


def test_bounded_int_parses_what_a_float_holds() -> None:
    from fuzzer.input.untrusted_json import bounded_int, loads

    assert loads("[12, -3]") == [12, -3]
    assert bounded_int("1" + "0" * 308) == 10**308 and bounded_int("-" + "9" * 308) == -int("9" * 308)
    for text in ("2" + "0" * 308, "-2" + "0" * 308, FLOATLESS, BIG):  # 2e308 and beyond: no float
        with pytest.raises(ValueError, match="beyond the range of a float"):
            bounded_int(text)


@pytest.mark.parametrize(
    ("field", "value"),
    [("t", 1e308), ("t", float("nan")), ("elapsed", float("inf")), ("t", -1.0), ("execs", 2**70)],
)
def test_the_report_skips_times_and_counters_past_their_range(field: str, value: float) -> None:
    """A snapshot with ``"t": 1e308`` or ``NaN``, or ``"elapsed": Infinity``, ended the report in
    a traceback (no ``time_t`` or plot axis holds them): its times are refused, or the line."""
    from fuzzer.report.records import Divergence, Snapshot

    good = {"t": 1.7e9, "pid": 7, "execs": 10, "elapsed": 2.0}
    assert Snapshot.parse(good) is not None
    snap = Snapshot.parse({**good, field: value})
    assert snap is None or (snap.elapsed == 0.0 and field == "elapsed")
    if field == "t":
        div = Divergence.parse({"sig": "s", "kind": "value", "t": value})
        assert div is not None and div.t is None


def test_triage_counts_only_string_signatures(tmp_path: Path) -> None:
    from fuzzer.triage.pipeline import collect

    (tmp_path / "divergences.jsonl").write_text('{"sig": [1, 2]}\n{"sig": {"a": 1}}\n')
    assert collect(tmp_path) == []  # TypeError: unhashable type: 'list' before


def test_the_report_opens_no_fifo_planted_as_a_sidecar(tmp_path: Path) -> None:
    from fuzzer.report.data import _sidecars

    os.mkfifo(tmp_path / (CRASH + ".json"))  # reading it would wait for a writer for ever
    valid = {"config": {"op": "move"}, "signature": {"key": "k"}}
    (tmp_path / "crash-1.json").write_text(json.dumps(valid))
    assert _sidecars(tmp_path) == [valid]


def test_a_huge_crash_file_is_refused_unread(tmp_path: Path) -> None:
    """A 3 GB sparse crash file took 3 GB of memory (and 15 s) in replay, report, coverage,
    minimize, export-bag and view before the size check: now no more than a test case is read."""
    import tracemalloc

    from fuzzer.input.testcase import MAX_BYTES, read_case

    crash = tmp_path / CRASH
    with open(crash, "wb") as handle:
        handle.truncate(3 << 30)
    tracemalloc.start()
    try:
        with pytest.raises(TestCaseError, match=f"larger than {MAX_BYTES} bytes"):
            read_case(crash)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 4 * MAX_BYTES


def test_a_log_line_past_its_length_is_skipped_unheld(tmp_path: Path) -> None:
    """A 2 GB sparse divergences.jsonl (one line of NULs) took 4.2 GB in triage: a line longer
    than MAX_LINE is now read past in pieces and skipped, and the lines after it are read."""
    import tracemalloc

    from fuzzer.input.untrusted_json import MAX_LINE, jsonl_records

    log = tmp_path / "divergences.jsonl"
    with open(log, "wb") as handle:
        handle.write(b'{"sig": "a"}\n')
        handle.seek(40 * MAX_LINE)
        handle.write(b'\n{"sig": "b"}\n\n[1]\n')
    tracemalloc.start()
    try:
        records = list(jsonl_records(log))
        triaged = [r["sig"] for r in read_lines(log)]  # triage's reader
        reported = read_records(log)  # the report's
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert records == [{"sig": "a"}, None, {"sig": "b"}, [1]]
    assert triaged == ["a", "b"] and reported == ([{"sig": "a"}, {"sig": "b"}], 2)
    assert peak < 16 * MAX_LINE  # a character of text takes up to 4 bytes in a str
