"""Batched differential FK sweeps (issue 11, fuzzer/generation/sweep.py), alone and in the harness."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import native
import python_impl
from benchmarks.zoo import deep
from fuzzer.execution.tolerance import Tolerance
from fuzzer.generation.sweep import CONFIRM, NOISE, ROWS, SCALES, Sweep, differences
from fuzzer.harness import Harness
from fuzzer.input.testcase import decode
from robot_api import robots
from tests.test_harness import make_harness

ANNO = robots.resolve("probot_anno")


def _limits() -> tuple[list[float], list[float]]:
    limits = native.RobotModel(ANNO).joint_limits
    return [lim.lower for lim in limits], [lim.upper for lim in limits]


def _rotation(axis: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    i, j = [k for k in range(3) if k != axis]
    r = np.eye(4)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def test_differences_are_the_position_gap_and_the_rotation_angle() -> None:
    a = np.stack([np.eye(4), np.eye(4), _rotation(2, 0.3), np.eye(4)])
    b = a.copy()
    b[0, :3, 3] = (3e-3, 4e-3, 0.0)  # 5 mm
    b[1] = _rotation(0, 1e-7)  # a tiny angle: well conditioned
    b[2] = _rotation(2, 0.3 + math.pi / 2)
    b[3, 0, 0] = math.nan
    position, angle = differences(a, b)
    assert position[0] == pytest.approx(5e-3) and angle[0] == 0.0
    assert angle[1] == pytest.approx(1e-7, rel=1e-6) and position[1] == 0.0
    assert angle[2] == pytest.approx(math.pi / 2)
    assert math.isinf(position[3]) and math.isinf(angle[3])


def test_a_sweep_is_seeded_and_stays_inside_the_limits() -> None:
    lower, upper = _limits()
    first = Sweep(lower, upper, Tolerance(), seed=3).batch([])
    again = Sweep(lower, upper, Tolerance(), seed=3).batch([])
    other = Sweep(lower, upper, Tolerance(), seed=4).batch([])
    assert first[0].shape == (ROWS, 6)
    assert np.array_equal(first[0], again[0]) and not np.array_equal(first[0], other[0])
    assert (first[0] >= np.array(lower)).all() and (first[0] <= np.array(upper)).all()
    assert set(first[1]) == {"sweep:sobol"} and set(first[2]) == {-1}


def test_pattern_rows_only_around_centres_with_a_difference_to_follow() -> None:
    lower, upper = _limits()
    sweep = Sweep(lower, upper, Tolerance(), seed=0)
    centre = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6)
    for ignored in (0.0, NOISE, 1.0):  # noise, or already divergent
        _, labels, _ = sweep.batch([(centre, ignored)])
        assert set(labels) == {"sweep:sobol"}
    q, labels, owner = sweep.batch([(centre, 1e-9)])
    pattern = [i for i, o in enumerate(owner) if o == 0]
    assert len(pattern) == len(SCALES) * 4 * 6  # +-each joint and 2 x dof directions per scale
    row = labels.index("sweep:3+0.001")
    moved = q[row] - np.array(centre)
    assert np.count_nonzero(moved) == 1 and moved[3] == pytest.approx(1e-3 * (upper[3] - lower[3]))


def test_a_sweep_flags_the_narrow_band_and_finds_nothing_between_correct_targets() -> None:
    lower, upper = _limits()
    twin, reference = python_impl.RobotModel(ANNO), native.RobotModel(ANNO)
    faulty = deep.narrower_band.RobotModel(ANNO)
    control = Sweep(lower, upper, Tolerance(), seed=1)
    for _ in range(50):
        assert control.run([reference, twin], []).flagged == ()
    assert control.compared == 50 * ROWS and control.flagged == 0
    sweep = Sweep(lower, upper, Tolerance(), seed=1)
    found = [row for _ in range(400) for row in sweep.run([reference, faulty], []).flagged]
    assert found, "a 1e-5-wide band in 400 x 1024 Sobol rows (about 4 expected)"
    assert len(found) <= 400 * CONFIRM
    for row in found:  # the single-call path agrees: each flagged row is a real divergence
        gap = (
            faulty.forward_kinematics(list(row.values)).position[2]
            - reference.forward_kinematics(list(row.values)).position[2]
        )
        assert gap == pytest.approx(deep.SHIFT, abs=1e-9) and row.label == "sweep:sobol"


def test_the_pattern_search_climbs_the_amplified_error() -> None:
    lower, upper = _limits()
    reference, faulty = native.RobotModel(ANNO), deep.amplified_error.RobotModel(ANNO)
    sweep = Sweep(lower, upper, Tolerance(), seed=2, rows=256)
    centre, difference = (0.1, 0.2, 0.3, 0.4, 1.5, 0.6), 0.0
    q = np.array([centre])
    difference = float(np.max(differences(*(m.forward_kinematics_batch(q) for m in (reference, faulty)))))
    flagged = []
    for _ in range(40):
        result = sweep.run([reference, faulty], [(centre, difference)])
        flagged += result.flagged
        if result.improved:
            centre, difference = result.improved[0].values, result.improved[0].difference
    assert flagged, "the search follows 1e-11 / |q5 - c| to the region above 1e-6"
    assert any(row.label != "sweep:sobol" for row in flagged)


def test_a_sweep_is_due_every_few_single_inputs_whatever_the_clock() -> None:
    """The schedule counts inputs, so a campaign's inputs depend on its seed, not its speed."""
    from fuzzer.generation import sweep as module

    lower, upper = _limits()
    sweep = Sweep(lower, upper, Tolerance())
    due = [sweep.due() for _ in range(4 * module.EVERY)]
    assert module.EVERY > 1
    assert due == ([False] * (module.EVERY - 1) + [True]) * 4
    assert not any(Sweep(lower, upper, Tolerance(), every=0).due() for _ in range(10)), "0: never due"


@pytest.mark.parametrize("op", ["fk", "move", "ik", "scenario"])
def test_the_full_engine_sweeps_fk_and_move_campaigns_each_at_its_own_pace(op: str) -> None:
    """``fk`` and ``move`` in process get sweeps (a move's: the FK of its goals), due every
    ``EVERY_OP[op]`` single inputs; ``ik`` and ``scenario`` none, nor a baseline."""
    from fuzzer.execution.session import RunConfig, Session
    from fuzzer.generation.sweep import EVERY_OP
    from fuzzer.selection.guidance import Features
    from fuzzer.selection.search import search_parts

    session = Session.open(RunConfig(op=op))
    sweep = search_parts(session, "rrosfuzz", 1, Features(enabled=False)).get("sweep")
    assert "sweep" not in search_parts(session, "weights", 1, Features(enabled=False))
    if op not in ("fk", "move"):
        assert sweep is None
        return
    assert isinstance(sweep, Sweep) and sweep.source == "sobol" and sweep.every == EVERY_OP[op]
    # its Sobol engine (scipy.stats, up to 1.1 s) made now, not in the first sweep's input, where
    # a -fork worker lost a Ctrl-C (tests/test_engine_cli.py, test_ctrl_c_ends_jobs...)
    assert sweep._stream._sobol is not None  # type: ignore[union-attr]
    assert EVERY_OP["move"] > EVERY_OP["fk"] > 1, "a move input costs several fk ones"


def test_a_failing_batch_path_switches_the_sweep_off() -> None:
    class Broken:
        def forward_kinematics_batch(self, q: object, link: object = None) -> object:
            raise RuntimeError("no batch here")

    lower, upper = _limits()
    sweep = Sweep(lower, upper, Tolerance())
    for _ in range(Sweep.MAX_FAILURES):
        assert sweep.run([Broken(), Broken()], []).rows == 0
    assert not sweep.enabled and not sweep.due()


@pytest.mark.parametrize(
    "name",
    [
        "narrow_band",
        "joint_relation",
        "computed_branch",
        "atan2_quadrant",
        "calibration_entry",
        "small_angle_wrist",
        "narrower_band",
        "tight_relation",
        "amplified_error",
    ],
)
def test_deep_fk_faults_are_the_same_on_the_batch_and_the_single_path(name: str) -> None:
    model = getattr(deep, name).RobotModel(ANNO)
    lower, upper = _limits()
    q = Sweep(lower, upper, Tolerance(), seed=5).batch([])[0][:300]
    # rows inside each region too (the regions of benchmarks/zoo/deep.py)
    inside = np.array(
        [
            [0.1, -2.0071 + 0.6173 * 4.0142 + 1e-3, 0.3, 0.0, 0.5, 0.0],
            [0.9, 0.2, 0.9 - (math.sqrt(2) - 1) + 2e-4, 0.0, 0.5, 0.0],
            [0.0, 0.2, 1.37, 0.0, 0.5, 0.0],
            [0.0, 0.2, 0.5, 0.3, 1e-3, 0.0],
            [0.1, -2.0071 + 0.3829 * 4.0142 + 2e-5, 0.3, 0.0, 0.5, 0.0],
            [0.1, 0.2, 0.3, math.exp(-1.0) - 0.2 + 1e-5, 0.5, 0.0],
            [0.1, 0.2, 0.3, 0.4, deep.AMPLIFIED_AT + 1e-6, 0.0],
        ]
    )
    rows = np.vstack([q, inside])
    batch = model.forward_kinematics_batch(rows)
    for row, transform in zip(rows, batch, strict=True):
        pose = model.forward_kinematics(list(row))
        assert np.allclose(transform[:3, 3], pose.position, atol=1e-12)


def _fk_harness(tmp_path: Path, targets: tuple[str, str]) -> Harness:
    h = make_harness(tmp_path, targets=targets, op="fk")
    lower, upper = _limits()
    h.sweep = Sweep(lower, upper, h.evaluator.tolerance, seed=0)
    h.joint_names = tuple(native.RobotModel(ANNO).joint_names)
    return h


def test_the_harness_reports_a_swept_divergence_as_an_ordinary_crash_file(tmp_path: Path) -> None:
    h = _fk_harness(tmp_path, ("native", "benchmarks.zoo.deep:narrower_band"))
    assert h.sweep is not None
    for _ in range(600):
        h.run_sweep()
        if h.stats.signatures:
            break
    assert h.stats.signatures, "the band is met within 600 sweeps"
    assert h.sweep.unconfirmed == 0
    crash = next(p for p in (tmp_path / "artifacts").glob("crash-*") if p.suffix != ".json")
    case = decode(crash.read_bytes())
    assert case.strategy == "sweep:sobol" and case.msg_type == "sensor_msgs/JointState"
    evaluation = h.evaluator.evaluate(case)
    assert evaluation.divergent and evaluation.comparison.field == "position"


def test_no_sweep_reports_between_correct_targets(tmp_path: Path) -> None:
    h = _fk_harness(tmp_path, ("native", "python"))
    assert h.sweep is not None
    for _ in range(100):
        h.run_sweep()
    assert not h.stats.signatures and h.sweep.flagged == 0 and h.sweep.compared == 100 * ROWS


def test_a_campaign_on_a_chain_without_joints_runs_without_space_filling(tmp_path: Path) -> None:
    """Baxter's default chain (base to torso) has no joint variable: no Sobol stream and no
    sweep can exist, and the campaign must still run (it raised in SpaceFill before)."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    done = subprocess.run(
        [
            sys.executable,
            str(root / "fuzz_diff.py"),
            str(tmp_path / "corpus"),
            "--op",
            "fk",
            "--robot",
            "baxter",
            f"--artifacts={tmp_path / 'artifacts'}",
            "-runs=50",
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
        cwd=root,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "Traceback" not in done.stderr
