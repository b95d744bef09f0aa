"""The bug zoo and the benchmark harness (a tiny run; the real one is `make bench`)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import native
from benchmarks import bench_zoo
from benchmarks.zoo import BY_NAME, CONTROL, ZOO
from fuzzer.execution.targets import load_target


def test_the_zoo_has_at_least_twelve_documented_bugs() -> None:
    assert len(ZOO) >= 12 and len({b.name for b in ZOO}) == len(ZOO)
    for bug in ZOO:
        assert bug.description and bug.source and bug.source != "SOURCE"
        impl = load_target(bug.target)  # every variant loads as a target
        impl.RobotModel(bench_zoo.ROOT / "robot_api" / "robots" / "probot_anno.urdf")


@pytest.mark.parametrize("name", ["axis_not_normalized", "missing_axis_z", "missing_lower_unlimited"])
def test_urdf_bugs_change_the_zoo_arm(name: str) -> None:
    """Each URDF-default bug really differs from native on the zoo arm (at some configuration)."""
    bug = BY_NAME[name]
    variant = load_target(bug.target).RobotModel(bug.robot)
    reference = native.RobotModel(bug.robot)
    if name == "missing_lower_unlimited":
        assert variant.joint_limits[1].lower < 0.0 == reference.joint_limits[1].lower
    else:
        q = [0.3, 0.4, 0.5, 0.6, 0.7, 0.05]
        assert variant.forward_kinematics(q).position != reference.forward_kinematics(q).position


def test_time_comparison_margins() -> None:
    inf = float("inf")
    assert bench_zoo.compare_times(1.0, inf) == "faster"
    assert bench_zoo.compare_times(inf, inf) == "tie"
    assert bench_zoo.compare_times(1.6, 1.7) == "tie"  # within 0.25 s
    assert bench_zoo.compare_times(2.0, 6.0) == "faster"
    assert bench_zoo.compare_times(9.0, 3.0) == "slower"


def test_a_small_benchmark_run(tmp_path: Path) -> None:
    out = tmp_path / "zoo.json"
    result = bench_zoo.main(["--bugs", "off_by_tolerance", CONTROL.name, "--engines", "full", "uniform",
                             "--seeds", "1", "--budget", "6", "--out", str(out)])
    assert json.loads(out.read_text())["runs"] and out.with_suffix(".png").is_file()
    cells = result["cells"]
    assert cells["off_by_tolerance/full"]["detected"] == 1
    assert cells["control/full"]["detected"] == 0 and cells["control/uniform"]["detected"] == 0
    assert cells["off_by_tolerance/full"]["median_exec_per_s"] > 0
    assert "| off_by_tolerance | move |" in bench_zoo.markdown(result)
