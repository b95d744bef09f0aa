"""The engine end to end, as a user runs it: fuzz_diff.py in a subprocess."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import python_impl
from fuzzer.artifacts.divlog import STATS
from fuzzer.input.testcase import TestCase, decode
from fuzzer.selection.state import BOUNDARY, SPACEFILL
from robot_api.robots import default_robot_path

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = str(ROOT / "fuzz_diff.py")
TIGHT = "tests.plugins.faults:tight_tolerance"


def fuzz(*args: str, timeout: float = 180) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(
        [sys.executable, SCRIPT, *args, "--no-progress"],
        cwd=ROOT,
        env=env,
        text=True,
        capture_output=True,
        timeout=timeout,
        check=False,
    )


def sidecars(artifacts: Path) -> list[dict]:  # type: ignore[type-arg]
    return [json.loads(p.read_text()) for p in sorted(artifacts.glob("crash-*.json"))]


def _assert_planted(run: subprocess.CompletedProcess[str], artifacts: Path) -> list[dict]:  # type: ignore[type-arg]
    assert run.returncode == 1, run.stderr[-2000:]  # new divergences: exit 1
    assert "campaign summary" in run.stderr
    found = sidecars(artifacts)
    assert found, run.stderr[-2000:]
    for sidecar in found:
        assert sidecar["signature"]["kind"] == "status"
        assert sidecar["signature"]["outcome_b"] == "rejected:OutOfBoundsError:30"
    return found


def test_finds_a_planted_divergence_within_a_bounded_budget(tmp_path: Path) -> None:
    """Tolerance 1e-5 instead of 1e-4: only values 1e-5..1e-4 past a limit show it. Hypothesis'
    seeds stay within the limits; the first round of boundary probes (5e-5 past a limit,
    ``fuzzer.generation.boundary``) is in the space-filling seeds and in the dry run
    (``fuzzer.dry_run``, which evaluates it before libFuzzer does), so those find it."""
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    run = fuzz(str(corpus), "-runs=5000", "-seed=1", f"--artifacts={artifacts}", f"--targets=native,{TIGHT}")
    found = _assert_planted(run, artifacts)
    assert any(s["lineage"] in ([], [BOUNDARY]) and s["testcase"]["origin"] == SPACEFILL for s in found), [
        (s["lineage"], s["testcase"]["origin"]) for s in found
    ]
    limits = python_impl.RobotModel(default_robot_path()).joint_limits
    outside = 0
    for seed in corpus.glob("seed-*"):
        case = decode(seed.read_bytes())
        values = case.message["position"]
        pairs = zip(values, limits, strict=True)
        past = [max(lim.lower - v, v - lim.upper) for v, lim in pairs if not lim.lower <= v <= lim.upper]
        if case.origin == "hypothesis":  # Hypothesis' seeds stay within the limits, where it cannot show
            assert not past
        else:  # a space-filling seed leaves them by one probe at most, 5e-5 on one joint
            assert case.origin == "spacefill" and len(past) <= 1 and all(abs(p - 5e-5) < 1e-12 for p in past)
            outside += len(past)
    assert outside == 2 * len(limits)  # every joint and side once


def test_finds_a_planted_divergence_from_the_hypothesis_seeds_alone(tmp_path: Path) -> None:
    """From the shipped corpus (Hypothesis seeds, all within the limits: no seeds are written),
    the campaign's own inputs have to find it: boundary probes or mutations."""
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    shutil.copytree(ROOT / "corpus", corpus)
    run = fuzz(str(corpus), "-runs=5000", "-seed=1", f"--artifacts={artifacts}", f"--targets=native,{TIGHT}")
    for sidecar in _assert_planted(run, artifacts):
        assert sidecar["lineage"], "found by a seed"
    assert sorted(corpus.glob("seed-*")) == sorted(corpus / p.name for p in (ROOT / "corpus").glob("seed-*"))


def test_crash_files_replay_their_verdict(tmp_path: Path) -> None:
    artifacts = tmp_path / "artifacts"
    run = fuzz(
        str(tmp_path / "corpus"),
        "-runs=5000",
        "-seed=1",
        f"--artifacts={artifacts}",
        f"--targets=native,{TIGHT}",
    )
    crash = sorted(p for p in artifacts.glob("crash-*") if not p.name.endswith(".json"))[0]
    again = fuzz(str(crash), "--trust-sidecar")  # its sidecar names a plugin target
    assert again.returncode == 1 and "still diverges (same signature)" in again.stdout
    fixed = fuzz(str(crash), "--targets=native,python")
    assert fixed.returncode == 0 and "now agrees" in fixed.stdout
    folder = fuzz("replay", str(artifacts), "--targets", f"native,{TIGHT}")
    assert folder.returncode == 1 and folder.stdout.count("still diverges") == len(sidecars(artifacts))
    assert run.returncode == 1  # the campaign found new divergences


def test_a_third_implementation_plugs_in_as_module_attribute(tmp_path: Path) -> None:
    artifacts = tmp_path / "artifacts"
    run = fuzz(
        str(tmp_path / "corpus"),
        "-runs=3000",
        "-seed=2",
        "--robot=kinova",
        f"--artifacts={artifacts}",
        "--targets=native,tests.plugins.faults:wrap_continuous",
    )
    assert run.returncode == 1, run.stderr[-2000:]
    found = sidecars(artifacts)
    assert found
    continuous = {0, 3, 5}  # Kinova's continuous joints
    for sidecar in found:  # the paper's "positive and negative" class
        # sign flip and joint indices are details of the comparison now, not of the signature,
        # which keys on the joint types (issue 12, one bug one bucket)
        sig, cmp = sidecar["signature"], sidecar["comparison"]
        assert (sig["kind"], sig["field"], cmp["sign_flip"]) == ("representation", "joint_values", True)
        assert sig["joint_types"] == ["continuous"] and set(cmp["joints"]) <= continuous
    assert len(found) == 1  # one bug, one bucket


def test_stop_on_divergence_is_a_libfuzzer_crash(tmp_path: Path) -> None:
    artifacts = tmp_path / "artifacts"
    run = fuzz(
        str(tmp_path / "corpus"),
        "-runs=5000",
        "-seed=1",
        f"--artifacts={artifacts}",
        f"--targets=native,{TIGHT}",
        "--stop-on-divergence",
    )
    assert run.returncode == 77
    crashes = [p for p in artifacts.glob("crash-*") if not p.name.endswith(".json")]
    assert len(crashes) == 1 and (artifacts / (crashes[0].name + ".json")).is_file()


def test_agreeing_targets_run_clean(tmp_path: Path) -> None:
    artifacts = tmp_path / "artifacts"
    run = fuzz(str(tmp_path / "corpus"), "-runs=1500", "-seed=3", f"--artifacts={artifacts}")
    assert run.returncode == 0, run.stderr[-2000:]
    assert "divergences: 0" in run.stderr and not sidecars(artifacts)


def test_a_campaign_repeats_itself_for_a_seed(tmp_path: Path) -> None:
    """Two runs of one command keep the same corpus: every random choice has its seed, and a
    single process no longer rereads its corpus folder (``-reload=0``, ``libfuzzer_flags.libfuzzer_argv``).
    libFuzzer's reread, once a second, ran again the seeds that had added no coverage, at an
    execution the clock chose: of three 800-input runs, one kept other inputs than the two others."""
    kept = []
    for name in ("a", "b"):
        corpus = tmp_path / name / "corpus"
        art = f"--artifacts={tmp_path / name / 'art'}"
        run = fuzz(str(corpus), "--op=move", "-runs=2500", "-seed=11", art)
        assert run.returncode == 0, run.stderr[-2000:]
        kept.append(sorted(p.name for p in corpus.iterdir() if p.is_file()))
    assert len(kept[0]) > 100 and kept[0] == kept[1]


def test_a_campaign_given_no_seed_prints_the_one_it_drew_and_that_seed_repeats_it(tmp_path: Path) -> None:
    """Without ``-seed`` libFuzzer draws one from the clock, and ``-verbosity=0`` hid it: such a
    campaign (``make run``'s) could not be repeated. Now the seed is drawn and printed, and the
    same command with it (and the harness's own seed, 0 as before) keeps the same corpus
    (``processes.drawn_seed``)."""
    import re

    kept, drawn = [], []
    for name, extra in (("a", ()), ("b", ("-seed=0",)), ("again", None)):
        corpus = tmp_path / name / "corpus"
        art = f"--artifacts={tmp_path / name / 'art'}"
        flags = extra if extra is not None else (f"-seed={drawn[0]}", "--seed=0")
        run = fuzz(str(corpus), "--op=fk", "-runs=600", art, *flags)
        assert run.returncode == 0, run.stderr[-2000:]
        said = re.findall(r"libFuzzer's -seed=(\d+): drawn for this campaign", run.stderr)
        if extra is None:
            assert said == []  # a seed given is a seed used
            # the harness's --seed reaches libFuzzer's argv (for its child processes) in a form
            # libFuzzer does not take for its own -seed mistyped
            assert "did you mean" not in run.stderr, run.stderr[-2000:]
        else:
            assert len(said) == 1, run.stderr[-2000:]
            drawn.append(int(said[0]))
        kept.append(sorted(p.name for p in corpus.iterdir() if p.is_file()))
        # the campaign log keeps the seeds too (the terminal's lines scroll away), in every
        # snapshot of the campaign's processes (the dry run's too)
        records = [json.loads(line) for line in (tmp_path / name / "art" / STATS).read_text().splitlines()]
        logged = [r["seed"] for r in records]
        assert len({r["pid"] for r in records}) > 1  # the dry run's processes and libFuzzer's
        assert logged and all(
            s == {"libfuzzer": drawn[0 if extra is None else -1], "harness": 0} for s in logged
        )
    assert all(0 < seed < 2**31 for seed in drawn)
    assert len(kept[0]) > 100 and kept[2] == kept[0]


def test_the_last_seed_flag_is_the_campaigns_as_libfuzzer_takes_it(tmp_path: Path) -> None:
    """libFuzzer keeps the last of two ``-seed`` flags; the harness took the first, so
    ``-seed=3 -seed=11`` ran libFuzzer's choices of seed 11 with the harness's of seed 3, a
    campaign neither seed repeats. Now both take the last: the same corpus as ``-seed=11``."""
    kept = []
    for name, seeds in (("twice", ("-seed=3", "-seed=11")), ("once", ("-seed=11",))):
        corpus = tmp_path / name / "corpus"
        run = fuzz(str(corpus), "--op=fk", "-runs=600", f"--artifacts={tmp_path / name / 'art'}", *seeds)
        assert run.returncode == 0, run.stderr[-2000:]
        records = [json.loads(line) for line in (tmp_path / name / "art" / STATS).read_text().splitlines()]
        assert records and all(r["seed"] == {"libfuzzer": 11, "harness": 11} for r in records)
        kept.append(sorted(p.name for p in corpus.iterdir() if p.is_file()))
    assert len(kept[0]) > 100 and kept[0] == kept[1]


def test_flags_read_as_libfuzzer_reads_them_the_last_one_wins(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from fuzzer import processes

    monkeypatch.delenv(processes.CHILD_ENV, raising=False)
    assert processes.flag_value(("-seed=3", "-runs=9", "-seed=11"), "-seed") == "11"
    assert processes.flag_value(("-runs=9",), "-seed") is None
    assert processes.libfuzzer_seed(("-seed=3", "-seed=11")) == 11
    assert processes.libfuzzer_seed(("-seed=3", "-seed=0")) is None  # libFuzzer draws
    assert processes.int_flag(("-jobs=2", "-jobs=0"), "-jobs", 5) == 0
    assert not processes.supervises(("-fork=2", "-fork=0"))
    folder = tmp_path / "corpus"
    folder.mkdir()
    flags, seed = processes.drawn_seed(("-seed=3", "-seed=0"), (folder,))  # libFuzzer would draw
    assert seed is not None and flags == (f"-seed={seed}",)
    assert processes.drawn_seed(("-seed=0", "-seed=3"), (folder,)) == (("-seed=0", "-seed=3"), None)


def test_a_seed_is_drawn_only_for_a_campaign_of_one_process(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from fuzzer import processes

    monkeypatch.delenv(processes.CHILD_ENV, raising=False)
    folder, file = tmp_path / "corpus", tmp_path / "input"
    folder.mkdir()
    file.write_bytes(b"{}")
    flags, seed = processes.drawn_seed(("-runs=5", "-seed=0", "-seed=0"), (folder,))
    assert seed is not None and flags == ("-runs=5", f"-seed={seed}")
    flags, seed = processes.drawn_seed(("-runs=5",), (folder,))
    assert seed is not None and flags == ("-runs=5", f"-seed={seed}")
    for flags, corpus in (
        (("-seed=7",), (folder,)),  # given
        (("-seed=-3",), (folder,)),  # libFuzzer's to judge
        (("-jobs=2",), (folder,)),  # one seed for every job would repeat one job's choices
        (("-fork=2",), (folder,)),
        (("-merge=1",), (folder, folder)),  # no random choices of a campaign
        (("-minimize_crash=1",), (file,)),
        ((), (folder, file)),  # libFuzzer runs the file
    ):
        assert processes.drawn_seed(flags, corpus) == (flags, None), flags
    monkeypatch.setenv(processes.CHILD_ENV, "1")  # a -jobs or -fork worker: its parent's flags
    assert processes.drawn_seed((), (folder,)) == ((), None)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--robot=/nonexistent.urdf"], "--robot"),
        (["--targets=native"], "exactly two targets"),
        (["--targets=native,no_such_module:x"], "cannot import no_such_module"),
        (["--targets=native,tests.plugins.faults:not_a_target"], "no callable MoveGroup"),
        (["--targets=native,tests.plugins.faults:nothing"], "has no attribute"),
        (["--tolerance=-1"], "--tolerance"),
        (["--msg-type=sensor_msgs/Nope"], "--msg-type"),
        (["--op=ik", "--msg-type=sensor_msgs/JointState"], "supported: geometry_msgs/PoseStamped"),
        (["--op=jump"], "invalid choice"),
        (["--seeds=-1"], "--seeds"),
        (["-dict=/nonexistent.dict"], "-dict"),
        (["--msg-path=/nonexistent"], "--msg-path"),
        (["--robot=ur5", "--tip-link=nope"], "tip link 'nope'"),
    ],
)
def test_bad_arguments_exit_2_with_a_clear_message(tmp_path: Path, args: list[str], message: str) -> None:
    run = fuzz(str(tmp_path / "corpus"), "-runs=10", *args, timeout=60)
    assert run.returncode == 2, (run.returncode, run.stderr[-1000:])
    assert message in run.stderr
    assert "Traceback" not in run.stderr


def test_malformed_corpus_files_are_skipped_with_a_warning(tmp_path: Path) -> None:
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    (corpus / "broken.json").write_bytes(b'{"rrosfuzz": 1, "msg_type": ')
    (corpus / "empty").write_bytes(b"")
    (corpus / "other-type").write_bytes(b'{"rrosfuzz": 1, "msg_type": "geometry_msgs/Pose", "message": {}}')
    with (corpus / "huge").open("wb") as sparse:  # read whole before its size was checked (3 GB: OOM)
        sparse.truncate(2 << 20)
    # a link out of the folder is refused, not skipped: libFuzzer read it (tests/test_hostile_files.py)
    run = fuzz(str(corpus), "-runs=300", "-seed=1", f"--artifacts={tmp_path / 'a'}")
    assert run.returncode == 0, run.stderr[-2000:]
    for name in ("broken.json", "empty", "other-type", "huge"):
        assert f"skipping corpus file {corpus / name}" in run.stderr
    assert "larger than a test case may be" in run.stderr
    assert "wrote 32 seeds" in run.stderr  # no usable file: seeds are generated


def test_a_hanging_target_hits_the_timeout(tmp_path: Path) -> None:
    artifacts = tmp_path / "artifacts"
    run = fuzz(
        str(tmp_path / "corpus"),
        "-runs=20000",
        "-seed=1",
        "-timeout=2",
        f"--artifacts={artifacts}",
        "--targets=native,tests.plugins.faults:hangs",
        timeout=300,
    )
    assert run.returncode == 70, run.stderr[-2000:]
    assert list(artifacts.glob("timeout-*"))


def test_a_dying_target_leaves_a_crash_file(tmp_path: Path) -> None:
    artifacts = tmp_path / "artifacts"
    run = fuzz(
        str(tmp_path / "corpus"),
        "-runs=20000",
        "-seed=1",
        f"--artifacts={artifacts}",
        "--targets=native,tests.plugins.faults:aborts",
    )
    assert run.returncode != 0 and "deadly signal" in run.stderr
    crashes = [p for p in artifacts.glob("crash-*") if not p.name.endswith(".json")]
    assert crashes
    assert decode(crashes[0].read_bytes()).message["position"][0] > 3.0  # the input that killed it


def test_a_crash_file_that_kills_its_replay_is_a_verdict_and_the_others_replay(tmp_path: Path) -> None:
    """A file a target aborts on killed `replay` with it: exit 134, no word, a folder's other
    files never replayed. Each file is replayed in a child process now."""
    folder = tmp_path / "crashes"
    folder.mkdir()
    for name, first in (("crash-aborts", 3.1), ("crash-fine", 0.5)):
        _move_case(folder / name, first)
    run = fuzz("replay", str(folder), "--op=move", "--targets=native,tests.plugins.faults:aborts")
    assert run.returncode == 1, (run.returncode, run.stderr[-2000:])
    assert f"{folder / 'crash-aborts'}: crashes the replaying process (killed by SIGABRT" in run.stdout
    assert f"{folder / 'crash-fine'}: the targets agree (no sidecar to compare with)" in run.stdout


def _move_case(path: Path, first: float) -> None:
    """A move test case to joint_1 = ``first`` (the others 0) at ``path``: the faulty plugins
    abort, exit or hang above 3 rad."""
    message = {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "name": [], "position": [first, 0.0, 0.0, 0.0, 0.0, 0.0], "velocity": [], "effort": [],
    }  # fmt: skip
    path.write_bytes(TestCase("sensor_msgs/JointState", message).encode())


def test_a_crash_file_a_target_exits_or_hangs_on_is_a_verdict(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A target's exit() was "the replay failed" (exit 2, a usage error); a hanging one made
    `replay` wait for good, and a SIGTERM to it left the child spinning at 100% CPU."""
    from fuzzer import cli
    from fuzzer.triage import isolated

    monkeypatch.setattr(isolated, "REPLAY_SECONDS", 3.0)
    crash = tmp_path / "crash-high"
    _move_case(crash, 3.1)
    verdicts = {
        "exits": "ends the replaying process (exit status 3: a target ended it)",
        "hangs": "hangs the replaying process (no verdict in 3 s: a target hangs on it)",
    }
    for plugin, said in verdicts.items():
        code = cli.main(
            ["replay", str(crash), "--op=move", f"--targets=native,tests.plugins.faults:{plugin}"]
        )
        out = capsys.readouterr().out
        assert code == 1 and f"{crash}: {said}" in out, (plugin, code, out)


def test_minimize_says_a_file_that_kills_its_process_is_libfuzzers_to_minimize(tmp_path: Path) -> None:
    """A file a target aborts on ended `minimize` with it: exit 134, no word."""
    artifacts = tmp_path / "a"
    run = fuzz(
        str(tmp_path / "c"), "-runs=300", "-seed=1", f"--artifacts={artifacts}", f"--targets=native,{TIGHT}"
    )
    assert run.returncode == 1, run.stderr[-2000:]
    sidecar = next(artifacts.glob("crash-*.json"))
    crash = tmp_path / "crash-high"
    _move_case(crash, 3.1)
    crash.with_name(crash.name + ".json").write_bytes(sidecar.read_bytes())
    from tests.support import fuzz as plain  # minimize takes no --no-progress
    from tests.support import sidecar_describes

    sidecar_describes(crash)  # another input's sidecar, made this file's

    run = plain("minimize", str(crash), "--targets=native,tests.plugins.faults:aborts")
    assert run.returncode == 1, (run.returncode, run.stderr[-2000:])
    assert f"{crash}: not minimized: it crashes the replaying process (killed by SIGABRT" in run.stdout
    assert "-minimize_crash=1 minimizes such an input" in run.stdout


def test_kill_minus_9_leaves_no_half_written_artifact(tmp_path: Path) -> None:
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen(
        [
            sys.executable,
            SCRIPT,
            str(corpus),
            "-max_total_time=60",
            "-seed=4",
            f"--artifacts={artifacts}",
            "--robot=kinova",
            "--targets=native,tests.plugins.faults:wrap_continuous",
            "--no-progress",
        ],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and len(list(artifacts.glob("crash-*"))) < 2:  # a file + sidecar
        time.sleep(0.2)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    crashes = [p for p in artifacts.glob("crash-*") if not p.name.endswith(".json")]
    assert crashes
    for crash in crashes:  # every crash file is whole and has its whole sidecar
        decode(crash.read_bytes())
        json.loads((artifacts / (crash.name + ".json")).read_text())
    # the next start removes leftovers of interrupted writes and runs on
    run = fuzz(
        str(corpus),
        "-runs=200",
        "-seed=5",
        f"--artifacts={artifacts}",
        "--robot=kinova",
        "--targets=native,tests.plugins.faults:wrap_continuous",
    )
    assert run.returncode in (0, 1), run.stderr[-2000:]  # 1 if it finds a signature not yet written
    assert not list(artifacts.glob(".tmp-*"))


def test_a_msg_path_that_cannot_matter_is_said_and_not_recorded(tmp_path: Path) -> None:
    """Every type an op reads is a definition the project ships, searched first, so a --msg-path
    folder is never read: said once, and not recorded (a relative one, recorded as typed, made
    crash files unusable from another working directory)."""
    folder = tmp_path / "msgs" / "std_msgs" / "msg"
    folder.mkdir(parents=True)
    (folder / "Float64MultiArray.msg").write_text("this is not a definition, and it is never read\n")
    corpus, artifacts = tmp_path / "corpus", tmp_path / "a"
    run = fuzz(
        str(corpus),
        "-runs=300",
        "-seed=1",
        f"--msg-path={tmp_path / 'msgs'}",
        "--msg-type=std_msgs/Float64MultiArray",
        f"--artifacts={artifacts}",
        "--tolerance=1e-17",  # rounding differences diverge: crash files are written
    )
    assert run.returncode == 1, run.stderr[-2000:]
    assert run.stderr.count("msgs: not read: std_msgs/Float64MultiArray and every type it uses") == 1
    manifest = json.loads((corpus / ".rrosfuzz" / "manifest.json").read_text())
    assert manifest["config"]["msg_path"] == []
    written = sidecars(artifacts)
    assert written and all(data["config"]["msg_path"] == [] for data in written)


def test_a_new_corpus_folder_is_checked_and_recorded_without_the_sidecar_reader(tmp_path: Path) -> None:
    """A campaign checks its corpus folders for a manifest before its first input; a new folder has
    none, and raising or catching ``SidecarError`` there loaded ``fuzzer.artifacts.sidecar``
    (0.45 ms of the full engine's start-up). A manifest that exists is still read through it."""
    from tests.support import python

    corpus = tmp_path / "corpus"
    program = (
        "import sys\n"
        "from pathlib import Path\n"
        "from fuzzer.artifacts import travel\n"
        "from fuzzer.execution.session import RunConfig\n"
        f"corpus = Path({str(corpus)!r})\n"
        "corpus.mkdir()\n"
        "travel.check_manifests([corpus], RunConfig())\n"
        "travel.record_corpus([corpus], RunConfig())\n"
        "assert (corpus / '.rrosfuzz' / 'manifest.json').is_file()\n"
        "assert 'fuzzer.artifacts.sidecar' not in sys.modules, 'loaded for a new corpus folder'\n"
        "travel.check_manifests([corpus], RunConfig())\n"
        "assert 'fuzzer.artifacts.sidecar' in sys.modules, 'a manifest read without its validator'\n"
    )
    done = python(program)
    assert done.returncode == 0, done.stderr[-2000:]


def test_fork_mode_reexecutes_the_script(tmp_path: Path) -> None:
    artifacts = tmp_path / "artifacts"
    run = fuzz(
        str(tmp_path / "corpus"),
        "-fork=2",
        "-max_total_time=20",
        "-seed=3",
        f"--artifacts={artifacts}",
        f"--targets=native,{TIGHT}",
    )
    assert run.returncode == (1 if sidecars(artifacts) else 0), run.stderr[-3000:]
    assert "-fork=2: fuzzing in separate process" in run.stderr
    assert "job: " in run.stderr  # workers ran


def _chain_urdf(joints: int) -> str:
    parts = ['<robot name="long">', '<link name="l0"/>']
    for i in range(joints):
        parts += [
            f'<link name="l{i + 1}"/>',
            f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
            '<origin xyz="0 0 0.01"/><axis xyz="0 0 1"/>'
            '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>',
        ]
    return "\n".join([*parts, "</robot>"])


def test_a_chain_hypothesis_cannot_draw_for_stops_everything_it_started(tmp_path: Path) -> None:
    # 1,300 joints: no seed message fits in a Hypothesis test case. It spent 42 s before its usage
    # error, the dry run's children ran on after it (about 15 s, evaluating inputs and writing to
    # the artifacts), and the corpus kept a manifest of a configuration that never ran
    robot = tmp_path / "chain.urdf"
    robot.write_text(_chain_urdf(1300))
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    with (tmp_path / "out").open("w") as out, (tmp_path / "err").open("w") as err:
        # to files, not pipes: the run returns when the campaign's process ends, not its children
        done = subprocess.run(
            [sys.executable, SCRIPT, str(corpus), "--robot", str(robot), "-runs=50", "-seed=1",
             f"--artifacts={artifacts}", "-timeout=60", "--no-progress"],
            cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)), stdout=out, stderr=err,
            timeout=120, check=False,
        )  # fmt: skip
    left = []
    for proc in Path("/proc").iterdir():
        try:
            if proc.name.isdigit() and str(corpus).encode() in (proc / "cmdline").read_bytes():
                left.append(proc.name)
        except OSError:
            continue
    stderr = (tmp_path / "err").read_text()
    assert done.returncode == 2, stderr[-2000:]
    assert "Hypothesis draws no seed message for a chain of 1300 joints" in stderr
    assert "Traceback" not in stderr
    assert not left, f"processes of the campaign left running: {left}"
    assert not (corpus / ".rrosfuzz").exists(), "a configuration that never ran was recorded"


def test_a_jobs_campaign_on_a_full_artifacts_folder_exits_74_saying_so(tmp_path: Path) -> None:
    """A -jobs supervisor learns only that a job ended non-zero: a full disk that ended both
    jobs with 74 ended the campaign with 1, "new divergences found; a job failed". It now sees
    the folder take no file and says so (a file size limit stands in for the full disk)."""
    import resource

    from tests.support import fuzz as fuzz_with

    def small_files() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (3072, 3072))

    run = fuzz_with(
        str(tmp_path / "corpus"),
        "-jobs=2",
        "-max_total_time=6",
        "-seed=1",
        f"--artifacts={tmp_path / 'artifacts'}",
        f"--targets=native,{TIGHT}",
        "--no-progress",
        "-handle_xfsz=0",
        preexec_fn=small_files,
        timeout=180,
    )
    assert run.returncode == 74, run.stderr[-3000:]
    assert "cannot be written (File too large): a job's divergences may be lost" in run.stderr
    assert "Traceback" not in run.stderr


def test_a_full_artifacts_folder_stops_the_campaign_and_loses_no_divergence(tmp_path: Path) -> None:
    # A full disk, made by a file size limit (RLIMIT_FSIZE: writes past 2 KB fail with EFBIG, as
    # ENOSPC would; a sidecar is larger, about 2.9 KB, so the first divergence's fails, before the
    # logs fill up; at 3 KB the stats lines of a move campaign's dry run, longer since its sweeps,
    # could fill stats.jsonl first). Before: Atheris' "Uncaught Python exception", exit 77
    # ("a target died"), an empty crash file from libFuzzer, and the divergence's input nowhere
    import resource

    from tests.support import fuzz as fuzz_with

    def small_files() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (2048, 2048))

    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    # no -handle_xfsz=0 given: the campaign passes it (libFuzzer's SIGXFSZ handler made the limit
    # a crash of its own: exit 77, no summary, the input unsaved)
    run = fuzz_with(
        str(corpus),
        "-runs=5000",
        "-seed=1",
        f"--artifacts={artifacts}",
        f"--targets=native,{TIGHT}",
        "--no-progress",
        preexec_fn=small_files,
    )
    assert run.returncode == 74, run.stderr[-3000:]
    assert "Traceback" not in run.stderr and "Uncaught Python exception" not in run.stderr
    assert "cannot write to the artifacts folder" in run.stderr
    assert "exit status 74 (the artifacts folder could not be written)" in run.stderr
    lines = run.stderr.splitlines()
    lost = [(line.split("signature ")[1].split()[0], lines[i + 1]) for i, line in enumerate(lines[:-1])
            if "could not be saved" in line]  # fmt: skip
    assert lost, run.stderr[-3000:]
    left = [p.name for p in artifacts.iterdir() if p.name.startswith(".tmp-")]
    assert not left and not [p for p in artifacts.glob("crash-*") if p.stat().st_size == 0]
    key, printed = lost[0]
    saved = tmp_path / "saved"
    saved.write_text(printed)  # the input printed is the divergence, whole
    again = fuzz(str(saved), f"--targets=native,{TIGHT}")
    assert again.returncode == 1, again.stdout + again.stderr
    assert f"diverges (no sidecar to compare with) (signature {key}:" in again.stdout


def _all_ended(processes: Callable[[], list[int]]) -> bool:
    """Whether the processes end within a minute (they do within a moment)."""
    for _ in range(600):
        if not processes():
            return True
        time.sleep(0.1)
    return False


def _sigint_as_in_a_terminal() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # a CI step's background job may ignore it


def _started(
    tmp_path: Path, *args: str, ready: Callable[[], bool]
) -> tuple[subprocess.Popen[bytes], Path, Callable[[], list[int]]]:
    """A campaign in a session of its own, once ``ready``; its stderr's file, and its processes
    (the ones whose command line names the corpus folder)."""
    corpus, err = tmp_path / "corpus", tmp_path / "err"
    with err.open("wb") as stream:
        process = subprocess.Popen(
            [sys.executable, SCRIPT, str(corpus), *args, "--no-progress"],
            cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)), stdout=stream, stderr=stream,
            start_new_session=True, preexec_fn=_sigint_as_in_a_terminal,
        )  # fmt: skip

    def processes() -> list[int]:
        found = []
        for proc in Path("/proc").iterdir():
            try:
                if proc.name.isdigit() and str(corpus).encode() in (proc / "cmdline").read_bytes():
                    found.append(int(proc.name))
            except OSError:
                continue
        return found

    for _ in range(1200):  # at most 2 minutes
        if ready() or process.poll() is not None:
            break
        time.sleep(0.1)
    return process, err, processes


@pytest.mark.parametrize(
    ("send", "status", "said"),
    [
        (lambda p: p.send_signal(signal.SIGTERM), 143, "exit status 143 (terminated (SIGTERM))"),
        (lambda p: os.killpg(p.pid, signal.SIGINT), 130, "exit status 130 (interrupted (Ctrl-C))"),
    ],
    ids=["sigterm", "ctrl-c"],
)
def test_a_signal_ends_a_campaign_with_its_summary(
    tmp_path: Path, send: Callable[[subprocess.Popen[bytes]], None], status: int, said: str
) -> None:
    # SIGTERM: libFuzzer's own handler ended it with _Exit(72), no summary, no last snapshot.
    # Ctrl-C (SIGINT to the whole process group, as a terminal sends it): exit 77 "a target
    # died" (a KeyboardInterrupt where Python ran next), or 130 under a summary saying 0
    def fuzzing() -> bool:
        err = tmp_path / "err"
        return err.exists() and b"INFO: seed corpus" in err.read_bytes()

    process, err, _ = _started(
        tmp_path, "-seed=1", "-max_total_time=60", f"--artifacts={tmp_path / 'a'}", ready=fuzzing
    )
    time.sleep(0.5)
    send(process)
    assert process.wait(timeout=60) == status
    text = err.read_text()
    assert "campaign summary" in text and said in text
    assert "Traceback" not in text and "Uncaught Python exception" not in text


def _snapshots(stats: Path) -> dict[Any, dict[str, Any]]:
    """Each process's last snapshot in a campaign's stats.jsonl, by pid (none yet: empty)."""
    last: dict[Any, dict[str, Any]] = {}
    for record in map(json.loads, stats.read_text().splitlines() if stats.exists() else []):
        last[record.get("pid")] = record
    return last


@pytest.mark.parametrize("flag", ["-jobs=2", "-fork=2"])
def test_workers_end_with_a_supervisor_killed_alone(tmp_path: Path, flag: str) -> None:
    # `kill PID` of a -jobs campaign (CI's timeout): its workers, each under a shell of its own,
    # fuzzed on with no end. Then the supervisor died in libFuzzer's handler: no summary, and its
    # workers' last counts lost; now it passes the SIGTERM on and ends with its summary, 143
    artifacts = tmp_path / "a"
    stats = artifacts / "stats.jsonl"

    def workers_fuzzing() -> bool:  # each worker snapshots its counters at its first input
        return len(_snapshots(stats)) >= 2

    process, err, processes = _started(
        tmp_path, "-seed=1", flag, "-max_total_time=120", f"--artifacts={artifacts}", ready=workers_fuzzing
    )
    try:
        if flag == "-jobs=2":  # a -fork job's command line names a folder of libFuzzer's, not ours
            assert len(processes()) > 1, "the workers never started"
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=60) == 143
        assert _all_ended(processes), "workers outlived their supervisor"
        text = err.read_text()
        assert "campaign summary" in text and "exit status 143 (terminated (SIGTERM))" in text, text[-2000:]
        last = _snapshots(stats).values()
        assert any(r.get("interrupted") for r in last), "no worker ended with its last snapshot"
    finally:
        for pid in processes():
            os.kill(pid, signal.SIGKILL)


@pytest.mark.parametrize("flag", ["-jobs=2", "-fork=2"])
def test_ctrl_c_ends_jobs_and_their_supervisor_with_130(tmp_path: Path, flag: str) -> None:
    # -jobs: each job's shell died of the SIGINT, and libFuzzer's supervisor, reading the
    # interrupted status from a Fuzzer it never made, segfaulted (139); a job interrupted in its
    # start-up died in libFuzzer's "deadly signal" handler (an empty crash file). -fork: 72.
    # A space in a -jobs path split the jobs' words (each job a usage error, exit 2)
    artifacts = tmp_path / ("a b" if flag == "-jobs=2" else "a")
    stats = artifacts / "stats.jsonl"

    def jobs_fuzzing() -> bool:  # each job snapshots its counters at its first input
        return len(_snapshots(stats)) >= (2 if flag == "-jobs=2" else 1)

    process, err, processes = _started(
        tmp_path, "-seed=1", flag, "-max_total_time=120", f"--artifacts={artifacts}", ready=jobs_fuzzing
    )
    try:
        assert jobs_fuzzing(), "the jobs never started"
        time.sleep(0.5)
        os.killpg(process.pid, signal.SIGINT)
        assert process.wait(timeout=60) == 130, err.read_text()[-3000:]
        said = err.read_text()
        assert "exit status 130 (interrupted (Ctrl-C))" in said, said[-3000:]
        assert "deadly signal" not in said and "Traceback" not in said
        assert not list(artifacts.glob("crash-*")), "the interrupt left a crash file"
        assert _all_ended(processes), "jobs outlived their supervisor"
    finally:
        for pid in processes():
            os.kill(pid, signal.SIGKILL)


def test_a_jobs_campaign_whose_job_failed_says_so(tmp_path: Path) -> None:
    # Atheris ends a -jobs supervisor with SystemExit(libFuzzer's status): the summary, made at
    # exit with no status, said nothing of it (or "exit status 0" when no job left a file). A job
    # that ended with no file to explain it (here a target calling exit(3)) leaves libFuzzer's 1
    artifacts = tmp_path / "a"
    run = fuzz(
        str(tmp_path / "corpus"), "-jobs=2", "-max_total_time=30", "-seed=1", f"--artifacts={artifacts}",
        "--no-progress", "--targets=native,tests.plugins.faults:exits", timeout=180,
    )  # fmt: skip
    assert run.returncode == 1, run.stderr[-3000:]
    said = "exit status 1 (a job failed: its fuzz-N.log in the artifacts folder says why)"
    assert said in run.stderr, run.stderr[-3000:]
    assert "exited with exit code 3" in run.stderr


@pytest.mark.parametrize(
    ("target", "flag", "code", "said", "left"),
    [
        ("aborts", "-seed=1", 77, "a target died, or --stop-on-divergence stopped at a divergence", "crash-"),
        ("python", "-rss_limit_mb=1", 71, "out of memory", "oom-"),
    ],
)
def test_a_jobs_campaign_whose_target_died_exits_as_one_process_would(
    tmp_path: Path, target: str, flag: str, code: int, said: str, left: str
) -> None:
    # libFuzzer's -jobs supervisor exits 1 for any failed job, the status of "new divergences":
    # a job whose target died (77 alone) or ran out of memory (71) read as one that found some
    artifacts = tmp_path / "a"
    run = fuzz(
        str(tmp_path / "corpus"), "-jobs=2", "-max_total_time=30", flag, f"--artifacts={artifacts}",
        "--no-progress", f"--targets=native,{'tests.plugins.faults:' if target != 'python' else ''}{target}",
        timeout=180,
    )  # fmt: skip
    assert run.returncode == code, run.stderr[-3000:]
    assert f"exit status {code} ({said}, in a job: its fuzz-N.log" in run.stderr, run.stderr[-3000:]
    assert [p for p in artifacts.glob(f"{left}*") if not p.name.endswith(".json")], f"no {left} file"


def test_stop_on_divergence_keeps_the_pair_and_counts_it(tmp_path: Path) -> None:
    # libFuzzer alone wrote the crash file: the summary, made before, counted no new file, and an
    # -exact_artifact_path took the input away from its sidecar (a folder there: the input lost)
    for exact in (None, tmp_path / "exact"):
        artifacts = tmp_path / f"a-{exact is not None}"
        run = fuzz(
            str(tmp_path / f"c-{exact is not None}"), "-seed=1", "-runs=300", "--stop-on-divergence",
            *([f"-exact_artifact_path={exact}"] if exact else []), f"--artifacts={artifacts}",
            "--targets=native,tests.plugins.faults:tight_tolerance", "--no-progress",
        )  # fmt: skip
        assert run.returncode == 77, run.stderr[-3000:]
        crashes = [p for p in artifacts.glob("crash-*") if not p.name.endswith(".json")]
        assert len(crashes) == 1 and crashes[0].with_name(crashes[0].name + ".json").is_file()
        assert "crash files (1 new this run)" in run.stderr, run.stderr[-3000:]
        # the summary ends with the status as every other one does (it had no such line)
        assert "exit status 77 (a target died, or --stop-on-divergence stopped" in run.stderr
        if exact is not None:
            assert exact.read_bytes() == crashes[0].read_bytes()


def test_a_fork_campaign_that_ignored_its_crashes_still_says_so(tmp_path: Path) -> None:
    # -fork=1 -ignore_crashes=1: 12 crash files of a dying target, "exit status 0 (no new
    # divergence)"; fork mode's ignored timeouts were already 70
    artifacts = tmp_path / "a"
    run = fuzz(
        str(tmp_path / "corpus"), "-fork=1", "-ignore_crashes=1", "-max_total_time=8", "-seed=3",
        f"--artifacts={artifacts}", "--targets=native,tests.plugins.faults:aborts", "--no-progress",
        timeout=180,
    )  # fmt: skip
    assert run.returncode == 77, run.stderr[-3000:]
    assert "exit status 77 (a target died" in run.stderr
    assert [p for p in artifacts.glob("crash-*") if not p.name.endswith(".json")]


def test_a_corpus_folder_removed_during_the_campaign_is_said(tmp_path: Path) -> None:
    """libFuzzer's writes into a corpus folder that is gone fail without a word: the campaign
    ended with a normal summary and exit 0, its new inputs lost (the special-files probe)."""
    from tests.support import ROOT, SCRIPT

    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    process = subprocess.Popen(
        [sys.executable, SCRIPT, str(corpus), "-max_total_time=6", "-seed=3", f"--artifacts={artifacts}"],
        env=dict(os.environ, PYTHONPATH=str(ROOT)),
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
    )
    assert process.stderr is not None
    lines = []
    for line in process.stderr:  # libFuzzer has read the corpus once it says "seed corpus"
        lines.append(line)
        if "seed corpus:" in line:
            shutil.rmtree(corpus)
            break
    text = "".join(lines) + process.stderr.read()
    process.wait(timeout=120)
    assert not corpus.exists() and "Traceback" not in text
    assert f"corpus folder {corpus} is gone" in text, (process.returncode, text[-2000:])
    assert process.returncode == 74, text[-2000:]
    assert "exit status 74 (a corpus folder is gone" in text
