"""Typed records of the engine: what a target did, and how two targets differ."""

from __future__ import annotations

import enum
import hashlib
import json
from dataclasses import asdict, dataclass, field
from typing import Any


class Status(enum.StrEnum):
    """How a call on one target ended."""

    OK = "ok"
    """Completed (``go()`` returned True, FK returned a pose, IK converged)."""
    FAILED = "failed"
    """Completed without success: ``go()`` returned False, IK reported NO_SOLUTION."""
    REJECTED = "rejected"
    """Raised an error of the API (``robot_api.errors``), with a class and a code."""
    CRASHED = "crashed"
    """Raised anything else: a robustness bug in the target."""


@dataclass(frozen=True)
class Outcome:
    """A target's answer to one input: (status, value).

    Attributes
    ----------
    status : Status
    error : str
        Exception class name (REJECTED/CRASHED), else ''.
    code : int or None
        ``ErrorCode`` value for REJECTED.
    message : str
        Exception text (never compared).
    values : dict of str to tuple of float
        Compared quantities: ``joint_values`` (rad, m), ``position`` (m), ``orientation`` (x, y, z, w).
    """

    status: Status
    error: str = ""
    code: int | None = None
    message: str = ""
    values: dict[str, tuple[float, ...]] = field(default_factory=dict)

    @property
    def label(self) -> str:
        """Status with the error class and code, e.g. ``rejected:OutOfBoundsError:30``."""
        if self.status in (Status.REJECTED, Status.CRASHED):
            return f"{self.status}:{self.error}:{self.code}"
        return str(self.status)

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        data["status"] = str(self.status)
        data["values"] = {k: list(v) for k, v in self.values.items()}
        return data

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Outcome:
        return cls(
            Status(data["status"]),
            data.get("error", ""),
            data.get("code"),
            data.get("message", ""),
            {k: tuple(float(x) for x in v) for k, v in data.get("values", {}).items()},
        )


class Kind(enum.StrEnum):
    """What kind of disagreement two outcomes show."""

    AGREE = "agree"
    STATUS = "status"
    """Different statuses, or different error classes/codes."""
    CRASH = "crash"
    """At least one target crashed (a non-API exception)."""
    VALUE = "value"
    """Values differ beyond tolerance even modulo true equivalence."""
    REPRESENTATION = "representation"
    """Equal modulo equivalence (q vs -q, angle vs angle +- 2pi) but not as numbers:
    the paper's "positive and negative" inconsistency."""
    ILL_CONDITIONED = "ill_conditioned"
    """A status divergence that a 1e-9 change of the IK seed flips on one target by itself."""
    FLAKY = "flaky"
    """Re-running the same input gave a different verdict: nondeterminism."""


@dataclass(frozen=True)
class Comparison:
    """The oracle's verdict on a pair of outcomes.

    Attributes
    ----------
    kind : Kind
    field : str
        ``status``, ``joint_values``, ``position`` or ``orientation``.
    difference : float
        Largest difference found (m or rad), raw for representation differences,
        after canonicalization for value differences; 0 for status divergences.
    sign_flip : bool
        The differing numbers have opposite signs (or the quaternions are q and -q).
    bucket : int
        ``floor(log10(difference))`` clipped to [-16, 3]; -99 when difference is 0.
    joints : tuple of int
        Joint indices that differ (joint values), else ().
    largest : float
        The paper's difference information: the largest raw difference over every
        compared field, whatever the verdict (0 without values).
    """

    kind: Kind
    field: str = ""
    difference: float = 0.0
    sign_flip: bool = False
    bucket: int = -99
    joints: tuple[int, ...] = ()
    largest: float = 0.0

    @property
    def divergent(self) -> bool:
        return self.kind is not Kind.AGREE


@dataclass(frozen=True)
class Signature:
    """What makes two divergences "the same problem" (dedup key)."""

    op: str
    outcome_a: str
    outcome_b: str
    kind: str
    field: str
    sign_flip: bool
    bucket: int
    joints: tuple[int, ...]

    @property
    def key(self) -> str:
        """Stable 12-hex-digit id."""
        text = json.dumps(asdict(self), sort_keys=True)
        return hashlib.sha1(text.encode()).hexdigest()[:12]

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "joints": list(self.joints), "key": self.key}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Signature:
        return cls(
            data["op"],
            data["outcome_a"],
            data["outcome_b"],
            data["kind"],
            data["field"],
            bool(data["sign_flip"]),
            int(data["bucket"]),
            tuple(int(j) for j in data["joints"]),
        )


def signature_of(op: str, a: Outcome, b: Outcome, comparison: Comparison) -> Signature:
    return Signature(
        op,
        a.label,
        b.label,
        str(comparison.kind),
        comparison.field,
        comparison.sign_flip,
        comparison.bucket,
        comparison.joints,
    )
