"""URDF reading for the twin: urdfdom's rules over the tree that ``python_impl.urdf_text`` reads.

What is accepted and what is an error follows urdfdom 3.0.1 (Debian 12) as
documented in ``docs/api.md`` ("URDF rules"): the same defaults, the same
number grammar, the first of repeated elements wins, the tree built over joints
sorted by name. The text layer under it (``python_impl.urdf_text``: the file's bytes, the
contract's hardened XML rules checked by expat, urdfdom's number grammar) mirrors the native
side's ``native/src/xml_guard.cpp``.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from xml.etree.ElementTree import Element

from python_impl.urdf_text import invalid, parse_number, parse_vector3, parse_xml, read_source

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")

_LONG = re.compile(r"[ \t\n\v\f\r]*([+-]?[0-9]+)")


@dataclass
class Limits:
    lower: float
    upper: float
    effort: float
    velocity: float


@dataclass
class Mimic:
    joint: str
    multiplier: float
    offset: float


@dataclass
class Joint:
    name: str
    type: str
    parent: str
    child: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    axis: tuple[float, float, float]
    limits: Limits | None
    mimic: Mimic | None


@dataclass
class Urdf:
    """A parsed URDF: the tree of links and joints."""

    name: str
    links: list[str]
    joints: dict[str, Joint]
    root: str
    parent_joint: dict[str, Joint] = field(default_factory=dict)
    child_joints: dict[str, list[Joint]] = field(default_factory=dict)


def _parse_version(text: str) -> None:
    # urdfdom's split_string: every piece before a '.', empty ones too, then the rest if any
    # ("1.0." is two pieces, "1..0" and ".1.0" three)
    pieces = text.split(".")
    if pieces[-1] == "":
        pieces.pop()
    if len(pieces) != 2:
        raise invalid("The version attribute should be in the form 'x.y'")
    numbers = []
    for piece in pieces:
        if not piece:
            raise invalid("One of the fields of the version attribute is blank")
        m = _LONG.match(piece)
        if not m:
            raise invalid("Version attribute is not an integer")
        if m.end() != len(piece):
            raise invalid("Extra characters after the version number")
        value = int(m.group(1))
        if value < 0:
            raise invalid("Version number must be positive")
        numbers.append(value % 2**32)
    if numbers != [1, 0]:
        raise invalid("Invalid 'version' specified; only version 1.0 is currently supported")


def _first(elem: Element, tag: str) -> Element | None:
    return elem.find(tag)


def _parse_limits(elem: Element, joint: str) -> Limits:
    def opt(key: str, default: float) -> float:
        raw = elem.get(key)
        return default if raw is None else parse_number(raw, f"joint [{joint}] limit {key}")

    lower = opt("lower", 0.0)
    upper = opt("upper", 0.0)
    if elem.get("effort") is None:
        raise invalid(f"joint [{joint}] limit: no effort")
    effort = parse_number(elem.get("effort", ""), f"joint [{joint}] limit effort")
    if elem.get("velocity") is None:
        raise invalid(f"joint [{joint}] limit: no velocity")
    velocity = parse_number(elem.get("velocity", ""), f"joint [{joint}] limit velocity")
    return Limits(lower, upper, effort, velocity)


def _check_optional_numbers(elem: Element, keys: tuple[str, ...], what: str) -> None:
    for key in keys:
        raw = elem.get(key)
        if raw is not None:
            parse_number(raw, f"{what} {key}")


def _parse_joint(elem: Element) -> Joint:
    name = elem.get("name")
    if name is None:
        raise invalid("unnamed joint found")
    jtype = elem.get("type")
    if jtype is None:
        raise invalid(f"joint [{name}] has no type")
    if jtype not in JOINT_TYPES:
        raise invalid(f"Joint [{name}] has no known type [{jtype}]")

    xyz = rpy = (0.0, 0.0, 0.0)
    origin = _first(elem, "origin")
    if origin is not None:
        if origin.get("xyz") is not None:
            xyz = parse_vector3(origin.get("xyz", ""), f"joint [{name}] origin xyz")
        if origin.get("rpy") is not None:
            rpy = parse_vector3(origin.get("rpy", ""), f"joint [{name}] origin rpy")

    parent_elem, child_elem = _first(elem, "parent"), _first(elem, "child")
    parent = (parent_elem.get("link") or "") if parent_elem is not None else ""
    child = (child_elem.get("link") or "") if child_elem is not None else ""

    axis = (0.0, 0.0, 0.0)
    if jtype not in ("fixed", "floating"):
        axis_elem = _first(elem, "axis")
        if axis_elem is None:
            axis = (1.0, 0.0, 0.0)
        elif axis_elem.get("xyz") is not None:
            axis = parse_vector3(axis_elem.get("xyz", ""), f"joint [{name}] axis")

    limits = None
    limit_elem = _first(elem, "limit")
    if limit_elem is not None:
        limits = _parse_limits(limit_elem, name)
    elif jtype in ("revolute", "prismatic"):
        raise invalid(f"Joint [{name}] is of type {jtype.upper()} but it does not specify limits")

    safety = _first(elem, "safety_controller")
    if safety is not None:
        if safety.get("k_velocity") is None:
            raise invalid(f"joint [{name}] safety: no k_velocity")
        _check_optional_numbers(
            safety, ("soft_lower_limit", "soft_upper_limit", "k_position", "k_velocity"), "safety"
        )
    calibration = _first(elem, "calibration")
    if calibration is not None:
        _check_optional_numbers(calibration, ("rising", "falling"), "calibration")

    mimic = None
    mimic_elem = _first(elem, "mimic")
    if mimic_elem is not None:
        target = mimic_elem.get("joint")
        if target is None:
            raise invalid(f"joint [{name}] mimic: no mimic joint specified")
        multiplier = mimic_elem.get("multiplier")
        offset = mimic_elem.get("offset")
        mimic = Mimic(
            target,
            1.0 if multiplier is None else parse_number(multiplier, "mimic multiplier"),
            0.0 if offset is None else parse_number(offset, "mimic offset"),
        )

    dynamics = _first(elem, "dynamics")
    if dynamics is not None:
        if dynamics.get("damping") is None and dynamics.get("friction") is None:
            raise invalid(f"joint [{name}] dynamics element specified with no damping and no friction")
        _check_optional_numbers(dynamics, ("damping", "friction"), "dynamics")

    return Joint(name, jtype, parent, child, xyz, rpy, axis, limits, mimic)


def _parse_materials(robot: Element) -> None:
    seen: set[str] = set()
    for material in robot.findall("material"):
        # urdfdom logs a nameless material but keeps it, under the name "" (model.cpp ignores
        # parseMaterial's result): accepted, and a second one is "not unique".
        name = material.get("name", "")
        if name in seen:
            raise invalid(f"material '{name}' is not unique.")
        seen.add(name)


def _build_tree(name: str, links: list[str], joints: dict[str, Joint]) -> Urdf:
    link_set = set(links)
    parent_of: dict[str, str] = {}
    parent_joint: dict[str, Joint] = {}
    child_joints: dict[str, list[Joint]] = {link: [] for link in links}
    for jname in sorted(joints):  # urdfdom's initTree: joints in std::map (name) order
        joint = joints[jname]
        if not joint.parent or not joint.child:
            raise invalid(f"Joint [{jname}] is missing a parent and/or child link specification.")
        if joint.child not in link_set:
            raise invalid(f"child link [{joint.child}] of joint [{jname}] not found")
        if joint.parent not in link_set:
            raise invalid(f"parent link [{joint.parent}] of joint [{jname}] not found")
        parent_of[joint.child] = joint.parent
    roots = [link for link in sorted(link_set) if link not in parent_of]
    if len(roots) > 1:
        raise invalid(f"Two root links found: [{roots[0]}] and [{roots[1]}]")
    if not roots:
        raise invalid("No root link found. The robot xml is not a valid tree.")

    # The contract's own graph rules: a tree, every link reachable from the root.
    for jname in sorted(joints):
        joint = joints[jname]
        if joint.child in parent_joint:
            other = parent_joint[joint.child].name
            raise invalid(f"link '{joint.child}' is the child of two joints, '{other}' and '{jname}'")
        parent_joint[joint.child] = joint
        child_joints[joint.parent].append(joint)
    reached = {roots[0]}
    stack = [roots[0]]
    while stack:
        for joint in child_joints[stack.pop()]:
            if joint.child not in reached:
                reached.add(joint.child)
                stack.append(joint.child)
    unreached = sorted(link_set - reached)
    if unreached:
        raise invalid(f"link '{unreached[0]}' is not connected to the root link '{roots[0]}'")
    return Urdf(name, links, joints, roots[0], parent_joint, child_joints)


def load_urdf(source: str, is_path: bool) -> Urdf:
    """Read a URDF file (``is_path``) or XML text and build its tree.

    Raises
    ------
    URDFError
        With ``URDF_INVALID`` or ``URDF_UNSUPPORTED`` and a message naming the problem.
    """
    root = parse_xml(read_source(source, is_path))
    if root.tag != "robot":
        raise invalid("Could not find the 'robot' element in the xml file")
    name = root.get("name")
    if name is None:
        raise invalid("No name given for the robot.")
    version = root.get("version")
    if version is not None:
        _parse_version(version)
    _parse_materials(root)

    links: list[str] = []
    seen: set[str] = set()
    for link in root.findall("link"):
        lname = link.get("name", "")
        if lname in seen:
            raise invalid(f"link '{lname}' is not unique.")
        seen.add(lname)
        links.append(lname)
    if not links:
        raise invalid("No link elements found in urdf file")

    joints: dict[str, Joint] = {}
    for elem in root.findall("joint"):
        joint = _parse_joint(elem)
        if joint.name in joints:
            raise invalid(f"joint '{joint.name}' is not unique.")
        joints[joint.name] = joint
    return _build_tree(name, links, joints)


def is_path_source(urdf: object) -> tuple[object, bool]:
    """The contract's rule: a PathLike or a str not starting with '<' is a file path."""
    if isinstance(urdf, os.PathLike):
        return os.fspath(urdf), True
    if isinstance(urdf, str):
        return urdf, not urdf.lstrip().startswith("<")
    return urdf, False
