"""Hostile ``.msg`` definitions (issue 12): every one is a clear ``MsgError`` naming the file
and line, or the documented behaviour; never a ``ValueError`` from ``int()``, a
``MemoryError``, a hang or a traceback.

Each row lays out definitions ``{'p/Type': text or bytes}`` under a temporary root and
asks the registry for ``p/A``. ``expect`` is ``None`` when the definition must be
accepted, otherwise a regular expression the ``MsgError`` message must match.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import pytest

from fuzzer.input.msgdef import MAX_FIXED_VALUES, MAX_MSG_BYTES, MessageRegistry, MsgError, parse_msg

BIG = "9" * 5000  # past Python's int-string limit (4300 digits)


@dataclass(frozen=True)
class Row:
    definitions: dict[str, str | bytes]
    expect: str | None  # None: accepted; else a regex of the MsgError message


ROWS: dict[str, Row] = {
    # numbers that int() refuses or that no field could hold
    "array_length_5000_digits": Row({"p/A": f"float64[{BIG}] x\n"}, r"A\.msg:1: fixed array length must be"),
    "array_length_25_digits": Row({"p/A": "int8[" + "1" * 25 + "] x\n"}, r"A\.msg:1: fixed array length"),
    "array_length_leading_zeros_5000": Row({"p/A": "int8[" + "0" * 5000 + "8] x\n"}, None),
    "array_length_zero": Row({"p/A": "int8[0] x\n"}, r"A\.msg:1: fixed array length"),
    "array_length_arabic_digit": Row({"p/A": "int8[\u0663] x\n"}, r"A\.msg:1: invalid type"),
    "array_length_negative": Row({"p/A": "int8[-3] x\n"}, r"A\.msg:1: invalid type"),
    "int32_constant_5000_digits": Row(
        {"p/A": f"int32 C={BIG}\n"}, r"A\.msg:1: int32 constant 9+\.\.\. out of range"
    ),
    "int64_constant_minus_5000_digits": Row({"p/A": f"int64 C=-{BIG}\n"}, r"A\.msg:1: int64 constant"),
    "uint64_constant_21_digits": Row({"p/A": "uint64 C=" + "1" * 21 + "\n"}, r"A\.msg:1: uint64 constant"),
    "uint64_constant_max": Row({"p/A": f"uint64 C={2**64 - 1}\n"}, None),
    "uint64_constant_max_plus_1": Row(
        {"p/A": f"uint64 C={2**64}\n"}, r"A\.msg:1: uint64 constant .* out of range"
    ),
    "int8_constant_leading_zeros_5000": Row({"p/A": "int8 C=-" + "0" * 5000 + "7\n"}, None),
    "int_constant_underscores": Row({"p/A": "int32 C=1_000\n"}, r"A\.msg:1: invalid int32 constant"),
    "int_constant_arabic_digits": Row({"p/A": "int32 C=\u0663\u0663\n"}, r"A\.msg:1: invalid int32 constant"),
    "float_constant_5000_digits_is_inf": Row({"p/A": f"float64 C={BIG}\n"}, None),
    "float_constant_5000_digit_exponent": Row({"p/A": f"float32 C=1e-{BIG}\n"}, None),
    "bool_constant_5000_digits": Row({"p/A": f"bool C={BIG}\n"}, r"A\.msg:1: invalid bool constant"),
    # bytes and layout
    "latin1_bytes": Row({"p/A": b"# caf\xe9\nint32 x\n"}, r"A\.msg: cannot read message definition"),
    "utf16_with_bom": Row({"p/A": "int32 x\n".encode("utf-16")}, r"A\.msg: cannot read message definition"),
    "nul_byte_in_field": Row({"p/A": "int32 x\x00y\n"}, r"A\.msg:1: invalid field name"),
    "carriage_returns_only": Row({"p/A": "int32 a\rint32 b\r"}, r"A\.msg:1: expected 'type name'"),
    "over_size_limit": Row(
        {"p/A": "#" * MAX_MSG_BYTES + "\nint32 x\n"}, r"A\.msg: cannot read .*larger than 1 MiB"
    ),
    "at_size_limit": Row({"p/A": "#" * (MAX_MSG_BYTES - 9) + "\nint32 x\n"}, None),
    # types
    "fixed_arrays_multiply_past_budget": Row(
        {"p/A": "B[1024] b\n", "p/B": "C[1024] c\n", "p/C": "float64[1024] x\n"},
        rf"B\.msg:1: p/B holds more than {MAX_FIXED_VALUES} values",
    ),
    "fixed_arrays_at_budget": Row({"p/A": "B[64] b\n", "p/B": "float64[1024] x\n"}, None),
    "time_counts_twice_past_budget": Row(
        {"p/A": "time[1024] t\nB[32] b\n", "p/B": "time[1024] u\n"}, r"A\.msg:2"
    ),
    "variable_arrays_do_not_count": Row(
        {"p/A": "B[] b\n", "p/B": "float64[1024] x\nfloat64[1024] y\n"}, None
    ),
    "recursive_self": Row({"p/A": "A[] children\n"}, r"recursive message definition: p/A -> p/A"),
    "recursive_through_fixed_array": Row(
        {"p/A": "B[2] b\n", "p/B": "A a\n"}, r"recursive message definition"
    ),
    "nesting_60_deep": Row(
        {**{f"p/{'A' if i == 0 else f'T{i}'}": f"T{i + 1} n\n" for i in range(60)}, "p/T60": "int8 x\n"},
        r"nesting deeper than 32",
    ),
    "unknown_nested_type": Row(
        {"p/A": "Missing m\n"}, r"unknown message type 'p/Missing' \(referenced by field 'm'"
    ),
}


def _lay_out(root: Path, definitions: dict[str, str | bytes]) -> MessageRegistry:
    for name, text in definitions.items():
        package, type_name = name.split("/")
        path = root / package / "msg" / f"{type_name}.msg"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8"))
    return MessageRegistry([root])


@pytest.mark.parametrize("name", sorted(ROWS))
def test_hostile_definition(tmp_path: Path, name: str) -> None:
    row = ROWS[name]
    registry = _lay_out(tmp_path, row.definitions)
    if row.expect is None:
        spec = registry.get("p/A")
        registry.default("p/A")  # builds every fixed-size value eagerly: bounded by MAX_FIXED_VALUES
        assert spec.full_name == "p/A"
    else:
        with pytest.raises(MsgError, match=row.expect):
            registry.get("p/A")


def test_accepted_values_are_the_documented_ones(tmp_path: Path) -> None:
    """Leading zeros are ignored; a float literal past float64 is inf (ROS1 genpy does the same)."""
    registry = _lay_out(tmp_path, {"p/A": f"int8 C=-{'0' * 5000}7\nfloat64 F={BIG}\nint8[{'0' * 5000}8] x\n"})
    spec = registry.get("p/A")
    assert [c.value for c in spec.constants] == [-7, math.inf]
    assert spec.fields[0].length == 8


def test_parse_msg_names_the_source_and_line() -> None:
    with pytest.raises(MsgError, match=r"^defs/A\.msg:3: fixed array length"):
        parse_msg(f"int8 a\n\nfloat64[{BIG}] x\n", "p/A", "defs/A.msg")
    with pytest.raises(MsgError, match=r"^<string>:2: int16 constant"):
        parse_msg(f"int8 a\nint16 C=+{BIG}\n", "p/A")


@pytest.mark.parametrize(
    ("kind", "says"),
    [
        ("fifo", "is a FIFO, not a regular file"),
        ("dev_zero", "is a device, not a regular file"),
        ("directory", "is a folder, not a regular file"),
        ("dangling", "cannot read message definition: No such file"),
        ("link_out", "a link out of its message folder"),
    ],
)
def test_non_regular_definition_files_are_not_opened(tmp_path: Path, kind: str, says: str) -> None:
    """A FIFO (which would block), /dev/zero (endless) or a folder named A.msg is not a definition,
    and the error says what it is (it said "unknown message type"); a link out of the folder is
    not followed (a link to /etc/passwd echoed its first line in the parse error)."""
    root = tmp_path / "root"
    folder = root / "p" / "msg"
    folder.mkdir(parents=True)
    target = folder / "A.msg"
    outside = tmp_path / "secret.txt"
    outside.write_text("root:x:0:0:root:/root:/bin/bash\n")
    if kind == "fifo":
        os.mkfifo(target)
    elif kind == "dev_zero":
        target.symlink_to("/dev/zero")
    elif kind == "dangling":
        target.symlink_to(tmp_path / "nothing.msg")
    elif kind == "link_out":
        target.symlink_to(outside)
    else:
        target.mkdir()
    with pytest.raises(MsgError, match=says) as raised:
        MessageRegistry([root]).get("p/A")
    assert "root:x" not in str(raised.value)
    assert "p/A" not in MessageRegistry([root]).known() or kind == "link_out"
    inside = folder / "B.msg"
    (folder / "real.txt").write_text("int8 x\n")
    inside.symlink_to(folder / "real.txt")  # a link inside the folder is read
    assert MessageRegistry([root]).get("p/B").fields[0].name == "x"
