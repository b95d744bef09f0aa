"""Typed records of the engine: what a target did, and how two targets differ."""

from __future__ import annotations

import enum
import hashlib
import json
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any, overload

import numpy as np


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


class Floats(Sequence[float]):
    """A flat, read-only sequence of floats kept only as a float64 array (``array``): equal to,
    hashed and printed as the tuple of its values, which it makes only when asked (iterating,
    comparing, hashing). A scenario's trajectory may have 60,001 points: kept as a tuple of
    Python floats beside its array, one plan's four fields took 47 MB per target instead of 11,
    and memory freed after such an input stayed with the process (BENCHMARKS.md, "Memory").
    :func:`floats` makes one, :func:`as_array` reads any sequence of floats as an array."""

    __slots__ = ("array",)
    array: np.ndarray

    def __init__(self, array: np.ndarray) -> None:
        self.array = array

    def __len__(self) -> int:
        return int(self.array.size)

    @overload
    def __getitem__(self, index: int) -> float: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[float, ...]: ...

    def __getitem__(self, index: int | slice) -> float | tuple[float, ...]:
        if isinstance(index, slice):
            return tuple(self.array[index].tolist())
        return float(self.array[index])

    def __iter__(self) -> Iterator[float]:
        return iter(self.array.tolist())

    def __array__(self, dtype: Any = None, copy: bool | None = None) -> np.ndarray:
        # numpy's protocol: ``copy`` True asks for a new (writeable) array; None or False may
        # share the read-only one, unless another dtype is asked for
        if copy or (dtype is not None and np.dtype(dtype) != self.array.dtype):
            return self.array.astype(dtype if dtype is not None else self.array.dtype)
        return self.array

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Floats | tuple):
            return tuple(self) == tuple(other)
        return NotImplemented

    def __hash__(self) -> int:
        return hash(tuple(self))

    def __repr__(self) -> str:
        return repr(tuple(self))

    def __add__(self, other: tuple[float, ...]) -> tuple[float, ...]:
        return tuple(self) + tuple(other)

    def __radd__(self, other: tuple[float, ...]) -> tuple[float, ...]:
        return tuple(other) + tuple(self)


def floats(values: Any) -> Floats:
    """Any array-like of reals as a flat :class:`Floats` (row-major): a read-only float64 copy
    (the target's own array may change)."""
    array = np.array(values, dtype=np.float64).ravel()
    array.flags.writeable = False
    return Floats(array)


def as_array(values: Any) -> np.ndarray:
    """``values`` (a :class:`Floats`, a tuple of floats, or any array-like of reals) as a
    float64 array: the read-only array a :class:`Floats` keeps, else a new one (``np.asarray``)."""
    array = getattr(values, "array", None)
    return array if isinstance(array, np.ndarray) else np.asarray(values, dtype=float)


def _listed(values: Sequence[float]) -> list[float]:
    return values.array.tolist() if isinstance(values, Floats) else list(values)


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
    values : dict of str to sequence of float
        Compared quantities: ``joint_values`` (rad, m), ``position`` (m), ``orientation`` (x, y, z, w);
        for a scenario step also its return values and trajectory (docs/engine.md, "Scenarios").
    steps : tuple of Outcome
        For ``--op scenario``: one outcome per executed step, in order (a step that crashed
        ends the scenario, so there may be fewer than the scenario's steps); else ().
    """

    status: Status
    error: str = ""
    code: int | None = None
    message: str = ""
    values: dict[str, Sequence[float]] = field(default_factory=dict)
    steps: tuple[Outcome, ...] = ()

    @property
    def label(self) -> str:
        """Status with the error class and code, e.g. ``rejected:OutOfBoundsError:30``."""
        if self.status in (Status.REJECTED, Status.CRASHED):
            return f"{self.status}:{self.error}:{self.code}"
        return str(self.status)

    def to_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {
            "status": str(self.status),
            "error": self.error,
            "code": self.code,
            "message": self.message,
            "values": {k: _listed(v) for k, v in self.values.items()},
        }
        if self.steps:
            data["steps"] = [step.to_json() for step in self.steps]
        return data

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Outcome:
        return cls(
            Status(data["status"]),
            data.get("error", ""),
            data.get("code"),
            data.get("message", ""),
            {k: tuple(float(x) for x in v) for k, v in data.get("values", {}).items()},
            tuple(cls.from_json(step) for step in data.get("steps", ())),
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
    STATE_DEPENDENT = "state_dependent"
    """Newly constructed targets agree on the input, the campaign's targets (with the calls
    made before it) diverge again: the answer depends on earlier calls."""
    PROPERTY = "property"
    """One target's own answer breaks the contract (an IK success outside the joint limits,
    or farther from the target than the solver's tolerance), whatever the other answered."""
    KNOWN_LIMITATION = "known_limitation"
    """A documented limitation of a target (docs/api.md, "Known limitations"), e.g. KDL's
    rotation dead zone near pi: not counted as a detection."""


UNCOUNTED = frozenset({Kind.KNOWN_LIMITATION, Kind.ILL_CONDITIONED})
"""Divergences the oracle explains: written as crash files for triage, never a finding (a
campaign does not fail on them; a replay that turns a file's divergence into one exits 0)."""

UNITS = {"position": "m", "orientation": "rad", "joint_values": "rad", "residual": "m"}


@dataclass(frozen=True)
class Comparison:
    """The oracle's verdict on a pair of outcomes.

    Attributes
    ----------
    kind : Kind
    field : str
        ``status``, ``joint_values``, ``position``, ``orientation``, or for ``property``
        ``joint_limits`` / ``residual``.
    difference : float
        The headline difference, in ``unit``: for value divergences the difference modulo
        equivalence (metres or radians); for representation divergences too (the numbers
        differ by a representation only, see ``raw``), so a representation is never a
        "large difference"; for property violations how far past the limit or tolerance;
        0 for status divergences.
    unit : str
        ``m``, ``rad`` or ``status`` (a scenario's quantities also ``s``, ``rad/s``...); for a
        value divergence on joint values, that of the joint the headline difference is from.
    sign_flip : bool
        Detail: the differing numbers have opposite signs (or the quaternions are q and -q):
        for a value divergence on joint values, the headline joint's; for a representation,
        those of the joint farthest apart as numbers.
    bucket : int
        Detail: ``floor(log10(difference))`` clipped to [-16, 3]; -99 when difference is 0.
    joints : tuple of int
        Joint indices that differ (joint values, property), else ().
    largest : float
        The paper's difference information: the largest raw difference (as numbers) over
        every compared field, whatever the verdict (0 without values). Never a headline.
    raw : float
        Detail: the gap as numbers in the reported field (for a representation divergence,
        e.g. 2pi for an angle, or a quaternion component gap for q vs -q).
    target : str
        The target a ``property`` violation belongs to, else ''.
    step : int or None
        For ``--op scenario``: the index (0-based) of the first divergent step; None otherwise.
    step_kind : str
        Its kind (``go``, ``plan``, ``cartesian_path``...; docs/engine.md, "Scenarios"), else ''.
        ``field`` then reads ``<step_kind>.<quantity>``, e.g. ``plan.trajectory.velocities``.
    unchecked : str
        The oracle's checks this verdict did not get to, else '': a campaign stops the
        ill-conditioning re-runs of one input at its time budget (``Evaluator.check_seconds``),
        and says so here; a replay runs them all.
    """

    kind: Kind
    field: str = ""
    difference: float = 0.0
    sign_flip: bool = False
    bucket: int = -99
    joints: tuple[int, ...] = ()
    largest: float = 0.0
    unit: str = "status"
    raw: float = 0.0
    target: str = ""
    step: int | None = None
    step_kind: str = ""
    unchecked: str = ""

    @property
    def divergent(self) -> bool:
        return self.kind is not Kind.AGREE

    def headline(self, joint_names: tuple[str, ...] = ()) -> str:
        """One line: kind, field, the headline difference with its unit, joint names."""
        return describe(
            str(self.kind),
            self.field,
            self.difference,
            self.unit,
            self.joints,
            joint_names,
            self.target,
            self.raw,
        )


def joint_label(joints: tuple[int, ...] | list[int], joint_names: tuple[str, ...] | list[str] = ()) -> str:
    """Joint names for people (``joint_2, joint_5``); ``joint #3`` when a name is unknown."""
    return ", ".join(joint_names[j] if 0 <= j < len(joint_names) else f"joint #{j + 1}" for j in joints)


def describe(
    kind: str,
    field_name: str,
    difference: float,
    unit: str,
    joints: tuple[int, ...] | list[int] = (),
    joint_names: tuple[str, ...] | list[str] = (),
    target: str = "",
    raw: float = 0.0,
) -> str:
    """The human-facing description of a divergence (summary, triage, report)."""
    text = f"{kind} on {field_name or 'status'}"
    if target:
        text += f" of {target}"
    if joints:
        text += f" ({joint_label(joints, joint_names)})"
    if unit and unit != "status" and kind != "flaky":
        text += f", difference {difference:.3g} {unit}"
        if kind == "representation" and raw > 0.0:
            text += f" (same value written differently: {raw:.3g} apart as numbers)"
    return text


@dataclass(frozen=True)
class Signature:
    """What makes two divergences "the same problem" (dedup key): what a person would call
    one problem, i.e. op, outcome pair, kind, field, the kinds of the joints involved and,
    for property violations, the target. The size of the difference and its sign are
    details of one occurrence, not part of the key. For status and crash divergences the
    outcome pair is coarse: ``completed`` stands for ok or failed beside a rejection or a
    crash, and ok vs failed is ``failed``/``ok`` whichever target failed (the sidecar's
    outcomes keep the exact labels)."""

    op: str
    outcome_a: str
    outcome_b: str
    kind: str
    field: str
    joint_types: tuple[str, ...] = ()
    target: str = ""

    @property
    def key(self) -> str:
        """Stable 12-hex-digit id."""
        text = json.dumps(asdict(self), sort_keys=True)
        return hashlib.sha1(text.encode()).hexdigest()[:12]

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "joint_types": list(self.joint_types), "key": self.key}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Signature:
        """Also reads the older format (with ``sign_flip``, ``bucket`` and joint indices,
        which are no longer part of the key): its key is then the new one."""
        fields = [data["op"], data["outcome_a"], data["outcome_b"], data["kind"], data["field"]]
        if not all(isinstance(x, str) for x in fields):
            raise TypeError("signature fields op, outcome_a, outcome_b, kind, field must be strings")
        types = data.get("joint_types", [])
        target = data.get("target", "")
        if not isinstance(types, list) or not all(isinstance(t, str) for t in types):
            raise TypeError("signature joint_types must be a list of strings")
        if not isinstance(target, str):
            raise TypeError("signature target must be a string")
        op, outcome_a, outcome_b, kind, field_name = fields
        return cls(op, outcome_a, outcome_b, kind, field_name, tuple(types), target)


COMPLETED = "completed"
"""A call that returned (ok or failed), in a signature beside a rejection or a crash."""


def _outcome_pair(field_name: str, a: str, b: str) -> tuple[str, str]:
    """The outcome labels of a divergence on the status (a status or crash divergence, and
    the kinds confirmation makes of them) as one problem: beside a rejection or a crash, ok
    and failed are both "completed" (the problem is that one side rejected or crashed); ok
    vs failed is one problem whichever side failed."""
    finished = {str(Status.OK), str(Status.FAILED)}
    if field_name == "status" or field_name.endswith(".status"):
        if a in finished and b in finished:
            return (str(Status.FAILED), str(Status.OK))
        return (COMPLETED if a in finished else a, COMPLETED if b in finished else b)
    return a, b


def signature_of(
    op: str, a: Outcome, b: Outcome, comparison: Comparison, joint_types: tuple[str, ...] = ()
) -> Signature:
    """The signature of a divergence; ``joint_types`` gives each joint's type by index."""
    types = sorted({joint_types[j] if j < len(joint_types) else "joint" for j in comparison.joints})
    outcome_a, outcome_b = _outcome_pair(comparison.field, a.label, b.label)
    return Signature(
        op, outcome_a, outcome_b, str(comparison.kind), comparison.field, tuple(types), comparison.target
    )
