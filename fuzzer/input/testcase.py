"""Test case files: the bytes libFuzzer mutates and stores, as JSON.

A test case (the shape of the paper's Fig. 5) is one ROS message plus where it
came from::

    {"rrosfuzz": 1, "msg_type": "sensor_msgs/JointState", "sequence": 7,
     "origin": "hypothesis", "lineage": ["arithmetic", "comb3"], "lineage_length": 2,
     "message": {"header": {...}, "name": [...], "position": [...], ...}}

``sequence`` is the number of the generated seed the case descends from (the
paper's sequence tag); ``lineage`` lists the mutators applied since that seed,
oldest first (the last ``LINEAGE_KEEP``; ``lineage_length`` counts them all): the
paper's mapping dict from each seed to its mutation strategy. Floats use
Python's JSON dialect, so NaN and +-Infinity survive a round trip (robustness
campaigns need them). Decoding never evaluates anything.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

FORMAT = 1
LINEAGE_KEEP = 64
MAX_BYTES = 1 << 20


class TestCaseError(ValueError):
    """The bytes are not a test case of this format."""

    __test__ = False  # not a pytest test class


@dataclass(frozen=True)
class TestCase:
    """One input of the fuzzer."""

    __test__ = False  # not a pytest test class

    msg_type: str
    message: dict[str, Any]
    sequence: int = 0
    origin: str = "hypothesis"
    lineage: tuple[str, ...] = ()
    lineage_length: int = 0

    def child(self, message: dict[str, Any], step: str) -> TestCase:
        """The case that mutator ``step`` made from this one."""
        lineage = (*self.lineage, step)[-LINEAGE_KEEP:]
        return replace(
            self, message=message, origin="mutation", lineage=lineage, lineage_length=self.lineage_length + 1
        )

    @property
    def strategy(self) -> str:
        """The mutation strategy that produced this case ('seed' for a generated one)."""
        return self.lineage[-1] if self.lineage else "seed"

    def to_json(self) -> dict[str, Any]:
        return {
            "rrosfuzz": FORMAT,
            "msg_type": self.msg_type,
            "sequence": self.sequence,
            "origin": self.origin,
            "lineage": list(self.lineage),
            "lineage_length": self.lineage_length,
            "message": self.message,
        }

    def encode(self) -> bytes:
        return json.dumps(self.to_json(), separators=(",", ":"), ensure_ascii=False).encode("utf-8")


def _reject_constant(name: str) -> float:
    # json accepts NaN / Infinity / -Infinity; keep them as floats (no other constants exist)
    return {"NaN": math.nan, "Infinity": math.inf, "-Infinity": -math.inf}[name]


def from_json(data: Any) -> TestCase:
    """Build a test case from parsed JSON, checking the envelope."""
    if not isinstance(data, dict):
        raise TestCaseError("a test case is a JSON object")
    if data.get("rrosfuzz") != FORMAT:
        raise TestCaseError(f"not an RROSFuzz test case (format {FORMAT})")
    msg_type, message = data.get("msg_type"), data.get("message")
    if not isinstance(msg_type, str) or not isinstance(message, dict):
        raise TestCaseError("msg_type must be a string and message an object")
    lineage = data.get("lineage", [])
    if not isinstance(lineage, list) or not all(isinstance(s, str) for s in lineage):
        raise TestCaseError("lineage must be a list of strings")
    sequence, length = data.get("sequence", 0), data.get("lineage_length", len(lineage))
    if type(sequence) is not int or type(length) is not int:
        raise TestCaseError("sequence and lineage_length must be integers")
    origin = data.get("origin", "external")
    if not isinstance(origin, str):
        raise TestCaseError("origin must be a string")
    return TestCase(msg_type, message, sequence, origin, tuple(lineage), length)


def read_bytes(path: Path) -> bytes:
    """A test case file's bytes, at most :data:`MAX_BYTES` of them read.

    Raises
    ------
    TestCaseError
        The file is larger than a test case may be (it is not read further: a 3 GB sparse file
        took 3 GB of memory and 15 s before the size check refused it).
    OSError
        The file cannot be read.
    """
    with open(path, "rb") as handle:
        data = handle.read(MAX_BYTES + 1)
    if len(data) > MAX_BYTES:
        raise TestCaseError(f"test case larger than {MAX_BYTES} bytes")
    return data


def read_case(path: Path) -> TestCase:
    """The test case in the file ``path`` (:func:`read_bytes`, then :func:`decode`).

    Raises
    ------
    TestCaseError
        Too large, or not a test case.
    OSError
        The file cannot be read.
    """
    return decode(read_bytes(path))


def decode(data: bytes) -> TestCase:
    """Parse test case bytes.

    Raises
    ------
    TestCaseError
        If the bytes are not UTF-8 JSON of this format (too large, truncated, ...).
    """
    if len(data) > MAX_BYTES:
        raise TestCaseError(f"test case larger than {MAX_BYTES} bytes")
    try:
        parsed = json.loads(data.decode("utf-8"), parse_constant=_reject_constant)
    except (ValueError, RecursionError) as exc:  # not UTF-8, not JSON, an int past 4,300 digits
        raise TestCaseError(f"not JSON: {exc}") from None
    return from_json(parsed)
