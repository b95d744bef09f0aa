"""The libFuzzer glue without libFuzzer: mutator, crossover, TestOneInput, artifacts."""

from __future__ import annotations

import hashlib
import json
import math
import random
import sys
from pathlib import Path

import pytest

from fuzzer import harness as harness_module
from fuzzer.artifacts.divlog import CampaignLog, read_lines
from fuzzer.artifacts.sidecar_record import build_sidecar
from fuzzer.artifacts.store import ArtifactStore, ArtifactsUnwritable, load_sidecar
from fuzzer.execution.session import RunConfig, Session
from fuzzer.execution.targets import module_of
from fuzzer.generation import corpus
from fuzzer.harness import DivergenceFound, Harness
from fuzzer.input.testcase import TestCase, decode
from fuzzer.mutation import mutators, session_values
from fuzzer.selection.guidance import Features
from fuzzer.selection.state import Pool


def make_harness(tmp_path: Path, targets: tuple[str, str] = ("native", "python"), **kw) -> Harness:  # type: ignore[no-untyped-def]
    config = RunConfig(targets=targets, **kw)
    session = Session.open(config)
    seeds = corpus.make_seeds(session, 8, 0)
    ctx = mutators.MutationContext(
        rng=random.Random(0),
        field_types=session_values.field_types(session, config.message_type),
        interesting_floats=tuple(session_values.interesting_values(session)),
    )
    versions = {"python": "test"}
    return Harness(
        evaluator=session.evaluator(),
        store=ArtifactStore(tmp_path / "artifacts"),
        features=Features(enabled=False),
        context=ctx,
        sidecar=lambda case, data, ev: build_sidecar(session, case, data, ev, versions, "digest"),
        seeds=seeds,
    )


def test_mutator_never_raises_and_respects_max_size(tmp_path: Path) -> None:
    h = make_harness(tmp_path)
    rng = random.Random(1)
    inputs = [
        h.seeds[0].encode(),
        b"",
        b"garbage",
        bytes(rng.randrange(256) for _ in range(300)),
        b'{"rrosfuzz":1}',
    ]
    for i in range(400):
        data = inputs[i % len(inputs)]
        out = h.mutate(data, 4096, i)
        assert isinstance(out, bytes) and len(out) <= 4096
        case = decode(out)  # garbage parents restart from a seed ("repair")
        assert case.msg_type == "sensor_msgs/JointState"
        assert len(h.mutate(data, 10, i)) <= 10


def test_mutation_is_deterministic_for_a_seed(tmp_path: Path) -> None:
    a, b = make_harness(tmp_path / "a"), make_harness(tmp_path / "b")
    data = a.seeds[3].encode()
    assert [a.mutate(data, 4096, s) for s in range(50)] == [b.mutate(data, 4096, s) for s in range(50)]


def test_lineage_records_the_mutator(tmp_path: Path) -> None:
    h = make_harness(tmp_path)
    parent = h.seeds[0]
    child = decode(h.mutate(parent.encode(), 4096, 7))
    assert child.lineage[:-1] == parent.lineage and child.lineage[-1] in {*mutators.MUTATORS, "noop"}
    spliced = decode(h.crossover(h.seeds[1].encode(), h.seeds[2].encode(), 4096, 3))
    assert spliced.lineage[-1] == "splice"


def test_inputs_are_counted_by_verdict(tmp_path: Path) -> None:
    h = make_harness(tmp_path)
    h.test_one_input(b"not a test case")
    nan_case = TestCase("sensor_msgs/JointState", dict(h.seeds[0].message, position=[math.nan] * 6))
    h.test_one_input(nan_case.encode())
    wrong_type = TestCase("geometry_msgs/Pose", {"x": 1})
    h.test_one_input(wrong_type.encode())
    h.test_one_input(h.seeds[0].encode())
    s = h.stats
    assert (s.execs, s.malformed, s.filtered, s.divergences) == (4, 2, 1, 0)


def test_the_decode_cache_is_bounded_in_bytes_and_in_count(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    h = make_harness(tmp_path)
    cases = [
        TestCase(h.seeds[0].msg_type, dict(h.seeds[0].message, position=[0.01 * i] * 6)) for i in range(12)
    ]
    datas = [c.encode() for c in cases]
    size = max(map(len, datas))
    monkeypatch.setattr(harness_module, "DECODE_BYTES", 3 * size)
    for data in datas[:5]:
        h.test_one_input(data)
    h.test_one_input(datas[4])  # seen again: counted once
    assert list(h._decoded) == datas[2:5] and h._decoded_bytes == sum(map(len, datas[2:5]))
    assert h._decode(datas[2]) == (cases[2], True) and h._decode(datas[0])[1] is False
    monkeypatch.setattr(harness_module, "DECODE_BYTES", 100 * size)
    monkeypatch.setattr(harness_module, "DECODE_CACHE", 4)
    for data in datas[5:]:
        h.test_one_input(data)
    assert list(h._decoded) == datas[-4:] and h._decoded_bytes == sum(map(len, datas[-4:]))
    monkeypatch.setattr(
        harness_module, "DECODE_BYTES", 1
    )  # one input larger than the bound: the newest stays
    h.test_one_input(datas[0])
    assert list(h._decoded) == [datas[0]] and h._decoded_bytes == len(datas[0])


def test_no_filter_evaluates_non_finite_inputs(tmp_path: Path) -> None:
    h = make_harness(tmp_path, filtering=False)
    nan_case = TestCase("sensor_msgs/JointState", dict(h.seeds[0].message, position=[math.nan] * 6))
    h.test_one_input(nan_case.encode())
    assert h.stats.filtered == 0 and h.stats.divergences == 0  # both targets reject it the same way


def test_a_divergence_writes_one_crash_file_per_signature(tmp_path: Path) -> None:
    h = make_harness(tmp_path, targets=("native", "tests.plugins.faults:tight_tolerance"))
    base = h.seeds[0].message
    for delta in (5e-5, 6e-5, 7e-5):
        message = dict(base, name=[], position=[3.1416 + delta, 0.0, 0.0, 0.0, 0.0, 0.0])
        h.test_one_input(TestCase("sensor_msgs/JointState", message).encode())
    assert h.stats.divergences == 3 and len(h.stats.signatures) == 1
    files = h.store.crash_files()
    assert len(files) == 1
    sidecar = load_sidecar(files[0])
    assert sidecar is not None
    assert sidecar["signature"]["kind"] == "status"
    assert sidecar["signature"]["outcome_b"] == "rejected:OutOfBoundsError:30"
    assert sidecar["config"]["targets"] == ["native", "tests.plugins.faults:tight_tolerance"]
    assert decode(files[0].read_bytes()).message["position"][0] == 3.1416 + 5e-5
    assert [o["target"] for o in sidecar["outcomes"]] == ["native", "tests.plugins.faults:tight_tolerance"]
    json.dumps(sidecar)  # JSON all the way down


@pytest.mark.parametrize("failing", ["crash file", "log"])
def test_an_unwritable_artifacts_folder_stops_with_the_input_it_could_not_save(
    tmp_path: Path, failing: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # a full disk: Atheris reported the OSError as a crash of the target, libFuzzer wrote an empty
    # crash file, and the divergence's input was nowhere
    h = make_harness(tmp_path, targets=("native", "tests.plugins.faults:tight_tolerance"))
    h.log = CampaignLog(tmp_path)

    def full(*_: object, **__: object) -> None:
        raise OSError(28, "No space left on device", str(tmp_path / "artifacts" / "x"))

    if failing == "crash file":
        monkeypatch.setattr(h.store, "record", full)
    else:
        monkeypatch.setattr(h.log, "divergence", full)
    message = dict(h.seeds[0].message, name=[], position=[3.1416 + 5e-5, 0.0, 0.0, 0.0, 0.0, 0.0])
    data = TestCase("sensor_msgs/JointState", message).encode()
    with pytest.raises(ArtifactsUnwritable):
        h.test_one_input(data)
    said = capsys.readouterr().err
    assert "cannot write to the artifacts folder" in said and "No space left on device" in said
    assert "could not be saved" in said and data.decode() in said.splitlines()
    assert not h.store.crash_files() and not h.stats.signatures


def test_an_unwritable_stats_log_stops_without_an_input_to_save(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    h = make_harness(tmp_path)
    h.log = CampaignLog(tmp_path)

    def read_only(*_: object) -> None:
        raise OSError(30, "Read-only file system", str(tmp_path / "stats.jsonl"))

    monkeypatch.setattr(h.log, "snapshot", read_only)
    with pytest.raises(ArtifactsUnwritable):
        h.test_one_input(h.seeds[0].encode())  # the first input's snapshot is right away
    said = capsys.readouterr().err
    assert "stats.jsonl: Read-only file system" in said and "could not be saved" not in said


def test_every_divergent_execution_is_a_line_of_the_campaign_log(tmp_path: Path) -> None:
    h = make_harness(tmp_path, targets=("native", "tests.plugins.faults:tight_tolerance"))
    h.log = CampaignLog(tmp_path)
    h.joint_names = tuple(f"joint_{i}" for i in range(1, 7))
    base = h.seeds[0].message
    inputs = []
    for delta in (5e-5, 6e-5):
        message = dict(base, name=[], position=[3.1416 + delta, 0.0, 0.0, 0.0, 0.0, 0.0])
        inputs.append(TestCase("sensor_msgs/JointState", message, lineage=("planted",)).encode())
        h.test_one_input(inputs[-1])
    h.test_one_input(h.seeds[0].encode())  # no divergence: no line
    lines = list(read_lines(tmp_path / "divergences.jsonl"))
    assert [line["sha1"] for line in lines] == [hashlib.sha1(data).hexdigest() for data in inputs]
    first = lines[0]
    assert first["sig"] in h.stats.signatures and first["kind"] == "status"
    assert (first["outcome_a"], first["outcome_b"]) == ("ok", "rejected:OutOfBoundsError:30")
    assert first["strategy"] == "planted" and first["near_zero"] == 5  # five joints at 0.0
    assert first["closer"] == "n/a"  # one target has no final state


def test_the_log_says_which_final_state_is_nearer_the_command(tmp_path: Path) -> None:
    """The paper's Table IV: a ``move`` naming every joint, both targets succeeding, the faulty
    twin wrapping a revolute target in [4.0, 4.05) rad into (-pi, pi] (``wrap_past_pi``, on the
    UR5, whose joints reach 2 pi): the native target ends nearer the command."""
    h = make_harness(tmp_path, targets=("native", "benchmarks.zoo.deep:wrap_past_pi"), robot="ur5")
    h.log = CampaignLog(tmp_path)
    names = [str(n) for n in h.evaluator.runners[0].model.joint_names]
    h.joint_names = tuple(names)
    message = dict(h.seeds[0].message, name=names, position=[4.02, 0.0, 0.0, 0.0, 0.0, 0.0])
    h.test_one_input(TestCase("sensor_msgs/JointState", message).encode())
    (line,) = read_lines(tmp_path / "divergences.jsonl")
    assert (line["outcome_a"], line["outcome_b"]) == ("ok", "ok")
    assert line["closer"] == "a"


def test_stop_on_divergence_raises_after_writing_the_sidecar(tmp_path: Path) -> None:
    h = make_harness(tmp_path, targets=("native", "tests.plugins.faults:tight_tolerance"))
    h.stop_on_divergence = True
    message = dict(h.seeds[0].message, name=[], position=[3.1416 + 5e-5, 0.0, 0.0, 0.0, 0.0, 0.0])
    with pytest.raises(DivergenceFound):
        h.test_one_input(TestCase("sensor_msgs/JointState", message).encode())
    assert list(h.store.directory.glob("crash-*.json"))


def test_pool_prefers_larger_differences() -> None:
    pool = Pool(size=3)
    for d, data in [(0.0, b"zero"), (1e-9, b"a"), (1e-3, b"b"), (1e-6, b"c"), (1.0, b"d")]:
        pool.offer(d, data)
    assert [data for _, data in pool.entries] == [b"c", b"b", b"d"]
    rng = random.Random(0)
    picks = [pool.pick(rng) for _ in range(600)]
    assert picks.count(b"d") > picks.count(b"b") > picks.count(b"c") > 0


def test_the_stats_snapshot_runs_no_code_of_the_instrumented_modules(tmp_path: Path) -> None:
    """A snapshot is due by the clock and runs inside an input's evaluation: code of an
    instrumented module (the targets', the oracle's) run there would be coverage that depends
    on the time, and two runs of one ``-seed`` would keep different corpora (it did: the twin's
    ``IkMemo.__len__``)."""
    h = make_harness(tmp_path, op="ik")
    h.log = CampaignLog(tmp_path)
    for seed in h.seeds[:3]:
        h.test_one_input(seed.encode())  # the twin's IK memory now holds answers
    instrumented = {module_of("python"), "fuzzer.execution.oracle"}  # as fuzzer.selection.instrument
    assert "python_impl.kinematics" in sys.modules
    called: list[str] = []

    def profile(frame, event, arg):  # type: ignore[no-untyped-def]
        if event == "call":
            called.append(str(frame.f_globals.get("__name__")))

    sys.setprofile(profile)
    try:
        h.maybe_snapshot(force=True)
    finally:
        sys.setprofile(None)
    assert called, "the profiler saw no call at all"
    inside = sorted({m for m in called if any(m == n or m.startswith(n + ".") for n in instrumented)})
    assert inside == []
    memo = list(read_lines(tmp_path / "stats.jsonl"))[-1]["ik_memo"]
    assert memo["kept"] >= 1 and memo["misses"] >= 1
