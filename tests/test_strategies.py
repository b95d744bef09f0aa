"""Tests of fuzzer.generation.strategies (Table I) and fuzzer.generation.seeds (Algorithm 1)."""

from __future__ import annotations

import json
import math
import os
import struct
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, find, given, settings
from hypothesis import strategies as st

from fuzzer.generation.seeds import canonical_json, generate_seeds
from fuzzer.generation.strategies import strategy_for, strategy_table
from fuzzer.input.msgdef import MessageRegistry, MessageSpec, MsgError

REPO = Path(__file__).resolve().parents[1]
SYSTEM_ROOT = Path("/usr/share")
HAVE_SYSTEM = (SYSTEM_ROOT / "sensor_msgs" / "msg" / "CameraInfo.msg").is_file()

ALL_TYPES = (
    "bool b\nint8 i8\nuint8 u8\nint16 i16\nuint16 u16\nint32 i32\nuint32 u32\nint64 i64\nuint64 u64\n"
    "float32 f32\nfloat64 f64\nstring s\ntime t\nduration d\nfloat32[3] fixed\nfloat64[] free\n"
    "time[2] stamps\nbyte y\nchar c\nInner[2] inners\nInner[] more\nInner inner\n"
)
DEFINITIONS = {
    "t/All": ALL_TYPES,
    "t/Inner": "Header header\nuint8[] data\nfloat32[] f32s\n",
    "t/Flag": "bool flag\n",
    "t/Empty": "# no fields\n",
}
PROPERTY = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@pytest.fixture(scope="module")
def registry(tmp_path_factory: pytest.TempPathFactory) -> MessageRegistry:
    root = tmp_path_factory.mktemp("msgs")
    for name, text in DEFINITIONS.items():
        package, type_name = name.split("/")
        (root / package / "msg").mkdir(parents=True, exist_ok=True)
        (root / package / "msg" / f"{type_name}.msg").write_text(text, encoding="utf-8")
    return MessageRegistry([root, *([SYSTEM_ROOT] if HAVE_SYSTEM else [])])


def floats_in(value: Any) -> list[float]:
    """Every float inside a message value."""
    if isinstance(value, float):
        return [value]
    items = value.values() if isinstance(value, dict) else value if isinstance(value, list) else []
    return [x for item in items for x in floats_in(item)]


def assert_field_order(registry: MessageRegistry, spec: MessageSpec, value: dict[str, Any]) -> None:
    assert list(value) == [f.name for f in spec.fields]
    for fld in spec.fields:
        if fld.type in ("time", "duration"):
            for item in value[fld.name] if fld.is_array else [value[fld.name]]:
                assert list(item) == ["secs", "nsecs"]
        elif not fld.is_builtin:
            for item in value[fld.name] if fld.is_array else [value[fld.name]]:
                assert_field_order(registry, registry.get(fld.type), item)


TYPES = ["t/All", "sensor_msgs/JointState", "geometry_msgs/PoseStamped", "std_msgs/Float64MultiArray"]
if HAVE_SYSTEM:
    TYPES += ["sensor_msgs/CameraInfo", "sensor_msgs/NavSatFix", "geometry_msgs/PoseWithCovarianceStamped"]


# --------------------------------------------------------------------------- strategies


@pytest.mark.parametrize("msg_type", TYPES)
@PROPERTY
@given(data=st.data())
def test_generated_values_are_valid_and_ordered(
    registry: MessageRegistry, msg_type: str, data: st.DataObject
) -> None:
    value = data.draw(strategy_for(registry, msg_type))
    registry.validate(msg_type, value)
    assert_field_order(registry, registry.get(msg_type), value)
    assert all(math.isfinite(x) for x in floats_in(value))


@PROPERTY
@given(data=st.data())
def test_all_builtins(registry: MessageRegistry, data: st.DataObject) -> None:
    value = data.draw(strategy_for(registry, "t/All", max_array=3))
    registry.validate("t/All", value)
    assert len(value["fixed"]) == 3 and len(value["stamps"]) == 2 and len(value["inners"]) == 2
    assert len(value["free"]) <= 3 and len(value["more"]) <= 3
    float32s = [value["f32"], *value["fixed"]] + [x for inner in value["more"] for x in inner["f32s"]]
    for x in float32s:
        assert struct.unpack("<f", struct.pack("<f", x))[0] == x
    assert all(0 <= b <= 255 for inner in value["inners"] for b in inner["data"])


@PROPERTY
@given(data=st.data())
def test_special_floats_allowed_still_valid(registry: MessageRegistry, data: st.DataObject) -> None:
    value = data.draw(strategy_for(registry, "t/All", allow_special_floats=True))
    registry.validate("t/All", value)
    for x in [value["f32"], *value["fixed"]]:
        assert math.isnan(x) or struct.unpack("<f", struct.pack("<f", x))[0] == x


def test_special_floats_switch(registry: MessageRegistry) -> None:
    quiet = settings(database=None, max_examples=2000, deadline=None)
    special = strategy_for(registry, "geometry_msgs/Point", allow_special_floats=True)
    assert math.isnan(find(special, lambda v: math.isnan(v["x"]), settings=quiet)["x"])
    assert math.isinf(find(special, lambda v: math.isinf(v["z"]), settings=quiet)["z"])


@PROPERTY
@given(data=st.data())
def test_max_array_zero(registry: MessageRegistry, data: st.DataObject) -> None:
    value = data.draw(strategy_for(registry, "t/All", max_array=0))
    assert value["free"] == [] and value["more"] == [] and len(value["fixed"]) == 3
    assert all(inner["data"] == [] for inner in value["inners"])


JOINTS = ["shoulder", "elbow", "wrist"]


@PROPERTY
@given(data=st.data())
def test_hints_replace_fields(registry: MessageRegistry, data: st.DataObject) -> None:
    hints = {
        "name": st.lists(st.sampled_from(JOINTS), unique=True, min_size=1),
        "position": st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
        "header.frame_id": st.just("base_link"),
        "header.stamp.secs": st.just(42),
    }
    value = data.draw(strategy_for(registry, "sensor_msgs/JointState", hints=hints))
    registry.validate("sensor_msgs/JointState", value)
    assert (
        value["name"] and set(value["name"]) <= set(JOINTS) and len(set(value["name"])) == len(value["name"])
    )
    assert len(value["position"]) == 3 and all(-1.0 <= p <= 1.0 for p in value["position"])
    assert value["header"]["frame_id"] == "base_link"
    assert value["header"]["stamp"]["secs"] == 42
    assert list(value) == ["header", "name", "position", "velocity", "effort"]


@PROPERTY
@given(data=st.data())
def test_hints_through_arrays_and_nesting(registry: MessageRegistry, data: st.DataObject) -> None:
    array_hints = {"layout.dim.label": st.just("rows"), "data": st.just([1.0])}
    value = data.draw(strategy_for(registry, "std_msgs/Float64MultiArray", hints=array_hints))
    assert all(dim["label"] == "rows" for dim in value["layout"]["dim"])
    assert value["data"] == [1.0]
    pose = data.draw(
        strategy_for(registry, "geometry_msgs/PoseStamped", hints={"pose.position.x": st.just(0.25)})
    )
    assert pose["pose"]["position"]["x"] == 0.25
    whole = {"pose": st.just({"position": {"x": 1.0, "y": 2.0, "z": 3.0}, "orientation": {}})}
    assert (
        data.draw(strategy_for(registry, "geometry_msgs/PoseStamped", hints=whole))["pose"]["orientation"]
        == {}
    )


@pytest.mark.parametrize(
    ("hints", "fragment"),
    [
        ({"nmae": st.just([])}, "unknown hint path 'nmae'"),
        ({"header.stamp.sec": st.just(0)}, "unknown hint path"),
        ({"position.x": st.just(0.0)}, "unknown hint path"),
        ({"": st.just(0)}, "unknown hint path"),
        ({"name": ["a"]}, "must be a hypothesis strategy"),
        ({"header": st.just({}), "header.seq": st.just(1)}, "shadowed by the hint on 'header'"),
    ],
)
def test_bad_hints(registry: MessageRegistry, hints: dict[str, Any], fragment: str) -> None:
    with pytest.raises(MsgError, match=fragment):
        strategy_for(registry, "sensor_msgs/JointState", hints=hints)


def test_strategy_errors(registry: MessageRegistry) -> None:
    with pytest.raises(MsgError, match="unknown message type"):
        strategy_for(registry, "nope_msgs/Nothing")
    with pytest.raises(ValueError, match="max_array"):
        strategy_for(registry, "sensor_msgs/JointState", max_array=-1)


def test_strategy_table() -> None:
    table = strategy_table()
    assert {"string", "time", "array", "complex"} <= set(table)
    assert "st.text" in table["string"] and "st.lists" in table["array"]
    assert "Time" in table["time"] and "fixed_dictionaries" in table["complex"]
    table.clear()
    assert strategy_table()


# --------------------------------------------------------------------------- seeds


def test_seeds_distinct_valid_and_deterministic(registry: MessageRegistry) -> None:
    strategy = strategy_for(registry, "sensor_msgs/JointState")
    seeds = generate_seeds(strategy, 25, seed=7)
    assert len(seeds) == 25
    assert len({canonical_json(s) for s in seeds}) == 25
    for value in seeds:
        registry.validate("sensor_msgs/JointState", value)
        assert list(value) == ["header", "name", "position", "velocity", "effort"]
        assert list(value["header"]) == ["seq", "stamp", "frame_id"]
    again = generate_seeds(strategy_for(registry, "sensor_msgs/JointState"), 25, seed=7)
    assert json.dumps(again) == json.dumps(seeds)
    assert json.dumps(generate_seeds(strategy, 25, seed=8)) != json.dumps(seeds)


SCRIPT = """
import json, sys
from fuzzer.input.msgdef import MessageRegistry
from fuzzer.generation.seeds import generate_seeds
from fuzzer.generation.strategies import strategy_for
registry = MessageRegistry()
strategy = strategy_for(registry, "geometry_msgs/PoseStamped", allow_special_floats=True)
sys.stdout.write(json.dumps(generate_seeds(strategy, 15, seed=1234)))
"""


def test_seeds_deterministic_across_processes() -> None:
    outputs = []
    for hash_seed in ("0", "12345"):
        env = {**os.environ, "PYTHONHASHSEED": hash_seed}
        proc = subprocess.run(
            [sys.executable, "-c", SCRIPT],
            cwd=REPO,
            env=env,
            capture_output=True,
            text=True,
            timeout=60,
            check=True,
        )
        outputs.append(proc.stdout)
    here = generate_seeds(
        strategy_for(MessageRegistry(), "geometry_msgs/PoseStamped", allow_special_floats=True), 15, 1234
    )
    assert len(json.loads(outputs[0])) == 15
    assert outputs[0] == outputs[1] == json.dumps(here)


LOCAL_MODULE = """
MAGIC_INTS = [987654321, 123456789, 555555555, 777777777, 4242424242]
MAGIC_FLOATS = [1234.5678, -8765.4321, 3.25e17, 6.02e23]
MAGIC_TEXT = ["rrosfuzz-local-constant", "another-local-constant", "zzz"]
"""


def test_seeds_ignore_literals_of_imported_local_modules(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Hypothesis mines literals from every imported local module; seeds must not depend on them.
    strategy = strategy_for(MessageRegistry(), "sensor_msgs/JointState", max_array=3)
    before = json.dumps(generate_seeds(strategy, 60, seed=99))
    package = tmp_path / "rrosfuzz_local_constants_pkg"
    package.mkdir()
    (package / "__init__.py").write_text(LOCAL_MODULE, encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "rrosfuzz_local_constants_pkg", raising=False)
    __import__("rrosfuzz_local_constants_pkg")
    assert json.dumps(generate_seeds(strategy, 60, seed=99)) == before


def test_seeds_small_spaces(registry: MessageRegistry) -> None:
    flags = generate_seeds(strategy_for(registry, "t/Flag"), 10, seed=3)
    assert sorted(f["flag"] for f in flags) == [False, True]
    assert generate_seeds(strategy_for(registry, "t/Empty"), 5, seed=3) == [{}]
    assert len(generate_seeds(st.sampled_from([{"a": 1}, {"a": 1.0}, {"a": 2}]), 10, seed=0)) == 3


def test_seeds_dedup_by_canonical_json() -> None:
    # Same content in a different key order is one seed; the first drawn order is kept.
    strategy = st.sampled_from([{"a": 1, "b": 2}, {"b": 2, "a": 1}, {"a": 3, "b": 4}])
    seeds = generate_seeds(strategy, 10, seed=0)
    assert len(seeds) == 2
    assert {canonical_json(s) for s in seeds} == {'{"a":1,"b":2}', '{"a":3,"b":4}'}
    zeros = generate_seeds(st.sampled_from([{"x": 0.0}, {"x": -0.0}, {"x": math.nan}]), 10, seed=0)
    assert len(zeros) == 3


def test_seeds_edge_arguments(registry: MessageRegistry) -> None:
    strategy = strategy_for(registry, "geometry_msgs/Point")
    assert generate_seeds(strategy, 0, seed=1) == []
    assert len(generate_seeds(strategy, 1, seed=1)) == 1
    with pytest.raises(ValueError, match="n must be"):
        generate_seeds(strategy, -1, seed=1)
    with pytest.raises(TypeError, match="hypothesis strategy"):
        generate_seeds({"x": 1.0}, 1, seed=1)  # type: ignore[arg-type]


def test_seeds_top_up_with_later_seeds() -> None:
    # 50 distinct values behind a wide integer range: one Hypothesis run of 50 examples draws
    # many duplicates (about 32 distinct), the runs with seed+1, seed+2, ... fill up the rest.
    strategy = st.integers(0, 10**6).map(lambda i: {"i": i % 50})
    seeds = generate_seeds(strategy, 50, seed=5)
    assert sorted(s["i"] for s in seeds) == list(range(50))
    assert len(generate_seeds(strategy, 60, seed=5)) == 50


def test_seeds_hypothesis_cannot_draw_are_a_usage_error(monkeypatch: pytest.MonkeyPatch) -> None:
    # a chain of 1,300 joints: every message past Hypothesis' buffer, Unsatisfiable as a traceback
    from hypothesis.errors import Unsatisfiable

    from fuzzer.execution.session import ConfigError, RunConfig, Session
    from fuzzer.generation import corpus, seeds

    def refuse(*_: object) -> None:
        raise Unsatisfiable("459 of 459 test cases were too large")

    monkeypatch.setattr(seeds, "generate_seeds", refuse)
    with pytest.raises(ConfigError, match="Hypothesis draws no seed message for a chain of 6 joints"):
        corpus.make_seeds(Session.open(RunConfig()), 4, 1)


def test_the_simplest_value_is_checked_before_hypothesis_draws(monkeypatch: pytest.MonkeyPatch) -> None:
    # with the health check suppressed Hypothesis drew 459 overrunning test cases first: a chain
    # of 1,300 joints spent 42 s before its Unsatisfiable
    from hypothesis.errors import Unsatisfiable

    from fuzzer.generation import seeds

    too_large = st.lists(st.floats(0.0, 1.0), min_size=2000, max_size=2000)
    assert not seeds.smallest_fits(too_large)
    assert seeds.smallest_fits(st.lists(st.floats(0.0, 1.0), min_size=600, max_size=600))
    assert seeds.smallest_fits(st.integers().filter(lambda i: i > 5))  # invalid is not too large

    def never(*_: object) -> list[object]:
        raise AssertionError("Hypothesis ran")

    monkeypatch.setattr(seeds, "_draw", never)
    with pytest.raises(Unsatisfiable, match="simplest value is larger"):
        seeds.generate_seeds(too_large, 4, seed=1)
    assert seeds.generate_seeds(too_large, 0, seed=1) == []


def test_the_simplest_check_takes_no_random_choice() -> None:
    from fuzzer.generation import seeds

    values = {"a": st.floats(-1.0, 1.0), "b": st.lists(st.integers(0, 9), max_size=4)}
    strategy = st.fixed_dictionaries(values)
    before = seeds.generate_seeds(strategy, 20, seed=3)
    assert seeds.smallest_fits(strategy)
    assert seeds.generate_seeds(strategy, 20, seed=3) == before
