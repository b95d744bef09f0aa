"""The dry run's first input, evaluated in the campaign's own process under a guard
(fuzzer/execution/guard.py): written ahead into the corpus, a hang guard, and what a rerun
does with an input a campaign died on."""

from __future__ import annotations

import hashlib
import json
import signal
from pathlib import Path

import pytest

from fuzzer.execution import guard
from fuzzer.input.testcase import decode
from tests.support import ROOT, fuzz, python

DATA = b'{"rrosfuzz": 1, "msg_type": "sensor_msgs/JointState", "message": {}}'


def test_the_input_is_written_ahead_and_removed_when_its_evaluation_returns(tmp_path: Path) -> None:
    pending = guard.write_ahead(tmp_path, DATA)
    assert pending.name == guard.PENDING + hashlib.sha1(DATA).hexdigest()
    assert pending.read_bytes() == DATA
    before = signal.getsignal(signal.SIGALRM)
    with guard.guarded(pending, DATA, tmp_path, 30.0, 70):
        assert pending.is_file(), "on disk while it is evaluated"
        assert signal.getitimer(signal.ITIMER_REAL)[0] > 0, "the hang guard is armed"
        assert guard.leftovers([tmp_path]) == [pending]
    assert not pending.exists()
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0), "disarmed"
    assert signal.getsignal(signal.SIGALRM) == before, "the handler it found is back"


def test_an_evaluation_that_raises_removes_the_written_input(tmp_path: Path) -> None:
    pending = guard.write_ahead(tmp_path, DATA)
    with pytest.raises(KeyboardInterrupt), guard.guarded(pending, DATA, tmp_path, 30.0, 70):
        raise KeyboardInterrupt
    assert not pending.exists() and guard.leftovers([tmp_path]) == []
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)


def test_leftovers_are_absolute_so_they_settle_from_another_working_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A -jobs supervisor changes into the artifacts folder before it settles the leftovers:
    with a relative corpus path (``fuzz_diff.py corpus/ -jobs=2``) the file was never renamed,
    and every later campaign warned of it again."""
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    left = corpus / f"{guard.PENDING}{'a' * 40}"
    left.write_bytes(b"{}")
    monkeypatch.chdir(tmp_path)
    found = guard.leftovers([Path("corpus")])
    assert found == [left] and found[0].is_absolute()
    (tmp_path / "art").mkdir()
    monkeypatch.chdir(tmp_path / "art")
    assert guard.settle(found) == [corpus / ("a" * 40)]
    assert not left.exists() and (corpus / ("a" * 40)).read_bytes() == b"{}"


def test_writing_ahead_into_a_missing_folder_raises_oserror(tmp_path: Path) -> None:
    with pytest.raises(OSError):
        guard.write_ahead(tmp_path / "missing", DATA)


def test_a_link_or_fifo_planted_under_the_predictable_name_is_replaced_not_followed(tmp_path: Path) -> None:
    """The name is the SHA-1 of a seed a default campaign always draws first: a dangling link
    there had the campaign create the file it led to, and a FIFO blocked it (the special-files
    probe)."""
    import os

    corpus = tmp_path / "corpus"
    corpus.mkdir()
    name = guard.PENDING + hashlib.sha1(DATA).hexdigest()
    victim = tmp_path / "victim"
    (corpus / name).symlink_to(victim)
    pending = guard.write_ahead(corpus, DATA)
    assert not victim.exists() and not pending.is_symlink() and pending.read_bytes() == DATA
    pending.unlink()
    os.mkfifo(corpus / name)
    assert guard.write_ahead(corpus, DATA).read_bytes() == DATA  # replaced, never opened
    assert sorted(p.name for p in corpus.iterdir()) == [name], "no temporary left"


def _program(body: str, corpus: Path, artifacts: Path) -> str:
    return f"""
import ctypes, signal
from pathlib import Path
from fuzzer.execution import guard
data = {DATA!r}
pending = guard.write_ahead(Path({str(corpus)!r}), data)
with guard.guarded(pending, data, Path({str(artifacts)!r}), 0.5, 70):
{body}
print("returned")
"""


def test_an_input_that_hangs_in_python_becomes_a_timeout_file_and_exit_70(tmp_path: Path) -> None:
    done = python(_program("    while True:\n        pass", tmp_path, tmp_path), timeout=60)
    assert done.returncode == 70, done.stderr
    assert "returned" not in done.stdout
    assert "timeout: the dry run's first input ran past 0.5 s" in done.stderr
    assert (tmp_path / f"timeout-{hashlib.sha1(DATA).hexdigest()}").read_bytes() == DATA
    assert guard.leftovers([tmp_path]) == [], "recorded as a timeout: not left for a rerun"


def test_an_input_that_hangs_in_compiled_code_ends_the_process_and_stays_written(tmp_path: Path) -> None:
    # the alarm blocked and a C call that holds the GIL (ctypes.PyDLL): no Python handler can run
    body = "    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGALRM})\n    ctypes.PyDLL(None).pause()"
    done = python(_program(body, tmp_path, tmp_path), timeout=60)
    assert done.returncode == 1, done.stderr  # faulthandler's watchdog: _exit(1)
    assert "Timeout" in done.stderr and "returned" not in done.stdout
    assert [p.read_bytes() for p in guard.leftovers([tmp_path])] == [DATA]


def _campaign(corpus: Path, artifacts: Path, target: str, *flags: str) -> list[str]:
    return [
        str(corpus),
        "-runs=200",
        "-seed=3",
        f"--artifacts={artifacts}",
        "--no-progress",
        "--robot=kinova",
        f"--targets=native,tests.plugins.faults:{target}",
        *flags,
    ]


def test_a_campaign_whose_first_input_hangs_writes_a_timeout_file(tmp_path: Path) -> None:
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    run = fuzz(*_campaign(corpus, artifacts, "always_hangs", "-timeout=1"), timeout=300)
    assert run.returncode == 70, run.stderr[-3000:]
    assert "timeout: the dry run's first input ran past 1 s" in run.stderr
    (timeout,) = artifacts.glob("timeout-*")
    assert decode(timeout.read_bytes()).lineage == ("spacefill:uniform",), "the first uniform configuration"
    assert guard.leftovers([corpus]) == []


def test_a_campaign_killed_by_its_first_input_leaves_it_for_libfuzzer_to_report(tmp_path: Path) -> None:
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    args = _campaign(corpus, artifacts, "always_aborts")
    first = fuzz(*args, timeout=300)
    assert first.returncode == -signal.SIGABRT, first.stderr[-3000:]
    (left,) = guard.leftovers([corpus])
    assert decode(left.read_bytes()).lineage == ("spacefill:uniform",)
    assert sorted(p.name for p in corpus.iterdir()) == [left.name], "killed before the seeds were written"
    again = fuzz(*args, timeout=300)  # the same command again
    assert f"{left}: a campaign ended while it evaluated this input in its own process" in again.stderr
    assert "deadly signal" in again.stderr, again.stderr[-3000:]  # libFuzzer ran it and reported it
    crashes = [p for p in artifacts.glob("crash-*") if p.suffix != ".json"]
    assert [p.read_bytes() for p in crashes] == [left.read_bytes()]
    assert left.is_file(), "kept: a seed, until the user removes it"


def test_the_dry_runs_first_move_input_is_the_campaigns_and_its_child_counts_it(tmp_path: Path) -> None:
    """On a fault every input shows: the first crash file comes from the campaign's process,
    before the child's; the child's first snapshot counts that input, the campaign's process
    logs no dry-run snapshot of its own."""
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    run = fuzz(*_campaign(corpus, artifacts, "wrap_continuous"), timeout=300)
    assert run.returncode == 1, run.stderr[-3000:]
    assert "Traceback" not in run.stderr
    stats = [json.loads(line) for line in (artifacts / "stats.jsonl").read_text().splitlines()]
    divergences = [json.loads(line) for line in (artifacts / "divergences.jsonl").read_text().splitlines()]
    campaign = stats[-1]["pid"]
    assert divergences[0]["pid"] == campaign and divergences[0]["strategy"] == "spacefill:uniform"
    children = sorted({r["pid"] for r in stats} - {campaign})
    assert len(children) == 2, "two dry-run stages"
    first_child = min(children, key=lambda pid: min(r["first_input"] for r in stats if r["pid"] == pid))
    opening = next(r for r in stats if r["pid"] == first_child)
    assert opening["execs"] == 1, "the child's first snapshot: the input evaluated before the fork"
    assert opening["first_input"] < min(r["first_input"] for r in stats if r["pid"] == campaign)
    ours = [r for r in stats if r["pid"] == campaign]
    assert ours[0]["first_input"] > opening["first_input"], "no dry-run snapshot under the campaign's pid"
    assert guard.leftovers([corpus]) == []


def test_off_the_main_thread_the_first_input_is_left_to_the_child(tmp_path: Path) -> None:
    """The hang guard sets a signal handler, which only the main thread may do: a campaign run
    from another thread evaluates its first input in the child, as before."""
    import threading

    from fuzzer import dry_run
    from fuzzer.execution.session import RunConfig, Session

    made: list[object] = []

    def make_harness(seeds: object, sweep: object) -> object:
        made.append(seeds)
        raise AssertionError("no Harness is made in this process")

    stages = dry_run.Stages(
        Session.open(RunConfig(op="move")), "rrosfuzz", 1, 4, 0, make_harness, corpus=tmp_path
    )  # type: ignore[arg-type]
    here: list[object] = []
    thread = threading.Thread(target=lambda: here.append(stages._first_here()))
    thread.start()
    thread.join()
    assert here == [None] and made == []
    assert guard.leftovers([tmp_path]) == []


def test_a_leftover_that_runs_without_harm_is_kept_under_its_sha1(tmp_path: Path) -> None:
    """A written-ahead input libFuzzer then ran as a seed, the campaign ending normally: renamed
    to libFuzzer's name for it, so the next campaign neither warns again nor gives up evaluating
    its first input in process (the file stayed for good; the docs probe)."""
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    corpus.mkdir()
    data = next(p for p in sorted((ROOT / "corpus").iterdir()) if p.name.startswith("seed-")).read_bytes()
    digest = hashlib.sha1(data).hexdigest()
    (corpus / f"{guard.PENDING}{digest}").write_bytes(data)
    run = fuzz(str(corpus), "-runs=30", "-seed=3", f"--artifacts={artifacts}", timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    assert "a campaign ended while it evaluated this input" in run.stderr
    assert guard.leftovers([corpus]) == [] and (corpus / digest).read_bytes() == data
    again = fuzz(str(corpus), "-runs=30", "-seed=3", f"--artifacts={artifacts}", timeout=300)
    assert again.returncode == 0 and "a campaign ended while it evaluated" not in again.stderr
