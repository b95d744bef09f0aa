"""From a URDF tree to the chain the API works on (docs/api.md, "The model").

The chain runs from the root link to the tip link; its variables are the
non-mimic movable joints on it, in order, followed by the masters of its mimic
joints that are not on it. Each chain joint becomes a *segment* with three
4x4 matrices such that its transform is ``A0 + u1 * A1 + u2 * A2`` with
``(u1, u2) = (sin q, 1 - cos q)`` for a revolute joint, ``(q, 0)`` for a
prismatic one and ``(0, 0)`` for a fixed one (Rodrigues' formula).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field, fields

import numpy as np
from numpy.typing import NDArray

from python_impl.transforms import homogeneous, rpy_matrix, skew, unit
from python_impl.urdf import Joint, Urdf
from robot_api.constants import DEFAULT_VELOCITY_LIMIT
from robot_api.errors import ErrorCode, UnknownNameError, URDFError
from robot_api.records import JointLimit, JointType, MimicJoint

MOVABLE = ("revolute", "continuous", "prismatic", "floating", "planar")

REVOLUTE, PRISMATIC, FIXED = 0, 1, 2


@dataclass(frozen=True)
class Chain:
    """The chain of a model, ready for kinematics.

    Attributes
    ----------
    name, root, tip : str
        Robot name and first/last link of the chain.
    link_names : tuple of str
        Links from root to tip; link ``k`` is the end of segment ``k - 1``.
    limits : tuple of JointLimit
        One per variable.
    mimics : tuple of MimicJoint
        Mimic joints on the chain.
    kind : ndarray of int, shape (S,)
        Per segment: REVOLUTE, PRISMATIC or FIXED.
    variable, multiplier, offset : ndarray, shape (S,)
        Segment value = ``multiplier * q[variable] + offset`` (variable -1: fixed).
    mimic : ndarray of bool, shape (S,)
    value_index : ndarray of int, shape (S,)
        ``variable`` with 0 for fixed segments (whose multiplier is 0).
    revolute, prismatic : ndarray of float, shape (S,)
        1.0 where the segment is of that kind, else 0.0.
    a0, a1, a2 : ndarray, shape (S, 4, 4)
        Segment transform coefficients (see module docstring).
    origin : ndarray, shape (S, 4, 4)
        Joint frame of each segment relative to its parent link.
    axis : ndarray, shape (S, 3)
        Unit joint axis in the joint frame (zero for fixed segments).
    key : bytes
        A digest of every field above (16 bytes), computed on construction: equal chains
        (the same robot loaded twice) have equal keys. The arrays are made read-only then, so
        the key stays true; a changed chain is a new one (``dataclasses.replace``).
    """

    name: str
    root: str
    tip: str
    link_names: tuple[str, ...]
    limits: tuple[JointLimit, ...]
    mimics: tuple[MimicJoint, ...]
    kind: NDArray[np.int64]
    variable: NDArray[np.int64]
    multiplier: NDArray[np.float64]
    offset: NDArray[np.float64]
    mimic: NDArray[np.bool_]
    value_index: NDArray[np.int64]
    revolute: NDArray[np.float64]
    prismatic: NDArray[np.float64]
    a0: NDArray[np.float64]
    a1: NDArray[np.float64]
    a2: NDArray[np.float64]
    origin: NDArray[np.float64]
    axis: NDArray[np.float64]
    key: bytes = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        digest = hashlib.blake2b(digest_size=16)
        for f in fields(self):
            if f.name == "key":
                continue
            value = getattr(self, f.name)
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
                digest.update(f"{f.name} {value.dtype.str} {value.shape}".encode())
                digest.update(np.ascontiguousarray(value).tobytes())
            else:
                digest.update(f"{f.name} {value!r}".encode())
        object.__setattr__(self, "key", digest.digest())

    @property
    def dof(self) -> int:
        return len(self.limits)


def _subtree_counts(urdf: Urdf) -> dict[str, int]:
    order: list[str] = []
    stack = [urdf.root]
    while stack:
        link = stack.pop()
        order.append(link)
        stack.extend(j.child for j in urdf.child_joints[link])
    count: dict[str, int] = {}
    for link in reversed(order):
        count[link] = sum((j.type in MOVABLE) + count[j.child] for j in urdf.child_joints[link])
    return count


def default_tip(urdf: Urdf) -> str:
    """Follow the only child, or the child subtree with strictly most movable joints."""
    count = _subtree_counts(urdf)
    link = urdf.root
    while urdf.child_joints[link]:
        children = urdf.child_joints[link]
        if len(children) == 1:
            link = children[0].child
            continue
        scores = [(j.type in MOVABLE) + count[j.child] for j in children]
        best = max(scores)
        if scores.count(best) != 1:
            break
        link = children[scores.index(best)].child
    return link


def deepest_links(urdf: Urdf, n: int = 4) -> list[str]:
    """Up to ``n`` leaf links with the most movable joints above them, most first (then by name):
    the tip links to suggest where :func:`default_tip` stops at a tie (Baxter's two arms)."""
    depth = {urdf.root: 0}
    stack = [urdf.root]
    while stack:
        link = stack.pop()
        for j in urdf.child_joints[link]:
            depth[j.child] = depth[link] + (j.type in MOVABLE)
            stack.append(j.child)
    leaves = [link for link in depth if not urdf.child_joints[link] and depth[link] > 0]
    return sorted(leaves, key=lambda link: (-depth[link], link))[:n]


def _check_joint(j: Joint) -> None:
    who = f"joint '{j.name}'"
    if j.type in ("floating", "planar"):
        raise URDFError(
            f"{who} is {j.type}: only revolute, continuous, prismatic and fixed joints are supported "
            "on the chain",
            ErrorCode.URDF_UNSUPPORTED,
        )
    if j.type == "fixed":
        return
    if j.axis == (0.0, 0.0, 0.0):
        raise URDFError(f"{who} has a zero axis", ErrorCode.URDF_INVALID)
    if j.type in ("revolute", "prismatic"):
        assert j.limits is not None  # the URDF reader requires them
        if j.limits.lower > j.limits.upper:
            raise URDFError(
                f"{who} has lower limit {j.limits.lower} above upper limit {j.limits.upper}",
                ErrorCode.URDF_INVALID,
            )


def _limit(j: Joint) -> JointLimit:
    velocity = j.limits.velocity if j.limits is not None else 0.0
    velocity = velocity if velocity > 0.0 else DEFAULT_VELOCITY_LIMIT
    if j.type == "continuous":
        return JointLimit(j.name, JointType.CONTINUOUS, -math.inf, math.inf, velocity)
    assert j.limits is not None
    kind = JointType.PRISMATIC if j.type == "prismatic" else JointType.REVOLUTE
    return JointLimit(j.name, kind, j.limits.lower, j.limits.upper, velocity)


def build_chain(urdf: Urdf, tip_link: str | None) -> Chain:
    """Select the chain, its variables and segments, and apply the chain rules.

    Raises
    ------
    URDFError, UnknownNameError
    """
    if tip_link is not None and tip_link not in urdf.child_joints:
        raise UnknownNameError(f"tip link '{tip_link}' is not in the URDF", ErrorCode.UNKNOWN_LINK)
    tip = tip_link if tip_link is not None else default_tip(urdf)

    path: list[Joint] = []
    link = tip
    while link in urdf.parent_joint:
        path.append(urdf.parent_joint[link])
        link = path[-1].parent
    path.reverse()

    for j in path:
        _check_joint(j)
    limits = [_limit(j) for j in path if j.type in MOVABLE and j.mimic is None]
    index = {lim.name: i for i, lim in enumerate(limits)}
    on_chain = {j.name for j in path}
    mimics: list[MimicJoint] = []
    for j in path:
        if j.mimic is None:
            continue
        who = f"mimic joint '{j.name}'"
        master = urdf.joints.get(j.mimic.joint)
        if master is None:
            raise URDFError(f"{who} follows unknown joint '{j.mimic.joint}'", ErrorCode.URDF_INVALID)
        if master.mimic is not None:
            raise URDFError(
                f"{who} follows '{master.name}', itself a mimic joint", ErrorCode.URDF_UNSUPPORTED
            )
        if master.type not in ("revolute", "continuous", "prismatic"):
            raise URDFError(
                f"{who} follows '{master.name}', a {master.type} joint", ErrorCode.URDF_UNSUPPORTED
            )
        if master.name not in on_chain and master.name not in index:
            _check_joint(master)
            index[master.name] = len(limits)
            limits.append(_limit(master))
        mimics.append(MimicJoint(j.name, master.name, j.mimic.multiplier, j.mimic.offset))

    n = len(path)
    kind = np.full(n, FIXED, dtype=np.int64)
    variable = np.full(n, -1, dtype=np.int64)
    multiplier = np.zeros(n)
    offset = np.zeros(n)
    mimic = np.zeros(n, dtype=bool)
    a0 = np.zeros((n, 4, 4))
    a1 = np.zeros((n, 4, 4))
    a2 = np.zeros((n, 4, 4))
    origin = np.zeros((n, 4, 4))
    axis = np.zeros((n, 3))
    for s, j in enumerate(path):
        t = homogeneous(rpy_matrix(*j.rpy), j.xyz)
        origin[s] = t
        a0[s] = t
        if j.type == "fixed":
            continue
        a = unit(j.axis)
        axis[s] = a
        if j.mimic is not None:
            variable[s], multiplier[s], offset[s], mimic[s] = (
                index[j.mimic.joint],
                j.mimic.multiplier,
                j.mimic.offset,
                True,
            )
        else:
            variable[s], multiplier[s] = index[j.name], 1.0
        if j.type == "prismatic":
            kind[s] = PRISMATIC
            e = np.zeros((4, 4))
            e[:3, 3] = a
            a1[s] = t @ e
        else:
            kind[s] = REVOLUTE
            k = np.zeros((4, 4))
            k[:3, :3] = skew(a)
            a1[s] = t @ k
            a2[s] = t @ k @ k
    return Chain(
        name=urdf.name,
        root=urdf.root,
        tip=tip,
        link_names=(urdf.root, *(j.child for j in path)),
        limits=tuple(limits),
        mimics=tuple(mimics),
        kind=kind,
        variable=variable,
        multiplier=multiplier,
        offset=offset,
        mimic=mimic,
        value_index=np.where(variable >= 0, variable, 0),
        revolute=(kind == REVOLUTE).astype(np.float64),
        prismatic=(kind == PRISMATIC).astype(np.float64),
        a0=a0,
        a1=a1,
        a2=a2,
        origin=origin,
        axis=axis,
    )
