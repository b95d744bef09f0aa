"""URDF reading for the twin: hardened XML (expat, the contract's XML rules) and urdfdom's rules.

What is accepted and what is an error follows urdfdom 3.0.1 (Debian 12) as
documented in ``docs/api.md`` ("URDF rules"): the same defaults, the same
number grammar, the first of repeated elements wins, the tree built over joints
sorted by name. On top of that come the contract's own XML rules (size limit,
UTF-8 only, well-formed, no DOCTYPE, no processing instructions, no '%' in
attribute values but file names, limits on depth and links, valid ``<origin>`` vectors),
checked in document order by an expat pass that mirrors the native side's
(``native/src/xml_guard.cpp``) handler for handler. The same pass builds the
tree, without namespace processing, as urdfdom's TinyXML reads it (``v:name``
is a plain attribute name). No DOCTYPE means no entity expansion and no external
entity, the attacks defusedxml exists to refuse.
"""

from __future__ import annotations

import os
import re
import stat
from dataclasses import dataclass, field
from xml.etree.ElementTree import Element, TreeBuilder
from xml.parsers import expat

from robot_api.errors import ErrorCode, URDFError

MAX_XML_DEPTH = 1000
MAX_LINKS = 10000
MAX_URDF_BYTES = 16 << 20
"""Largest URDF accepted, in bytes (a file, or text encoded as UTF-8): 16 MiB."""

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")

# urdfdom's strToDouble: optional leading whitespace, a decimal number, nothing after.
_NUMBER = re.compile(r"[ \t\n\v\f\r]*[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?\Z")
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


def _invalid(message: str) -> URDFError:
    return URDFError(message, ErrorCode.URDF_INVALID)


def parse_number(text: str, what: str) -> float:
    """Parse a scalar as urdfdom does (finite decimal, no trailing characters)."""
    if not _NUMBER.match(text):
        raise _invalid(f"{what} value ({text}) is not a valid float")
    value = float(text)
    if value in (float("inf"), float("-inf")):
        raise _invalid(f"{what} value ({text}) is not a valid float")
    return value


def parse_vector3(text: str, what: str) -> tuple[float, float, float]:
    """Parse 'x y z' as urdfdom does: split on spaces only, exactly three numbers."""
    pieces = [p for p in text.split(" ") if p]
    values = [parse_number(p, what) for p in pieces]
    if len(values) != 3:
        raise _invalid(f"{what}: found {len(values)} elements but 3 expected in [{text}]")
    return (values[0], values[1], values[2])


def _read_source(source: str, is_path: bool) -> bytes:
    """The document's bytes: text as UTF-8, or at most ``MAX_URDF_BYTES + 1`` bytes of a regular file.

    The file is opened non-blocking, so that a FIFO without a writer cannot hang
    the open, and anything but a regular file is refused before a byte is read.
    """
    if not is_path:
        return source.encode("utf-8")
    where = f"cannot read URDF file '{source}'"
    try:
        fd = os.open(source, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except ValueError:  # an embedded NUL
        raise _invalid(f"{where}: the path contains a NUL character") from None
    except OSError as exc:
        raise _invalid(f"{where}: {exc.strerror}") from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise _invalid(f"{where}: not a regular file")
        chunks: list[bytes] = []
        size = 0
        while size <= MAX_URDF_BYTES:
            chunk = os.read(fd, min(1 << 16, MAX_URDF_BYTES + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        return b"".join(chunks)
    except OSError as exc:
        raise _invalid(f"{where}: {exc.strerror}") from None
    finally:
        os.close(fd)


def _clip(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[:limit] + "..."


class _Guard:
    """The contract's XML rules, checked by expat in document order (native: xml_guard.cpp)."""

    def __init__(self) -> None:
        self.depth = 0
        self.links = 0
        self.root_is_robot = False
        self.tree = TreeBuilder()
        self.colon_name: str | None = None
        """The first attribute name starting with ':' (XML allows it, urdfdom's TinyXML does not;
        an element name starting with ':' it reads)."""
        # "UTF-8" overrides the document's own declaration; on_xml_decl rejects any other.
        self.parser = expat.ParserCreate("UTF-8")
        self.parser.XmlDeclHandler = self.on_xml_decl
        self.parser.StartDoctypeDeclHandler = self.on_doctype
        self.parser.ProcessingInstructionHandler = self.on_processing_instruction
        self.parser.EntityDeclHandler = self.on_entity_decl
        self.parser.ExternalEntityRefHandler = self.on_external_entity
        self.parser.StartElementHandler = self.on_start
        self.parser.EndElementHandler = self.on_end

    def fail(self, message: str, code: ErrorCode = ErrorCode.URDF_INVALID) -> URDFError:
        return URDFError(f"URDF {message} (line {self.parser.CurrentLineNumber})", code)

    def on_start(self, name: str, attrs: dict[str, str]) -> None:
        self.depth += 1
        if self.depth > MAX_XML_DEPTH:
            raise self.fail(f"XML is nested deeper than {MAX_XML_DEPTH} elements", ErrorCode.URDF_UNSUPPORTED)
        if self.depth == 1:
            self.root_is_robot = name == "robot"
        if self.depth == 2 and self.root_is_robot and name == "link":
            self.links += 1
            if self.links > MAX_LINKS:
                raise self.fail(f"has more than {MAX_LINKS} links", ErrorCode.URDF_UNSUPPORTED)
        if self.colon_name is None:
            self.colon_name = next((key for key in attrs if key.startswith(":")), None)
        for key, value in attrs.items():
            # file names are never formatted by urdfdom; URL-encoded ones ("my%20arm.stl") are common
            if "%" in value and key != "filename":
                raise self.fail(
                    f"<{_clip(name)} {_clip(key)}=\"{_clip(value)}\">: '%' is not allowed in attribute "
                    "values (urdfdom would pass it to printf as a format directive)"
                )
        if name == "origin":
            for key in ("xyz", "rpy"):
                vector = attrs.get(key)
                if vector is not None:
                    try:
                        parse_vector3(vector, f"origin {key}")
                    except URDFError:
                        raise self.fail(
                            f'origin {key}="{_clip(vector)}" is not a vector of 3 numbers'
                        ) from None
        self.tree.start(name, attrs)

    def on_end(self, name: str) -> None:
        self.depth -= 1
        self.tree.end(name)

    def on_xml_decl(self, version: str, encoding: str | None, standalone: int) -> None:
        if encoding is not None and encoding.lower() != "utf-8":
            raise self.fail(f"declares encoding '{_clip(encoding)}'; only UTF-8 is supported")

    def on_doctype(self, name: str, *rest: object) -> None:
        raise self.fail(f"DOCTYPE declarations are not allowed (<!DOCTYPE {_clip(name)}>)")

    def on_processing_instruction(self, target: str, data: str) -> None:
        raise self.fail(f"processing instructions are not allowed (<?{_clip(target)} ...?>)")

    def on_entity_decl(self, name: str, *rest: object) -> None:
        raise self.fail(f"entity declarations are not allowed (entity '{_clip(name)}')")

    def on_external_entity(self, *rest: object) -> int:
        raise self.fail("external entities are not allowed")


def _parse_xml(data: bytes) -> Element:
    """The root element, once the document passes the contract's XML rules (URDFError otherwise)."""
    if len(data) > MAX_URDF_BYTES:
        raise URDFError(f"URDF is larger than {MAX_URDF_BYTES >> 20} MiB", ErrorCode.URDF_UNSUPPORTED)
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        raise _invalid("URDF must be UTF-8 (it starts with a UTF-16/UTF-32 byte order mark)")
    nul = data.find(b"\0")
    if nul >= 0:  # expat reads "<\0" as UTF-16 whatever it is told; XML has no NUL character
        raise _invalid(f"URDF must be UTF-8 text (NUL byte at offset {nul})")
    guard = _Guard()
    try:
        guard.parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise _invalid(
            f"URDF is not well-formed XML: {expat.ErrorString(exc.code)} (line {exc.lineno})"
        ) from None
    if guard.colon_name is not None:
        # urdfdom's TinyXML reads a name only from a letter or '_' ("Error reading Attributes")
        raise _invalid(
            f"URDF attribute name '{_clip(guard.colon_name)}' starts with ':' "
            "(urdfdom's XML parser refuses it)"
        )
    root: Element = guard.tree.close()
    return root


def _parse_version(text: str) -> None:
    pieces = [p for p in text.split(".") if p]
    if len(pieces) != 2:
        raise _invalid("The version attribute should be in the form 'x.y'")
    numbers = []
    for piece in pieces:
        m = _LONG.match(piece)
        if not m or m.end() != len(piece):
            raise _invalid("Version attribute is not an integer")
        value = int(m.group(1))
        if value < 0:
            raise _invalid("Version number must be positive")
        numbers.append(value % 2**32)
    if numbers != [1, 0]:
        raise _invalid("Invalid 'version' specified; only version 1.0 is currently supported")


def _first(elem: Element, tag: str) -> Element | None:
    return elem.find(tag)


def _parse_limits(elem: Element, joint: str) -> Limits:
    def opt(key: str, default: float) -> float:
        raw = elem.get(key)
        return default if raw is None else parse_number(raw, f"joint [{joint}] limit {key}")

    lower = opt("lower", 0.0)
    upper = opt("upper", 0.0)
    if elem.get("effort") is None:
        raise _invalid(f"joint [{joint}] limit: no effort")
    effort = parse_number(elem.get("effort", ""), f"joint [{joint}] limit effort")
    if elem.get("velocity") is None:
        raise _invalid(f"joint [{joint}] limit: no velocity")
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
        raise _invalid("unnamed joint found")
    jtype = elem.get("type")
    if jtype is None:
        raise _invalid(f"joint [{name}] has no type")
    if jtype not in JOINT_TYPES:
        raise _invalid(f"Joint [{name}] has no known type [{jtype}]")

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
        raise _invalid(f"Joint [{name}] is of type {jtype.upper()} but it does not specify limits")

    safety = _first(elem, "safety_controller")
    if safety is not None:
        if safety.get("k_velocity") is None:
            raise _invalid(f"joint [{name}] safety: no k_velocity")
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
            raise _invalid(f"joint [{name}] mimic: no mimic joint specified")
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
            raise _invalid(f"joint [{name}] dynamics element specified with no damping and no friction")
        _check_optional_numbers(dynamics, ("damping", "friction"), "dynamics")

    return Joint(name, jtype, parent, child, xyz, rpy, axis, limits, mimic)


def _parse_materials(robot: Element) -> None:
    seen: set[str] = set()
    for material in robot.findall("material"):
        # urdfdom logs a nameless material but keeps it, under the name "" (model.cpp ignores
        # parseMaterial's result): accepted, and a second one is "not unique".
        name = material.get("name", "")
        if name in seen:
            raise _invalid(f"material '{name}' is not unique.")
        seen.add(name)


def _build_tree(name: str, links: list[str], joints: dict[str, Joint]) -> Urdf:
    link_set = set(links)
    parent_of: dict[str, str] = {}
    parent_joint: dict[str, Joint] = {}
    child_joints: dict[str, list[Joint]] = {link: [] for link in links}
    for jname in sorted(joints):  # urdfdom's initTree: joints in std::map (name) order
        joint = joints[jname]
        if not joint.parent or not joint.child:
            raise _invalid(f"Joint [{jname}] is missing a parent and/or child link specification.")
        if joint.child not in link_set:
            raise _invalid(f"child link [{joint.child}] of joint [{jname}] not found")
        if joint.parent not in link_set:
            raise _invalid(f"parent link [{joint.parent}] of joint [{jname}] not found")
        parent_of[joint.child] = joint.parent
    roots = [link for link in sorted(link_set) if link not in parent_of]
    if len(roots) > 1:
        raise _invalid(f"Two root links found: [{roots[0]}] and [{roots[1]}]")
    if not roots:
        raise _invalid("No root link found. The robot xml is not a valid tree.")

    # The contract's own graph rules: a tree, every link reachable from the root.
    for jname in sorted(joints):
        joint = joints[jname]
        if joint.child in parent_joint:
            other = parent_joint[joint.child].name
            raise _invalid(f"link '{joint.child}' is the child of two joints, '{other}' and '{jname}'")
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
        raise _invalid(f"link '{unreached[0]}' is not connected to the root link '{roots[0]}'")
    return Urdf(name, links, joints, roots[0], parent_joint, child_joints)


def load_urdf(source: str, is_path: bool) -> Urdf:
    """Read a URDF file (``is_path``) or XML text and build its tree.

    Raises
    ------
    URDFError
        With ``URDF_INVALID`` or ``URDF_UNSUPPORTED`` and a message naming the problem.
    """
    root = _parse_xml(_read_source(source, is_path))
    if root.tag != "robot":
        raise _invalid("Could not find the 'robot' element in the xml file")
    name = root.get("name")
    if name is None:
        raise _invalid("No name given for the robot.")
    version = root.get("version")
    if version is not None:
        _parse_version(version)
    _parse_materials(root)

    links: list[str] = []
    seen: set[str] = set()
    for link in root.findall("link"):
        lname = link.get("name", "")
        if lname in seen:
            raise _invalid(f"link '{lname}' is not unique.")
        seen.add(lname)
        links.append(lname)
    if not links:
        raise _invalid("No link elements found in urdf file")

    joints: dict[str, Joint] = {}
    for elem in root.findall("joint"):
        joint = _parse_joint(elem)
        if joint.name in joints:
            raise _invalid(f"joint '{joint.name}' is not unique.")
        joints[joint.name] = joint
    return _build_tree(name, links, joints)


def is_path_source(urdf: object) -> tuple[object, bool]:
    """The contract's rule: a PathLike or a str not starting with '<' is a file path."""
    if isinstance(urdf, os.PathLike):
        return os.fspath(urdf), True
    if isinstance(urdf, str):
        return urdf, not urdf.lstrip().startswith("<")
    return urdf, False
