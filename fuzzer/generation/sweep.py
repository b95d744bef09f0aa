"""Batched differential FK (issue 11): many configurations through both targets at once.

A single test case costs the engine about a millisecond of Python around microseconds of
kinematics. For ``--op fk`` (and ``move``: the FK of its goals) a sweep instead hands
``ROWS`` configurations to each target's ``forward_kinematics_batch`` in one call and compares
the two (N, 4, 4) answers with a vectorized oracle (``differences``): the position gap (m,
Euclidean, as the single-call oracle's) and the rotation angle between the two rotation
matrices (rad). The rows are:

* **a pattern search** around the campaign's highest-difference inputs (the harness's pool,
  Algorithm 3) that are not divergent yet, when their difference is above rounding noise
  (``NOISE``): every joint moved
  alone by +- each of ``SCALES`` of its range, and as many random directions (an
  alternating-variable / Hooke-Jeeves exploratory step, all of it in one batch). A row whose
  difference grows goes back to the pool, so the next sweep starts from it: the search
  follows the difference uphill;
* **space-filling** rows for the rest: the next block of a scrambled Sobol sequence inside the
  limits (``SpaceFill``, its own seed), so a fault confined to a narrow region of the joint
  space is met at batch speed. The dry run's sweeps (``fuzzer.dry_run``), made before
  ``scipy.stats`` is imported, draw uniform pseudo-random rows instead (``source`` ``uniform``,
  ``spacefill.Uniform``).

The vectorized oracle is only a filter. A row it flags (either gap above half the campaign's
tolerance, or a non-finite answer) becomes an ordinary test case (a ``JointState`` or
``Float64MultiArray`` made from a seed, lineage ``sweep:sobol`` (``sweep:uniform``) or
``sweep:<joint>:<step>``)
that the harness evaluates like any other input: the single-call oracle, confirmation on
fresh targets, a crash file and sidecar per new signature. A flagged row the single call does
not confirm (the targets' batch and single paths disagree) is counted, not reported.
Representation-only differences (a quaternion's sign) do not exist in rotation matrices;
the single-call path keeps finding those.

A sweep is due after every ``EVERY`` single inputs (``Sweep.due``), so which inputs a campaign
runs depends only on its seed, not on the clock: two runs of one ``-runs`` command keep the
same corpus (docs/engine.md, "Reproducing a campaign"). ``EVERY`` is chosen to give the sweeps
about half of an instrumented campaign's time on the default arm.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fuzzer.execution.tolerance import Tolerance
from fuzzer.generation.spacefill import SpaceFill, Uniform

ROWS = 1024
"""Configurations per sweep (a power of two keeps the Sobol block balanced)."""

EVERY = 3
"""Single inputs per sweep. A sweep of ``ROWS`` rows costs about as much as three instrumented
single ``fk`` inputs on the default arm (``stats.jsonl``'s ``sweep.seconds`` against the
campaign's), so this gives the sweeps about half of the time, as the clock-shared schedule
before 2026-12-03 did (``SHARE`` then: 0.5)."""

EVERY_OP = {"fk": EVERY, "move": 64}
"""Single inputs per sweep, per op (``SWEEP_OPS``). A ``move`` input costs several ``fk`` ones
(a plan, its execution, FK of the end), and a sweep finds only what the FK of a move's goal
shows (a ``move`` row becomes a move to that configuration at default scaling), not what the
plan or its execution get wrong. With a sweep every 32 inputs, a ``move`` campaign ran 17%
fewer single inputs a second (696 against 836, 9 runs each; a sweep about 7.7 ms there):
every 64 gives them about a tenth."""

SWEEP_OPS = frozenset(EVERY_OP)
"""Ops whose full-engine campaigns sweep, in process (``fuzzer.selection.search``)."""

SCALES = (1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
"""Pattern-search steps, as fractions of each joint's range."""

CENTRES = 4
"""Pool inputs a sweep searches around (the highest differences)."""

NOISE = 1e-12
"""A difference (m or rad) at or below this is rounding noise: nothing to follow."""

CONFIRM = 2
"""Flagged rows per sweep handed to the single-call path (the others wait for later sweeps)."""

Array = NDArray[np.float64]

SOURCES: dict[str, type[SpaceFill] | type[Uniform]] = {"sobol": SpaceFill, "uniform": Uniform}
"""A sweep's space-filling rows, by name (its lineage label ``sweep:<name>``)."""


def differences(a: Array, b: Array) -> tuple[Array, Array]:
    """Position gap (m) and rotation angle (rad) per row of two (N, 4, 4) transform stacks.

    The angle is ``2 asin(|Ra - Rb|_F / (2 sqrt 2))``, exact for rotation matrices and
    well-conditioned near zero (unlike ``acos((trace - 1) / 2)``). A non-finite answer in
    either stack gives ``inf`` in both.
    """
    position = np.sqrt(np.sum((a[:, :3, 3] - b[:, :3, 3]) ** 2, axis=1))
    frobenius = np.sqrt(np.sum((a[:, :3, :3] - b[:, :3, :3]) ** 2, axis=(1, 2)))
    with np.errstate(invalid="ignore"):
        angle = 2.0 * np.arcsin(np.minimum(1.0, frobenius / (2.0 * math.sqrt(2.0))))
    bad = ~(np.isfinite(a).all(axis=(1, 2)) & np.isfinite(b).all(axis=(1, 2)))
    position[bad] = np.inf
    angle[bad] = np.inf
    return position, angle


@dataclass(frozen=True)
class Row:
    """One configuration of a sweep worth a test case."""

    values: tuple[float, ...]
    label: str
    """The lineage step: ``sweep:sobol``, ``sweep:uniform`` or ``sweep:<joint index><+|-><step>``."""
    difference: float
    """max(position gap in m, rotation angle in rad)."""


@dataclass(frozen=True)
class SweepResult:
    flagged: tuple[Row, ...]
    """Rows above half the tolerance (largest first, at most ``CONFIRM``)."""
    improved: tuple[Row, ...]
    """Per centre, its best neighbour when that beats the centre (not flagged)."""
    rows: int


@dataclass
class Sweep:
    """Batched neighbourhood and space-filling evaluation for ``--op fk``.

    Parameters
    ----------
    lower, upper : sequence of float, length dof
        Joint limits (rad, m); infinite bounds (continuous joints) become -pi / pi.
    tolerance : Tolerance
        The campaign's; rows above half of it are flagged.
    seed : int
        Seeds the Sobol stream and the random directions.
    link : str or None
        The link the campaign's FK calls ask for (None: the tip).
    source : {"sobol", "uniform"}
        The space-filling rows: ``SpaceFill`` (imports ``scipy.stats``) or ``Uniform``.
    every : int
        Single inputs per sweep (``due``; 0: never due, the caller runs them).
    """

    lower: Sequence[float]
    upper: Sequence[float]
    tolerance: Tolerance
    seed: int = 0
    link: str | None = None
    source: str = "sobol"
    rows: int = ROWS
    every: int = EVERY
    first_rows: int = 0
    """Rows of the first sweep (0: ``rows``). The dry run's first is small (``fuzzer.dry_run.FIRST_ROWS``):
    a divergence most configurations show is then reported about 2 ms after the first input,
    not after 1,024 rows through two targets (3 ms on the first call)."""
    sweeps: int = 0
    compared: int = 0
    flagged: int = 0
    """Rows the vectorized oracle flagged (all of them, confirmed or not)."""
    unconfirmed: int = 0
    """Flagged rows the single-call path did not confirm (counted by the harness)."""
    failed: int = 0
    """Sweeps a target raised in (the sweep is then switched off after ``MAX_FAILURES``)."""
    seconds: float = 0.0
    _waited: int = field(default=0, repr=False)
    """Single inputs since the last sweep ``due`` allowed."""
    _stream: SpaceFill | Uniform = field(init=False, repr=False)
    _rng: np.random.Generator | None = field(default=None, init=False, repr=False)
    """The neighbourhoods' random directions, made at the first centre (importing
    ``numpy.random`` costs 7-10 ms, which a dry run's first sweep, without centres, need not wait for)."""

    MAX_FAILURES = 3

    def __post_init__(self) -> None:
        if self.source not in SOURCES:
            raise ValueError(f"unknown sweep source {self.source!r} (one of {', '.join(SOURCES)})")
        self._stream = SOURCES[self.source](self.lower, self.upper, seed=self.seed)
        self._lo, self._hi = self._stream.box()

    def prime(self) -> None:
        """Make the Sobol engine now (``scipy.stats``: 0.55-1.1 s of imports), not inside the
        first sweep's input. A ``-fork`` worker, which writes no space-filling seeds, otherwise
        paid it inside an input, where a Ctrl-C was lost: the job ran on and its supervisor
        started the next job."""
        if isinstance(self._stream, SpaceFill):
            self._stream.ready()

    @property
    def enabled(self) -> bool:
        return self.failed < self.MAX_FAILURES

    def due(self) -> bool:
        """Whether a sweep is due: called once per single input, true on every ``every``-th
        call (never with ``every`` 0, or once the sweeps are off)."""
        if not (self.every > 0 and self.enabled):
            return False
        self._waited += 1
        if self._waited < self.every:
            return False
        self._waited = 0
        return True

    def batch(self, centres: Sequence[tuple[tuple[float, ...], float]]) -> tuple[Array, list[str], list[int]]:
        """The rows of the next sweep: (q of shape (rows, dof), lineage label per row, index of
        the centre per row or -1 for a space-filling row)."""
        dof = len(self._lo)
        span = np.where(self._hi > self._lo, self._hi - self._lo, 0.0)
        parts: list[Array] = []
        labels: list[str] = []
        owner: list[int] = []
        rows = self.first_rows if self.first_rows and not self.sweeps else self.rows
        budget = rows // 2
        ceiling = 0.5 * min(self.tolerance.metres, self.tolerance.radians)
        for c, (values, difference) in enumerate(centres[:CENTRES]):
            if not NOISE < difference < ceiling or len(values) != dof:
                continue  # nothing to follow, or already divergent (found: the pool keeps it)
            centre = np.asarray(values, dtype=np.float64)
            for scale in SCALES:
                if budget < 4 * dof:
                    break
                steps = np.diag(span * scale)
                if self._rng is None:
                    self._rng = np.random.default_rng(self.seed)
                directions = self._rng.standard_normal((2 * dof, dof)) * (span * scale)
                block = centre + np.vstack([steps, -steps, directions])
                parts.append(block)
                labels += [f"sweep:{j}+{scale:g}" for j in range(dof)]
                labels += [f"sweep:{j}-{scale:g}" for j in range(dof)]
                labels += [f"sweep:dir{scale:g}"] * (2 * dof)
                owner += [c] * (4 * dof)
                budget -= 4 * dof
        used = sum(len(p) for p in parts)
        fill = self._stream.block(rows - used)
        parts.append(fill)
        labels += [f"sweep:{self.source}"] * len(fill)
        owner += [-1] * len(fill)
        q = np.clip(np.vstack(parts), self._lo, self._hi)
        return q, labels, owner

    def run(self, models: Sequence[Any], centres: Sequence[tuple[tuple[float, ...], float]]) -> SweepResult:
        """Evaluate one sweep on two models (each with ``forward_kinematics_batch``)."""
        began = time.monotonic()
        try:
            q, labels, owner = self.batch(centres)
            try:
                a = np.asarray(models[0].forward_kinematics_batch(q, self.link), dtype=np.float64)
                b = np.asarray(models[1].forward_kinematics_batch(q, self.link), dtype=np.float64)
            except Exception:  # noqa: BLE001 - a target's batch path failing is not this sweep's input
                self.failed += 1
                return SweepResult((), (), 0)
            if a.shape != (len(q), 4, 4) or b.shape != a.shape:
                self.failed += 1
                return SweepResult((), (), 0)
            position, angle = differences(a, b)
            worst = np.maximum(position, angle)
            over = (position > 0.5 * self.tolerance.metres) | (angle > 0.5 * self.tolerance.radians)
            picked = np.flatnonzero(over)
            self.flagged += len(picked)
            picked = picked[np.argsort(-worst[picked], kind="stable")][:CONFIRM]
            flagged = tuple(Row(tuple(map(float, q[i])), labels[i], float(worst[i])) for i in picked)
            improved = []
            owners = np.asarray(owner)
            for c in sorted(set(owner) - {-1}):
                rows = np.flatnonzero((owners == c) & ~over)
                if len(rows):
                    best = rows[int(np.argmax(worst[rows]))]
                    if worst[best] > centres[c][1]:
                        improved.append(Row(tuple(map(float, q[best])), labels[best], float(worst[best])))
            self.sweeps += 1
            self.compared += len(q)
            return SweepResult(flagged, tuple(improved), len(q))
        finally:
            self.seconds += time.monotonic() - began

    def to_json(self) -> dict[str, Any]:
        return {
            "sweeps": self.sweeps,
            "compared": self.compared,
            "flagged": self.flagged,
            "unconfirmed": self.unconfirmed,
            "failed": self.failed,
            "seconds": round(self.seconds, 3),
        }
