"""Triage, replay and the HTML report of scenario divergences (``--op scenario``, issue 10 item 5).

Hand-made sidecars first (schema rows, step lists, the first divergent step, the report's step
table and trajectory figure, escaping of hostile step contents), then one real campaign
against a twin whose state goes stale after its second ``go()``.
"""

from __future__ import annotations

import base64
import copy
import io
import json
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import matplotlib.image
import numpy as np
import pytest

from fuzzer.artifacts.sidecar import SidecarError, read_sidecar
from fuzzer.artifacts.trust import config_from
from fuzzer.execution.evaluate import Evaluation, Verdict
from fuzzer.execution.records import Comparison, Kind, Outcome, Signature, Status
from fuzzer.input.testcase import TestCase
from fuzzer.report import write_report
from fuzzer.report.records import Divergence
from fuzzer.report.scenario import COLORS, Trajectory, TrajectoryStep, figure, file_name, trajectory, view_of
from fuzzer.report.steps import LISTED_STEPS, shown_steps
from fuzzer.report.tables import ROW_COORDINATES, ROW_OTHER, ROW_ROTATIONS, classify
from fuzzer.triage import pipeline as triage
from fuzzer.triage.replay import scenario_lines

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = str(ROOT / "fuzz_diff.py")
JOINTS = [f"joint_{i}" for i in range(1, 7)]
HOSTILE = "<script>alert(1)</script>\x1b[2J"
HEADER = {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}
STEPS: list[dict[str, Any]] = [
    {"topic": "/velocity_scaling", "msg": {"data": 0.5}},
    {"topic": "/joint_target", "msg": {"header": HEADER, "name": [], "position": [0.1] * 6,
                                       "velocity": [], "effort": []}},
    {"topic": "/plan", "msg": {}},
    {"topic": "/go", "msg": {}},
    {"topic": "/named_target", "msg": {"data": HOSTILE}},
    {"topic": "/go", "msg": {}},
]  # fmt: skip
TIMES = [0.0, 0.5, 1.0, 1.5]
DIVERGENT = 2
"""The first divergent step of the hand-made scenario: /plan, velocities twice as large on b."""


def plan_values(speed: float) -> dict[str, tuple[float, ...]]:
    """A /plan step's values: 4 points from 0 to 0.1 rad on every joint, velocities x ``speed``."""
    positions = [0.1 * t / TIMES[-1] for t in TIMES for _ in JOINTS]
    velocities = [speed * 0.1 / TIMES[-1] for _ in TIMES for _ in JOINTS]
    return {
        "trajectory.time_from_start": tuple(TIMES),
        "trajectory.positions": tuple(positions),
        "trajectory.velocities": tuple(velocities),
        "trajectory.accelerations": tuple(0.0 for _ in positions),
        "success": (1.0,),
        "joint_values": (0.0,) * 6,
    }


def step_outcomes(speed: float, crash_at: int | None = None) -> list[Outcome]:
    out = []
    for i, _ in enumerate(STEPS):
        if i == crash_at:
            out.append(Outcome(Status.CRASHED, "KeyError", None, "boom"))
            break
        values = plan_values(speed) if i == DIVERGENT else FINAL
        out.append(Outcome(Status.OK, values=values))
    return out


FINAL: dict[str, tuple[float, ...]] = {"joint_values": (0.1,) * 6}


def scenario_sidecar() -> dict[str, Any]:
    """A scenario sidecar as build_sidecar writes one: b plans twice as fast and crashes at step 4."""
    a, b = step_outcomes(1.0), step_outcomes(2.0, crash_at=4)
    signature = Signature("scenario", "ok", "ok", "value", "plan.trajectory.velocities", ("revolute",))
    comparison = Comparison(
        Kind.VALUE,
        "plan.trajectory.velocities",
        0.0667,
        joints=(0, 1),
        unit="rad/s",
        step=2,
        step_kind="plan",
    )
    config = {"op": "scenario", "robot": "probot_anno", "targets": ["native", "python"], "max_steps": 16}
    return copy.deepcopy({
        "rrosfuzz_sidecar": 1,
        "signature": signature.to_json(),
        "comparison": {**comparison.__dict__, "kind": "value", "joints": [0, 1]},
        "difference": 0.0667,
        "config": config,
        "joint_names": JOINTS,
        "testcase": TestCase("rrosfuzz/Scenario", {"steps": STEPS}).to_json(),
        "lineage": [],
        "call": {"kind": "ScenarioCall", "steps": [{"kind": s["topic"][1:], "message": s["msg"]}
                                                   for s in STEPS]},
        "outcomes": [
            {"target": "native", **Outcome(Status.OK, values=FINAL, steps=tuple(a)).to_json()},
            {"target": "python", **Outcome(Status.CRASHED, "KeyError", steps=tuple(b)).to_json()},
        ],
    })  # fmt: skip


def write_crash(directory: Path, sidecar: dict[str, Any], name: str = "crash-5ce0") -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    crash = directory / name
    crash.write_bytes(TestCase("rrosfuzz/Scenario", {"steps": STEPS}).encode())
    crash.with_name(name + ".json").write_text(json.dumps(sidecar))
    (directory / "divergences.jsonl").open("a").write(json.dumps({"sig": sidecar["signature"]["key"]}) + "\n")
    return crash


# -- the sidecar's schema ------------------------------------------------------------------------------------


def test_the_schema_accepts_a_scenario_sidecar(tmp_path: Path) -> None:
    crash = write_crash(tmp_path, scenario_sidecar())
    data = read_sidecar(crash)
    assert data is not None and data["comparison"]["step"] == DIVERGENT
    config = config_from(data, crash, {})
    assert (config.op, config.max_steps, config.message_type) == ("scenario", 16, "rrosfuzz/Scenario")


def _set(path: str, value: Any) -> Callable[[dict[str, Any]], None]:
    """A change of the sidecar at a path of keys separated by '/' (list indices as numbers)."""

    def change(data: dict[str, Any]) -> None:
        keys: list[Any] = [int(k) if k.isdigit() else k for k in path.split("/")]
        for key in keys[:-1]:
            data = data[key]
        data[keys[-1]] = value

    return change


TOO_MANY = [{"kind": "go", "message": {}}] * 17
NESTED = Outcome(Status.OK, steps=(Outcome(Status.OK),)).to_json()
REJECTED = [
    ("call.steps", _set("call/steps", [])),
    ("call.steps", _set("call/steps", TOO_MANY)),  # more than config.max_steps
    ("call.steps", _set("call/steps", "go")),
    ("call.steps[1].kind", _set("call/steps/1/kind", 3)),
    ("call.steps[2].message", _set("call/steps/2/message", None)),
    ("call.kind", _set("call/kind", "MoveCall")),
    ("call.steps", _set("call/steps", TOO_MANY[:5])),  # not the test case's steps
    ("testcase.message.steps[0].msg", _set("testcase/message/steps/0/msg", "x")),
    ("outcomes[1].steps[3].status", _set("outcomes/1/steps/3/status", "exploded")),
    ("outcomes[0].steps", _set("outcomes/0/steps", [Outcome(Status.OK).to_json()] * 7)),  # 7 for 6 steps
    ("outcomes[0].steps", _set("outcomes/0/steps", {"0": {}})),
    ("outcomes[0].steps[0].steps", _set("outcomes/0/steps/0", NESTED)),
    ("outcomes[0].steps[2].values.trajectory.positions",
     _set("outcomes/0/steps/2/values/trajectory.positions", ["x"])),
    ("outcomes[0].steps[2].code", _set("outcomes/0/steps/2/code", "30")),
    ("outcomes[0].steps[2].shortened", _set("outcomes/0/steps/2/shortened", ["all"])),  # the writer's note
    ("outcomes[1]", _set("outcomes/1", [])),
    ("comparison.step", _set("comparison/step", 6)),
    ("comparison.step", _set("comparison/step", True)),
    ("comparison.step", _set("comparison/step", -1)),
    ("comparison.step_kind", _set("comparison/step_kind", 5)),
    ("config.max_steps", _set("config/max_steps", 0)),
    ("config.max_steps", _set("config/max_steps", 257)),
]  # fmt: skip


@pytest.mark.parametrize(("field", "change"), REJECTED, ids=[f"{r[0]}-{i}" for i, r in enumerate(REJECTED)])
def test_the_schema_rejects_malformed_scenario_sidecars(
    tmp_path: Path, field: str, change: Callable[[dict[str, Any]], None]
) -> None:
    sidecar = scenario_sidecar()
    change(sidecar)
    crash = write_crash(tmp_path, sidecar)
    with pytest.raises(SidecarError, match=rf"{crash.name}\.json: field '{re.escape(field)}' "):
        read_sidecar(crash)


def test_a_damaged_scenario_sidecar_is_its_own_bucket_naming_the_field(tmp_path: Path) -> None:
    sidecar = scenario_sidecar()
    sidecar["outcomes"][1]["steps"][3]["status"] = "exploded"
    write_crash(tmp_path, sidecar)
    (bucket,) = triage.collect(tmp_path)
    assert bucket.signature is None and "outcomes[1].steps[3].status" in bucket.describe()


# -- triage and replay ---------------------------------------------------------------------------------------


def test_triage_lists_the_steps_and_the_first_divergent_step(tmp_path: Path) -> None:
    write_crash(tmp_path, scenario_sidecar())
    (bucket,) = triage.collect(tmp_path)
    assert bucket.describe().endswith("ok vs ok at step 2 (/plan)")
    lines = triage.table([bucket])
    assert "first divergent step 2 (/plan, kind plan): ok vs ok" in lines[3]
    rows = [line for line in lines if re.match(r"\s+>?\s*\d+ /", line)]
    assert len(rows) == len(STEPS)
    for i, (row, step) in enumerate(zip(rows, STEPS, strict=True)):
        assert row.split(step["topic"])[0].split()[-1] == str(i), row
        assert row.lstrip().startswith(">") is (i == DIVERGENT), row
    assert "position=(0.1, 0.1, 0.1, 0.1, 0.1, 0.1)" in rows[1] and rows[0].endswith("0.5  [ok | ok]")
    assert rows[4].endswith("[ok | crashed:KeyError:None]") and rows[5].endswith("[ok | -]"), "b crashed at 4"
    # hostile contents: quoted, control characters escaped, nothing raw reaches the terminal
    assert '"<script>alert(1)</script>\\u001b[2J"' in rows[4] and "\x1b" not in "".join(lines)
    scenario = json.loads(triage.dumps([bucket]))[0]["scenario"]
    assert (scenario["first_step"], scenario["step_kind"]) == (DIVERGENT, "plan")
    assert [s["topic"] for s in scenario["steps"]] == [s["topic"] for s in STEPS]


def test_triage_cli_shows_the_step_list(tmp_path: Path) -> None:
    write_crash(tmp_path, scenario_sidecar())
    run = subprocess.run(
        [sys.executable, SCRIPT, "triage", str(tmp_path)],
        cwd=ROOT,
        text=True,
        capture_output=True,
        timeout=60,
    )
    assert run.returncode == 0, run.stderr
    assert "first divergent step 2 (/plan, kind plan)" in run.stdout and ">  2 /plan" in run.stdout


def test_a_long_scenario_lists_the_first_divergent_step() -> None:
    assert shown_steps(10, 3) == list(range(10))
    for first in (0, 30, 199):
        shown = shown_steps(200, first)
        assert first in shown and len(shown) <= LISTED_STEPS and shown == sorted(set(shown))


def test_replay_text_shows_the_steps_at_the_first_divergent_step() -> None:
    case = TestCase("rrosfuzz/Scenario", {"steps": STEPS})
    a = Outcome(Status.OK, steps=tuple(step_outcomes(1.0)))
    b = Outcome(Status.OK, steps=(*step_outcomes(1.0)[:3], Outcome(Status.FAILED)))
    comparison = Comparison(Kind.STATUS, "go.status", step=3, step_kind="go")
    evaluation = Evaluation(Verdict.EVALUATED, None, (a, b), comparison)
    lines = scenario_lines(case, evaluation, ("native", "python"))
    assert lines[0] == "first divergent step 3 (/go, kind go): ok vs failed"
    assert lines[1] == "6 step(s) (native | python):"
    assert lines[2 + 3].lstrip().startswith(">  3 /go") and lines[2 + 3].endswith("[ok | failed]")
    assert lines[-1].endswith("[ok | -]")
    move = TestCase("sensor_msgs/JointState", {"position": [0.0]})
    assert scenario_lines(move, evaluation, ("native", "python")) == ()


# -- the report ----------------------------------------------------------------------------------------------


def test_the_report_shows_the_step_table_and_the_trajectory_figure(tmp_path: Path) -> None:
    sidecar = scenario_sidecar()
    write_crash(tmp_path / "art", sidecar)
    page = write_report(tmp_path / "art", tmp_path / "out")
    html = page.read_text()
    key = sidecar["signature"]["key"]
    assert "<th>Topic</th><th>Arguments</th>" in html
    hot = html.split("<tr class='hot'><td class='num'>")[1].split("</tr>")[0]
    assert hot.startswith("2<br><b>first divergent</b>") and "<code>/plan</code>" in hot
    png = tmp_path / "out" / file_name(key, DIVERGENT)
    assert png.is_file(), sorted(p.name for p in (tmp_path / "out").iterdir())
    assert f"href='{png.name}'" in html and base64.b64encode(png.read_bytes()).decode() in html
    pixels = matplotlib.image.imread(png)[:, :, :3]
    for color in COLORS:  # both targets are drawn
        rgb = np.array([int(color[i : i + 2], 16) for i in (1, 3, 5)]) / 255
        assert np.sum(np.all(np.abs(pixels - rgb) < 0.02, axis=2)) > 100, color
    # the values at the divergent step, the compared quantity highlighted
    assert "<tr class='hot'><td><code>trajectory.velocities</code></td>" in html
    # hostile step contents are escaped (a String step whose data is <script>)
    assert "<script" not in html and "&quot;&lt;script&gt;alert(1)&lt;/script&gt;\\u001b[2J&quot;" in html


def test_a_single_call_report_has_no_scenario_parts(tmp_path: Path) -> None:
    sidecar = scenario_sidecar()
    for name in ("call", "comparison"):
        del sidecar[name]
    sidecar["testcase"] = TestCase("sensor_msgs/JointState", {"position": [0.0] * 6}).to_json()
    sidecar["config"]["op"] = "move"
    for outcome in sidecar["outcomes"]:
        del outcome["steps"]
    assert view_of(sidecar) is None
    write_crash(tmp_path / "art", sidecar)
    html = write_report(tmp_path / "art", tmp_path / "out").read_text()
    assert "<h3>Steps" not in html and not list((tmp_path / "out").glob("trajectory-*"))


def test_a_trajectory_of_the_wrong_length_gets_a_note_not_a_plot() -> None:
    good = Outcome(Status.OK, values=plan_values(1.0))
    bad = Outcome(Status.OK, values={**plan_values(1.0), "trajectory.velocities": (0.0,) * 5})
    found, note = trajectory(good, "a", 6)
    assert found is not None and len(found.positions) == 4 and len(found.positions[0]) == 6 and note == ""
    missing, note = trajectory(bad, "b", 6)
    assert missing is None and note == "b: 5 velocities for 4 time point(s) and 6 joint(s): not drawn"
    assert figure(TrajectoryStep(2, "/plan", tuple(JOINTS), (None, None))) is None
    png = figure(TrajectoryStep(2, "/plan", tuple(JOINTS), (found, None)))
    assert png is not None
    width = matplotlib.image.imread(io.BytesIO(png)).shape[1]
    two = Trajectory(
        "a", found.time, tuple(r[:2] for r in found.positions), tuple(r[:2] for r in found.velocities)
    )
    narrow = figure(TrajectoryStep(2, "/plan", tuple(JOINTS[:2]), (two, None)))
    assert narrow is not None and matplotlib.image.imread(io.BytesIO(narrow)).shape[1] < width


def test_table_iii_reads_a_scenario_field_by_its_quantity() -> None:
    rows = {}
    for field in ("go.orientation", "execute.position", "plan.trajectory.positions", "orientation"):
        line = Divergence.parse({"sig": "s", "kind": "representation", "field": field})
        assert line is not None
        rows[field] = classify(line)
    assert rows == {
        "go.orientation": ROW_ROTATIONS,
        "execute.position": ROW_COORDINATES,
        "plan.trajectory.positions": ROW_OTHER,
        "orientation": ROW_ROTATIONS,
    }


# -- a real campaign --------------------------------------------------------------------------------------


@pytest.mark.slow
def test_a_real_scenario_campaign_triages_replays_and_reports(tmp_path: Path) -> None:
    """The twin whose state goes stale after its second go(): found, listed, replayed, drawn."""
    art = tmp_path / "art"
    target = "--targets=native,tests.plugins.scenario_report_fault:stale_second_go"

    def fuzz(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [sys.executable, SCRIPT, *args],
            cwd=ROOT,
            text=True,
            capture_output=True,
            timeout=300,
        )

    run = fuzz(str(tmp_path / "corpus"), "--op=scenario", "-runs=60", "-seed=1", f"--artifacts={art}", target,
               "--no-progress")  # fmt: skip
    assert run.returncode in (0, 1), run.stderr[-3000:]
    crashes = sorted(p for p in art.glob("crash-*") if p.suffix != ".json")
    assert crashes, run.stderr[-3000:]
    buckets = triage.collect(art)
    fields = {b.signature.field for b in buckets if b.signature is not None}
    assert "go.joint_values" in fields, fields  # the planted fault: the second go leaves the state
    listed = fuzz("triage", str(art))
    assert listed.returncode == 0, listed.stderr
    for bucket in buckets:
        scenario = bucket.scenario
        assert scenario is not None and scenario.first is not None
        assert scenario.headline() in listed.stdout
    replayed = fuzz("replay", *map(str, crashes), target)
    assert replayed.stdout.count("still diverges (same signature)") == len(crashes), replayed.stdout[-3000:]
    assert replayed.stdout.count("first divergent step") == len(crashes)
    page = write_report(art, tmp_path / "out", trust=True).read_text()
    assert page.count("<b>first divergent</b>") == len(buckets)
    drawn = list((tmp_path / "out").glob("trajectory-*.png"))
    with_plans = [
        b
        for b in buckets
        if b.scenario and any(s.topic in ("/plan", "/cartesian_path") for s in b.scenario.steps)
    ]
    assert len(drawn) >= len(with_plans) and all(f"href='{p.name}'" in page for p in drawn)
