"""The regression suite: every promoted crash file still does what its sidecar expects.

``diverge``: a known divergence reproduces with the same signature.
``agree``: a fixed divergence stays fixed. Add files with
``python fuzz_diff.py promote CRASH [--fixed] --note "..."``.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from fuzzer.artifacts.store import load_sidecar
from fuzzer.execution.session import RunConfig
from fuzzer.triage.regressions import PromoteError, promote, suite_files
from fuzzer.triage.replay import ROBOT_CHANGED, Result, replay_file

FILES = suite_files()
ROOT = Path(__file__).resolve().parents[1]  # sidecars name crafted URDFs relative to the repository


def test_the_suite_is_not_empty() -> None:
    assert FILES, "tests/regressions/ holds no promoted crash files"
    expectations = {load_sidecar(p)["regression"]["expect"] for p in FILES}  # type: ignore[index]
    assert expectations == {"agree", "diverge"}


@pytest.mark.parametrize("path", FILES, ids=[p.name[:24] for p in FILES])
def test_regression(path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    sidecar = load_sidecar(path)
    assert sidecar is not None
    expect = sidecar["regression"]["expect"]
    result = replay_file(path, RunConfig(), {}, trust=True)  # the project's own suite: trusted
    if expect == "agree":
        assert result.result is Result.AGREES, f"{path.name} diverges again: {result.detail}"
    else:
        assert result.result is Result.SAME, f"{path.name}: {result.result} {result.detail}"
        assert result.evaluation is not None and result.evaluation.signature is not None
        assert result.evaluation.signature.key == sidecar["regression"]["signature"]
        # the sidecar describes this file (the minimizer of 2026-11-22 kept the original
        # input's call, outcomes and sha1 in eight minimized files; FINDINGS quoted them)
        assert sidecar["sha1"] == hashlib.sha1(path.read_bytes()).hexdigest()
        assert sidecar["difference"] == pytest.approx(result.evaluation.difference, rel=1e-9, abs=1e-15)


def test_promote_refuses_contradicting_claims(tmp_path: Path) -> None:
    fixed = next(p for p in FILES if load_sidecar(p)["regression"]["expect"] == "agree")  # type: ignore[index]
    with pytest.raises(PromoteError, match="promote it with --fixed"):
        promote(fixed, fixed=False, suite=tmp_path, trust=True)
    known = next(p for p in FILES if load_sidecar(p)["regression"]["expect"] == "diverge")  # type: ignore[index]
    with pytest.raises(PromoteError, match="not fixed yet"):
        promote(known, fixed=True, suite=tmp_path, trust=True)
    done = promote(known, fixed=False, note="copy", suite=tmp_path, trust=True)
    assert done.expect == "diverge" and (tmp_path / known.name).is_file()
    assert load_sidecar(tmp_path / known.name)["regression"]["note"] == "copy"  # type: ignore[index]


def test_promote_again_in_place_and_a_suite_that_is_a_file_are_named(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(ROOT)
    known = next(p for p in FILES if load_sidecar(p)["regression"]["expect"] == "diverge")  # type: ignore[index]
    first = promote(known, fixed=False, note="first", suite=tmp_path, trust=True)
    data = first.path.read_bytes()
    # promoting the suite's own copy again (a new note; --fixed once it is fixed) was SameFileError
    again = promote(first.path, fixed=False, note="again", suite=tmp_path, trust=True)
    assert again.path == first.path and first.path.read_bytes() == data
    assert load_sidecar(first.path)["regression"]["note"] == "again"  # type: ignore[index]
    a_file = tmp_path / "a-file"
    a_file.write_text("not a folder")
    for suite in (a_file, a_file / "sub"):
        with pytest.raises(PromoteError, match="cannot hold the crash file"):
            promote(known, fixed=False, suite=suite, trust=True)


@pytest.mark.parametrize("failure", ["EROFS", "ENOSPC", "EACCES"])
def test_promote_into_a_suite_that_takes_no_file_exits_74(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, failure: str
) -> None:
    """A read-only, full or foreign suite folder is the exit table's 74 for every file, as every
    folder that takes no file is; it was each file's "not promoted", exit 1."""
    import errno
    import os

    from fuzzer.input.paths import FolderUnwritable
    from fuzzer.triage import regressions

    monkeypatch.chdir(ROOT)
    known = next(p for p in FILES if load_sidecar(p)["regression"]["expect"] == "diverge")  # type: ignore[index]

    def refuse(path: Path, data: bytes) -> None:
        code = getattr(errno, failure)
        raise OSError(code, os.strerror(code), str(path))

    monkeypatch.setattr(regressions, "atomic_write", refuse)
    with pytest.raises(FolderUnwritable, match=f"--suite {tmp_path}: cannot hold the crash file"):
        promote(known, fixed=False, suite=tmp_path, trust=True)


def test_promote_leaves_no_crash_file_without_its_sidecar(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A suite with room for the crash file but not its sidecar kept the file alone (its test
    then failed for want of a sidecar)."""
    import errno
    import os

    from fuzzer.input.paths import FolderUnwritable
    from fuzzer.triage import regressions

    monkeypatch.chdir(ROOT)
    known = next(p for p in FILES if load_sidecar(p)["regression"]["expect"] == "diverge")  # type: ignore[index]
    write = regressions.atomic_write

    def full_for_sidecars(path: Path, data: bytes) -> None:
        if path.name.endswith(".json"):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        write(path, data)

    monkeypatch.setattr(regressions, "atomic_write", full_for_sidecars)
    with pytest.raises(FolderUnwritable, match="cannot hold the crash file and its sidecar"):
        promote(known, fixed=False, suite=tmp_path, trust=True)
    assert list(tmp_path.iterdir()) == []


def test_a_replay_on_another_robot_file_says_so(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The sidecar's ``robot_sha256`` against today's file: a robot edited since the campaign
    made "now agrees" read as a fix, without a word (the URDF probe)."""
    import json
    import shutil

    monkeypatch.chdir(ROOT)
    known = next(p for p in FILES if load_sidecar(p)["regression"]["expect"] == "diverge")  # type: ignore[index]
    same = replay_file(known, RunConfig(), {}, trust=True)
    assert ROBOT_CHANGED not in same.detail
    copy = tmp_path / known.name
    shutil.copyfile(known, copy)
    sidecar = load_sidecar(known)
    assert sidecar is not None and sidecar["robot_sha256"]
    sidecar["robot_sha256"] = "0" * 64
    (tmp_path / f"{known.name}.json").write_text(json.dumps(sidecar))
    other = replay_file(copy, RunConfig(), {}, trust=True)
    assert other.result is same.result and ROBOT_CHANGED in other.detail


def test_promote_keeps_a_robot_file_the_suite_can_replay_elsewhere(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A crash file names its robot file relative to the campaign's working folder, which the
    suite is not replayed from: promoted as it was, it could not be replayed (the docs probe)."""
    import json
    import shutil

    from fuzzer.triage.regressions import SUITE, _suite_name

    known = next(p for p in FILES if p.name.startswith("minimized-481e74c1"))  # ikpy, scaled_axes.urdf
    campaign = tmp_path / "campaign"
    (campaign / "robots").mkdir(parents=True)
    arm = campaign / "robots/arm.urdf"
    shutil.copyfile(ROOT / "tests/regressions/urdfs/scaled_axes.urdf", arm)
    sidecar = load_sidecar(known)
    assert sidecar is not None
    del sidecar["regression"]
    sidecar["config"]["robot"] = "robots/arm.urdf"
    crash = campaign / known.name
    shutil.copyfile(known, crash)
    (campaign / f"{known.name}.json").write_text(json.dumps(sidecar))
    suite = tmp_path / "suite"
    monkeypatch.chdir(campaign)
    done = promote(crash, fixed=False, suite=suite, trust=True)
    kept = list((suite / "urdfs").iterdir())
    assert len(kept) == 1 and kept[0].read_bytes() == (campaign / "robots/arm.urdf").read_bytes()
    promoted = load_sidecar(done.path)
    assert promoted is not None and promoted["config"]["robot"] == str(kept[0].resolve())
    assert promoted["regression"]["robot_from"] == "robots/arm.urdf"
    again = promote(done.path, fixed=False, note="again", suite=suite, trust=True)  # in place: no 2nd copy
    assert list((suite / "urdfs").iterdir()) == kept and again.path == done.path
    monkeypatch.chdir(ROOT)  # replayed from elsewhere, as the suite is
    replayed = replay_file(done.path, RunConfig(), {}, trust=True)
    assert replayed.result is Result.SAME and ROBOT_CHANGED not in replayed.detail
    # the default suite names its copies from the repository's root, as the shipped ones are
    assert _suite_name(SUITE / "urdfs" / "x.urdf", SUITE) == "tests/regressions/urdfs/x.urdf"
    # promoted from another folder: the relative path leads nowhere, and --robot names the file
    with pytest.raises(PromoteError, match="promote, export-bag, view and report take --robot"):
        promote(crash, fixed=False, suite=tmp_path / "elsewhere", trust=True)
    elsewhere = promote(crash, fixed=False, suite=tmp_path / "elsewhere", trust=True, robot=str(arm))
    assert load_sidecar(elsewhere.path)["regression"]["robot_from"] == str(arm)  # type: ignore[index]
    with pytest.raises(PromoteError, match="not the campaign's"):  # --robot must be the campaign's file
        promote(
            crash,
            fixed=False,
            suite=tmp_path / "other",
            trust=True,
            robot=str(ROOT / "tests/regressions/urdfs/tilted.urdf"),
        )
    # a robot file edited since the campaign is not kept as if it were the campaign's
    (campaign / "robots/arm.urdf").write_text((campaign / "robots/arm.urdf").read_text() + "\n")
    monkeypatch.chdir(campaign)
    with pytest.raises(PromoteError, match="not the campaign's"):
        promote(crash, fixed=False, suite=tmp_path / "other", trust=True)


def test_promote_of_a_file_that_diverges_differently_points_nowhere_else(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Without --fixed it said "promote it with --fixed", with it "promote it without" (the
    triage probe)."""
    import json
    import shutil

    monkeypatch.chdir(ROOT)
    known = next(p for p in FILES if load_sidecar(p)["regression"]["expect"] == "diverge")  # type: ignore[index]
    copy = tmp_path / known.name
    shutil.copyfile(known, copy)
    sidecar = load_sidecar(known)
    assert sidecar is not None
    del sidecar["regression"]
    sidecar["signature"]["key"] = "0" * 40
    (tmp_path / f"{known.name}.json").write_text(json.dumps(sidecar))
    for fixed in (False, True):
        with pytest.raises(PromoteError, match="diverges differently") as refused:
            promote(copy, fixed=fixed, suite=tmp_path / "suite", trust=True)
        assert "--fixed" not in str(refused.value) and "the file's 000000000000" in str(refused.value)


def test_an_unreadable_crash_file_is_an_error_not_skipped(monkeypatch: pytest.MonkeyPatch) -> None:
    """It read "skipped (not a test case: Permission denied)" with exit 0, which CI takes for a
    pass; promote then sent --fixed and its absence at each other (the special-files probe)."""
    from fuzzer.input.paths import PathError
    from fuzzer.triage import replay

    def unreadable(path: Path) -> None:
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(replay, "read_case", unreadable)
    known = FILES[0]
    with pytest.raises(PathError, match="cannot be read: Permission denied"):
        replay_file(known, RunConfig(), {}, trust=True)
    with pytest.raises(PromoteError, match="cannot be read"):
        promote(known, fixed=False, suite=ROOT / "nowhere", trust=True)


def test_a_replay_under_settings_other_than_the_campaign_s_names_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A verdict of "now agrees" under other targets, another tolerance, or in process for a file found over
    ROS read as a fix; the verdict now names each setting that is not the campaign's."""
    import json
    import shutil

    from fuzzer.execution.tolerance import Tolerance

    monkeypatch.chdir(ROOT)
    fixed = next(p for p in FILES if load_sidecar(p)["regression"]["expect"] == "agree")  # type: ignore[index]
    same = replay_file(fixed, RunConfig(), {}, trust=True)
    assert same.result is Result.AGREES and "replayed with" not in same.detail
    other = replay_file(fixed, RunConfig(), {"targets": ("native", "native")}, trust=True)
    assert "replayed with targets native,native (the campaign's: native,python)" in other.detail
    looser = replay_file(fixed, RunConfig(), {"tolerance": Tolerance(1e-3, 1e-3)}, trust=True)
    assert "tolerance 0.001 m / 0.001 rad (the campaign's: 1e-06 m / 1e-06 rad)" in looser.detail
    tip = replay_file(fixed, RunConfig(), {"tip_link": "link_4"}, trust=True)
    assert "tip link link_4 (the campaign's: the default)" in tip.detail  # another chain
    copy = tmp_path / fixed.name
    shutil.copyfile(fixed, copy)
    sidecar = load_sidecar(fixed)
    assert sidecar is not None
    sidecar["config"]["transport"] = "ros"
    (tmp_path / f"{fixed.name}.json").write_text(json.dumps(sidecar))
    in_process = replay_file(copy, RunConfig(), {}, trust=True)
    assert "replayed with transport inprocess (the campaign's: ros)" in in_process.detail
