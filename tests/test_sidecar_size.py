"""Sidecars stay small enough to read back (fuzzer/artifacts/shorten.py).

The regression: a scenario whose ``/plan`` ran at acceleration scaling 1e-4 returned
a 35,450-point trajectory on both targets; its sidecar was 37 MB, larger than every
reader accepts, so replay refused the file and the campaign counted a
``known_limitation`` divergence as a finding (exit 1).
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fuzzer.artifacts import shorten
from fuzzer.artifacts.shorten import MAX_OUTCOME_NUMBERS, MAX_SIDECAR_BYTES, encode_sidecar, fit_outcomes
from fuzzer.artifacts.sidecar import read_sidecar
from fuzzer.report.scenario import view_of
from tests.support import fuzz

ZERO = {"frame_id": "", "seq": 0, "stamp": {"secs": 0, "nsecs": 0}}
JOINTS = [f"joint_{i}" for i in range(1, 7)]
LONG_PLAN = [  # probot_anno: a known_limitation at step 3, then a 35,450-point plan
    {"topic": "/execute", "msg": {}},
    {
        "topic": "/position_target",
        "msg": {
            "header": ZERO,
            "point": {"x": 0.21652527735553875, "y": -2.4161803651909497e-06, "z": 0.001001},
        },
    },
    {"topic": "/execute", "msg": {}},
    {"topic": "/go", "msg": {}},
    {"topic": "/acceleration_scaling", "msg": {"data": 0.0001}},
    {
        "topic": "/joint_target",
        "msg": {
            "header": ZERO,
            "name": JOINTS,
            "position": [
                1.5707963267948966,
                0.0,
                1.090541243669763,
                3.14155,
                0.6116149658057838,
                -1.541576451896131,
            ],
            "velocity": [],
            "effort": [],
        },
    },
    {"topic": "/plan", "msg": {}},
]


def _trajectory(points: int, dof: int = 6) -> dict[str, list[float]]:
    return {
        "trajectory.time_from_start": [0.01 * k for k in range(points)],
        "trajectory.positions": [k + j / 10 for k in range(points) for j in range(dof)],
        "trajectory.velocities": [-(k + j / 10) for k in range(points) for j in range(dof)],
        "trajectory.accelerations": [0.0] * (points * dof),
    }


def _outcome(target: str, steps: list[dict[str, Any]]) -> dict[str, Any]:
    return {
        "target": target,
        "status": "ok",
        "error": "",
        "code": None,
        "message": "",
        "values": {},
        "steps": steps,
    }


def _step(values: dict[str, list[float]]) -> dict[str, Any]:
    return {"status": "ok", "error": "", "code": None, "message": "", "values": values}


def _numbers(outcomes: list[Any]) -> int:
    return sum(len(v) for r in shorten._records(outcomes) for v in r["values"].values())


def test_outcomes_that_fit_are_kept_as_they_are() -> None:
    outcomes = [
        _outcome(t, [_step({"joint_values": [0.5] * 6}), _step(_trajectory(100))]) for t in ("a", "b")
    ]
    assert fit_outcomes(outcomes) is outcomes
    assert json.loads(encode_sidecar({"outcomes": outcomes})) == {"outcomes": outcomes}


def test_a_long_trajectory_keeps_whole_rows_evenly_spread_with_both_ends() -> None:
    small = _step({"joint_values": [0.5] * 6, "fraction": [1.0]})
    outcomes = [_outcome(t, [small, _step(_trajectory(35_450))]) for t in ("native", "python")]
    fitted = fit_outcomes(outcomes)
    assert _numbers(fitted) <= MAX_OUTCOME_NUMBERS < _numbers(outcomes)
    for before, after in zip(outcomes, fitted, strict=True):
        assert after["steps"][0] is small  # only the long series is touched
        values = after["steps"][1]["values"]
        time = values["trajectory.time_from_start"]
        m = len(time)
        assert 1000 < m < 35_450
        assert time[0] == 0.0 and time[-1] == before["steps"][1]["values"]["trajectory.time_from_start"][-1]
        assert all(b > a for a, b in itertools.pairwise(time))
        rows = [round(t / 0.01) for t in time]
        for name in ("positions", "velocities"):
            flat = values[f"trajectory.{name}"]
            assert len(flat) == 6 * m
            sign = 1 if name == "positions" else -1
            assert flat == [sign * (k + j / 10) for k in rows for j in range(6)]  # whole, matching rows
        gaps = {b - a for a, b in itertools.pairwise(rows)}
        assert max(gaps) - min(gaps) <= 1  # evenly spread
        assert after["steps"][1]["shortened"] == (
            f"trajectory: {m} of 35450 points kept, evenly spaced, first and last included"
        )
    assert "shortened" not in outcomes[0]["steps"][1]  # the caller's records are not changed


def test_other_long_vectors_keep_their_first_numbers() -> None:
    outcomes = [
        {"target": "a", "status": "ok", "values": {"sweep": list(map(float, range(500))), "x": [1.0]}}
    ]
    fitted = fit_outcomes(outcomes, limit=101)
    assert fitted[0]["values"] == {"sweep": list(map(float, range(100))), "x": [1.0]}
    assert fitted[0]["shortened"] == "sweep: first 100 of 500 numbers kept"


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.tuples(st.integers(1, 60), st.integers(1, 4), st.integers(0, 30)), min_size=1, max_size=6),
    st.integers(20, 400),
)
def test_the_common_length_is_the_longest_that_fits(shapes: list[tuple[int, int, int]], limit: int) -> None:
    outcomes = [
        _outcome(
            "a", [_step({**_trajectory(points, dof), "v": [1.0] * extra}) for points, dof, extra in shapes]
        )
    ]
    fitted = fit_outcomes(outcomes, limit=limit)
    series = [g for r in shorten._records(outcomes) for g in shorten._series(r)]
    if _numbers(outcomes) <= limit:
        assert fitted is outcomes
        return
    cap = max(len(s["values"]["trajectory.time_from_start"]) for s in fitted[0]["steps"])
    cap = max(cap, *(len(s["values"]["v"]) for s in fitted[0]["steps"]))
    if shorten._cost(series, 1) <= limit:  # then it fits, and one more point would not
        assert _numbers(fitted) <= limit
        assert shorten._cost(series, cap + 1) > limit
    for (points, _, extra), step in zip(shapes, fitted[0]["steps"], strict=True):
        assert len(step["values"]["trajectory.time_from_start"]) == min(points, cap)
        assert len(step["values"]["v"]) == min(extra, cap)


def test_a_sidecar_that_would_still_be_too_large_keeps_statuses_without_values(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    outcomes = [_outcome(t, [_step({"joint_values": [0.25] * 6})] * 3) for t in ("a", "b")]
    sidecar = {"signature": {"kind": "value"}, "outcomes": outcomes}
    monkeypatch.setattr(shorten, "MAX_SIDECAR_BYTES", len(encode_sidecar(sidecar)) - 1)
    data = json.loads(encode_sidecar(sidecar))
    assert data["signature"] == {"kind": "value"}
    for outcome in data["outcomes"]:
        assert outcome["values"] == {} and [s["status"] for s in outcome["steps"]] == ["ok"] * 3
        assert all(s["values"] == {} and "values not recorded" in s["shortened"] for s in outcome["steps"])


def test_a_campaign_writes_a_long_plan_sidecar_that_replays(tmp_path: Path) -> None:
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    corpus.mkdir()
    case = {"rrosfuzz": 1, "msg_type": "rrosfuzz/Scenario", "message": {"steps": LONG_PLAN}}
    (corpus / "long-plan").write_text(json.dumps(case))
    done = fuzz(
        str(corpus),
        "-runs=0",
        "--op=scenario",
        "--robot=probot_anno",
        f"--artifacts={artifacts}",
        "--no-progress",
    )
    assert done.returncode == 0, done.stderr[-2000:]  # a known_limitation is not a finding
    assert "known_limitation 1" in done.stderr
    (side,) = artifacts.glob("crash-*.json")
    assert side.stat().st_size < MAX_SIDECAR_BYTES // 8
    data = read_sidecar(side.with_suffix(""))
    assert data is not None and data["signature"]["kind"] == "known_limitation"
    notes = [s.get("shortened", "") for o in data["outcomes"] for s in o["steps"]]
    assert sum("of 35450 points kept" in n for n in notes) == 2, notes
    view = view_of(data)  # the report draws what was kept and says so under the figure
    assert view is not None and [p.index for p in view.plots] == [6]
    assert [n.split(":")[0] for n in view.plots[0].notes if "points kept" in n] == ["native", "python"]
    again = fuzz(str(side.with_suffix("")), "--no-progress")
    assert again.returncode == 1, again.stderr[-2000:]  # replay: exit 1 while it diverges, 2 if unreadable
    assert "still diverges (same signature)" in again.stdout


def test_a_sidecar_larger_than_readers_accept_is_not_read(tmp_path: Path) -> None:
    """Written by an older version, or planted: triage says why it has no bucket of its own,
    and nothing reads the file (a sparse file of 32 MiB + 1 byte, not valid JSON either)."""
    from fuzzer.artifacts.store import load_sidecar
    from fuzzer.triage import pipeline

    crash = tmp_path / ("crash-" + "ab" * 20)
    crash.write_bytes(b'{"rrosfuzz": 1}')
    with open(crash.with_name(crash.name + ".json"), "wb") as handle:
        handle.truncate(MAX_SIDECAR_BYTES + 1)
    assert load_sidecar(crash) is None
    (bucket,) = pipeline.collect(tmp_path)
    assert bucket.signature is None
    assert f"its sidecar is larger than {MAX_SIDECAR_BYTES} bytes: not read" in bucket.describe()
