"""fuzz_diff.py view: RViz under Xvfb draws both targets' arms (a screenshot is checked)."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fuzzer.input.testcase import TestCase
from tests.support import skip_or_fail
from tests.test_ros_tf import _processes_with

ROOT = Path(__file__).resolve().parents[1]


def _crash(folder: Path, q0: list[float], q1: list[float]) -> Path:
    message = {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "name": [], "position": q0, "velocity": [], "effort": [],
    }  # fmt: skip
    crash = folder / "crash-00112233445566778899aabbccddeeff00112233"
    crash.write_bytes(TestCase("sensor_msgs/JointState", message).encode())
    outcomes = [
        {"target": "native", "status": "ok", "values": {"joint_values": q0}},
        {"target": "python", "status": "ok", "values": {"joint_values": q1}},
    ]
    sidecar = {
        "config": {"op": "move", "robot": "probot_anno"},
        "signature": {"key": "k"},
        "outcomes": outcomes,
    }
    crash.with_name(crash.name + ".json").write_text(json.dumps(sidecar))
    return crash


def test_coloured_pixels_sees_arms_not_grey_or_blank() -> None:
    from fuzzer.ros.view import coloured_pixels

    blank = np.full((50, 80, 3), 40, dtype=np.uint8)
    assert coloured_pixels(blank) == (0, 0)
    grey = blank.copy()
    grey[10:20, 10:20] = (120, 120, 120)
    assert coloured_pixels(grey) == (0, 0)
    arms = blank.copy()
    arms[5:15, 5:25] = (200, 30, 30)  # a shaded red
    arms[20:30, 5:20] = (40, 80, 220)  # a shaded blue
    assert coloured_pixels(arms) == (200, 150)


def test_view_draws_both_arms_under_xvfb(tmp_path: Path) -> None:
    from fuzzer.ros import env

    gone = env.missing() + [tool for tool in ("rviz", "Xvfb", "import") if shutil.which(tool) is None]
    if gone:
        skip_or_fail(f"ROS 1, RViz or Xvfb missing ({', '.join(gone)}): run scripts/ros-ensure.sh --viz")
    crash = _crash(tmp_path, [0.5, 0.3, -0.4, 0.0, 0.6, 0.0], [-1.2, 0.9, 0.4, 0.0, -0.6, 0.0])
    shot = tmp_path / "view.ppm"
    environment = {k: v for k, v in os.environ.items() if not k.startswith("ROS_") and k != "DISPLAY"}
    logs = tmp_path / "ros-logs"  # this test's own (its processes are found by it), not a /tmp folder
    logs.mkdir()
    environment["ROS_LOG_DIR"] = str(logs)
    run = subprocess.run(
        [sys.executable, str(ROOT / "fuzz_diff.py"), "view", str(crash), "--screenshot", str(shot)],
        capture_output=True, text=True, timeout=180, env=environment, cwd=tmp_path, check=False,
    )  # fmt: skip
    assert run.returncode == 0, run.stdout + run.stderr[-3000:]
    counts = re.search(r"(\d+) red and (\d+) blue pixels", run.stdout)
    assert counts is not None and min(int(counts[1]), int(counts[2])) >= 200, run.stdout
    assert shot.read_bytes().startswith(b"P6")
    log_dir = re.search(r"logs in (\S+)\)", run.stderr)
    assert log_dir is not None and log_dir[1] == str(logs) and (logs / "rviz.log").is_file()
    assert _processes_with(log_dir[1]) == []  # Xvfb, RViz, master, nodes: gone


def test_view_refuses_a_missing_crash_file(tmp_path: Path) -> None:
    run = subprocess.run(
        [sys.executable, str(ROOT / "fuzz_diff.py"), "view", str(tmp_path / "crash-nope")],
        capture_output=True, text=True, timeout=60, cwd=tmp_path, check=False,
    )  # fmt: skip
    assert run.returncode == 2 and "no such file" in run.stderr


def test_a_sidecar_whose_robot_no_longer_loads_is_named(tmp_path: Path) -> None:
    from fuzzer.execution.session import ConfigError
    from fuzzer.ros.view import load

    crash = tmp_path / "crash-0123456789abcdef0123456789abcdef01234567"
    crash.write_bytes(TestCase("std_msgs/Float64MultiArray", {"data": [0.0] * 6}).encode())
    config = {"op": "move", "robot": "probot_anno", "tip_link": "nope"}
    sidecar = {"config": config, "signature": {"key": "k"}}
    crash.with_name(crash.name + ".json").write_text(json.dumps(sidecar))
    with pytest.raises(ConfigError, match="its sidecar's robot probot_anno does not load: UnknownNameError"):
        load(crash)  # UnknownNameError from the view's loader until 2026-12-05


def test_a_sidecar_robot_outside_the_folders_is_not_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from fuzzer.execution.session import ConfigError
    from fuzzer.ros.view import load

    monkeypatch.chdir(tmp_path)
    crash = tmp_path / "crash-0123456789abcdef0123456789abcdef01234567"
    crash.write_bytes(TestCase("std_msgs/Float64MultiArray", {"data": [0.0] * 6}).encode())
    outside = ROOT / "README.md"
    sidecar = {"config": {"op": "move", "robot": str(outside)}, "signature": {"key": "k"}}
    crash.with_name(crash.name + ".json").write_text(json.dumps(sidecar))
    with pytest.raises(ConfigError, match=r"README\.md' leads outside"):
        load(crash)
    with pytest.raises(ConfigError, match=r"README\.md does not load: URDFError"):
        load(crash, trust=True)  # read, as the user vouched for the file


def test_a_relative_robot_path_from_another_folder_is_given_again_with_robot(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A campaign run with ``--robot my.urdf`` records the path as typed; from any other working
    folder it does not resolve. ``view``/``export-bag --robot`` give the file again (checked by
    its SHA-256); they had only ``--trust-sidecar``, which cannot make the path resolve."""
    import hashlib

    from fuzzer.execution.session import ConfigError
    from fuzzer.ros.view import load
    from robot_api import robots

    campaign, elsewhere = tmp_path / "campaign", tmp_path / "elsewhere"
    (campaign / "art").mkdir(parents=True)
    elsewhere.mkdir()
    urdf = campaign / "my.urdf"
    shutil.copyfile(robots.resolve("probot_anno"), urdf)
    crash = _crash(campaign / "art", [0.1] * 6, [0.2] * 6)
    sidecar = json.loads(crash.with_name(crash.name + ".json").read_text())
    sidecar["config"]["robot"] = "my.urdf"
    sidecar["robot_sha256"] = hashlib.sha256(urdf.read_bytes()).hexdigest()
    crash.with_name(crash.name + ".json").write_text(json.dumps(sidecar))
    monkeypatch.chdir(elsewhere)
    for trust in (False, True):
        with pytest.raises(ConfigError, match=r"'my\.urdf' is neither a shipped robot nor an existing file"):
            load(crash, trust)
    _, _, model, _ = load(crash, robot=str(urdf))
    assert model.dof == 6
    with pytest.raises(ConfigError, match=r"--robot ur5: not the robot file .* SHA-256 .* differs"):
        load(crash, robot="ur5")


def test_a_robot_digest_that_is_no_sha256_is_refused_and_a_missing_one_is_said(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``robot_sha256: 12345`` turned the ``--robot`` check off; an uppercase copy of the right
    digest was refused as "differs"."""
    import hashlib

    from fuzzer.artifacts.trust import check_given_robot
    from fuzzer.execution.session import ConfigError
    from robot_api import robots

    source = tmp_path / "crash-x.json"
    with pytest.raises(ConfigError, match="robot_sha256 is not a SHA-256"):
        check_given_robot("probot_anno", "12345", source)
    with pytest.raises(ConfigError, match="robot_sha256 is not a SHA-256"):
        check_given_robot("probot_anno", 12345, source)
    digest = hashlib.sha256(robots.resolve("probot_anno").read_bytes()).hexdigest()
    check_given_robot("probot_anno", digest.upper(), source)
    check_given_robot("probot_anno", None, source)
    assert "records no robot_sha256, so --robot probot_anno is not checked" in capsys.readouterr().err
