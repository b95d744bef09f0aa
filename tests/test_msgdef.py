"""Tests of fuzzer.input.msgdef: .msg parsing, registry lookup, validation and message classes."""

from __future__ import annotations

import copy
import dataclasses
import math
from pathlib import Path
from typing import Any

import pytest

from fuzzer.input.msgdef import (
    SHIPPED_MSG_ROOT,
    ConstantSpec,
    FieldSpec,
    MessageRegistry,
    MsgError,
    RosDuration,
    RosTime,
    parse_msg,
)

SYSTEM_ROOT = Path("/usr/share")
SYSTEM_FILES = sorted(SYSTEM_ROOT.glob("*_msgs/msg/*.msg"))
needs_system_msgs = pytest.mark.skipif(
    not (SYSTEM_ROOT / "sensor_msgs" / "msg" / "JointState.msg").is_file(),
    reason="Debian ROS message packages (ros-sensor-msgs, ...) not installed",
)

SHIPPED = [
    "geometry_msgs/Point",
    "geometry_msgs/PointStamped",
    "geometry_msgs/Pose",
    "geometry_msgs/PoseArray",
    "geometry_msgs/PoseStamped",
    "geometry_msgs/Quaternion",
    "sensor_msgs/JointState",
    "std_msgs/Empty",
    "std_msgs/Float64",
    "std_msgs/Float64MultiArray",
    "std_msgs/Header",
    "std_msgs/MultiArrayDimension",
    "std_msgs/MultiArrayLayout",
    "std_msgs/String",
]


def write_msgs(root: Path, definitions: dict[str, str]) -> MessageRegistry:
    """Lay out ``{'pkg/Type': text}`` under ``root`` and return a registry searching it."""
    for name, text in definitions.items():
        package, type_name = name.split("/")
        path = root / package / "msg" / f"{type_name}.msg"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return MessageRegistry([root])


@pytest.fixture(scope="module")
def shipped() -> MessageRegistry:
    return MessageRegistry()


@pytest.fixture(scope="module")
def system() -> MessageRegistry:
    return MessageRegistry([SYSTEM_ROOT])


def _resolvable(system: MessageRegistry, known: list[str]) -> list[str]:
    """The known definitions that must resolve: every one of a ``*_msgs`` package.

    Other packages' .msg files can lie under /usr/share without their dependencies (Debian's
    libactionlib-dev ships actionlib/msg/*.msg that use actionlib_msgs/GoalID, whose .msg files
    no Debian package ships); those must fail with a MsgError naming the missing type.
    """
    must = []
    for name in known:
        if name.split("/", 1)[0].endswith("_msgs"):
            must.append(name)
            continue
        try:
            system.get(name)
            system.default(name)
        except MsgError as exc:
            assert "unknown message type" in str(exc), exc
            continue
        must.append(name)
    return must


# --------------------------------------------------------------------------- shipped definitions


def test_shipped_definitions_are_known_and_resolve(shipped: MessageRegistry) -> None:
    assert shipped.known() == SHIPPED
    for name in SHIPPED:
        spec = shipped.get(name)
        assert spec.full_name == name
        assert Path(spec.source).is_relative_to(SHIPPED_MSG_ROOT)
        assert spec.fields or name == "std_msgs/Empty"


def test_joint_state_fields(shipped: MessageRegistry) -> None:
    spec = shipped.get("sensor_msgs/JointState")
    assert spec.fields == (
        FieldSpec("header", "std_msgs/Header", False, None),
        FieldSpec("name", "string", True, None),
        FieldSpec("position", "float64", True, None),
        FieldSpec("velocity", "float64", True, None),
        FieldSpec("effort", "float64", True, None),
    )
    assert spec.constants == ()
    assert not spec.fields[0].is_builtin
    assert all(f.is_builtin for f in spec.fields[1:])
    header = shipped.get("std_msgs/Header")
    assert [(f.name, f.type) for f in header.fields] == [
        ("seq", "uint32"),
        ("stamp", "time"),
        ("frame_id", "string"),
    ]


def test_unqualified_nested_types_resolve_to_own_package(shipped: MessageRegistry) -> None:
    assert [f.type for f in shipped.get("geometry_msgs/Pose").fields] == [
        "geometry_msgs/Point",
        "geometry_msgs/Quaternion",
    ]
    assert [f.type for f in shipped.get("geometry_msgs/PoseStamped").fields] == [
        "std_msgs/Header",
        "geometry_msgs/Pose",
    ]
    layout = shipped.get("std_msgs/MultiArrayLayout").fields[0]
    assert layout == FieldSpec("dim", "std_msgs/MultiArrayDimension", True, None)


@needs_system_msgs
@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_definitions_match_debian(name: str) -> None:
    """Our hand-written definitions declare the same fields and constants as Debian's."""
    package, type_name = name.split("/")
    debian = SYSTEM_ROOT / package / "msg" / f"{type_name}.msg"
    ours = SHIPPED_MSG_ROOT / package / "msg" / f"{type_name}.msg"
    theirs_spec = parse_msg(debian.read_text(encoding="utf-8"), name)
    ours_spec = parse_msg(ours.read_text(encoding="utf-8"), name)
    assert ours_spec.fields == theirs_spec.fields
    assert ours_spec.constants == theirs_spec.constants


# --------------------------------------------------------------------------- Debian definitions


@needs_system_msgs
def test_every_system_definition_parses_and_resolves(system: MessageRegistry) -> None:
    assert len(SYSTEM_FILES) >= 80
    for path in SYSTEM_FILES:
        name = f"{path.parent.parent.name}/{path.stem}"
        parse_msg(path.read_text(encoding="utf-8"), name, str(path))
    known = system.known()
    assert {f"{p.parent.parent.name}/{p.stem}" for p in SYSTEM_FILES} <= set(known)
    for name in _resolvable(system, known):
        spec = system.get(name)
        system.validate(name, system.default(name))
        for fld in spec.fields:
            if not fld.is_builtin:
                assert fld.type in known


@needs_system_msgs
def test_camera_info_fixed_arrays(system: MessageRegistry) -> None:
    fields = {f.name: f for f in system.get("sensor_msgs/CameraInfo").fields}
    assert fields["K"] == FieldSpec("K", "float64", True, 9)
    assert fields["R"] == FieldSpec("R", "float64", True, 9)
    assert fields["P"] == FieldSpec("P", "float64", True, 12)
    assert fields["D"] == FieldSpec("D", "float64", True, None)
    assert fields["roi"].type == "sensor_msgs/RegionOfInterest"
    assert fields["header"].type == "std_msgs/Header"
    default = system.default("sensor_msgs/CameraInfo")
    assert default["K"] == [0.0] * 9
    assert default["D"] == []


@needs_system_msgs
def test_system_constants(system: MessageRegistry) -> None:
    status = system.get("sensor_msgs/NavSatStatus")
    consts = {c.name: c for c in status.constants}
    assert consts["STATUS_NO_FIX"] == ConstantSpec("STATUS_NO_FIX", "int8", -1)
    assert consts["SERVICE_COMPASS"] == ConstantSpec(
        "SERVICE_COMPASS", "uint16", 4
    )  # trailing comment dropped
    assert [f.name for f in status.fields] == ["status", "service"]
    rng = {c.name: c.value for c in system.get("sensor_msgs/Range").constants}
    assert rng == {"ULTRASOUND": 0, "INFRARED": 1}  # written without spaces around '='
    assert len(system.get("sensor_msgs/BatteryState").constants) == 21


@needs_system_msgs
def test_system_aliases(system: MessageRegistry) -> None:
    assert system.get("std_msgs/Char").fields == (FieldSpec("data", "uint8", False, None),)
    assert system.get("std_msgs/Byte").fields == (FieldSpec("data", "int8", False, None),)
    assert system.get("std_msgs/ByteMultiArray").fields[1] == FieldSpec("data", "int8", True, None)
    assert system.get("std_msgs/Empty").fields == ()
    assert system.get("std_msgs/Duration").fields == (FieldSpec("data", "duration", False, None),)
    qualified = {f.name: f.type for f in system.get("geometry_msgs/Inertia").fields}
    assert qualified["com"] == "geometry_msgs/Vector3"


# --------------------------------------------------------------------------- grammar


def test_grammar_details() -> None:
    text = (
        "# leading comment\r\n"
        "\n"
        "  Header   header   # the header\r\n"
        "byte b\n"
        "char c\n"
        "\tfloat32[3]\tv\n"
        "other_pkg/Thing[] things\n"
        "Thing thing\n"
        "std_msgs/Header explicit\n"
        "time[2] stamps\n"
        "duration[] waits\n"
        "string S1 = hello # not a comment = really\n"
        "string S2=\n"
        "int8 NEG = -128\n"
        "uint64 BIG = 18446744073709551615\n"
        "bool T = True\n"
        "bool F=0\n"
        "float32 PI = 3.14159  # comment\n"
        "float64 E = -1e-3\n"
        "float64 NOT_A_NUMBER = nan\n"
        "byte BYTE = -1\n"
    )
    spec = parse_msg(text, "my_pkg/Sample", "sample.msg")
    assert spec.full_name == "my_pkg/Sample"
    assert spec.source == "sample.msg"
    assert [(f.name, f.type, f.is_array, f.length) for f in spec.fields] == [
        ("header", "std_msgs/Header", False, None),
        ("b", "int8", False, None),
        ("c", "uint8", False, None),
        ("v", "float32", True, 3),
        ("things", "other_pkg/Thing", True, None),
        ("thing", "my_pkg/Thing", False, None),
        ("explicit", "std_msgs/Header", False, None),
        ("stamps", "time", True, 2),
        ("waits", "duration", True, None),
    ]
    assert [f.line for f in spec.fields] == [3, 4, 5, 6, 7, 8, 9, 10, 11]
    values = {c.name: (c.type, c.value) for c in spec.constants}
    assert values["S1"] == ("string", "hello # not a comment = really")
    assert values["S2"] == ("string", "")
    assert values["NEG"] == ("int8", -128)
    assert values["BIG"] == ("uint64", 2**64 - 1)
    assert values["T"] == ("bool", True) and values["F"] == ("bool", False)
    assert values["PI"] == ("float32", 3.14159)
    assert values["E"] == ("float64", -1e-3)
    assert math.isnan(float(values["NOT_A_NUMBER"][1]))
    assert values["BYTE"] == ("int8", -1)
    assert type(values["T"][1]) is bool and type(values["NEG"][1]) is int


def test_empty_definition() -> None:
    spec = parse_msg("# nothing here\n\n   \n", "p/Empty")
    assert spec.fields == () and spec.constants == ()


BAD_SNIPPETS = [
    # (text, expected line, fragment of the message)
    ("float64 x\nfloat64\n", 2, "expected 'type name'"),
    ("float64 x y\n", 1, "expected 'type name'"),
    ("float64 1x\n", 1, "invalid field name"),
    ("float64 _x\n", 1, "invalid field name"),
    ("float64 x-y\n", 1, "invalid field name"),
    ("flo@t x\n", 1, "invalid type"),
    ("a/b/C x\n", 1, "invalid type"),
    ("float64[x] v\n", 1, "invalid type"),
    ("float64[-1] v\n", 1, "invalid type"),
    ("float64[[3]] v\n", 1, "invalid type"),
    ("float64[3][3] v\n", 1, "invalid type"),
    ("float64[0] v\n", 1, "fixed array length"),
    ("float64[100000] v\n", 1, "fixed array length"),
    ("---\n", 1, "expected 'type name'"),
    ("\n\nint32 x\nint32 x\n", 4, "duplicate name 'x'"),
    ("int32 X\nint32 X=1\n", 2, "duplicate name 'X'"),
    ("int32 X=1\nint32 X=2\n", 2, "duplicate name 'X'"),
    ("int8 C=128\n", 1, "out of range"),
    ("uint8 C=-1\n", 1, "out of range"),
    ("int32 C=1.5\n", 1, "invalid int32 constant"),
    ("int32 C=0x10\n", 1, "invalid int32 constant"),
    ("int32 C=\n", 1, "invalid int32 constant"),
    ("int32 C=1 2\n", 1, "invalid int32 constant"),
    ("float64 C=abc\n", 1, "invalid float64 constant"),
    ("float64 C=1_000.0\n", 1, "invalid float64 constant"),
    ("float32 C=1e39\n", 1, "out of range"),
    ("bool C=yes\n", 1, "invalid bool constant"),
    ("bool C=2\n", 1, "invalid bool constant"),
    ("time C=0\n", 1, "constant type"),
    ("duration C=0\n", 1, "constant type"),
    ("int32[] C=1\n", 1, "constant type"),
    ("int32[2] C=1\n", 1, "constant type"),
    ("Point C=1\n", 1, "constant type"),
    ("int32 =1\n", 1, "invalid constant name"),
    ("int32 A B=1\n", 1, "invalid constant name"),
    ("int32=1\n", 1, "expected 'type NAME=value'"),
    ("string 9S=x\n", 1, "invalid constant name"),
    ("float64 \u00e9t\u00e9\n", 1, "invalid field name"),
]


@pytest.mark.parametrize(("text", "line", "fragment"), BAD_SNIPPETS)
def test_malformed_definitions_are_rejected(text: str, line: int, fragment: str) -> None:
    with pytest.raises(MsgError) as err:
        parse_msg(text, "bad_pkg/Bad", "bad.msg")
    assert f"bad.msg:{line}:" in str(err.value)
    assert fragment in str(err.value)


@pytest.mark.parametrize("name", ["JointState", "a/b/c", "../etc/passwd", "pkg/", "/Type", "pkg/Ty-pe", ""])
def test_bad_message_names(shipped: MessageRegistry, name: str) -> None:
    with pytest.raises(MsgError, match="invalid message type name"):
        parse_msg("int32 x\n", name)
    with pytest.raises(MsgError, match="invalid message type name"):
        shipped.get(name)


# --------------------------------------------------------------------------- registry


def test_get_accepts_ros2_style_name_and_caches(shipped: MessageRegistry) -> None:
    spec = shipped.get("sensor_msgs/msg/JointState")
    assert spec.full_name == "sensor_msgs/JointState"
    assert shipped.get("sensor_msgs/JointState") is spec


def test_search_order_prefers_earlier_roots(tmp_path: Path) -> None:
    first, second = tmp_path / "a", tmp_path / "b"
    write_msgs(first, {"p/T": "int32 first\n"})
    write_msgs(second, {"p/T": "int32 second\n", "p/U": "T t\n", "std_msgs/Header": "int32 overridden\n"})
    registry = MessageRegistry([first, second])
    assert registry.get("p/T").fields[0].name == "first"
    assert registry.get("p/U").fields[0].type == "p/T"
    assert registry.get("std_msgs/Header").fields[0].name == "seq"  # shipped definitions come first
    assert {"p/T", "p/U", "sensor_msgs/JointState"} <= set(registry.known())
    assert MessageRegistry(str(first)).get("p/T").fields[0].name == "first"  # a single root


def test_unknown_types_name_the_referrer(tmp_path: Path) -> None:
    registry = write_msgs(tmp_path, {"p/A": "# A\nint32 x\nB child\n", "p/Top": "A a\n"})
    with pytest.raises(MsgError) as err:
        registry.get("p/Top")
    text = str(err.value)
    assert "'p/B'" in text and "field 'child' of p/A" in text and "A.msg:3" in text
    with pytest.raises(MsgError, match="unknown message type 'p/Missing'"):
        registry.get("p/Missing")
    with pytest.raises(MsgError, match="unknown message type"):
        registry.default("p/A")


@pytest.mark.parametrize(
    "definitions",
    [
        {"p/A": "A self\n"},
        {"p/A": "A[] children\n"},
        {"p/A": "B b\n", "p/B": "int32 x\nC c\n", "p/C": "p/A[2] a\n"},
    ],
)
def test_recursive_definitions_are_rejected(tmp_path: Path, definitions: dict[str, str]) -> None:
    registry = write_msgs(tmp_path, definitions)
    with pytest.raises(MsgError, match=r"recursive message definition: p/A -> .*p/A"):
        registry.get("p/A")


def test_shared_nested_type_is_not_recursion(tmp_path: Path) -> None:
    registry = write_msgs(
        tmp_path, {"p/A": "B one\nB two\nB[] more\n", "p/B": "C c\nC d\n", "p/C": "bool b\n"}
    )
    assert len(registry.get("p/A").fields) == 3


def test_deep_nesting_is_bounded(tmp_path: Path) -> None:
    chain = {f"p/T{i}": f"T{i + 1} next\n" for i in range(60)}
    chain["p/T60"] = "int32 x\n"
    registry = write_msgs(tmp_path, chain)
    with pytest.raises(MsgError, match="nesting deeper"):
        registry.get("p/T0")
    assert registry.get("p/T40").fields[0].type == "p/T41"


def test_unreadable_definitions(tmp_path: Path) -> None:
    registry = write_msgs(tmp_path, {"p/Ok": "int32 x\n"})
    (tmp_path / "p" / "msg" / "Latin.msg").write_bytes(b"# caf\xe9\nint32 x\n")
    (tmp_path / "p" / "msg" / "Dir.msg").mkdir()
    with pytest.raises(MsgError, match=r"Latin\.msg: cannot read"):
        registry.get("p/Latin")
    with pytest.raises(MsgError, match=r"Dir\.msg: is a folder, not a regular file"):
        registry.get("p/Dir")
    assert "p/Dir" not in registry.known()
    (tmp_path / "p" / "msg" / "Bom.msg").write_bytes(b"\xef\xbb\xbfint32 x\n")
    assert registry.get("p/Bom").fields[0].name == "x"


def test_bad_nested_definition_names_its_file(tmp_path: Path) -> None:
    registry = write_msgs(tmp_path, {"p/A": "B b\n", "p/B": "int32 x\nint32 x\n"})
    with pytest.raises(MsgError, match=r"B\.msg:2: duplicate name"):
        registry.get("p/A")


# --------------------------------------------------------------------------- defaults and validation


def test_defaults(shipped: MessageRegistry) -> None:
    assert shipped.default("sensor_msgs/JointState") == {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "name": [],
        "position": [],
        "velocity": [],
        "effort": [],
    }
    pose = shipped.default("geometry_msgs/PoseStamped")["pose"]
    assert list(pose) == ["position", "orientation"]
    assert pose["orientation"] == {"x": 0.0, "y": 0.0, "z": 0.0, "w": 0.0}
    assert shipped.default("std_msgs/Header") is not shipped.default("std_msgs/Header")


ALL_TYPES = (
    "bool b\nint8 i8\nuint8 u8\nint16 i16\nuint16 u16\nint32 i32\nuint32 u32\nint64 i64\nuint64 u64\n"
    "float32 f32\nfloat64 f64\nstring s\ntime t\nduration d\nfloat32[3] fixed\nstring[] names\n"
    "time[2] stamps\nbyte y\nchar c\nInner[2] inners\nInner inner\n"
)
INNER = "Header header\nuint8[] data\n"


@pytest.fixture(scope="module")
def custom(tmp_path_factory: pytest.TempPathFactory) -> MessageRegistry:
    return write_msgs(tmp_path_factory.mktemp("msgs"), {"t/All": ALL_TYPES, "t/Inner": INNER})


def test_validate_accepts_defaults_and_extremes(custom: MessageRegistry) -> None:
    value = custom.default("t/All")
    custom.validate("t/All", value)
    assert value["fixed"] == [0.0, 0.0, 0.0] and len(value["inners"]) == 2
    extreme = copy.deepcopy(value)
    extreme.update(
        i8=-128, u8=255, i64=-(2**63), u64=2**64 - 1, f32=math.inf, f64=math.nan, s="\u00e9\0\U0001f600",
        t={"secs": 2**32 - 1, "nsecs": 999_999_999}, d={"secs": -(2**31), "nsecs": 0}, names=["a", ""],
    )  # fmt: skip
    extreme["inner"]["data"] = [0, 255, 7]
    custom.validate("t/All", extreme)
    reordered = dict(reversed(list(extreme.items())))
    custom.validate("t/All", reordered)


def _set(value: dict[str, Any], path: str, new: Any) -> None:
    keys = path.replace("[", ".").replace("]", "").split(".")
    target: Any = value
    for key in keys[:-1]:
        target = target[int(key)] if isinstance(target, list) else target[key]
    if isinstance(target, list):
        target[int(keys[-1])] = new
    else:
        target[keys[-1]] = new


BAD_VALUES = [
    # (path to change, new value, path named in the error, fragment)
    ("b", 1, "b", "expected bool"),
    ("i8", True, "i8", "expected int"),
    ("i8", 128, "i8", "out of range"),
    ("u8", -1, "u8", "out of range"),
    ("u64", 2**64, "u64", "out of range"),
    ("i64", -(2**63) - 1, "i64", "out of range"),
    ("i32", 1.0, "i32", "expected int"),
    ("c", 256, "c", "out of range"),
    ("y", 128, "y", "out of range"),
    ("f64", 1, "f64", "expected float"),
    ("f32", True, "f32", "expected float"),
    ("f64", "1.0", "f64", "expected float"),
    ("s", b"bytes", "s", "expected str"),
    ("s", "\ud800", "s", "UTF-8"),
    ("t", 0, "t", "expected time"),
    ("t", {"secs": 0}, "t", "expected time"),
    ("t", {"secs": 0, "nsecs": 0, "x": 1}, "t", "expected time"),
    ("t.secs", -1, "t.secs", "out of range"),
    ("t.secs", 2**32, "t.secs", "out of range"),
    ("t.nsecs", 10**9, "t.nsecs", "out of range"),
    ("t.nsecs", -1, "t.nsecs", "out of range"),
    ("t.secs", False, "t.secs", "expected int"),
    ("d.secs", -(2**31) - 1, "d.secs", "out of range"),
    ("d.secs", 2**31, "d.secs", "out of range"),
    ("fixed", [0.0, 0.0], "fixed", "exactly 3"),
    ("fixed", (0.0, 0.0, 0.0), "fixed", "expected a list"),
    ("fixed[1]", 0, "fixed[1]", "expected float"),
    ("names", "abc", "names", "expected a list"),
    ("names", ["a", 1], "names[1]", "expected str"),
    ("stamps[1].nsecs", 2**40, "stamps[1].nsecs", "out of range"),
    ("inners", [], "inners", "exactly 2"),
    ("inners[1].header.stamp.secs", -5, "inners[1].header.stamp.secs", "out of range"),
    ("inners[0].data", [1, 256], "inners[0].data[1]", "out of range"),
    ("inner", None, "inner", "expected a dict"),
    ("inner.header", [], "inner.header", "expected a dict"),
    ("inner.header.seq", True, "inner.header.seq", "expected int"),
    ("inner.header.stamp.nsecs", 1.5, "inner.header.stamp.nsecs", "expected int"),
    ("inner.header.frame_id", None, "inner.header.frame_id", "expected str"),
    ("inner.header.extra", 1, "inner.header.extra", "unexpected field"),
    ("inner.bogus", 1, "inner.bogus", "unexpected field"),
]


@pytest.mark.parametrize(("path", "new", "named", "fragment"), BAD_VALUES)
def test_validate_rejects_wrong_values(
    custom: MessageRegistry, path: str, new: Any, named: str, fragment: str
) -> None:
    value = custom.default("t/All")
    _set(value, path, new)
    with pytest.raises(MsgError) as err:
        custom.validate("t/All", value)
    assert f"at '{named}'" in str(err.value)
    assert fragment in str(err.value)


def test_validate_missing_fields_and_non_dicts(shipped: MessageRegistry) -> None:
    value = shipped.default("sensor_msgs/JointState")
    del value["header"]["stamp"]
    with pytest.raises(MsgError, match=r"at 'header\.stamp': missing field"):
        shipped.validate("sensor_msgs/JointState", value)
    with pytest.raises(MsgError, match="at '<message>': expected a dict"):
        shipped.validate("sensor_msgs/JointState", [])


# --------------------------------------------------------------------------- message classes


def test_make_class_round_trip(shipped: MessageRegistry) -> None:
    cls = shipped.make_class("sensor_msgs/JointState")
    assert cls is shipped.make_class("sensor_msgs/JointState")
    assert cls.__name__ == "JointState" and cls._type == "sensor_msgs/JointState"  # type: ignore[attr-defined]
    assert [f.name for f in dataclasses.fields(cls)] == ["header", "name", "position", "velocity", "effort"]
    value = {
        "header": {"seq": 3, "stamp": {"secs": 10, "nsecs": 5}, "frame_id": "base"},
        "name": ["j1", "j2"],
        "position": [0.5, -1.0],
        "velocity": [],
        "effort": [math.inf, 2.0],
    }
    msg = cls.from_dict(value)  # type: ignore[attr-defined]
    assert msg.header.stamp == RosTime(10, 5)
    assert msg.header.frame_id == "base" and msg.position == (0.5, -1.0)
    assert type(msg.header) is shipped.make_class("std_msgs/Header")
    assert msg.to_dict() == value
    assert list(msg.to_dict()) == list(value)
    assert cls.from_dict(msg.to_dict()) == msg  # type: ignore[attr-defined]
    assert hash(msg) == hash(cls.from_dict(copy.deepcopy(value)))  # type: ignore[attr-defined]
    with pytest.raises(dataclasses.FrozenInstanceError):
        msg.name = ()
    assert cls().to_dict() == shipped.default("sensor_msgs/JointState")
    value["header"]["seq"] = -1
    with pytest.raises(MsgError, match=r"header\.seq"):
        cls.from_dict(value)  # type: ignore[attr-defined]


def test_make_class_all_types(custom: MessageRegistry) -> None:
    cls = custom.make_class("t/All")
    default = cls()
    assert default.fixed == (0.0, 0.0, 0.0)
    assert default.d == RosDuration(0, 0)
    assert default.stamps == (RosTime(), RosTime())
    assert default.to_dict() == custom.default("t/All")
    value = custom.default("t/All")
    value["d"] = {"secs": -3, "nsecs": 7}
    value["inner"]["data"] = [1, 2, 3]
    msg = cls.from_dict(value)  # type: ignore[attr-defined]
    assert msg.d == RosDuration(-3, 7) and msg.inner.data == (1, 2, 3)
    assert msg.to_dict() == value


@needs_system_msgs
def test_make_class_constants(system: MessageRegistry) -> None:
    cls = system.make_class("sensor_msgs/NavSatStatus")
    assert cls.STATUS_NO_FIX == -1 and cls.SERVICE_GALILEO == 8  # type: ignore[attr-defined]
    assert [f.name for f in dataclasses.fields(cls)] == ["status", "service"]
    for name in _resolvable(system, system.known()):
        msg_cls = system.make_class(name)
        assert msg_cls().to_dict() == system.default(name)


@pytest.mark.parametrize("text", ["int32 from\n", "int32 to_dict\n", "int32 from_dict=1\n", "bool None\n"])
def test_make_class_rejects_unusable_attribute_names(tmp_path: Path, text: str) -> None:
    registry = write_msgs(tmp_path, {"p/Kw": text})
    registry.get("p/Kw")  # a legal ROS definition...
    with pytest.raises(MsgError, match="cannot be a class attribute"):
        registry.make_class("p/Kw")  # ...that cannot become a Python class
