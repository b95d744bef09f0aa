"""The text layer of the twin's URDF reading: a document's bytes, the contract's XML rules, and
urdfdom's number grammar (``python_impl.urdf`` builds the robot from what this returns).

The contract's own XML rules (size limit, UTF-8 only, well-formed, no DOCTYPE, no processing
instructions, no '%' in attribute values but file names, limits on depth, links and attributes, valid
``<origin>`` vectors) are checked in document order by an expat pass that mirrors the native
side's (``native/src/xml_guard.cpp``) handler for handler. The same pass builds the tree,
without namespace processing, as urdfdom's TinyXML reads it (``v:name`` is a plain attribute
name). No DOCTYPE means no entity expansion and no external entity, the attacks defusedxml
exists to refuse.
"""

from __future__ import annotations

import os
import re
import stat
from xml.etree.ElementTree import Element, TreeBuilder
from xml.parsers import expat

from robot_api.errors import ErrorCode, URDFError

MAX_XML_DEPTH = 1000
MAX_LINKS = 10000
MAX_ATTRIBUTES = 256
"""Attributes on one element: urdfdom's TinyXML looks each up in a list (80,000 took 21 s)."""
MAX_URDF_BYTES = 16 << 20
"""Largest URDF accepted, in bytes (a file, or text encoded as UTF-8): 16 MiB."""

# urdfdom's strToDouble: optional leading whitespace, a decimal number, nothing after.
_NUMBER = re.compile(r"[ \t\n\v\f\r]*[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?\Z")


def invalid(message: str) -> URDFError:
    return URDFError(message, ErrorCode.URDF_INVALID)


def parse_number(text: str, what: str) -> float:
    """Parse a scalar as urdfdom does (finite decimal, no trailing characters)."""
    if not _NUMBER.match(text):
        raise invalid(f"{what} value ({text}) is not a valid float")
    value = float(text)
    if value in (float("inf"), float("-inf")):
        raise invalid(f"{what} value ({text}) is not a valid float")
    return value


def parse_vector3(text: str, what: str) -> tuple[float, float, float]:
    """Parse 'x y z' as urdfdom does: split on spaces only, exactly three numbers."""
    pieces = [p for p in text.split(" ") if p]
    values = [parse_number(p, what) for p in pieces]
    if len(values) != 3:
        raise invalid(f"{what}: found {len(values)} elements but 3 expected in [{text}]")
    return (values[0], values[1], values[2])


def read_source(source: str, is_path: bool) -> bytes:
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
        raise invalid(f"{where}: the path contains a NUL character") from None
    except OSError as exc:
        raise invalid(f"{where}: {exc.strerror}") from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise invalid(f"{where}: not a regular file")
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
        raise invalid(f"{where}: {exc.strerror}") from None
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
        if len(attrs) > MAX_ATTRIBUTES:
            raise self.fail(
                f"<{_clip(name)}> has more than {MAX_ATTRIBUTES} attributes", ErrorCode.URDF_UNSUPPORTED
            )
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


def parse_xml(data: bytes) -> Element:
    """The root element, once the document passes the contract's XML rules (URDFError otherwise)."""
    if len(data) > MAX_URDF_BYTES:
        raise URDFError(f"URDF is larger than {MAX_URDF_BYTES >> 20} MiB", ErrorCode.URDF_UNSUPPORTED)
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        raise invalid("URDF must be UTF-8 (it starts with a UTF-16/UTF-32 byte order mark)")
    nul = data.find(b"\0")
    if nul >= 0:  # expat reads "<\0" as UTF-16 whatever it is told; XML has no NUL character
        raise invalid(f"URDF must be UTF-8 text (NUL byte at offset {nul})")
    guard = _Guard()
    try:
        guard.parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise invalid(
            f"URDF is not well-formed XML: {expat.ErrorString(exc.code)} (line {exc.lineno})"
        ) from None
    if guard.colon_name is not None:
        # urdfdom's TinyXML reads a name only from a letter or '_' ("Error reading Attributes")
        raise invalid(
            f"URDF attribute name '{_clip(guard.colon_name)}' starts with ':' "
            "(urdfdom's XML parser refuses it)"
        )
    root: Element = guard.tree.close()
    return root
