"""Hostile URDF inputs (issue 12): both targets give the same clear outcome, never a crash.

Every row is one document (text, file bytes, or a special path such as a FIFO) with
the outcome both targets must give: ``"ok"`` (accepted, same name, links and
joints) or the ``URDFError`` code. The rules are in docs/api.md ("URDF rules").

The rows run in child processes (``python -m tests.test_hostile_urdf CHILD ...``),
each row's outcome written as a line as soon as it is known: a row that kills its
process (urdfdom 3.0.1 reaching ``printf`` with a ``%n`` from an attribute) or hangs
(a FIFO opened for a blocking read) fails as ``crashed``/``hung`` and the other
rows still run, in a fresh child.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from robot_api import robots

REPO = Path(__file__).resolve().parent.parent
PCT = "%n%n%s%s"  # the directives that killed urdfdom in the issue
MIB = 1 << 20
LIMIT = 16 * MIB  # docs/api.md: a URDF is at most 16 MiB
SHIPPED = robots.default_robot_path().read_text(encoding="utf-8")
GEOM = '<geometry><box size="1 1 1"/></geometry>'
INERTIA = '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/>'
LONG = "\u00e9" * 700  # 1400 bytes: console_bridge cuts urdfdom's messages at 1023, inside a character
Q0, Q1, QP = '"0"', '"1"', f'"{PCT}"'
LIMIT_EL = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'


def link_doc(inner: str, top: str = "", robot_attrs: str = 'name="r"') -> str:
    return f'<?xml version="1.0"?>\n<robot {robot_attrs}>{top}<link name="a">{inner}</link></robot>\n'


def joint_doc(inner: str = "", attrs: str = 'name="j" type="revolute"', parent: str = "a") -> str:
    head = f'<joint {attrs}><parent link="{parent}"/><child link="b"/><axis xyz="0 0 1"/>'
    body = f"{head}{LIMIT_EL}{inner}</joint>"
    return f'<robot name="r"><link name="a"/><link name="b"/>{body}</robot>'


@dataclass(frozen=True)
class Row:
    kind: str  # "text": a str; "file": these bytes in a file; "special": a path the child prepares
    data: str | bytes
    expect: str  # "ok", "URDF_INVALID" or "URDF_UNSUPPORTED"


INV, UNS, OK = "URDF_INVALID", "URDF_UNSUPPORTED", "ok"

# Every attribute urdfdom 3.0.1 formats with printf (urdf_parser/src/link.cpp, pose.cpp,
# model.cpp), and a sample of the ones it does not: the rule is "no '%' in any attribute but a
# file name" (mesh and texture file names never reach a format string).
PRINTF_ROWS: dict[str, str] = {
    "visual_box_size": link_doc(f'<visual><geometry><box size="{PCT}"/></geometry></visual>'),
    "collision_box_size": link_doc(f'<collision><geometry><box size="{PCT}"/></geometry></collision>'),
    "collision_sphere_radius": link_doc(
        f'<collision><geometry><sphere radius="{PCT}"/></geometry></collision>'
    ),
    "visual_sphere_radius": link_doc(f'<visual><geometry><sphere radius="{PCT}"/></geometry></visual>'),
    "visual_cylinder_length": link_doc(
        f'<visual><geometry><cylinder length="{PCT}" radius="1"/></geometry></visual>'
    ),
    "collision_cylinder_radius": link_doc(
        f'<collision><geometry><cylinder length="1" radius="{PCT}"/></geometry></collision>'
    ),
    "inertial_mass": link_doc(f'<inertial><mass value="{PCT}"/>{INERTIA}</inertial>'),
    "inertia_ixx": link_doc(
        f'<inertial><mass value="1"/>{INERTIA.replace("ixx=" + Q1, "ixx=" + QP)}</inertial>'
    ),
    "inertia_iyz": link_doc(
        f'<inertial><mass value="1"/>{INERTIA.replace("iyz=" + Q0, "iyz=" + QP)}</inertial>'
    ),
    "inertial_origin_xyz": link_doc(f'<inertial><origin xyz="{PCT}"/><mass value="1"/>{INERTIA}</inertial>'),
    "top_material_name_bad_rgba": link_doc("", top=f'<material name="{PCT}"><color rgba="x"/></material>'),
    "top_material_name_no_color": link_doc("", top=f'<material name="{PCT}"/>'),
    "top_material_rgba": link_doc("", top=f'<material name="m"><color rgba="{PCT}"/></material>'),
    "visual_material_name": link_doc(f'<visual>{GEOM}<material name="{PCT}"/></visual>'),
    "visual_material_rgba": link_doc(
        f'<visual>{GEOM}<material name="m"><color rgba="{PCT}"/></material></visual>'
    ),
    "visual_origin_rpy": link_doc(f'<visual><origin rpy="{PCT}"/>{GEOM}</visual>'),
    "visual_name": link_doc(f'<visual name="{PCT}">{GEOM}</visual>'),
    "mesh_scale": link_doc(f'<visual><geometry><mesh filename="m.stl" scale="{PCT}"/></geometry></visual>'),
    "robot_version": link_doc("", robot_attrs=f'name="r" version="{PCT}"'),
    "robot_name": link_doc("", robot_attrs=f'name="{PCT}"'),
    "xmlns_declaration": link_doc("", robot_attrs=f'name="r" xmlns:x="{PCT}"'),
    "link_name": f'<robot name="r"><link name="{PCT}"/></robot>',
    "joint_name": joint_doc(attrs=f'name="{PCT}" type="revolute"'),
    "joint_type": joint_doc(attrs=f'name="j" type="{PCT}"'),
    "joint_parent_link": joint_doc(parent=PCT),
    "joint_origin_xyz": joint_doc(f'<origin xyz="{PCT}"/>'),
    "joint_origin_rpy": joint_doc(f'<origin rpy="0 {PCT} 0"/>'),
    "joint_limit_effort_second": joint_doc(f'<limit effort="{PCT}" velocity="1"/>'),
    "joint_mimic_joint": joint_doc(f'<mimic joint="{PCT}"/>'),
    "joint_dynamics_damping": joint_doc(f'<dynamics damping="{PCT}"/>'),
    "joint_safety_k_velocity": joint_doc(f'<safety_controller k_velocity="{PCT}"/>'),
    "joint_calibration_rising": joint_doc(f'<calibration rising="{PCT}"/>'),
    "unknown_element_attribute": link_doc("", top=f'<gazebo reference="{PCT}"/>'),
    "char_reference_percent": link_doc('<visual><geometry><box size="&#37;n&#37;n"/></geometry></visual>'),
    "many_s_in_mass": link_doc(f'<inertial><mass value="{"%s" * 40}"/>{INERTIA}</inertial>'),
    "huge_width_in_radius": link_doc(
        '<collision><geometry><sphere radius="%999999999d"/></geometry></collision>'
    ),
    "positional_n_in_rgba": link_doc("", top='<material name="m"><color rgba="%1$n %2$n"/></material>'),
    "shipped_robot_with_printf_mass": SHIPPED.replace(
        '<link name="base_link"',
        f'<link name="base_link"><inertial><mass value="{PCT}"/></inertial></link><link name="unused"',
        1,
    ),
}


def _attributes(extra: int) -> str:
    """A robot whose one link has ``name`` and ``extra`` more attributes."""
    return '<robot name="r"><link name="a" ' + " ".join(f'a{i}="x"' for i in range(extra)) + "/></robot>"


ROWS: dict[str, Row] = {f"printf_{k}": Row("text", v, INV) for k, v in PRINTF_ROWS.items()}
ROWS.update(
    {
        # '%' outside attribute values is data urdfdom never formats
        "percent_in_text_content": Row("text", link_doc("100% %n%n"), OK),
        "percent_in_comment_hiding_markup": Row("text", link_doc(f'<!-- <mass value="{PCT}"/> -->'), OK),
        "percent_in_cdata": Row("text", link_doc(f"<![CDATA[{PCT}]]>"), OK),
        # file names are never formatted by urdfdom, and URL-encoded ones are common
        "url_encoded_mesh_filename": Row(
            "text",
            link_doc(
                '<visual><geometry><mesh filename="package://arm/meshes/my%20base.stl"/></geometry></visual>'
            ),
            OK,
        ),
        "printf_in_mesh_filename": Row(
            "text", link_doc(f'<visual><geometry><mesh filename="{PCT}"/></geometry></visual>'), OK
        ),
        "printf_in_texture_filename": Row(
            "text", link_doc("", top=f'<material name="m"><texture filename="{PCT}"/></material>'), OK
        ),
        "shipped_robot": Row("text", SHIPPED, OK),
        # found by the harness in differential mode: urdfdom keeps a nameless material as ""
        "material_without_name": Row("text", link_doc("", top="<material/>"), OK),
        "two_materials_without_name": Row("text", link_doc("", top="<material/><material/>"), INV),
        "nameless_and_empty_material": Row("text", link_doc("", top='<material/><material name=""/>'), INV),
        # ... and reads no namespaces: a prefix need not be bound (the twin used to refuse these)
        "unbound_prefix_attribute": Row("text", link_doc("", robot_attrs='name="r" v:ersion="2.0"'), OK),
        "unbound_prefix_element": Row("text", link_doc("", top='<x:link name="b"/>'), OK),
        # markup TinyXML reads differently from expat: hidden elements would skip the guard
        "pi_hiding_an_element": Row(
            "text", link_doc(f'<?pi ><inertial><mass value="{PCT}"/></inertial>?>'), INV
        ),
        "pi_before_root": Row(
            "text", '<?xml version="1.0"?><?pi x?><robot name="r"><link name="a"/></robot>', INV
        ),
        "doctype_internal_subset_no_entities": Row(
            "text", '<!DOCTYPE robot [ <!ELEMENT robot ANY> ]>\n<robot name="r"><link name="a"/></robot>', INV
        ),
        "doctype_empty_internal_subset": Row(
            "text", '<!DOCTYPE robot [ ]><robot name="r"><link name="a"/></robot>', INV
        ),
        "doctype_without_subset": Row(
            "text", '<!DOCTYPE robot><robot name="r"><link name="a"/></robot>', INV
        ),
        "doctype_system_literal_hiding_markup": Row(
            "text",
            f"<!DOCTYPE robot SYSTEM \"><robot name='r'><link name='{PCT}'/></robot>\">"
            '<robot name="r"><link name="a"/></robot>',
            INV,
        ),
        "doctype_attlist_default_percent": Row(
            "text",
            f'<!DOCTYPE robot [ <!ATTLIST mass value CDATA "{PCT}"> ]><robot name="r"><link name="a">'
            "<inertial><mass/></inertial></link></robot>",
            INV,
        ),
        # encodings: UTF-8 only, decided before urdfdom (TinyXML would keep Latin-1 bytes)
        "latin1_declared_file": Row(
            "file",
            b'<?xml version="1.0" encoding="ISO-8859-1"?>\n<robot name="caf\xe9"><link name="a"/></robot>',
            INV,
        ),
        "latin1_declared_ascii_text": Row(
            "text", '<?xml version="1.0" encoding="ISO-8859-1"?><robot name="r"><link name="a"/></robot>', INV
        ),
        "cp1252_declared": Row(
            "text", '<?xml version="1.0" encoding="cp1252"?><robot name="r"><link name="a"/></robot>', INV
        ),
        "utf8_spelled_without_dash": Row(
            "text", '<?xml version="1.0" encoding="UTF8"?><robot name="r"><link name="a"/></robot>', INV
        ),
        "utf8_declared_lowercase": Row(
            "text", '<?xml version="1.0" encoding="utf-8"?><robot name="r"><link name="a"/></robot>', OK
        ),
        "utf16le_with_bom_file": Row(
            "file",
            '<?xml version="1.0" encoding="UTF-16"?><robot name="r"><link name="a"/></robot>'.encode(
                "utf-16"
            ),
            INV,
        ),
        "utf16be_with_bom_file": Row(
            "file", b"\xfe\xff" + '<robot name="r"><link name="a"/></robot>'.encode("utf-16-be"), INV
        ),
        "utf16_without_bom_file": Row(
            "file", '<robot name="r"><link name="a"/></robot>'.encode("utf-16-le"), INV
        ),
        "utf8_bom_file": Row("file", b'\xef\xbb\xbf<robot name="r"><link name="a"/></robot>', OK),
        "latin1_byte_undeclared_file": Row("file", b'<robot name="caf\xe9"><link name="a"/></robot>', INV),
        "utf8_surrogate_bytes_file": Row("file", b'<robot name="\xed\xa0\x80"><link name="a"/></robot>', INV),
        "utf8_overlong_slash_file": Row("file", b'<robot name="\xc0\xaf"><link name="a"/></robot>', INV),
        "nul_byte_in_text": Row("text", '<robot name="r\x00"><link name="a"/></robot>', INV),
        "char_reference_e9_undeclared": Row("text", '<robot name="caf&#xE9;"><link name="a"/></robot>', OK),
        "astral_characters_in_names": Row(
            "text", '<robot name="\U0001f916"><link name="\u00e9\U0001f9be"/></robot>', OK
        ),
        "long_non_ascii_names_in_error": Row(
            "text",
            f'<robot name="r"><link name="{LONG}"/><link name="{LONG}"/></robot>',
            INV,
        ),
        # files: only regular files, read with a bound, never opened for a blocking read
        "fifo": Row("special", "fifo", INV),
        "symlink_to_fifo": Row("special", "symlink_to_fifo", INV),
        "dev_zero": Row("special", "/dev/zero", INV),
        "dev_null": Row("special", "/dev/null", INV),
        "proc_self_mem_read_error": Row("special", "/proc/self/mem", INV),
        "proc_self_status_not_xml": Row("special", "/proc/self/status", INV),
        "directory": Row("special", "directory", INV),
        "missing_file": Row("special", "missing", INV),
        "nul_in_path": Row("special", "nul_in_path", INV),
        "empty_file": Row("file", b"", INV),
        "symlink_to_shipped_robot": Row("special", "symlink_to_shipped", OK),
        "file_one_byte_over_limit": Row("special", "file_over_limit", UNS),
        "file_at_limit": Row("special", "file_at_limit", OK),
        "text_one_byte_over_limit": Row("special", "text_over_limit", UNS),
        # attributes on one element: TinyXML's lookup is quadratic (80,000 took 21 s natively)
        "attributes_at_limit": Row("text", _attributes(255), OK),
        "attributes_one_over_limit": Row("text", _attributes(256), UNS),
        "attributes_200000": Row("text", _attributes(200_000), UNS),
    }
)


def _padded(size: int) -> bytes:
    head = b'<robot name="r"><link name="a"/></robot>\n'
    return head + b" " * (size - len(head))


def _source(row: Row, name: str, tmp: Path) -> str:
    """The argument given to RobotModel for this row (prepared in the child)."""
    if row.kind == "text":
        assert isinstance(row.data, str)
        return row.data
    if row.kind == "file":
        assert isinstance(row.data, bytes)
        (tmp / f"{name}.urdf").write_bytes(row.data)
        return str(tmp / f"{name}.urdf")
    spec = str(row.data)
    fifo = tmp / "fifo.urdf"
    if spec in ("fifo", "symlink_to_fifo") and not fifo.exists():
        os.mkfifo(fifo)
    special = {
        "fifo": str(fifo),
        "directory": str(tmp),
        "missing": str(tmp / "missing.urdf"),
        "nul_in_path": str(tmp / "a\x00b.urdf"),
    }
    if spec == "symlink_to_fifo":
        (tmp / "to_fifo.urdf").symlink_to(fifo)
        return str(tmp / "to_fifo.urdf")
    if spec == "symlink_to_shipped":
        (tmp / "shipped.urdf").symlink_to(robots.default_robot_path())
        return str(tmp / "shipped.urdf")
    if spec in ("file_over_limit", "file_at_limit"):
        (tmp / f"{spec}.urdf").write_bytes(_padded(LIMIT + (spec == "file_over_limit")))
        return str(tmp / f"{spec}.urdf")
    if spec == "text_over_limit":
        return _padded(LIMIT + 1).decode("ascii")
    return special.get(spec, spec)


def _outcome(impl: Any, source: str) -> list[Any]:
    try:
        model = impl.RobotModel(source)
        return ["ok", model.name, list(model.link_names), list(model.joint_names)]
    except Exception as exc:  # noqa: BLE001 - any failure is recorded and compared
        code = getattr(exc, "code", None)
        return [type(exc).__name__, code.name if code is not None else str(exc)[:200]]


def _child(tmp: str, names: list[str]) -> None:
    import native  # imported here: a crash in the parent's import would not be a row's fault
    import python_impl

    for name in names:
        print(json.dumps({"start": name}), flush=True)  # noqa: T201 - the parent reads these lines
        source = _source(ROWS[name], name, Path(tmp))
        result = {"native": _outcome(native, source), "python": _outcome(python_impl, source)}
        print(json.dumps({"done": name, **result}), flush=True)  # noqa: T201


def _run_children(names: list[str]) -> dict[str, dict[str, Any]]:
    """Run rows in child processes until every row has an outcome (crashed and hung rows included)."""
    results: dict[str, dict[str, Any]] = {}
    todo = list(names)
    while todo:
        with tempfile.TemporaryDirectory(prefix="hostile-urdf-") as tmp:
            cmd = [sys.executable, "-m", "tests.test_hostile_urdf", "CHILD", tmp, *todo]
            try:
                proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=300, check=False)
                out, verdict = proc.stdout, f"crashed (exit {proc.returncode}): {proc.stderr[-300:]}"
            except subprocess.TimeoutExpired as exc:
                raw = exc.stdout or b""
                out, verdict = raw.decode() if isinstance(raw, bytes) else raw, "hung (killed after 300 s)"
        current = None
        for line in out.splitlines():
            record = json.loads(line)
            if "start" in record:
                current = record["start"]
            else:
                results[record.pop("done")] = record
                current = None
        if current is not None:
            results[current] = {"native": [verdict], "python": [verdict]}
        todo = [n for n in todo if n not in results]
        if current is None and todo:  # the child died between rows: blame the next one
            results[todo[0]] = {"native": [verdict], "python": [verdict]}
            todo = todo[1:]
    return results


@pytest.fixture(scope="module")
def outcomes() -> dict[str, dict[str, Any]]:
    return _run_children(sorted(ROWS))


@pytest.mark.parametrize("name", sorted(ROWS))
def test_hostile_urdf(outcomes: dict[str, dict[str, Any]], name: str) -> None:
    got = outcomes[name]
    want = ROWS[name].expect
    for target in ("native", "python"):
        if want == OK:
            assert got[target][0] == "ok", (target, got)
        else:
            assert got[target] == ["URDFError", want], (target, got)
    assert got["native"] == got["python"]  # accepted: same name, links and joints


def test_table_covers_the_issue() -> None:
    """The rows the issue reported, and at least 60 in all."""
    reported = {
        "printf_visual_box_size", "printf_collision_sphere_radius", "printf_inertial_mass",
        "printf_top_material_name_bad_rgba", "printf_top_material_rgba", "fifo", "dev_zero",
        "latin1_declared_file", "utf16le_with_bom_file", "doctype_internal_subset_no_entities",
    }  # fmt: skip
    assert reported <= set(ROWS) and len(ROWS) >= 60


@pytest.mark.parametrize("kind", ["printf_attribute", "fifo"])
def test_cli_names_the_problem(tmp_path: Path, kind: str) -> None:
    """Through ``fuzz_diff.py --robot``: exit 2 and one line naming the problem, no crash or hang."""
    robot = tmp_path / "robot.urdf"
    if kind == "fifo":
        os.mkfifo(robot)
        expected = "is not a regular file"
    else:
        robot.write_text(str(PRINTF_ROWS["visual_box_size"]), encoding="utf-8")
        expected = "'%' is not allowed in attribute values"
    cmd = [sys.executable, "fuzz_diff.py", str(tmp_path / "corpus"), "--robot", str(robot), "-runs=1"]
    proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert expected in proc.stderr and "Traceback" not in proc.stderr


if __name__ == "__main__" and sys.argv[1:2] == ["CHILD"]:
    _child(sys.argv[2], sys.argv[3:])
