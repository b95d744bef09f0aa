"""Atheris harness: arbitrary URDF documents into the native loader (``native.RobotModel``).

The property: whatever the bytes, loading either succeeds or raises ``URDFError``;
never a crash, a sanitizer report, a hang or another exception. The twin loads
every input too: the same property holds for it, its Python coverage (Atheris
instruments ``python_impl``) guides the search when the native module has no
counters (the regular build), and both must give the same verdict (accepted, or
the same ``URDFError`` code) except on the documented divergence (raw whitespace
in attribute values); ``RROSFUZZ_URDF_DIFFERENTIAL=0`` turns that check off. Under
``make fuzz-urdf`` the native module is the clang build with AddressSanitizer and
libFuzzer's edge counters (``make native-cov``), so the search is guided by
urdfdom's and the guard's C++ coverage; ``tests/test_fuzz_urdf_loader.py`` runs a
bounded, seeded campaign in CI.

Usage::

    python tests/fuzz_urdf_loader.py [libFuzzer flags] [corpus dirs]

Seeds (the shipped robot, ``tests/urdf_cases.py`` and the hostile rows of
``tests/test_hostile_urdf.py``) and an XML/URDF dictionary are written to a
temporary folder added as the last corpus directory. An input whose first byte is
odd is loaded from a file (the bytes as they are: any encoding, BOMs, NULs); an even
one is decoded as UTF-8 (invalid bytes replaced) and passed as XML text.
"""

from __future__ import annotations

import os
import re
import sys
import tempfile
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

import atheris  # noqa: E402

import python_impl  # noqa: E402


def _instrument_twin() -> None:
    """Give the twin's functions Atheris edge counters (``instrument_imports`` finds none here,
    ``instrument_all`` takes half a minute): they guide the search when native has none."""
    done: set[int] = set()
    for name, module in list(sys.modules.items()):
        if not name.startswith("python_impl"):
            continue
        for value in list(vars(module).values()):
            members = list(vars(value).values()) if isinstance(value, type) else [value]
            for member in members:
                func = getattr(member, "__func__", getattr(member, "fget", member))
                code = getattr(func, "__code__", None)
                if code is not None and code.co_filename.startswith(str(REPO)) and id(func) not in done:
                    done.add(id(func))
                    atheris.instrument_func(func)


_instrument_twin()

import native  # noqa: E402
from robot_api.errors import URDFError  # noqa: E402

DICTIONARY = [
    "<robot", "</robot>", "<link", "</link>", "<joint", "</joint>", " name=", " type=", "revolute",
    "continuous", "prismatic", "fixed", "<parent link=", "<child link=", "<origin", " xyz=", " rpy=",
    "<axis", "<limit", " lower=", " upper=", " effort=", " velocity=", "<mimic", " joint=",
    " multiplier=", " offset=", "<dynamics", " damping=", "<safety_controller", " k_velocity=",
    "<calibration", " rising=", "<visual>", "<collision>", "<geometry>", "<box", " size=", "<sphere",
    " radius=", "<cylinder", " length=", "<mesh", " filename=", " scale=", "<inertial>", "<mass",
    " value=", "<inertia", " ixx=", " iyz=", "<material", "<color", " rgba=", "<texture", " version=",
    "/>", "\"", "'", "%n", "%s", "%99999d", "&#37;", "&#xE9;", "&amp;", "<!--", "-->", "<![CDATA[",
    "]]>", "<!DOCTYPE", "<!ENTITY", "<?pi ?>", "<?xml version=\"1.0\"?>", " encoding=\"ISO-8859-1\"",
    " encoding=\"UTF-16\"", "\xef\xbb\xbf", "\xff\xfe", "1e308", "1e-310", "nan", "inf", " 0 0 1",
]  # fmt: skip


def _seeds() -> list[bytes]:
    from tests.test_hostile_urdf import ROWS
    from tests.urdf_cases import all_cases

    texts = [text for _, text, *_ in all_cases() if len(text) < 100_000]
    texts += [row.data for row in ROWS.values() if row.kind == "text" and isinstance(row.data, str)]
    seeds = [b"\x00" + text.encode("utf-8") for text in texts]  # even first byte: passed as text
    seeds += [
        b"\x01" + row.data for row in ROWS.values() if row.kind == "file" and isinstance(row.data, bytes)
    ]
    return seeds


def _write_seeds(folder: Path) -> Path:
    corpus = folder / "seeds"
    corpus.mkdir(parents=True, exist_ok=True)
    for index, seed in enumerate(_seeds()):
        (corpus / f"seed-{index:04d}").write_bytes(seed)
    words = folder / "urdf.dict"
    escape = {"\\": "\\\\", '"': '\\"'}
    lines = []
    for word in DICTIONARY:
        body = "".join(escape.get(c, c) if 32 <= ord(c) < 127 else f"\\x{ord(c):02x}" for c in word)
        lines.append(f'"{body}"')
    words.write_text("\n".join(lines) + "\n", encoding="ascii")
    return corpus


# docs/api.md, "Known divergences": a literal tab, newline or CR inside an attribute value
# (expat normalizes it to a space, TinyXML keeps it). Such documents are not compared.
_RAW_WHITESPACE_IN_ATTRIBUTE = re.compile(rb"=\s*(\"[^\"]*[\t\n\r][^\"]*\"|'[^']*[\t\n\r][^']*')")


def _verdict(target: Any, source: str) -> str:
    try:
        target.RobotModel(source)
    except URDFError as exc:
        return f"URDFError {exc.code.name}"
    return "ok"


class Harness:
    """The fuzz target: one input, one ``RobotModel`` load by each target.

    Parameters
    ----------
    scratch : Path
        Folder for the file inputs.
    differential : bool
        Also require both targets to give the same verdict (accepted, or the same
        ``URDFError`` code), as ``tests/test_urdf_cases.py`` does for its table.
    """

    def __init__(self, scratch: Path, differential: bool) -> None:
        self.file = scratch / "input.urdf"
        self.differential = differential

    def __call__(self, data: bytes) -> None:
        if not data:
            return
        if data[0] & 1:
            self.file.write_bytes(data[1:])
            source, raw = str(self.file), data[1:]
        else:
            source = data[1:].decode("utf-8", errors="replace")
            if not source.lstrip().startswith("<"):
                source = "<" + source  # text, never a path
            raw = source.encode("utf-8")
        ours, twin = _verdict(native, source), _verdict(python_impl, source)
        if self.differential and ours != twin and not _RAW_WHITESPACE_IN_ATTRIBUTE.search(raw):
            raise AssertionError(f"native: {ours}, python_impl: {twin}")


def main(argv: list[str]) -> None:
    """Run libFuzzer over ``argv`` (flags and corpus directories) plus the seeds. The seeds,
    the dictionary and the harness's file go to ``RROSFUZZ_URDF_SCRATCH`` (a folder, made if
    missing) or else a new temporary folder: libFuzzer ends the process, so nothing here can
    remove it afterwards; the test gives its own ``tmp_path``."""
    named = os.environ.get("RROSFUZZ_URDF_SCRATCH")
    scratch = Path(named) if named else Path(tempfile.mkdtemp(prefix="fuzz-urdf-"))
    scratch.mkdir(parents=True, exist_ok=True)
    seeds = _write_seeds(scratch)
    flags = [a for a in argv[1:] if a.startswith("-")]
    dirs = [a for a in argv[1:] if not a.startswith("-")]
    for folder in dirs:
        os.makedirs(folder, exist_ok=True)
    if not any(f.startswith("-dict=") for f in flags):
        flags.append(f"-dict={scratch / 'urdf.dict'}")
    differential = os.environ.get("RROSFUZZ_URDF_DIFFERENTIAL", "1") != "0"
    atheris.Setup([argv[0], *flags, *dirs, str(seeds)], Harness(scratch, differential))
    atheris.Fuzz()


if __name__ == "__main__":
    main(sys.argv)
