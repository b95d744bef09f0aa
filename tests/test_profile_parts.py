"""benchmarks.profile: a py-spy raw profile tabulated by part of the engine."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from benchmarks import profile
from benchmarks.profile import REST, SWEEPS, ProfileError, markdown, part_of_stack, tabulate

LIBFUZZER = "<module> (fuzz_diff.py:20)"
TESTONE = "test_one_input (fuzzer/harness.py:120)"


def stack(*frames: str) -> list[str]:
    return [LIBFUZZER, TESTONE, *frames]


def test_a_sample_counts_in_the_first_part_from_its_leaf() -> None:
    twin = "inverse_kinematics (python_impl/kinematics.py:88)"
    oracle = "evaluate (fuzzer/execution/evaluate.py:300)"
    assert part_of_stack(stack(oracle, twin)) == "twin target (python_impl)"
    assert part_of_stack(stack(twin, oracle)) == "evaluation and oracle"
    # numpy and standard library frames count for the repository code that called them
    assert (
        part_of_stack(stack(oracle, twin, "solve (numpy/linalg/_linalg.py:410)"))
        == "twin target (python_impl)"
    )
    assert part_of_stack(stack(oracle, "deepcopy (copy.py:128)")) == "evaluation and oracle"
    # ... but the json module is the encoding's, whoever called it
    mutate = "mutate (fuzzer/mutation/registry.py:90)"
    assert part_of_stack(stack(mutate, "encode (json/encoder.py:200)")) == "JSON encode/decode"
    assert part_of_stack(stack(mutate)) == "mutator, crossover, bandits"
    assert part_of_stack(stack("watch (fuzzer/selection/compared.py:150)")) == "float-comparison tracing"
    assert part_of_stack(stack("observe (fuzzer/selection/guidance.py:60)")) == "feature bookkeeping"
    assert part_of_stack(stack("pull (fuzzer/selection/bandit.py:40)")) == "mutator, crossover, bandits"
    assert part_of_stack(stack("check (fuzzer/scenario/oracle_ik.py:40)")) == "evaluation and oracle"
    assert part_of_stack(stack("forward_kinematics (native/__init__.py:30)")) == "native target"
    # absolute paths (py-spy --full-filenames) read the same
    assert part_of_stack(stack("fk (/work/x/python_impl/kinematics.py:9)")) == "twin target (python_impl)"


def test_the_sweeps_and_the_rest() -> None:
    sweep = "run_sweep (fuzzer/harness.py:156)"
    assert part_of_stack(stack(sweep, "fk_batch (python_impl/kinematics.py:50)")) == SWEEPS
    assert part_of_stack(stack()) == REST  # harness bookkeeping: no part
    assert part_of_stack(["<module> (<frozen importlib._bootstrap>:1)", "_call (atheris/x.py:3)"]) == REST
    assert part_of_stack(["not a frame", "neither"]) == REST
    # a repository file whose name merely contains a part's fragment is not that part
    assert part_of_stack(stack("f (fuzzer/nativeish.py:1)", "g (myjson/x.py:2)")) == REST


def test_tabulate_and_markdown() -> None:
    lines = [
        ";".join(stack("fk (python_impl/kinematics.py:9)")) + " 30\n",
        ";".join(stack("evaluate (fuzzer/execution/evaluate.py:3)")) + " 10\n",
        "\n",
        ";".join(stack()) + " 60\n",
    ]
    counts = tabulate(lines)
    assert counts == {"twin target (python_impl)": 30, "evaluation and oracle": 10, REST: 60}
    table = markdown(counts, "fk").splitlines()
    assert table[0] == "| part (% of 100 samples) | fk |"
    assert table[2:] == [
        "| twin target (python_impl) | 30.0 |",
        "| evaluation and oracle | 10.0 |",
        f"| {REST} | 60.0 |",
    ]


def test_a_sample_with_no_python_frame_counts_in_the_rest() -> None:
    # py-spy writes ' 1' for a sample that caught the process with no Python frame on it
    assert tabulate([" 2\n", ";".join(stack()) + " 3\n"]) == {REST: 5}
    with pytest.raises(ProfileError, match="line 1"):
        tabulate(["7"])


def test_a_broken_profile_is_named_not_a_traceback(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(ProfileError, match="line 2"):
        tabulate([LIBFUZZER + " 3", "no count here"])
    with pytest.raises(ProfileError, match="no samples"):
        markdown(tabulate([]), "x")
    bad = tmp_path / "bad.txt"
    bad.write_bytes(b"\xff\xfe garbage")
    with pytest.raises(SystemExit, match=r"bad\.txt: line 1"):
        profile.main(["--from", str(bad)])
    with pytest.raises(SystemExit, match="cannot read"):
        profile.main(["--from", str(tmp_path / "missing.txt")])
    good = tmp_path / "good.txt"
    good.write_text(";".join(stack("fk (python_impl/kinematics.py:9)")) + " 4\n")
    profile.main(["--from", str(good)])
    assert "| twin target (python_impl) | 100.0 |" in capsys.readouterr().out


def test_a_failed_recording_is_an_error_not_an_old_profile(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "fk.txt"
    out.write_text(";".join(stack()) + " 9\n")  # a profile of an earlier run
    monkeypatch.setattr(profile, "py_spy", lambda: shutil.which("false") or "/bin/false")
    with pytest.raises(SystemExit, match="py-spy wrote no profile"):
        profile.record("fk", 1.0, 1, 200, out)
    assert not out.exists()


def test_a_folder_as_out_gets_the_default_name_inside_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    recorded: list[Path] = []

    def fake_record(op: str, seconds: float, seed: int, rate: int, out: Path) -> None:
        recorded.append(out)
        out.write_text(";".join(stack()) + " 3\n")

    monkeypatch.setattr(profile, "record", fake_record)
    profile.main(["--op", "move", "--seed", "4", "--seconds", "1", "--out", str(tmp_path)])
    assert recorded == [tmp_path / "profile-move-seed4.txt"]
    assert "| part (% of 3 samples) |" in capsys.readouterr().out


@pytest.mark.slow
@pytest.mark.skipif(profile.find_py_spy() is None, reason="py-spy not installed (make setup installs it)")
def test_a_real_campaign_profile_has_the_targets_and_the_engine(tmp_path: Path) -> None:
    out = tmp_path / "fk.txt"
    profile.record("fk", 3.0, 1, 200, out)
    with out.open() as lines:
        counts = tabulate(lines)
    assert counts["twin target (python_impl)"] > 0 and counts[SWEEPS] > 0
    assert counts["mutator, crossover, bandits"] > 0 and counts["evaluation and oracle"] > 0
