"""Hostile and mistaken command lines (issue 12): a clear message, the documented exit
status, never a traceback. Also ``--help`` and the exit status of campaigns."""

from __future__ import annotations

import os
import shlex
import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from tests.support import ROOT, SCRIPT, fuzz

if TYPE_CHECKING:
    from fuzzer.campaign import CampaignOptions

TIGHT = "tests.plugins.faults:tight_tolerance"


HOSTILE = [
    # --targets
    (["--targets=native,native"], "names 'native' twice"),
    (["--targets=python,python"], "names 'python' twice"),
    (["--targets=native"], "exactly two targets, got 1"),
    (["--targets=native,python,python"], "exactly two targets, got 3"),
    (["--targets=,"], "exactly two targets, got 0"),
    (["--targets=native,python,"], "an empty name between its commas"),
    (["--targets=native,no_such_module_xyz:impl"], "cannot import no_such_module_xyz"),
    (["--targets=native,os:path"], "no callable RobotModel"),
    (["--targets=native,justaname"], "expected native, python, ros_tf or module:attribute"),
    (["--targets=native,pinocchio"], "or module:attribute (an adapter: adapters.pinocchio_adapter:api)"),
    (["--targets=native,:x"], "expected module:attribute"),
    (["--targets=native,tests.plugins.faults:nothing"], "has no attribute"),
    (
        ["--targets=native,tests.plugins.faults:wrong_constructor"],
        "target 'tests.plugins.faults:wrong_constructor': its RobotModel(probot_anno.urdf) raised TypeError",
    ),
    # --progress-interval
    (["--progress-interval=-1"], "--progress-interval: '-1': must be a positive, finite number"),
    (["--progress-interval=nan"], "--progress-interval: 'nan': must be a positive, finite number"),
    (["--progress-interval=NaN"], "--progress-interval: 'NaN': must be a positive, finite number"),
    (["--progress-interval=inf"], "--progress-interval: 'inf': must be a positive, finite number"),
    (["--progress-interval=0"], "--progress-interval: '0': must be a positive, finite number"),
    (["--progress-interval=soon"], "'soon' is not a number of seconds"),
    (["--progress-interval"], "expected one argument"),
    # other options
    (["--op=jump"], "invalid choice: 'jump'"),
    (["--mutator=afl"], "invalid choice: 'afl'"),
    (["--tolerance=-1"], "--tolerance"),
    (["--tolerance=nan"], "--tolerance"),
    (["--seeds=-1"], "--seeds must be from 0 to 100000"),
    (["--seeds=100000001"], "--seeds must be from 0 to 100000 (each is a file in the corpus"),
    (["--seeds=many"], "invalid int value: 'many'"),
    (["--seed=x"], "invalid int value: 'x'"),
    (["--robot=/nonexistent/robot.urdf"], "--robot"),
    (["--robot=ur5", "--tip-link=nope"], "tip link 'nope'"),
    (["--tolerance=m=1e-5,m=1e-6"], "m given twice"),
    # float() and int() take 1_0 for 10 and other scripts' digits (libFuzzer's flags are refused them)
    (["--tolerance=1_0"], "tolerance '1_0' is not a number"),
    (["--tolerance=\u0661"], "is not a number"),
    (["--max-steps=\u0665"], "--max-steps '\u0665': not an integer"),
    (["--max-steps=1_6"], "--max-steps '1_6': not an integer"),
    (["--progress-interval=1_0"], "'1_0' is not a number of seconds"),
    (["--tolerance=,"], "an empty part"),
    (["--msg-type=sensor_msgs/Nope"], "--msg-type"),
    (["--op=ik", "--msg-type=sensor_msgs/JointState"], "supported: geometry_msgs/PoseStamped"),
    (["--msg-path=/nonexistent/msgs"], "--msg-path /nonexistent/msgs: not a folder"),
    (["-dict=/nonexistent.dict"], "-dict=/nonexistent.dict: no such file"),
    # given a corpus folder, libFuzzer ran the folder as an input: std::bad_alloc, exit 77
    (["-minimize_crash=1"], "-minimize_crash=1 and -cleanse_crash=1 take one crash file, not the folder"),
    (["-cleanse_crash=1"], "take one crash file"),
    # fork mode's merge crashed at every divergent input (31 retries in 20 s, nothing fuzzed)
    (["-fork=1", "--stop-on-divergence"], "--stop-on-divergence with -fork: libFuzzer's fork mode"),
    # libFuzzer said "Test unit written to /proc/1/crash-..." and wrote nothing: the input lost
    (["-artifact_prefix=README.md/"], "-artifact_prefix=README.md/: README.md is a file, not a folder"),
    # libFuzzer's integer flags: Atheris' stoul raised (then the interpreter crashed, exit 139,
    # under a summary saying "exit status 0"); -jobs=-1 started jobs without end
    (["-seed=abc"], "-seed=abc: libFuzzer's -seed takes an integer from 0 to 4294967295"),
    (["-seed=99999999999999999999"], "-seed takes an integer from 0 to 4294967295"),
    (["-timeout=abc"], "-timeout=abc: libFuzzer's -timeout takes an integer"),
    (["-max_len=-1"], "-max_len=-1: libFuzzer's -max_len takes an integer from 0"),
    (["-jobs=-1"], "-jobs=-1: libFuzzer's -jobs takes an integer from 0"),
    (["-fork=-1"], "-fork=-1: libFuzzer's -fork takes an integer from 0"),
    (["-runs=1x"], "-runs=1x: libFuzzer's -runs takes an integer from -1"),
    # an empty path is the current folder: an unset shell variable wrote seeds there
    (["--artifacts="], "argument --artifacts: an empty path (an unset shell variable?)"),
    (["--no-such-option"], "unrecognized arguments: --no-such-option"),
    # libFuzzer passes a -fork parent's words to its jobs through a shell, unquoted
    (["-fork=2", "-exact_artifact_path=/tmp/a b"], "'-exact_artifact_path=/tmp/a b': libFuzzer hands this"),
]


@pytest.mark.parametrize(("args", "message"), HOSTILE, ids=[" ".join(a) for a, _ in HOSTILE])
def test_hostile_command_lines_exit_2_with_a_message(tmp_path: Path, args: list[str], message: str) -> None:
    run = fuzz(str(tmp_path / "corpus"), "-runs=10", f"--artifacts={tmp_path / 'a'}", "--no-progress", *args)
    assert run.returncode == 2, (run.returncode, run.stderr[-1500:])
    assert message in run.stderr, run.stderr[-1500:]
    assert "Traceback" not in run.stderr + run.stdout
    assert not list((tmp_path / "a").glob("crash-*"))  # nothing ran


def test_help_lists_the_subcommands_and_exit_statuses() -> None:
    run = fuzz("--help")
    assert run.returncode == 0, run.stderr
    for command in ("replay", "triage", "minimize", "report", "promote", "coverage"):
        assert f"\n  {command} " in run.stdout, command
    assert "exit status of a campaign" in run.stdout and "--verbose" in run.stdout


def test_a_campaign_that_finds_new_divergences_exits_1_and_then_0(tmp_path: Path) -> None:
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    args = (str(corpus), f"--artifacts={artifacts}", f"--targets=native,{TIGHT}", "--no-progress")
    first = fuzz(*args, "-runs=5000", "-seed=1")
    assert first.returncode == 1, first.stderr[-2000:]
    assert "exit status 1 (new divergences found)" in first.stderr
    # libFuzzer's own lines are hidden without --verbose; the empty input is not "malformed"
    assert " NEW " not in first.stderr and "REDUCE" not in first.stderr
    assert "malformed 0" in first.stderr
    # the same signature again: nothing new, so 0
    second = fuzz(*args, "-runs=300", "-seed=1")
    assert second.returncode == 0, second.stderr[-2000:]
    assert "crash files (0 new this run)" in second.stderr


def test_verbose_shows_libfuzzer_lines(tmp_path: Path) -> None:
    run = fuzz(str(tmp_path / "c"), "-runs=400", "-seed=2", f"--artifacts={tmp_path / 'a'}", "--verbose")
    assert run.returncode == 0, run.stderr[-2000:]
    assert " NEW " in run.stderr or "INITED" in run.stderr


def test_jobs_run_in_parallel_and_keep_their_logs_in_the_artifacts_folder(tmp_path: Path) -> None:
    from fuzzer.artifacts.divlog import STATS, read_lines

    work = tmp_path / "work"
    work.mkdir()
    run = fuzz("corpus", "-jobs=2", "-runs=3000", "-seed=5", "--artifacts=art", "--no-progress", cwd=work)
    assert run.returncode == 0, run.stderr[-2000:]
    assert not list(work.glob("fuzz-*.log")), "libFuzzer's job logs belong in the artifacts folder"
    assert sorted(p.name for p in (work / "art").glob("fuzz-*.log")) == ["fuzz-0.log", "fuzz-1.log"]
    assert "campaign summary (totals over 2 child process(es)" in run.stderr
    spans: dict[int, list[float]] = {}
    for record in read_lines(work / "art" / STATS):
        spans.setdefault(record["pid"], []).append(record["t"])
    (a_first, a_last), (b_first, b_last) = ((min(v), max(v)) for v in spans.values())
    assert a_first < b_last and b_first < a_last, "the two jobs ran one after the other"


def _options(flags: tuple[str, ...], forwarded: tuple[str, ...] = ()) -> CampaignOptions:
    from fuzzer.campaign import CampaignOptions

    return CampaignOptions(
        corpus=(Path("corpus"),),
        artifacts=Path("art"),
        libfuzzer_flags=flags,
        forwarded=forwarded,
        seeds=None,
        seed=0,
        stop_on_divergence=False,
        progress=False,
        progress_interval=5.0,
        dictionary_file=None,
    )


def test_jobs_get_as_many_workers_and_absolute_paths(tmp_path: Path) -> None:
    from fuzzer.input.libfuzzer_flags import libfuzzer_argv

    options = _options(("-jobs=3", "-dict=my.dict"), ("--robot=ur5", f"--msg-path={tmp_path}"))
    argv = libfuzzer_argv(options)
    assert "-workers=3" in argv and "-verbosity=0" in argv
    assert f"-dict={os.path.abspath('my.dict')}" in argv
    assert "--robot=ur5" in argv  # a robot name stays a name
    assert argv[-1] == str(Path("corpus").resolve())
    given = libfuzzer_argv(_options(("-jobs=3", "-workers=1"), options.forwarded))
    assert "-workers=1" in given and "-workers=3" not in given
    assert not any(f.startswith("-reload") for f in argv)  # jobs share their corpus by rereading it


def test_the_forwarded_options_parse_back_to_the_same_campaign() -> None:
    """libFuzzer's child processes (``-jobs``, ``-fork``) rerun our command from the tokens of
    ``forwarded_options``: they parse back to the same options, and none is a libFuzzer flag
    name behind ``--`` (``--seed=3`` drew libFuzzer's "did you mean '-seed=3'")."""
    from fuzzer.cli_options import campaign_parser, forwarded_options

    parser = campaign_parser()
    args = parser.parse_args(["corpus", "--seed", "3", "--op", "fk", "--robot", "ur5", "--seeds=7"])
    tokens = forwarded_options(args)
    assert not any(t.startswith("--seed=") for t in tokens), tokens
    again = parser.parse_args(["corpus", *tokens])
    assert (again.seed, again.op, again.robot, again.seeds) == (3, "fk", "ur5", 7)


def test_a_single_process_does_not_reread_its_corpus(monkeypatch: pytest.MonkeyPatch) -> None:
    """``-reload=0`` for one process (its corpus has no other writer; the reread made runs of one
    command differ), the user's ``-reload`` kept, none with ``-fork`` or in a worker of one."""
    from fuzzer.input.libfuzzer_flags import libfuzzer_argv
    from fuzzer.processes import CHILD_ENV

    def argv(*flags: str) -> list[str]:
        return [f for f in libfuzzer_argv(_options(flags)) if f.startswith("-reload")]

    monkeypatch.delenv(CHILD_ENV, raising=False)
    assert argv() == ["-reload=0"] and argv("-runs=9") == ["-reload=0"]
    assert argv("-reload=5") == ["-reload=5"]
    assert argv("-fork=2") == [] and argv("-jobs=2") == []
    monkeypatch.setenv(CHILD_ENV, "1")
    assert argv() == []


def test_sigterm_is_left_to_python_in_a_campaign_and_its_jobs(monkeypatch: pytest.MonkeyPatch) -> None:
    """``-handle_term=0`` where Python's handler runs (``signals.on_signal``: the summary), in a
    ``-jobs``/``-fork`` supervisor and its workers too (the supervisor's wakeup pipe and its
    forwarder: ``signals.forward_term_to_jobs``); merges and a crash's minimization keep
    libFuzzer's handler."""
    from fuzzer.input.libfuzzer_flags import libfuzzer_argv
    from fuzzer.processes import CHILD_ENV

    def argv(*flags: str) -> list[str]:
        return [f for f in libfuzzer_argv(_options(flags)) if f.startswith("-handle_term")]

    monkeypatch.delenv(CHILD_ENV, raising=False)
    assert argv() == ["-handle_term=0"] and argv("-runs=9") == ["-handle_term=0"]
    assert argv("-handle_term=1") == ["-handle_term=1"]
    for flags in ("-fork=2", "-jobs=2"):
        assert argv(flags) == ["-handle_term=0"], flags
    for flags in ("-merge=1", "-minimize_crash=1"):
        assert argv(flags) == [], flags
    monkeypatch.setenv(CHILD_ENV, "1")
    assert argv() == []


def test_an_artifact_prefix_that_takes_no_file_exits_74(tmp_path: Path) -> None:
    """libFuzzer said "Test unit written to /proc/1/crash-..." and wrote nothing: the input that
    killed a target was lost. A folder that takes no file exits 74, as --artifacts does."""
    run = fuzz(str(tmp_path / "c"), "-runs=1", "-artifact_prefix=/proc/1/", f"--artifacts={tmp_path / 'a'}")
    assert run.returncode == 74, run.stderr[-1500:]
    assert "-artifact_prefix=/proc/1/: cannot write into the folder /proc/1" in run.stderr


def test_jobs_with_one_seed_are_said_to_repeat_each_other(tmp_path: Path) -> None:
    """libFuzzer gives every -jobs job the -seed given: each repeated the others' choices (a
    probe's two jobs evaluated 259 of 995 divergent inputs twice), with no word of it. And
    -max_total_time bounds the whole -jobs campaign, as it does -fork's (-jobs=3 -workers=1
    -max_total_time=10 ran 35 s: the jobs started after it now exit at once)."""
    run = fuzz(str(tmp_path / "c"), "-jobs=2", "-workers=1", "-max_total_time=3", "-seed=5",
               f"--artifacts={tmp_path / 'a'}", "--no-progress")  # fmt: skip
    assert run.returncode == 0, run.stderr[-2000:]
    assert "-jobs with -seed=5: libFuzzer gives every job that seed" in run.stderr
    logs = sorted((tmp_path / "a").glob("fuzz-*.log"))
    assert len(logs) == 2 and b"INFO: seed corpus" not in logs[1].read_bytes(), "the second job fuzzed"


def test_jobs_are_execd_by_libfuzzers_shell(monkeypatch: pytest.MonkeyPatch) -> None:
    """libFuzzer runs each job (``-jobs``, ``-fork``, a merge's, a crash minimization's) as
    ``sh -c "<argv> > log"``: a Ctrl-C killed the shell, and a ``-jobs`` supervisor read that
    status from a Fuzzer it never made (a segfault). ``exec`` makes the job the shell's process;
    the script's path is quoted for the shell. One process runs no command: its argv is plain."""
    import shlex

    from fuzzer.input.libfuzzer_flags import libfuzzer_argv
    from fuzzer.processes import CHILD_ENV

    monkeypatch.delenv(CHILD_ENV, raising=False)
    monkeypatch.setattr(sys, "argv", ["/a folder/fuzz_diff.py"])
    for flags in (("-jobs=2",), ("-fork=2",), ("-merge=1",), ("-minimize_crash=1",)):
        first = libfuzzer_argv(_options(flags))[0]
        assert first == "exec '/a folder/fuzz_diff.py'", flags
        assert shlex.split(first) == ["exec", "/a folder/fuzz_diff.py"]
    assert libfuzzer_argv(_options(()))[0] == "/a folder/fuzz_diff.py"
    spaced = replace(_options(("-jobs=2",)), corpus=(Path("/x y/corpus"),), artifacts=Path("/x y/$HOME"))
    words = libfuzzer_argv(spaced)  # a -jobs supervisor reads flags only: every word quoted
    parsed = shlex.split(" ".join(words))  # what the job's shell makes of libFuzzer's command
    assert parsed[:2] == ["exec", "/a folder/fuzz_diff.py"] and "-jobs=2" in words
    assert "/x y/corpus" in parsed and "-artifact_prefix=/x y/$HOME/" in parsed
    for flags in (("-fork=2",), ("-merge=1",)):  # their parent reads the words its jobs get
        with pytest.raises(ValueError, match="libFuzzer hands this to its jobs through a shell"):
            libfuzzer_argv(replace(spaced, libfuzzer_flags=flags))
    monkeypatch.setenv(CHILD_ENV, "1")
    assert libfuzzer_argv(_options(()))[0] == "/a folder/fuzz_diff.py"


def test_a_signal_is_kept_for_the_next_input_once_libfuzzer_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    """Before libFuzzer, a KeyboardInterrupt where Python runs next; after, the signal waits for
    the next input (a KeyboardInterrupt in Hypothesis' gc callback was lost), and a second
    Ctrl-C or SIGTERM acts at once (a target that never returns). A SIGTERM marks the run
    terminated."""
    import signal as signals_

    from fuzzer import signals

    for name in ("_PENDING", "_DEFERRING", "_TERMINATED"):
        monkeypatch.setattr(signals, name, [])
    monkeypatch.setattr(signals_, "getsignal", lambda _: signals_.default_int_handler)
    installed: list[object] = []
    monkeypatch.setattr(signals_, "signal", lambda _num, handler: installed.append(handler))
    with pytest.raises(KeyboardInterrupt):
        signals.on_signal(signals_.SIGINT, None)
    assert not signals.stop_requested()
    signals.defer_to_next_input()
    assert installed == [signals.on_signal]
    signals.on_signal(signals_.SIGTERM, None)
    assert signals.stop_requested() and signals.terminated()
    signals.on_signal(signals_.SIGINT, None)  # the first Ctrl-C waits
    with pytest.raises(KeyboardInterrupt):
        signals.on_signal(signals_.SIGINT, None)  # the second does not
    with pytest.raises(KeyboardInterrupt):
        signals.on_signal(signals_.SIGTERM, None)  # nor does a second SIGTERM


def test_a_kept_signal_stops_drawing_and_writing_seeds(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """A Ctrl-C kept until the seeds were made waited for all of them: 100,000 seeds, 200,000
    files, 6 minutes. Drawing and writing them now stop at the next seed."""
    from hypothesis import strategies as st

    from fuzzer import signals
    from fuzzer.generation import seeds as seeds_module
    from fuzzer.generation.corpus import write_seeds
    from fuzzer.input.testcase import TestCase

    monkeypatch.setattr(seeds_module, "stop_requested", lambda: True)
    with pytest.raises(KeyboardInterrupt):
        seeds_module.generate_seeds(st.integers().map(lambda i: {"data": [float(i)]}), 50, 1)
    monkeypatch.setattr(signals, "stop_requested", lambda: True)
    with pytest.raises(KeyboardInterrupt):
        write_seeds(tmp_path, [TestCase("std_msgs/Float64MultiArray", {"data": [1.0]})])
    assert not list(tmp_path.iterdir())


def test_a_supervisor_counts_its_interrupted_jobs(tmp_path: Path) -> None:
    from fuzzer.artifacts.divlog import STATS, append_line, worker_totals

    append_line(tmp_path / STATS, {"t": 10.0, "pid": 1, "execs": 5})
    append_line(tmp_path / STATS, {"t": 11.0, "pid": 1, "execs": 9, "interrupted": True})
    append_line(tmp_path / STATS, {"t": 11.0, "pid": 2, "execs": 4, "interrupted": "yes"})  # not a bool
    append_line(tmp_path / STATS, {"t": 1.0, "pid": 3, "execs": 4, "interrupted": True})  # an earlier run
    totals = worker_totals(tmp_path, since=5.0)
    assert totals["interrupted"] == 1 and totals["execs"] == 13 and totals["processes"] == 2


def test_a_dictionary_libfuzzer_would_refuse_is_named_before_start_up(tmp_path: Path) -> None:
    bad = tmp_path / "bad.dict"
    bad.write_text('# a comment\nkw="ok"\n"value"  # a comment after it\n')
    run = fuzz(str(tmp_path / "corpus"), "-runs=10", f"--artifacts={tmp_path / 'a'}", f"-dict={bad}")
    assert run.returncode == 2, run.stderr[-1500:]
    assert f"-dict={bad}: line 3 is not a libFuzzer dictionary entry" in run.stderr
    assert "ParseDictionaryFile" not in run.stderr + run.stdout and "Traceback" not in run.stderr


@pytest.mark.slow
def test_a_dictionary_the_check_accepts_libfuzzer_accepts(tmp_path: Path) -> None:
    good = tmp_path / "good.dict"
    good.write_text('# joints\n\n  kw1="0.5"\n"1.5707963"\nx="\\x41\\\\\\"q"\n  \t\n"a b"\r\n')
    run = fuzz(str(tmp_path / "c"), "-runs=5", f"--artifacts={tmp_path / 'a'}", f"-dict={good}", "--verbose")
    assert run.returncode == 0, run.stderr[-2000:]
    assert "ParseDictionaryFile" not in run.stderr + run.stdout
    assert "Dictionary: 4 entries" in run.stderr + run.stdout


def test_ctrl_c_before_libfuzzer_runs_is_a_message_not_a_traceback(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    from fuzzer import cli

    def interrupted(*_: object) -> int:
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "campaign_main", interrupted)
    assert cli.main([str(tmp_path / "corpus")]) == 130
    assert capsys.readouterr().err == "fuzz_diff.py: interrupted\n"


def test_output_to_a_full_device_is_named_with_its_own_status() -> None:
    # /dev/full: a traceback and exit 1, which for show and replay means "still diverges"
    import subprocess
    import sys

    from tests.support import ROOT, SCRIPT

    agree = ROOT / "tests" / "regressions" / "crash-364397c4d569c4ab0b32ab7ec9ef57821af1a621"
    for args in (["show", str(agree)], [str(agree)], ["triage", str(agree.parent)]):
        with open("/dev/full", "w") as full:
            run = subprocess.run(
                [sys.executable, SCRIPT, *args],
                cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)), stdout=full, stderr=subprocess.PIPE,
                text=True, timeout=120, check=False,
            )  # fmt: skip
        assert run.returncode == 74, (args, run.stderr[-2000:])
        assert run.stderr.strip().endswith("fuzz_diff.py: error: <stdout>: No space left on device"), args


def test_minimize_into_a_full_folder_exits_74_and_an_already_minimal_file_writes_nothing(
    tmp_path: Path,
) -> None:
    # a full disk was exit 2, the status of an unreadable file; a minimized file minimized again
    # was written again under a new name (the same message, its lineage one step longer)
    import resource
    import shutil
    import subprocess
    import sys

    from tests.support import ROOT, SCRIPT

    minimized = ROOT / "tests" / "regressions" / "minimized-34e1a33bf5c25be1ca333b3736986c6e1f2cc248"
    # a crash file that still diverges under its sidecar's targets (the suite's crash- files are
    # fixed ones, which minimize now refuses): the minimized one under a crash- name
    crash = tmp_path / "src" / "crash-34e1a33bf5c25be1ca333b3736986c6e1f2cc248"
    crash.parent.mkdir()
    shutil.copyfile(minimized, crash)
    shutil.copyfile(f"{minimized}.json", f"{crash}.json")

    def run(path: Path, out: Path, limit: int | None = None) -> subprocess.CompletedProcess[str]:
        def small_files() -> None:
            if limit is not None:
                resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))  # EFBIG past it, as ENOSPC

        return subprocess.run(
            [sys.executable, SCRIPT, "minimize", str(path), "--trust-sidecar", "-o", str(out)],
            cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)), preexec_fn=small_files,
            capture_output=True, text=True, timeout=180, check=False,
        )  # fmt: skip

    again = run(minimized, tmp_path / "again")
    assert again.returncode == 0, again.stderr[-2000:]
    assert "already minimal" in again.stdout and not list((tmp_path / "again").glob("minimized-*"))
    full = run(crash, tmp_path / "full", limit=1024)  # the crash file fits, its sidecar does not
    assert full.returncode == 74, full.stderr[-2000:]
    assert "Traceback" not in full.stderr
    assert f"fuzz_diff.py: error: cannot write into {tmp_path / 'full'}: File too large" in full.stderr
    assert [p.name for p in (tmp_path / "full").iterdir()] == [".signatures"]  # no half of a pair
    fits = run(crash, tmp_path / "fits")
    assert fits.returncode == 0 and "minimized to" in fits.stdout, fits.stderr[-2000:]


def test_a_fork_campaign_runs_from_a_working_folder_with_a_space(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The default ``-artifact_prefix`` was absolute, so ``-fork`` and merges run from a folder
    such as "/home/me/My robots" were refused (their words reach the jobs through a shell,
    unquoted). The jobs run in the same working folder: the prefix is made relative to it
    there, where the absolute one is not a safe word; elsewhere it stays absolute."""
    from fuzzer.input.libfuzzer_flags import libfuzzer_argv
    from fuzzer.processes import CHILD_ENV

    monkeypatch.delenv(CHILD_ENV, raising=False)
    work = tmp_path / "my robots"
    work.mkdir()
    monkeypatch.chdir(work)
    for flags in (("-fork=2",), ("-merge=1",), ("-minimize_crash=1",)):
        words = libfuzzer_argv(_options(flags))
        assert "-artifact_prefix=art/" in words, flags
    # one process runs no shell, -jobs quotes its words: the prefix stays absolute
    assert f"-artifact_prefix={work / 'art'}/" in libfuzzer_argv(_options(()))
    assert shlex.quote(f"-artifact_prefix={work / 'art'}/") in libfuzzer_argv(_options(("-jobs=2",)))
    plain = tmp_path / "plain"
    plain.mkdir()
    monkeypatch.chdir(plain)
    assert f"-artifact_prefix={plain / 'art'}/" in libfuzzer_argv(_options(("-fork=2",)))
    monkeypatch.chdir(work)
    with pytest.raises(ValueError, match="my robots/my art/': libFuzzer hands this"):  # the user's own space
        libfuzzer_argv(replace(_options(("-fork=2",)), artifacts=Path("my art")))


def test_a_long_scenario_campaign_gets_room_for_its_seeds() -> None:
    """At ``--max-steps 256`` 20 of the 32 Hypothesis seeds were longer than the default
    ``-max_len=16384``: libFuzzer cut them short into malformed inputs, never run, never said.
    A scenario campaign's default makes room for its steps; a given ``-max_len`` is kept."""
    from fuzzer.execution.session import RunConfig, Session
    from fuzzer.generation.corpus import make_seeds
    from fuzzer.input.libfuzzer_flags import default_max_len, libfuzzer_argv

    assert default_max_len("move", 256) == default_max_len("scenario", 16) == 16384
    room = default_max_len("scenario", 256)
    seeds = make_seeds(Session.open(RunConfig(op="scenario", max_steps=256)), 32, 1)
    assert max(len(case.encode()) for case in seeds) > 16384  # what was cut short
    assert all(len(case.encode()) <= room for case in seeds)
    options = replace(_options(()), max_len=room)
    assert f"-max_len={room}" in libfuzzer_argv(options)
    assert "-max_len=999" in libfuzzer_argv(replace(options, libfuzzer_flags=("-max_len=999",)))


def test_an_ik_tolerance_below_the_solvers_precision_is_warned_of() -> None:
    """``--op ik --tolerance 1e-10`` reported the solver's own tolerance as divergences (a helper's
    probe: two, both answers within sqrt(3) IK_EPS of the target), with no word of it."""
    from fuzzer.execution.tolerance import Tolerance, below_ik_precision, default_tolerance

    said = below_ik_precision("ik", Tolerance(1e-10, 1e-10))
    assert said is not None and "below what two correct IK answers can differ by (3.5e-06" in said
    assert below_ik_precision("ik", Tolerance(1e-5, 1e-6)) is not None  # either one
    assert below_ik_precision("ik", default_tolerance("ik")) is None
    assert below_ik_precision("fk", Tolerance(1e-10, 1e-10)) is None


def test_a_given_max_len_shorter_than_the_seeds_is_warned_of() -> None:
    """At ``-max_len=1`` libFuzzer cut all 64 seeds into malformed inputs: a campaign that tested
    nothing, exit 0, with no word of it."""
    from fuzzer.input.libfuzzer_flags import cut_seeds

    said = cut_seeds(("-max_len=100",), [50, 411, 200])
    assert said is not None and said.startswith("2 of 3 seeds are longer than -max_len=100")
    assert cut_seeds(("-max_len=500",), [50, 411]) is None
    assert cut_seeds(("-max_len=0",), [50, 411]) is None  # 0: libFuzzer's choice, from the seeds
    assert cut_seeds((), [50, 411]) is None


def test_max_steps_outside_a_scenario_is_said_to_do_nothing(tmp_path: Path) -> None:
    run = fuzz(str(tmp_path / "c"), "-runs=1", "--op=move", "--max-steps=5", f"--artifacts={tmp_path / 'a'}")
    assert run.returncode == 0, run.stderr[-2000:]
    assert "--max-steps 5: only a scenario has steps; --op move ignores it" in run.stderr


WHITESPACE_NAMES = (
    '<robot name="r"><link name="base"/><link name="l\n1"/><link name="l2"/>'
    '<joint name="j\t1" type="revolute"><parent link="base"/><child link="l\n1"/><axis xyz="0 0 1"/>'
    '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
    '<joint name="j2" type="revolute"><parent link="l\n1"/><child link="l2"/><axis xyz="0 0 1"/>'
    '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
)


def test_targets_that_read_different_robots_are_refused_and_leave_no_folder(tmp_path: Path) -> None:
    """A literal tab or newline in a name: urdfdom keeps it, the twin's expat reads a space. Every
    input diverged for that alone (493 "status" divergences in 10 s); now refused at start-up,
    before the drawn -seed is announced, and the folders made for the campaign are removed."""
    robot = tmp_path / "ws.urdf"
    robot.write_text(WHITESPACE_NAMES)
    corpus, artifacts = tmp_path / "c", tmp_path / "a"
    run = fuzz(str(corpus), "--op=fk", "-runs=10", f"--robot={robot}", f"--artifacts={artifacts}")
    assert run.returncode == 2, run.stderr[-2000:]
    assert "the targets read different robots from ws.urdf: joint 0 is 'j\\t1' to native" in run.stderr
    assert "drawn for this campaign" not in run.stderr
    assert not corpus.exists() and not artifacts.exists()
    kept = tmp_path / "kept"
    kept.mkdir()
    run = fuzz(str(kept), "--op=fk", "-runs=10", "--robot=nosuchbot", f"--artifacts={artifacts}")
    assert run.returncode == 2 and kept.is_dir() and not artifacts.exists(), run.stderr[-2000:]


def test_a_robot_with_no_joint_to_move_is_warned_of(tmp_path: Path) -> None:
    robot = tmp_path / "one.urdf"
    robot.write_text('<robot name="r"><link name="a"/></robot>')
    run = fuzz(str(tmp_path / "c"), "--op=fk", "-runs=5", f"--robot={robot}", f"--artifacts={tmp_path / 'a'}")
    assert run.returncode == 0, run.stderr[-2000:]
    assert "one.urdf: no joint moves its tip link; every input makes the same call" in run.stderr
    assert "--tip-link" not in run.stderr, "no link to suggest: the robot has no joint"


def test_a_tie_of_the_default_tip_rule_suggests_tip_links(tmp_path: Path) -> None:
    """Baxter's two arms tie, so the default tip is its torso: 69,143 executions that tested
    nothing read as a clean pass (a helper's probe). The warning names tip links to choose."""
    run = fuzz(str(tmp_path / "c"), "--op=fk", "-runs=5", "--robot=baxter", f"--artifacts={tmp_path / 'a'}")
    assert run.returncode == 0, run.stderr[-2000:]
    assert "nothing is tested; pass --tip-link l_gripper_l_finger_tip or " in run.stderr


def test_show_into_a_reader_that_leaves_early_ends_with_141(tmp_path: Path) -> None:
    """``show DIR | head``: the reader took 65,536 of the bytes and left; the program ended with
    status 0, the rest lost without a word. Now the next write's broken pipe ends it with 141."""
    import shutil
    import subprocess

    for source in sorted((ROOT / "corpus-scenario").glob("seed-*"))[:40]:
        shutil.copy(source, tmp_path / source.name)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    run = subprocess.Popen(
        [sys.executable, SCRIPT, "show", str(tmp_path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
    )
    assert run.stdout is not None and run.stderr is not None
    assert run.stdout.read(10)
    run.stdout.close()  # the reader leaves, as head does
    err = run.stderr.read().decode()
    assert run.wait(timeout=60) == 141, err
    assert "Traceback" not in err


def test_an_artifacts_folder_shared_by_two_configurations_is_said(tmp_path: Path) -> None:
    """A signature names a symptom: a campaign on another robot or targets, writing into an
    artifacts folder of another one, got no crash file for a symptom on file there, and its
    divergences went into the other's bucket, without a word (the triage probe)."""
    from fuzzer.artifacts.travel import CONFIGURATION, note_configuration
    from fuzzer.execution.session import RunConfig

    note_configuration(tmp_path, RunConfig(robot="probot_anno"))
    first = (tmp_path / CONFIGURATION).read_text()
    assert first.startswith("robot probot_anno (") and "targets native,python" in first
    run = fuzz(str(tmp_path / "c"), "-runs=1", "--robot=ur5", f"--artifacts={tmp_path}", "--no-progress")
    assert run.returncode == 0, run.stderr[-2000:]
    assert "holds crash files of a campaign on another configuration (robot probot_anno" in run.stderr
    assert (tmp_path / CONFIGURATION).read_text() == first  # the first one's, kept
    again = fuzz(str(tmp_path / "c2"), "-runs=1", f"--artifacts={tmp_path}", "--no-progress")
    assert again.returncode == 0 and "another configuration" not in again.stderr, again.stderr[-2000:]
