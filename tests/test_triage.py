"""Triage (buckets), minimization and coverage of the twin."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from fuzzer.artifacts.divlog import append_line
from fuzzer.execution.records import Signature
from fuzzer.execution.session import RunConfig, Session
from fuzzer.input.testcase import TestCase
from fuzzer.triage import pipeline as triage
from fuzzer.triage.minimize import Minimizer, joints_that_matter

ROOT = Path(__file__).resolve().parents[1]
TIGHT = ("native", "tests.plugins.faults:tight_tolerance")


def fake_crash(
    directory: Path,
    name: str,
    kind: str,
    difference: float = 0.0,
    count: int = 1,
    field: str = "joint_values",
) -> str:
    sig = Signature("move", "ok", "ok", kind, field, ("revolute",) if field == "joint_values" else ())
    unit = {"joint_values": "rad", "position": "m"}.get(field, "status")
    sidecar = {
        "signature": sig.to_json(),
        "config": {},
        "difference": difference,
        "comparison": {"joints": [1] if field == "joint_values" else [], "unit": unit},
        "joint_names": ["shoulder", "elbow"],
    }
    (directory / name).write_bytes(b"{}")
    (directory / f"{name}.json").write_text(json.dumps(sidecar))
    for _ in range(count):
        append_line(directory / "divergences.jsonl", {"sig": sig.key})
    return sig.key


def test_buckets_are_counted_and_ordered_by_severity(tmp_path: Path) -> None:
    # the size of a difference is no longer part of the signature (issue 12, one bug one
    # bucket): the two value buckets differ by field here, and order by their difference
    rep = fake_crash(tmp_path, "crash-aa", "representation", 0.0, count=50)
    small = fake_crash(tmp_path, "crash-bb", "value", 2e-6, count=3)
    big = fake_crash(tmp_path, "crash-cc", "value", 0.1, count=1, field="position")
    status = fake_crash(tmp_path, "crash-dd", "status", count=7, field="status")
    (tmp_path / "crash-ee").write_bytes(b"native crash, no sidecar")
    (tmp_path / "divergences.jsonl").open("a").write("not json\n")
    buckets = triage.collect(tmp_path)
    assert [b.key for b in buckets] == ["crash-ee", status, big, small, rep]
    assert [b.count for b in buckets] == [1, 7, 1, 3, 50]
    lines = triage.table(buckets)
    assert lines[0].startswith("5 bucket(s), 62 divergent execution(s)")
    # joint names and units in titles, never 0-based indices
    assert "value on joint_values (elbow), difference 2e-06 rad: ok vs ok" in "\n".join(lines)
    assert "value on position, difference 0.1 m" in "\n".join(lines)
    assert triage.table([]) == ["no divergences"]
    assert json.loads(triage.dumps(buckets))[1]["key"] == status


def test_a_minimized_file_becomes_the_representative(tmp_path: Path) -> None:
    key = fake_crash(tmp_path, "crash-aa", "status")
    (tmp_path / "minimized-bb").write_bytes(b"{}")
    (tmp_path / "minimized-bb.json").write_text((tmp_path / "crash-aa.json").read_text())
    [bucket] = triage.collect(tmp_path)
    assert bucket.key == key and bucket.best == tmp_path / "minimized-bb"


def test_a_bucket_says_what_the_file_it_shows_holds(tmp_path: Path) -> None:
    """Triage printed the minimized file's path under the original's description and step list
    (16 steps over a file of 2), and of two minimized files the last by name (the triage probe)."""
    key = fake_crash(tmp_path, "crash-aa", "value", 0.5)
    sidecar = json.loads((tmp_path / "crash-aa.json").read_text())
    for name, difference, size in (("minimized-b1", 0.25, 40), ("minimized-b0", 0.125, 80)):
        (tmp_path / name).write_bytes(b" " * size)
        (tmp_path / f"{name}.json").write_text(json.dumps({**sidecar, "difference": difference}))
    [bucket] = triage.collect(tmp_path)
    assert bucket.key == key and bucket.representative == tmp_path / "crash-aa"
    assert bucket.best == tmp_path / "minimized-b1"  # the smaller of the two
    text = "\n".join(triage.table([bucket]))
    assert "difference 0.25 rad" in text and str(tmp_path / "minimized-b1") in text


@pytest.fixture(scope="module")
def tight() -> Session:
    return Session.open(RunConfig(targets=TIGHT))


def divergent_case() -> TestCase:
    message = {
        "header": {"seq": 912, "stamp": {"secs": 77, "nsecs": 123456}, "frame_id": "link_3"},
        "name": [],
        "position": [3.1416 + 5.123456789e-5, 0.3333333, 1.25, -0.75, 2.5, -1.125],
        "velocity": [0.9],
        "effort": [0.5],
    }
    return TestCase("sensor_msgs/JointState", message, lineage=("comb3",), lineage_length=1)


def test_minimize_keeps_the_signature_and_simplifies(tight: Session) -> None:
    case = divergent_case()
    key = tight.evaluator().evaluate(case).signature.key  # type: ignore[union-attr]
    shrunk = Minimizer(tight).minimize(case)
    assert shrunk.complete and shrunk.accepted > 0
    m = shrunk.case.message
    assert tight.evaluator().evaluate(shrunk.case).signature.key == key  # type: ignore[union-attr]
    assert m["position"][1:] == [0.0] * 5 and m["velocity"] == [] and m["effort"] == []
    assert m["header"] == {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}
    assert len(repr(m["position"][0])) < len(repr(case.message["position"][0]))
    assert 3.1416 + 1e-5 < m["position"][0] <= 3.1416 + 1e-4  # still in the band the fault mishandles
    assert joints_that_matter(shrunk.case, tight.reference.joint_names) == ["joint_1"]
    assert shrunk.case.lineage[-1] == "minimize"
    assert Minimizer(tight).minimize(case).case == shrunk.case  # deterministic


def test_minimize_converges_where_any_smaller_value_still_diverges() -> None:
    """A continuous joint wrapped to [0, 2pi) diverges at every negative value: halving took
    -1.81 to -2.5e-94 and never converged (the budget every time, a longer file each run)."""
    session = Session.open(
        RunConfig(
            robot="double_pendulum_continuous", targets=("native", "tests.plugins.faults:wrap_continuous")
        )
    )
    message = {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "name": [], "position": [-1.8123456, 0.0], "velocity": [], "effort": [],
    }  # fmt: skip
    shrunk = Minimizer(session).minimize(TestCase("sensor_msgs/JointState", message))
    assert shrunk.complete and shrunk.case.message["position"] == [-0.5, 0.0], shrunk.case.message
    again = Minimizer(session).minimize(shrunk.case)
    assert again.case.message == shrunk.case.message and again.accepted == 0


def test_minimize_refuses_an_agreeing_input() -> None:
    session = Session.open(RunConfig())
    with pytest.raises(ValueError, match="does not diverge"):
        Minimizer(session).minimize(divergent_case())


def test_minimize_respects_its_budget(tight: Session) -> None:
    shrunk = Minimizer(tight, budget=5).minimize(divergent_case())
    assert shrunk.evaluations <= 5 and not shrunk.complete


def test_cli_triage_minimize_and_coverage(tmp_path: Path) -> None:
    artifacts = tmp_path / "artifacts"

    def run(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [sys.executable, str(ROOT / "fuzz_diff.py"), *args],
            cwd=ROOT,
            text=True,
            capture_output=True,
            timeout=180,
            check=False,
        )

    fuzz = run(
        str(tmp_path / "corpus"),
        "-runs=4000",
        "-seed=1",
        f"--artifacts={artifacts}",
        "--targets=" + ",".join(TIGHT),
        "--no-progress",
    )
    assert fuzz.returncode == 1, fuzz.stderr[-2000:]  # it finds new divergences
    listed = run("triage", str(artifacts))
    assert listed.returncode == 0 and "bucket(s)" in listed.stdout
    crash = next(p for p in artifacts.glob("crash-*") if not p.name.endswith(".json"))
    shrunk = run("minimize", str(crash), "--trust-sidecar")  # its sidecar names a plugin target
    assert shrunk.returncode == 0 and "minimized to" in shrunk.stdout, shrunk.stderr[-2000:]
    minimized = next(artifacts.glob("minimized-*[0-9a-f]"))
    assert run(str(minimized), "--trust-sidecar").stdout.count("still diverges (same signature)") == 1
    assert str(minimized) in run("triage", str(artifacts)).stdout
    cov = run("coverage", str(tmp_path / "corpus"), "--html", str(tmp_path / "html"))
    assert cov.returncode == 0, cov.stderr[-2000:]
    assert "python_impl coverage over" in cov.stdout and "branches" in cov.stdout
    assert (tmp_path / "html" / "index.html").is_file()
    bad = run("triage", str(tmp_path / "missing"))
    assert bad.returncode == 2 and "no such file" in bad.stderr
