"""Forward and inverse kinematics of the twin (numpy; no kinematics library).

FK multiplies the segment transforms ``A0 + u1 A1 + u2 A2`` (see
:mod:`python_impl.chain`). IK is Newton-Raphson on the error twist with a
truncated-SVD pseudo-inverse of the geometric Jacobian and joint limits
enforced by clamping after every step (docs/api.md, "Inverse kinematics"). An
iteration is a function of its iterate alone, so an iterate seen before (clamped joints
or steps that undo each other, common when the target is out of reach) starts a cycle:
the loop then skips to the iterate its last iteration would leave (``_cycle_end``), bit
for bit the answer of running every iteration. It is the loop's only shortcut: a solve that stalls
(steps of a few ulps, far from the target) runs on to the last iteration as KDL's does, since
a stall can be an unstable fixed point that the iterate leaves later (docs/benchmarks-log.md, "A stall
rule for the twin's IK measured and rejected"). ``ik`` is a function of its problem alone
(the chain, the target, the seed, the link), so it answers a problem it solved recently from
memory (``IK_MEMO``): scripts of calls repeat them (a scenario re-run to confirm a divergence,
a corpus' scripts that share their first steps).
"""

from __future__ import annotations

import math
import os
import struct
import threading
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from python_impl.angles import normalize_angle
from python_impl.chain import REVOLUTE, Chain
from python_impl.transforms import rotation_angle, rotation_vector
from robot_api.constants import IK_EPS, IK_MAX_ITERATIONS, IK_PINV_EPS

Array = NDArray[np.float64]


def segment_values(chain: Chain, q: Array) -> Array:
    """Joint value of every segment, shape (S,) or (N, S) for q of shape (dof,) or (N, dof)."""
    if q.shape[-1] == 0:  # no joint variable (a chain of fixed joints): nothing to index
        return np.zeros((*q.shape[:-1], len(chain.value_index))) + chain.offset
    return q[..., chain.value_index] * chain.multiplier + chain.offset


def _coefficients(chain: Chain, values: Array) -> tuple[Array, Array]:
    """(u1, u2) of every segment: (sin q, 1 - cos q) revolute, (q, 0) prismatic, (0, 0) fixed."""
    u1 = np.sin(values) * chain.revolute + values * chain.prismatic
    u2 = (1.0 - np.cos(values)) * chain.revolute
    return u1, u2


def segment_transforms(chain: Chain, q: Array, link: int) -> Array:
    """Transforms (link, 4, 4) of the first ``link`` segments, each relative to its parent link."""
    u1, u2 = _coefficients(chain, segment_values(chain, q))
    m: Array = (
        chain.a0[:link] + u1[:link, None, None] * chain.a1[:link] + u2[:link, None, None] * chain.a2[:link]
    )
    return m


def fk(chain: Chain, q: Array, link: int) -> Array:
    """Transform (4, 4) of link ``link`` (index into ``chain.link_names``) for q of shape (dof,).

    The segment transforms multiplied from the root, each product a 4x4 ``ndarray.dot`` (the
    same bits as ``@``, which costs twice as much a call on arrays this small).
    """
    if link == 0:
        return np.eye(4)
    m = segment_transforms(chain, q, link)
    t: Array = m[0]
    for s in range(1, link):
        t = t.dot(m[s])
    return t


def fk_batch(chain: Chain, q: Array, link: int) -> Array:
    """Transforms (N, 4, 4) of link ``link`` for q of shape (N, dof).

    Per segment, ``T (A0 + u1 A1 + u2 A2)`` is computed as ``T A0 + u1 (T A1) + u2 (T A2)``:
    three products of the stacked transforms with one constant 4x4 matrix each (one BLAS call
    on an (4N, 4) array), about twice as fast as N small matrix products. The result equals
    ``fk``'s row by row up to rounding (a few ulp).
    """
    n = q.shape[0]
    if link == 0 or n == 0:
        return np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    u1, u2 = _coefficients(chain, segment_values(chain, q))
    out: Array = chain.a0[0] + u1[:, 0, None, None] * chain.a1[0] + u2[:, 0, None, None] * chain.a2[0]
    for s in range(1, link):
        flat = out.reshape(n * 4, 4)
        nxt = (flat @ chain.a0[s]).reshape(n, 4, 4)
        if chain.revolute[s] or chain.prismatic[s]:
            nxt += u1[:, s, None, None] * (flat @ chain.a1[s]).reshape(n, 4, 4)
            nxt += u2[:, s, None, None] * (flat @ chain.a2[s]).reshape(n, 4, 4)
        out = nxt
    return out


@dataclass(frozen=True)
class Movable:
    """The movable segments among a chain's first ``link`` segments (``movable_segments``)."""

    mask: tuple[bool, ...]
    """Per segment: it moves."""
    columns: NDArray[np.int64]
    """(k,) the variable (Jacobian column) of each movable segment, in chain order."""
    axes: Array
    """(k, 3, 1) its unit axis in its joint frame."""
    revolute: NDArray[np.bool_]
    """(k,) bool: it is revolute (else prismatic)."""
    origins: Array
    """(k', 4, 4) the joint frames (``chain.origin``) of the movable segments after segment 0."""
    all_revolute: bool
    """Every movable segment is revolute (most arms): the Jacobian needs no per-column choice."""
    in_order: bool
    """The movable segments drive variables 0, 1, ..., k - 1, one each (no mimic joint)."""


def movable_segments(chain: Chain, link: int) -> Movable:
    """The movable segments before link ``link`` (once per IK call, not per iteration)."""
    variable = chain.variable[:link]
    index = np.flatnonzero(variable >= 0)
    revolute = chain.kind[index] == REVOLUTE
    return Movable(
        tuple(v >= 0 for v in variable.tolist()),
        variable[index],
        chain.axis[index][:, :, None],
        revolute,
        chain.origin[index[index > 0]],
        bool(revolute.all()),
        variable[index].tolist() == list(range(index.size)),
    )


_NEXT = np.array([1, 2, 0])
_AFTER = np.array([2, 0, 1])


def jacobian(chain: Chain, q: Array, link: int, nvars: int) -> Array:
    """Geometric Jacobian (6, nvars) of link ``link`` at its origin, in the root frame.

    Rows are (linear velocity, angular velocity); columns the first ``nvars``
    variables, which drive the first ``nvars`` movable segments (no mimics).
    """
    return fk_and_jacobian(chain, q, link, nvars)[1]


def fk_and_jacobian(
    chain: Chain, q: Array, link: int, nvars: int, movable: Movable | None = None
) -> tuple[Array, Array]:
    """``(fk(chain, q, link), jacobian(chain, q, link, nvars))`` from one pass over the segments.

    The running product of the segment transforms is ``fk``'s (the same products in the same
    order), so the transform equals ``fk``'s exactly. Each movable segment's joint frame is that
    product times the segment's origin; the Jacobian's columns are computed for all of them at
    once: ``(z x (p_tip - p_joint), z)`` for a revolute joint with world axis ``z``, ``(z, 0)``
    for a prismatic one. ``movable``: ``movable_segments(chain, link)``, if the caller has it.
    """
    if link == 0:
        return np.eye(4), np.zeros((6, nvars))
    m = segment_transforms(chain, q, link)
    if movable is None:
        movable = movable_segments(chain, link)
    # a movable segment's joint frame: the running product before it times its origin (the
    # products of all of them in one call); segment 0's origin is in the root frame already
    before: list[Array] = []
    mask = movable.mask
    t: Array = m[0]
    for s in range(1, link):
        if mask[s]:
            before.append(t)
        t = t.dot(m[s])  # fk's products, in fk's order
    if not movable.columns.size:
        return t, np.zeros((6, nvars))
    f = np.matmul(np.array(before), movable.origins) if before else movable.origins  # (k', 4, 4)
    if mask[0]:
        f = np.concatenate((chain.origin[:1], f))  # (k, 4, 4)
    z = np.matmul(f[:, :3, :3], movable.axes)[:, :, 0]  # (k, 3): world axis of each movable joint
    r = t[:3, 3] - f[:, :3, 3]
    # z x r: np.cross's own arithmetic (z1*r2 - z2*r1, z2*r0 - z0*r2, z0*r1 - z1*r0) on columns
    # rolled into place, without its per-call overhead
    cross = (z[:, _NEXT] * r[:, _AFTER] - z[:, _AFTER] * r[:, _NEXT]).T  # (3, k)
    if movable.all_revolute and movable.in_order and nvars == movable.columns.size:
        return t, np.concatenate((cross, z.T))  # every column filled, in order
    jac = np.zeros((6, nvars))
    jac[:3, movable.columns] = np.where(movable.revolute, cross, z.T)
    jac[3:, movable.columns] = np.where(movable.revolute, z.T, 0.0)
    return t, jac


def error_twist(current: Array, target: Array) -> Array:
    """(target position - position, rotation vector of ``R^T R_target`` in the root frame)."""
    rot = current[:3, :3]
    spin = rot.dot(rotation_vector(rot.T.dot(target[:3, :3])))
    return np.concatenate((target[:3, 3] - current[:3, 3], spin))


_ERROR_TWIST = error_twist
"""The module's own ``error_twist`` (``IK_MEMO`` is not consulted while it is replaced)."""


def is_small(twist: Array) -> bool:
    """Every component strictly inside ``(-IK_EPS, IK_EPS)``: the contract's "within IK_EPS"
    (docs/api.md, "Inverse kinematics"), open as KDL's ``Equal`` is (``a + eps > b && a - eps <
    b``); closed until 2026-12-06, a target exactly ``IK_EPS`` away was a twin's success and
    KDL's failure."""
    return all(x < IK_EPS and x + IK_EPS > 0.0 for x in twist.tolist())


def pinv_step(jac: Array, twist: Array) -> Array:
    """``J^+ twist`` with singular values below ``IK_PINV_EPS`` treated as zero."""
    u, s, vt = np.linalg.svd(jac, full_matrices=False)
    ut_twist = u.T.dot(twist).tolist()
    inv = [0.0 if abs(v) < IK_PINV_EPS else w / v for v, w in zip(s.tolist(), ut_twist, strict=True)]
    step: Array = vt.T.dot(inv)
    return step


IkAnswer = tuple[bool, tuple[float, ...], float, float]


class IkMemo:
    """The answers of recent IK problems, so that ``ik`` solves each only once.

    A problem is the chain (``Chain.key``: its content, so the same robot loaded again by a
    fresh model shares answers), the target's 16 floats, the seed's values, the link and the
    number of variables solved for, all by their bytes (``-0.0`` and ``0.0`` are different
    problems). Newton-Raphson is deterministic, so an answer from memory is the one solving
    again would give, bit for bit. The least recently used answer goes past ``size``
    problems. ``hits`` and ``misses`` count lookups since the last ``clear``, and ``kept`` is
    how many answers are held: plain attributes, so that a campaign's stats snapshot reads
    them without running this module's code, which the campaign instruments for coverage (a
    snapshot is due by the clock: code it ran would make the coverage depend on the time).

    Not consulted while the module's ``error_twist`` is replaced (the oracle's model of KDL's
    rotation dead zone, ``fuzzer.execution.dead_zone``), nor for a call that records a trace.
    """

    def __init__(self, size: int) -> None:
        self.size = size
        self.hits = 0
        self.misses = 0
        self.kept = 0
        self._answers: OrderedDict[bytes, IkAnswer] = OrderedDict()
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return len(self._answers)

    def clear(self) -> None:
        with self._lock:
            self._answers.clear()
            self.hits = self.misses = self.kept = 0

    def forked(self) -> None:
        """In a child just forked: its lookups are its own (the parent's lock may be held by a
        thread the child does not have, so the child gets a new one)."""
        self._lock = threading.Lock()
        self.hits = self.misses = 0

    def get(self, problem: bytes) -> IkAnswer | None:
        with self._lock:
            answer = self._answers.get(problem)
            if answer is None:
                self.misses += 1
            else:
                self.hits += 1
                self._answers.move_to_end(problem)
            return answer

    def put(self, problem: bytes, answer: IkAnswer) -> None:
        with self._lock:
            self._answers[problem] = answer
            self._answers.move_to_end(problem)
            while len(self._answers) > self.size:
                self._answers.popitem(last=False)
            self.kept = len(self._answers)


IK_MEMO = IkMemo(8192)
"""Answers of the last 8,192 IK problems (about 5 MB: 640 bytes each for a 6-joint arm)."""
if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=IK_MEMO.forked)


def _problem(chain: Chain, target: Array, seed: list[float], link: int, nvars: int) -> bytes:
    q = np.asarray(seed, dtype=np.float64)
    head = struct.pack("<qqq", link, nvars, q.size)
    return b"".join((chain.key, head, np.asarray(target, dtype=np.float64).tobytes(), q.tobytes()))


def ik(
    chain: Chain,
    target: Array,
    seed: list[float],
    link: int,
    nvars: int,
    trace: list[float] | None = None,
) -> tuple[bool, list[float], float, float]:
    """Newton-Raphson IK of link ``link``; returns (converged, q, position error, orientation error).

    ``seed`` is already clamped into the limits; variables from ``nvars`` on keep their seed values.
    A non-finite iterate (an absurd target) ends as not converged, with the seed's values.
    ``trace``, when given, receives the rotation error (rad, in [0, pi]) of every iterate, in order.
    A problem solved recently is answered from ``IK_MEMO``.
    """
    memo = IK_MEMO if trace is None and error_twist is _ERROR_TWIST else None
    problem = _problem(chain, target, seed, link, nvars) if memo is not None else b""
    known = memo.get(problem) if memo is not None else None
    if known is not None:
        converged, values, position_error, orientation_error = known
        return converged, list(values), position_error, orientation_error
    with np.errstate(all="ignore"):  # absurd targets overflow; handled below, not warned about
        answer = _ik(chain, target, seed, link, nvars, trace)
    if memo is not None:
        memo.put(problem, (answer[0], tuple(answer[1]), answer[2], answer[3]))
    return answer


_SETUPS: dict[tuple[bytes, int, int], tuple[Movable, Array, Array]] = {}
"""``_setup``'s answers by (``Chain.key``, link, number of variables)."""
_MAX_SETUPS = 256


def _setup(chain: Chain, link: int, nvars: int) -> tuple[Movable, Array, Array]:
    """What every IK problem of this chain, link and number of variables shares: the movable
    segments and the lower and upper limits of the variables solved for, shape (nvars,). A
    chain's arrays are read-only (``Chain``), so these are made once per process (a bounded
    table: at most :data:`_MAX_SETUPS` kept, all forgotten when it is full)."""
    key = (chain.key, link, nvars)
    setup = _SETUPS.get(key)
    if setup is None:
        lower = np.array([lim.lower for lim in chain.limits[:nvars]])
        upper = np.array([lim.upper for lim in chain.limits[:nvars]])
        setup = (movable_segments(chain, link), lower, upper)
        for array in (*setup[1:], setup[0].columns, setup[0].axes, setup[0].revolute, setup[0].origins):
            array.flags.writeable = False
        if len(_SETUPS) >= _MAX_SETUPS:
            _SETUPS.clear()
        _SETUPS[key] = setup
    return setup


def _ik(
    chain: Chain, target: Array, seed: list[float], link: int, nvars: int, trace: list[float] | None
) -> tuple[bool, list[float], float, float]:
    q = np.array(seed, dtype=np.float64)
    converged = False
    reached: Array | None = None  # fk at the last iterate, when the loop computed it
    if nvars == 0:
        converged = is_small(error_twist(fk(chain, q, link), target))
    else:
        start = q.copy()
        movable, lower, upper = _setup(chain, link, nvars)
        whole = nvars == q.size  # every variable is solved for: no slice of q to take
        # iterates so far (their bytes) and where each first came: an iterate seen before means
        # the rest is a cycle, whose end the loop would reach step by step (see _cycle_end)
        seen: dict[bytes, int] = {}
        iterates: list[bytes] = []
        base = len(trace) if trace is not None else 0  # where this call's rotation errors start
        for k in range(IK_MAX_ITERATIONS):
            key = q.tobytes()
            if key in seen:
                q = _cycle_end(iterates, seen[key], k, trace, base)
                break
            seen[key] = k
            iterates.append(key)
            current, jac = fk_and_jacobian(chain, q, link, nvars, movable)
            twist = error_twist(current, target)
            if trace is not None:
                trace.append(float(np.linalg.norm(twist[3:])))
            if is_small(twist):
                converged, reached = True, current
                break
            if not (np.isfinite(twist).all() and np.isfinite(jac).all()):
                q = start  # a non-finite iterate (absurd target): keep the clamped seed
                break
            if whole:
                q += pinv_step(jac, twist)
                np.minimum(np.maximum(q, lower), upper, out=q)
            else:
                q[:nvars] += pinv_step(jac, twist)
                q[:nvars] = np.minimum(np.maximum(q[:nvars], lower), upper)
        if not np.isfinite(q).all():
            q, converged = start, False
    values = q.tolist()
    for i, lim in enumerate(chain.limits[:nvars]):
        if lim.type == "continuous":
            values[i] = normalize_angle(values[i])
            reached = None  # the answer may differ from the last iterate
    if reached is None:  # else it is the last iterate, whose transform the loop has: fk's
        reached = fk(chain, np.array(values), link)
    d = reached[:3, 3] - target[:3, 3]
    position_error = math.sqrt(float(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
    orientation_error = rotation_angle(reached[:3, :3].T @ target[:3, :3])
    return converged, values, position_error, orientation_error


def _cycle_end(
    iterates: list[bytes], first: int, now: int, trace: list[float] | None, base: int = 0
) -> Array:
    """The iterate the loop would end with, once iterate ``now`` repeats iterate ``first``.

    Each iteration is a function of its iterate alone, so from ``first`` on the iterates
    repeat with period ``now - first``, none of them converged nor non-finite (they were
    all run once): the loop's last iterate is known without running the rest. ``trace``
    (this call's rotation errors from index ``base`` on, one per iterate run so far) gets
    those the remaining iterations would have appended. The result is bit for bit the one of
    running every iteration.
    """
    period = now - first
    if trace is not None:
        cycle = trace[base + first : base + now]
        trace.extend(cycle[(k - first) % period] for k in range(now, IK_MAX_ITERATIONS))
    last = first + (IK_MAX_ITERATIONS - first) % period
    return np.frombuffer(iterates[last], dtype=np.float64).copy()
