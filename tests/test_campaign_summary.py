"""The end-of-campaign summary names every crash file a run wrote: findings, and the ones whose
divergence the oracle explains (``known_limitation``, ``ill_conditioned``), which a campaign keeps
for triage without counting them as findings."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from fuzzer import reporting
from fuzzer.artifacts.store import sidecar_path
from fuzzer.processes import NOT_FINDINGS, OOM_EXIT, failed_job_status, new_artifacts
from fuzzer.selection.state import Stats
from tests.support import fuzz


def _crash(folder: Path, name: str, kind: str | None) -> Path:
    path = folder / f"crash-{name}"
    path.write_bytes(b"{}")
    side = {"signature": {"kind": kind}} if kind is not None else "not a sidecar object"
    sidecar_path(path).write_text(json.dumps(side))
    return path


def test_explained_crash_files_are_listed_apart_from_findings(tmp_path: Path) -> None:
    value = _crash(tmp_path, "a", "value")
    known = _crash(tmp_path, "b", "known_limitation")
    chaotic = _crash(tmp_path, "c", "ill_conditioned")
    unreadable = _crash(tmp_path, "d", None)  # a sidecar no reader understands: a finding
    (tmp_path / "crash-e").write_bytes(b"x")  # no sidecar: the target crashed
    found = new_artifacts(tmp_path, since=0.0)
    assert found.divergences == [value, unreadable]
    assert found.explained == [known, chaotic]
    assert [p.name for p in found.crashes] == ["crash-e"]
    assert dict(found.explained_kinds()) == {"known_limitation": 1, "ill_conditioned": 1}


def test_a_failed_job_s_status_is_what_its_files_say(tmp_path: Path) -> None:
    """A -jobs supervisor's 1 (some job ended non-zero) becomes what one process would have
    exited with: a target that died or a divergence under --stop-on-divergence first, then an
    out-of-memory, then a timeout; 1 when no file explains it."""

    def status(stop: bool = False) -> int:
        return failed_job_status(new_artifacts(tmp_path, since=0.0), stop, timeout_code=70, error_code=77)

    assert status() == 1  # nothing left: a job's usage error, a job killed
    _crash(tmp_path, "a", "value")
    assert status() == 1 and status(stop=True) == 77  # a divergence fails no job unless it stops
    (tmp_path / "timeout-b").write_bytes(b"x")
    assert status() == 70
    (tmp_path / "oom-c").write_bytes(b"x")
    assert status() == OOM_EXIT
    (tmp_path / "leak-d").write_bytes(b"x")
    assert status() == 77


def test_recovered_files_are_sorted_by_kind_too(tmp_path: Path) -> None:
    value = _crash(tmp_path, "a", "value")
    known = _crash(tmp_path, "b", "known_limitation")
    found = new_artifacts(tmp_path, since=2**40)  # written "before" the run: none is new
    assert not found.divergences and not found.explained
    found = found.with_recovered([known, value])
    assert found.divergences == [value] and found.explained == [known]


def test_the_summary_counts_explained_files_by_kind(capsys: pytest.CaptureFixture[str]) -> None:
    stats = Stats()
    reporting.summary(stats, 0, "arts", ["c"], [], explained={"known_limitation": 4, "ill_conditioned": 1})
    err = capsys.readouterr().err
    assert "crash files (0 new this run) in: arts" in err
    assert "5 more crash file(s) new this run (ill_conditioned 1, known_limitation 4)" in err
    assert "fuzz_diff.py triage arts" in err
    reporting.summary(stats, 0, "arts", ["c"], [], explained={})
    assert "explained" not in capsys.readouterr().err


def test_a_campaign_reports_the_explained_crash_files_it_wrote(tmp_path: Path) -> None:
    """The default robot's scenario campaign: its seed-1 run of 200 inputs writes known-limitation
    crash files and no finding; the summary used to say only "0 new"."""
    artifacts = tmp_path / "a"
    run = fuzz("--op", "scenario", str(tmp_path / "c"), "-runs=200", "-seed=1", f"--artifacts={artifacts}")
    assert run.returncode == 0, run.stderr[-2000:]
    files = [p for p in artifacts.glob("crash-*") if not p.name.endswith(".json")]
    kinds = [json.loads(sidecar_path(p).read_text())["signature"]["kind"] for p in files]
    explained = [k for k in kinds if k in NOT_FINDINGS]
    assert explained and len(explained) == len(kinds), kinds
    match = re.search(r"explained, not findings: (\d+) more crash file\(s\) new this run", run.stderr)
    assert match and int(match.group(1)) == len(explained), run.stderr[-2000:]
    assert "crash files (0 new this run)" in run.stderr
    # the campaign's divergences and the dry run's are every line of the log (they were its
    # process's alone: 811 of 820 in a probe's campaign)
    ours = re.search(r"\]\s+divergences: (\d+)", run.stderr)
    dry = re.search(
        r"the dry run, besides \(\d+ child process\(es\) before libFuzzer\): \d+ executions, (\d+)",
        run.stderr,
    )
    assert ours and dry, run.stderr[-2000:]
    logged = (artifacts / "divergences.jsonl").read_text().splitlines()
    assert int(ours.group(1)) + int(dry.group(1)) == len(logged)


def test_a_merge_s_summary_adds_up_its_inner_process(tmp_path: Path) -> None:
    """-merge=1 runs the inputs in an inner process: its summary said "executions: 0,
    divergences: 0" beside the crash files it listed."""
    into, source, artifacts = tmp_path / "into", tmp_path / "source", tmp_path / "a"
    into.mkdir()
    seeded = fuzz(str(source), "-runs=1", "--seeds=12", "-seed=1", f"--artifacts={tmp_path / 'seeding'}")
    assert seeded.returncode in (0, 1), seeded.stderr[-2000:]
    run = fuzz(str(into), str(source), "-merge=1", f"--artifacts={artifacts}",
               "--targets=native,tests.plugins.faults:tight_tolerance")  # fmt: skip
    assert run.returncode in (0, 1), run.stderr[-2000:]
    executions = re.search(r"executions: (\d+) in", run.stderr)
    logged = (artifacts / "divergences.jsonl").read_text().splitlines() if run.returncode else []
    divergences = re.search(r"\]\s+divergences: (\d+)", run.stderr)
    assert executions and int(executions.group(1)) >= 12, run.stderr[-2000:]
    assert divergences and int(divergences.group(1)) == len(logged), run.stderr[-2000:]
    assert "totals over 1 child process(es)" in run.stderr


def test_close_fd_mask_silences_the_target_not_the_summary(tmp_path: Path) -> None:
    """``-close_fd_mask=2`` sends file descriptor 2 to /dev/null to silence the target; the
    engine's summary went with it, while libFuzzer keeps its own lines on a copy of stderr."""
    for mask in ("", "-close_fd_mask=2"):
        run = fuzz(str(tmp_path / f"c{mask}"), "-runs=60", "-seed=1", f"--artifacts={tmp_path / f'a{mask}'}",
                   "--targets=native,tests.plugins.faults:noisy", *([mask] if mask else []))  # fmt: skip
        assert run.returncode == 0, run.stderr[-2000:]
        assert "campaign summary" in run.stderr and "exit status 0" in run.stderr, run.stderr[-2000:]
        libfuzzer_lines = "INFO: seed corpus:" in run.stderr
        assert libfuzzer_lines, run.stderr[-2000:]
        noise = run.stderr.count("noisy target says hello")
        assert (noise == 0) if mask else (noise > 0), (mask, noise)


def test_the_summary_counts_the_dry_run_apart(capsys: pytest.CaptureFixture[str]) -> None:
    dry = {"processes": 1, "execs": 40, "divergences": 3, "divergent": {"value": 2, "ill_conditioned": 1}}
    reporting.summary(Stats(), 0, "arts", ["c"], [], dry_run=dry)
    err = capsys.readouterr().err
    assert "the dry run, besides (1 child process(es) before libFuzzer): 40 executions, 3 divergences" in err
    assert "(ill_conditioned 1, value 2)" in err
    reporting.summary(Stats(), 0, "arts", ["c"], [], dry_run={"processes": 0, "execs": 0})
    assert "dry run" not in capsys.readouterr().err


def test_value_divergences_of_no_finite_difference_are_not_said_to_be_none(
    capsys: pytest.CaptureFixture[str],
) -> None:
    stats = Stats()
    stats.divergent["value"] = 3  # each of an infinite difference: none became max_difference
    reporting.summary(stats, 0, "arts", ["c"], [])
    assert "largest value difference: not finite" in capsys.readouterr().err
    reporting.summary(Stats(), 0, "arts", ["c"], [])
    assert "largest value difference: none (no value divergence)" in capsys.readouterr().err
