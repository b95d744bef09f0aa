"""The HTML report (fuzzer.report): aggregation on synthetic logs, then a real campaign end to end,
then the page as headless Chromium renders it."""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import matplotlib.image
import numpy as np
import pytest

from fuzzer.artifacts.divlog import DIVERGENCES, NEAR_ZERO, STATS
from fuzzer.execution.records import Signature
from fuzzer.execution.session import RunConfig
from fuzzer.input.mapping import MoveCall
from fuzzer.report import write_report
from fuzzer.report.arm import Sessions, _command, chain
from fuzzer.report.data import gather, runs
from fuzzer.report.records import Divergence, Snapshot, processes
from fuzzer.report.tables import (
    ROW_1E2_1E1,
    ROW_ABOVE_1E1,
    ROW_BELOW_1E2,
    ROW_COORDINATES,
    ROW_CRASH,
    ROW_OTHER,
    ROW_OTHER_UNITS,
    ROW_PROPERTY,
    ROW_ROTATIONS,
    ROW_STATUS,
    classify,
    differences,
    strategies,
    table_iii,
)

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = str(ROOT / "fuzz_diff.py")
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
DATA_URI = re.compile(r"data:image/png;base64,[A-Za-z0-9+/=]+")


# -- helpers ----------------------------------------------------------------------------------------------


def write_lines(path: Path, records: list[Any], garbage: tuple[str, ...] = ()) -> None:
    with open(path, "a", encoding="utf-8") as handle:
        for record in records:
            handle.write(json.dumps(record) + "\n")
        for line in garbage:
            handle.write(line + "\n")


def div(sig: str = "s1", kind: str = "value", **fields: Any) -> dict[str, Any]:
    return {
        "t": 1000.0,
        "pid": 1,
        "sig": sig,
        "kind": kind,
        "field": "position",
        "difference": 1e-3,
        "sign_flip": False,
        "strategy": "arithmetic",
        "near_zero": 2,
        "closer": "n/a",
        "sha1": "x",
        **fields,
    }


def snap(pid: int, t: float, elapsed: float, execs: int, **fields: Any) -> dict[str, Any]:
    return {
        "t": t,
        "pid": pid,
        "elapsed": elapsed,
        "execs": execs,
        "filtered": 0,
        "malformed": 0,
        "divergent": {},
        "by_strategy": {},
        "executed_by_strategy": {},
        "signatures": 0,
        "max_difference": 0.0,
        "near_zero": {},
        **fields,
    }


def line(**fields: Any) -> Divergence:
    parsed = Divergence.parse(div(**fields))
    assert parsed is not None
    return parsed


def sidecar(key_fields: dict[str, Any], config: dict[str, Any], sha1: str, **extra: Any) -> dict[str, Any]:
    signature = Signature(**key_fields)
    return {
        "config": config,
        "signature": signature.to_json(),
        "sha1": sha1,
        "outcomes": [
            {"target": config["targets"][0], "status": "ok", "values": {}},
            {"target": config["targets"][1], "status": "failed", "values": {}},
        ],
        "testcase": {"rrosfuzz": 1, "msg_type": "sensor_msgs/JointState", "message": {}, "lineage": []},
        **extra,
    }


def signature_fields(field: str = "position", **changes: Any) -> dict[str, Any]:
    base = {
        "op": "move",
        "outcome_a": "ok",
        "outcome_b": "ok",
        "kind": "value",
        "field": field,
        "joint_types": (),  # the signature no longer holds sign flip, magnitude bucket or joints
    }
    return {**base, **changes}


def config(robot: str = "probot_anno", targets: tuple[str, str] = ("native", "python")) -> dict[str, Any]:
    return {
        "op": "move",
        "robot": robot,
        "targets": list(targets),
        "tolerance": {"m": 1e-6, "rad": 1e-6},
        "msg_type": "sensor_msgs/JointState",
        "msg_path": [],
        "filtering": True,
        "tip_link": None,
    }


def place_crash(directory: Path, name: str, data: bytes, car: dict[str, Any]) -> Path:
    path = directory / name
    path.write_bytes(data)
    path.with_name(name + ".json").write_text(json.dumps(car))
    return path


def external_references(page: str) -> list[str]:
    """Anything in the page that would reach outside it (data URIs removed first: base64 may spell 'http')."""
    text = DATA_URI.sub("data:", page)
    found = re.findall(r"https?:|//[a-z0-9.-]+\.[a-z]{2,}/|<script|<link|@import|url\(", text, re.IGNORECASE)
    found += [src for src in re.findall(r"""src=["']?([^"' >]*)""", text) if not src.startswith("data:")]
    return found


# -- Table III ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("fields", "row"),
    [
        ({"kind": "value", "difference": 5e-3}, ROW_BELOW_1E2),
        ({"kind": "value", "difference": 1e-2}, ROW_1E2_1E1),  # limits belong to the upper row
        ({"kind": "value", "difference": 0.099}, ROW_1E2_1E1),
        ({"kind": "value", "difference": 0.1}, ROW_ABOVE_1E1),
        ({"kind": "value", "difference": math.inf}, ROW_ABOVE_1E1),
        ({"kind": "value", "difference": math.nan}, ROW_ABOVE_1E1),
        ({"kind": "representation", "field": "joint_values", "difference": 6.28}, ROW_COORDINATES),
        ({"kind": "value", "field": "position", "sign_flip": True, "difference": 5e-3}, ROW_COORDINATES),
        ({"kind": "representation", "field": "orientation", "sign_flip": True}, ROW_ROTATIONS),
        ({"kind": "value", "field": "orientation", "sign_flip": True, "difference": 0.5}, ROW_ROTATIONS),
        # opposite signs on another field are sized as the other values (they went to the last row)
        ({"kind": "value", "field": "go.named", "sign_flip": True, "difference": 0.5}, ROW_ABOVE_1E1),
        (
            {"kind": "value", "field": "plan.trajectory.positions", "sign_flip": True, "difference": 5e-3},
            ROW_BELOW_1E2,
        ),
        ({"kind": "representation", "field": "go.named", "difference": 6.28}, ROW_OTHER),
        ({"kind": "status", "field": "status", "difference": 0.0}, ROW_STATUS),
        ({"kind": "crash", "field": "status"}, ROW_CRASH),
        (
            {"kind": "value", "field": "cartesian_path.trajectory.time_from_start", "unit": "s"},
            ROW_OTHER_UNITS,
        ),
        ({"kind": "value", "difference": 0.5, "unit": "rad"}, ROW_ABOVE_1E1),
        ({"kind": "property", "field": "cartesian_path.acceleration_limits"}, ROW_PROPERTY),
        ({"kind": "flaky"}, ROW_OTHER),
        ({"kind": "ill_conditioned", "field": "status"}, ROW_OTHER),
    ],
)
def test_table_iii_rule_of_each_kind(fields: dict[str, Any], row: str) -> None:
    assert classify(line(**fields)) == row


def test_a_report_written_again_keeps_no_figure_of_the_earlier_one(tmp_path: Path) -> None:
    """Re-run on a folder emptied since, the page said "Nothing to show" beside the figures and
    3D views of buckets that no longer exist."""
    from fuzzer.report.build import write_report

    out = tmp_path / "report"
    out.mkdir()
    old = ["fig6-strategies.png", "over-time.png", "arm-abc123.png", "trajectory-abc123-step0.png"]
    for name in [*old, "mine.png", "arm-notes.txt"]:
        (out / name).write_bytes(PNG_MAGIC)
    page = write_report(tmp_path, out)
    assert "Nothing to show" in page.read_text()
    assert sorted(p.name for p in out.iterdir()) == ["arm-notes.txt", "mine.png", "report.html"]


def test_a_report_output_folder_that_cannot_be_written_exits_74(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """As every tool whose output cannot be written (docs/engine.md: a read-only mount, a full
    disk); report said 2, a usage error."""
    import errno

    from fuzzer import cli

    def read_only(self: Path, *args: Any, **kwargs: Any) -> None:
        raise OSError(errno.EROFS, "Read-only file system", str(self))

    monkeypatch.setattr(Path, "mkdir", read_only)
    assert cli.main(["report", str(tmp_path), "-o", str(tmp_path / "out")]) == 74
    said = capsys.readouterr().err
    assert f"report output {tmp_path / 'out'}: cannot create the folder: Read-only file system" in said


def test_fig_6_rate_labels_read_as_percentages() -> None:
    from fuzzer.report.figures import rate_label

    assert rate_label(1.0, 1818) == "100% of 1,818"  # it printed "1e+02% of 1,818"
    assert rate_label(0.999, 1000) == "99.9% of 1,000" and rate_label(0.0123, 1000) == "1.2% of 1,000"
    assert rate_label(0.0, 0) == rate_label(None, None) == "n/a (no executions recorded)"  # "0% of 0"


def test_fig_8_draws_only_metres_and_radians() -> None:
    """A scenario's durations (40.8 s) were drawn on Fig. 8's axis of "m or rad", past Table III's
    1e-1 limit, while Table III put them in a row of their own."""
    lines = [line(difference=2e-3), line(kind="representation", field="orientation", difference=6.28)]
    lines += [line(field="cartesian_path.trajectory.time_from_start", unit="s", difference=40.8)] * 3
    drawn = differences(lines)
    assert drawn.values == (2e-3,) and drawn.representations == (6.28,) and drawn.other_units == 3
    assert not differences([line(unit="s", difference=1.0)]).empty


def test_table_iii_counts_and_proportions_over_executions() -> None:
    lines = [line(difference=1e-3)] * 3 + [line(difference=0.05)] * 2 + [line(kind="status", field="status")]
    lines += [line(kind="representation", field="orientation")] * 4
    rows = {r.label: r for r in table_iii(lines, executions=200)}
    assert rows[ROW_BELOW_1E2].count == 3 and rows[ROW_BELOW_1E2].proportion == pytest.approx(3 / 200)
    assert rows[ROW_1E2_1E1].count == 2 and rows[ROW_1E2_1E1].share == pytest.approx(2 / 10)
    assert rows[ROW_ROTATIONS].count == 4 and rows[ROW_COORDINATES].count == 0
    assert rows[ROW_STATUS].count == 1 and rows[ROW_CRASH].count == 0
    assert not {ROW_OTHER, ROW_OTHER_UNITS, ROW_PROPERTY} & set(rows), "rows not the paper's: only when used"
    total = table_iii(lines, 200)[-1]
    assert total.group == "total" and total.count == 10 and total.proportion == pytest.approx(0.05)
    assert sum(r.count for r in table_iii(lines, 200)[:-1]) == total.count, "rows partition the divergences"
    assert table_iii(lines, 0)[0].proportion is None, "no executions: no proportion, no division by zero"


# -- Table IV ----------------------------------------------------------------------------------------------


def test_table_iv_counts_per_target_pair(tmp_path: Path) -> None:
    """Lines are attributed to a configuration by their process (the crash file's input was logged by
    it), else by signature; unattributable lines form their own row."""
    first, second = config(targets=("native", "python")), config(targets=("native", "plug:b"))
    place_crash(tmp_path, "crash-aaa", b"{}", sidecar(signature_fields("position"), first, "sha-a"))
    place_crash(tmp_path, "crash-bbb", b"{}", sidecar(signature_fields("orientation"), second, "sha-b"))
    key_a = Signature(**signature_fields("position")).key
    key_b = Signature(**signature_fields("orientation")).key
    records = [
        div(key_a, pid=10, sha1="sha-a", closer="a"),  # pid 10 is the first configuration
        div("other-sig", pid=10, closer="a"),  # same process, a signature without crash file
        div(key_a, pid=10, closer="tie"),
        div(key_a, pid=10, closer="n/a"),
        div(key_b, pid=20, sha1="sha-b", closer="b"),  # pid 20 is the second
        div(key_b, pid=20, closer="b"),
        div(key_b, pid=99, closer="a"),  # unknown process: by signature, the second configuration
        div("lost", pid=98, closer="b"),  # nothing to attribute it with
    ]
    write_lines(tmp_path / DIVERGENCES, records)
    rows = {(r.target_a, r.target_b): r for r in gather(tmp_path).table_iv}
    assert set(rows) == {("native", "python"), ("native", "plug:b"), ("target a", "target b")}
    one = rows[("native", "python")]
    assert (one.a, one.b, one.tie, one.excluded, one.compared) == (2, 0, 1, 1, 3)
    two = rows[("native", "plug:b")]
    assert (two.a, two.b, two.tie, two.excluded) == (1, 2, 0, 0)
    assert rows[("target a", "target b")].b == 1


# -- stats.jsonl: processes, Fig. 7, over time --------------------------------------------------------------


def test_fig7_sums_the_last_snapshot_of_each_process(tmp_path: Path) -> None:
    write_lines(
        tmp_path / STATS,
        [
            snap(1, 100.0, 1.0, 256, near_zero={"0": 5, "2": 1}),
            snap(2, 100.5, 0.5, 256, near_zero={"1": 7}),
            snap(1, 105.0, 6.0, 1000, near_zero={"0": 50, "2": 10}),  # supersedes pid 1's first
            snap(2, 110.0, 10.0, 2000, near_zero={"1": 70, "3": 3}),
            # pid 1 recycled by a later campaign: counters restart, a new process
            snap(1, 500.0, 2.0, 300, near_zero={"0": 1}),
        ],
    )
    write_lines(
        tmp_path / DIVERGENCES, [div(near_zero=2), div(near_zero=2), div(near_zero=0), div(near_zero=None)]
    )
    data = gather(tmp_path)
    assert data.near_zero.evaluated == {0: 51, 1: 70, 2: 10, 3: 3}
    assert data.near_zero.divergent == {0: 1, 2: 2}
    assert data.near_zero.threshold == NEAR_ZERO
    assert data.summary.executions == 1000 + 2000 + 300
    assert data.summary.processes == 3


def test_over_time_sums_processes_on_a_common_axis_and_splits_distant_runs() -> None:
    snaps = [
        Snapshot.parse(s)
        for s in (
            snap(1, 10.0, 10.0, 100),  # started at 0
            snap(1, 20.0, 20.0, 200),
            snap(2, 15.0, 10.0, 50, divergent={"value": 5}),  # started at 5
            snap(2, 25.0, 20.0, 150, divergent={"value": 9}),
            snap(3, 1000.0, 10.0, 40),  # far later: another run
        )
    ]
    procs = processes(s for s in snaps if s is not None)
    found = runs(procs, lambda pid: "even" if pid % 2 == 0 else "odd")
    assert len(found) == 2
    first, second = found
    assert first.processes == 2 and first.times[0] == 0.0 and first.times[-1] == 25.0
    assert [b.label for b in first.bands] == ["odd", "even"]
    at = dict(zip(first.times, first.execs, strict=True))
    assert at[10.0] == pytest.approx(100 + 25)  # pid 2 halfway to its first snapshot
    assert at[25.0] == pytest.approx(200 + 150)  # pid 1 held at its last value
    assert first.divergences[-1] == pytest.approx(9)
    assert all(b >= a for a, b in zip(first.execs, first.execs[1:], strict=False)), "cumulative"
    assert second.start == 990.0 and second.execs[-1] == 40
    together = runs(procs, lambda pid: "one configuration")[0]
    assert len(together.bands) == 1 and together.bands[0].execs == pytest.approx(first.execs)


def test_strategies_rate_and_order() -> None:
    procs = processes(
        s
        for s in (
            Snapshot.parse(
                snap(1, 10.0, 10.0, 100, executed_by_strategy={"comb3": 40, "splice": 50, "zero": 10})
            ),
            Snapshot.parse(snap(2, 10.0, 10.0, 100, executed_by_strategy={"comb3": 10, "bit_flip": 20})),
        )
        if s is not None
    )
    lines = [line(strategy="comb3")] * 5 + [line(strategy="splice")] * 7 + [line(strategy="seed")]
    rows = strategies(lines, procs)
    assert [r.name for r in rows] == ["bit_flip", "comb3", "splice", "seed", "zero"]
    by = {r.name: r for r in rows}
    assert by["comb3"].rate == pytest.approx(5 / 50) and by["comb3"].paper
    assert by["splice"].rate == pytest.approx(7 / 50) and not by["splice"].paper
    assert by["bit_flip"].rate == 0.0 and by["seed"].rate is None  # no executions recorded for 'seed'
    assert strategies(lines, [])[0].executions is None, "without stats.jsonl there are no rates"


def test_malformed_lines_are_skipped_and_counted(tmp_path: Path) -> None:
    write_lines(
        tmp_path / DIVERGENCES,
        [div(kind="status", field="status"), div(), [1, 2], {"kind": "value"}, {"sig": 3, "kind": "value"}],
        garbage=("not json", "", '{"sig": "s", "kind": "va'),
    )
    write_lines(
        tmp_path / STATS,
        [snap(1, 10.0, 1.0, 10), {"t": "late", "pid": 1, "execs": 5}, snap(1, 20.0, 11.0, 30)],
        garbage=("\x00\x01garbage", "{"),
    )
    data = gather(tmp_path)
    assert data.summary.divergent == 2 and data.summary.executions == 30
    assert any("5 malformed line(s) of divergences.jsonl" in n for n in data.notes), data.notes
    assert any("3 malformed line(s) of stats.jsonl" in n for n in data.notes), data.notes
    page = write_report(tmp_path).read_text()
    assert "malformed line(s)" in page


# -- pages from synthetic folders ----------------------------------------------------------------------------


def test_empty_folder_gives_a_page_saying_so(tmp_path: Path) -> None:
    page = write_report(tmp_path, tmp_path / "out")
    assert page == tmp_path / "out" / "report.html"
    text = page.read_text()
    assert text.startswith("<!DOCTYPE html>") and text.rstrip().endswith("</html>")
    assert "Nothing to show" in text
    assert not external_references(text)
    assert not list((tmp_path / "out").glob("*.png"))


def test_logs_without_crash_files(tmp_path: Path) -> None:
    write_lines(
        tmp_path / STATS, [snap(7, 50.0, 5.0, 400, near_zero={"1": 300}, executed_by_strategy={"comb1": 9})]
    )
    write_lines(
        tmp_path / DIVERGENCES, [div(difference=0.02, strategy="comb1"), div(kind="status", field="status")]
    )
    page = write_report(tmp_path).read_text()
    assert "Table III" in page and "Table IV" in page and "Nothing to show" not in page
    assert "No crash files in this folder" in page
    assert "0.25%" in page, "1 of 400 executions in the 1e-2 .. 1e-1 row"
    for name in ("fig6-strategies.png", "fig7-near-zero.png", "fig8-differences.png", "over-time.png"):
        assert (tmp_path / "report" / name).read_bytes().startswith(PNG_MAGIC)


def test_every_process_of_a_one_configuration_folder_is_labelled_with_it(tmp_path: Path) -> None:
    """A process is known by a divergence line that is a crash file's input; the dry run's
    children write those, so a campaign's main process (31,343 of 31,540 executions) was drawn as
    "configuration not recorded" in a folder of one configuration. Its folder's first campaign
    on another configuration, or two configurations on file, keep the honest label."""
    from fuzzer.report.data import UNKNOWN_CONFIG, config_label, gather

    first = config(targets=("native", "python"))
    place_crash(tmp_path, "crash-aaa", b"{}", sidecar(signature_fields("position"), first, "sha-a"))
    key = Signature(**signature_fields("position")).key
    write_lines(tmp_path / STATS, [snap(1, 50.0, 5.0, 40), snap(2, 50.0, 5.0, 4000)])
    write_lines(
        tmp_path / DIVERGENCES, [div(sig=key, pid=1, sha1="sha-a"), div(sig=key, pid=2, sha1="other")]
    )

    def labels() -> set[str]:
        return {band.label for run in gather(tmp_path).runs for band in run.bands}

    assert labels() == {config_label(first)}
    marker = tmp_path / ".rrosfuzz-configuration"
    marker.write_text("robot probot_anno (e1c799e10ae1), tip link None, targets native,python\n")
    assert labels() == {config_label(first)}
    marker.write_text("robot ur5 (cede880fc2a9), tip link None, targets native,python\n")
    assert labels() == {config_label(first), UNKNOWN_CONFIG}
    marker.unlink()
    place_crash(tmp_path, "crash-bbb", b"{}", sidecar(signature_fields("orientation"), config("ur5"), "s-b"))
    assert labels() == {config_label(first), UNKNOWN_CONFIG}


def test_a_folder_without_crash_files_names_its_first_campaign_s_configuration(tmp_path: Path) -> None:
    from fuzzer.report.data import gather

    write_lines(tmp_path / STATS, [snap(7, 50.0, 5.0, 400)])
    (tmp_path / ".rrosfuzz-configuration").write_text(
        "robot ur5 (cede880fc2a9), tip link None, targets native,python\n"
    )
    notes = gather(tmp_path).notes
    assert any("first campaign ran on: robot ur5 (cede880fc2a9)" in n for n in notes), notes


def test_strings_from_files_are_escaped_and_a_missing_robot_gives_a_note(tmp_path: Path) -> None:
    evil = "<script>alert(1)</script>"
    bad = config(robot=f"/gone/{evil}.urdf", targets=("native", f"mod:{evil}"))
    car = sidecar(signature_fields(), bad, "sha-x")
    car["outcomes"][1]["message"] = evil
    car["testcase"]["message"] = {"name": [evil]}
    place_crash(tmp_path, "crash-evil", b"{}", car)
    (tmp_path / "timeout-1234").write_bytes(evil.encode())  # libFuzzer's own file, no sidecar
    text = write_report(tmp_path).read_text()
    assert "<script" not in text.lower()
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in text
    assert "Cannot re-run under the recorded configuration" in text
    assert "timeout-1234" in text and "no sidecar" in text


def test_control_and_bidi_characters_from_files_are_shown_as_escapes(tmp_path: Path) -> None:
    """A right-to-left override (U+202E) reorders what a reader sees; NUL, ESC and a lone
    surrogate are not text. The page shows each as its escape."""
    odd = "a\x00b\x1b[31mc\u202edcba\ud800"
    bad = config(robot=f"/gone/{odd}.urdf", targets=("native", f"mod:{odd}"))
    car = sidecar(signature_fields(), bad, "sha-odd")
    car["outcomes"][1]["message"] = odd
    place_crash(tmp_path, "crash-odd", b"{}", car)
    text = write_report(tmp_path).read_text()
    assert not set(text) & {"\x00", "\x1b", "\u202e", "\ud800"}
    assert "a\\x00b\\x1b[31mc\\u202edcba\\ud800" in text


# -- the 3D view's pieces ---------------------------------------------------------------------------------


def test_chain_is_each_link_of_the_model_from_the_root() -> None:
    session = Sessions().get(config())
    assert not isinstance(session, str), session
    runner = session.runners[1]
    q = [0.3, -0.4, 0.2, 0.1, 0.5, -0.2]
    drawn = chain(runner, q, "python")
    assert len(drawn.points) == len(runner.model.link_names)
    assert drawn.points[0] == pytest.approx((0.0, 0.0, 0.0))
    assert drawn.points[-1] == pytest.approx(tuple(runner.model.forward_kinematics(q).position))
    names = tuple(runner.model.joint_names)
    assert _command(MoveCall(tuple(reversed(names)), (6.0, 5.0, 4.0, 3.0, 2.0, 1.0)), names) == (
        1.0,
        2.0,
        3.0,
        4.0,
        5.0,
        6.0,
    )
    assert _command(MoveCall(names[:2], (1.0, 2.0)), names) is None, "a partial command is not drawn"


def test_sessions_are_cached_per_configuration() -> None:
    sessions = Sessions()
    assert sessions.get(config()) is sessions.get(dict(reversed(list(config().items()))))
    assert isinstance(sessions.get(config(robot="/no/such/robot.urdf")), str)
    assert RunConfig.from_json(config()).robot == "probot_anno"


def _suite_ik_crash(folder: Path) -> Path:
    """A copy of the suite's IK crash file on Kinova whose goal lies at x = -1.8e308 m."""
    name = "crash-71f78e4fcc3be2f3a2216b1111a7d9dd961c70b8"
    folder.mkdir(parents=True, exist_ok=True)
    for suffix in ("", ".json"):
        shutil.copyfile(ROOT / "tests" / "regressions" / (name + suffix), folder / (name + suffix))
    return folder / name


def test_an_ik_goal_far_off_the_arm_is_a_note_not_the_picture_s_scale(tmp_path: Path) -> None:
    """The goal at -1.8e308 m set the 3D view's scale: numpy overflowed ("RuntimeWarning:
    overflow encountered in scalar subtract" on the console) and the arm was a dot."""
    import warnings

    crash = _suite_ik_crash(tmp_path / "art")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        text = write_report(crash.parent).read_text()
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]
    assert "The requested position (IK), (-1.798e+308, 0.151, 0.2155) m, lies far off the arm" in text


def test_report_robot_replaces_a_relative_robot_path_by_its_sha256(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A campaign's ``--robot my.urdf`` does not resolve from another working folder, and
    ``--trust-sidecar`` cannot make it; ``report --robot FILE`` gives it again, for the sidecars
    that record its SHA-256."""
    import hashlib

    from robot_api import robots

    crash = _suite_ik_crash(tmp_path / "campaign" / "art")
    urdf = tmp_path / "campaign" / "my.urdf"
    shutil.copyfile(robots.resolve("kinova"), urdf)
    car = json.loads(crash.with_name(crash.name + ".json").read_text())
    car["config"]["robot"] = "my.urdf"
    car["robot_sha256"] = hashlib.sha256(urdf.read_bytes()).hexdigest()
    crash.with_name(crash.name + ".json").write_text(json.dumps(car))
    monkeypatch.chdir(crash.parent)  # the file lies outside both the folder and the working one
    unresolved = "robot &#x27;my.urdf&#x27; is neither a shipped robot nor an existing file"
    assert unresolved in write_report(crash.parent, tmp_path / "r1", trust=True).read_text()
    digest = car["robot_sha256"]
    text = write_report(crash.parent, tmp_path / "r2", robots={digest: str(urdf)}).read_text()
    assert "Cannot re-run" not in text and "re-run: failed vs failed" in text
    other = write_report(crash.parent, tmp_path / "r3", robots={"0" * 64: str(urdf)}).read_text()
    assert unresolved in other, "a file of another digest is not used"


# -- end to end: a real campaign -----------------------------------------------------------------------------


def fuzz(*args: str) -> None:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    # -reload=0: libFuzzer's default 1-s reload of the corpus folder runs the seed files it does
    # not hold, and one at the loop's top runs after -runs is reached, so the count checked
    # below would depend on the machine's speed (tests/test_fuzz_urdf_loader.py)
    run = subprocess.run(
        [sys.executable, SCRIPT, *args, "-reload=0", "--no-progress"],
        cwd=ROOT,
        env=env,
        text=True,
        capture_output=True,
        timeout=120,
        check=False,
    )
    assert run.returncode == 1, run.stderr[-2000:]  # both campaigns find new divergences


@pytest.fixture(scope="module")
def campaign(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """Two planted faults, two robots, one artifacts folder; then the report."""
    root = tmp_path_factory.mktemp("report")
    artifacts = root / "artifacts"
    fuzz(
        str(root / "c1"),
        "-runs=3000",
        "-seed=1",
        f"--artifacts={artifacts}",
        "--targets=native,tests.plugins.faults:tight_tolerance",
    )
    fuzz(
        str(root / "c2"),
        "-runs=3000",
        "-seed=2",
        "--robot=kinova",
        f"--artifacts={artifacts}",
        "--targets=native,tests.plugins.faults:wrap_continuous",
    )
    return artifacts, write_report(artifacts, trust=True)  # its sidecars name the tests' plugin targets


def _dry_run(robot: str, target: str) -> int:
    """The inputs a move campaign's dry run evaluates on ``robot`` against ``target`` besides
    its 32 seeds (both stages: uniform and aligned configurations, boundary probes, and the
    configurations at the numbers the target's module compares against)."""
    from fuzzer import dry_run
    from fuzzer.execution.session import RunConfig, Session

    def no_harness(*_: object) -> Any:
        raise AssertionError("counting the inputs makes no harness")

    session = Session.open(RunConfig(robot=robot, targets=("native", target)))
    stages = dry_run.Stages(session, "rrosfuzz", 1, 32, 0, no_harness)
    return len(stages.first_cases()) + len(stages.second_cases([])) + len(stages.literal_cases())


def test_report_of_a_real_campaign(campaign: tuple[Path, Path]) -> None:
    artifacts, page = campaign
    assert page == artifacts / "report" / "report.html"
    text = page.read_text(encoding="utf-8")
    assert not external_references(text), external_references(text)[:5]
    assert "Table III: difference statistics" in text and "Table IV: which implementation" in text
    data = gather(artifacts)
    # both campaigns' processes, last snapshot each; -runs=3000 includes libFuzzer's empty
    # input, which is not a test case and not counted; each campaign's dry run (its own
    # processes, fuzzer/dry_run.py) evaluated its 32 Hypothesis seeds, its robot's boundary
    # probes and its uniform and aligned configurations
    plugins = (("probot_anno", "tight_tolerance"), ("kinova", "wrap_continuous"))
    dry = sum(32 + _dry_run(robot, f"tests.plugins.faults:{fault}") for robot, fault in plugins)
    assert data.summary.executions == 2 * 2999 + dry, "both campaigns' processes, last snapshot each"
    assert {"probot_anno", "kinova"} <= set(data.summary.robots)
    kinds = {b.kind for b in data.buckets}
    assert {"status", "representation"} <= kinds, kinds
    for bucket in data.buckets:
        assert bucket.key in text
        # the plugin targets named, as a replay needs them (its command exited 2 without)
        targets = ",".join(bucket.sidecar["config"]["targets"])  # type: ignore[index]
        assert f"python fuzz_diff.py {bucket.best.resolve()} --targets {targets}</code>" in text
        assert f"python fuzz_diff.py view {bucket.best.resolve()}</code>" in text
        assert f"python fuzz_diff.py export-bag {bucket.best.resolve()}</code>" in text
        arm = page.parent / f"arm-{bucket.key}.png"
        assert arm.read_bytes().startswith(PNG_MAGIC), f"no 3D view for {bucket.key}"
    assert "same signature as recorded" in text
    assert text.count("<img ") == 4 + len(data.buckets)
    for png in page.parent.glob("*.png"):
        image = matplotlib.image.imread(str(png))
        assert image.shape[0] > 200 and image.shape[1] > 200 and image.std() > 0.01, png.name
    pairs = {(r.target_a, r.target_b) for r in data.table_iv}
    assert ("native", "tests.plugins.faults:wrap_continuous") in pairs
    wrap = next(r for r in data.table_iv if r.target_b.endswith("wrap_continuous"))
    assert wrap.compared > 0 and wrap.a > 0, "native reports the commanded angle, the fault wraps it"


def test_report_is_deterministic_except_the_timestamp(campaign: tuple[Path, Path]) -> None:
    artifacts, page = campaign
    again = write_report(artifacts, artifacts.parent / "again", trust=True)
    strip = re.compile(r"Generated [0-9: -]+UTC")
    assert strip.sub("", again.read_text()) == strip.sub("", page.read_text())


@pytest.mark.skipif(shutil.which("chromium") is None, reason="Debian's chromium is not installed")
def test_headless_chromium_renders_the_page(campaign: tuple[Path, Path]) -> None:
    _, page = campaign
    shot = page.parent / "screenshot.png"
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run(
            [
                "chromium",
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--hide-scrollbars",
                f"--user-data-dir={profile}",
                "--window-size=1280,4000",
                f"--screenshot={shot}",
                page.resolve().as_uri(),
            ],
            capture_output=True,
            timeout=60,
            check=False,
        )
    assert shot.is_file(), "chromium wrote no screenshot"
    image = matplotlib.image.imread(str(shot))[:, :, :3]
    assert image.shape[:2] == (4000, 1280)
    not_white = (image < 0.95).any(axis=2).mean()
    colors = np.unique((image * 255).astype(np.uint8).reshape(-1, 3), axis=0)
    assert not_white > 0.05, f"only {not_white:.1%} of the page is not white"
    assert len(colors) > 50, f"only {len(colors)} colors: the figures did not render"
    blue = ((image[:, :, 2] > 0.6) & (image[:, :, 0] < 0.3)).mean()
    assert blue > 0.001, "no figure bars (the report's blue) in the rendering"


def test_a_report_that_cannot_be_written_leaves_the_last_one_whole(
    campaign: tuple[Path, Path], tmp_path: Path
) -> None:
    # a full disk: the page was written in place and cut short (no </html>), the old one gone
    import resource

    artifacts, page = campaign
    out = tmp_path / "out"
    shutil.copytree(page.parent, out)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    limit = len(before["report.html"]) // 2

    def small_files() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))  # EFBIG past it, as ENOSPC

    run = subprocess.run(
        [sys.executable, SCRIPT, "report", str(artifacts), "-o", str(out), "--trust-sidecar"],
        cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)), preexec_fn=small_files,
        capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip
    assert run.returncode == 74, run.stderr[-2000:]
    assert "Traceback" not in run.stderr and f"fuzz_diff.py: error: {out}" in run.stderr
    after = {p.name: p.read_bytes() for p in out.iterdir()}
    assert after["report.html"] == before["report.html"] and after["report.html"].rstrip().endswith(
        b"</html>"
    )
    assert not [name for name in after if name.startswith(".tmp-")]
    for name, data in after.items():  # a figure is the old one or a whole new one
        assert data == before.get(name) or data.endswith(b"IEND\xaeB`\x82"), name
