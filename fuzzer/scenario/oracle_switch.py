"""Accelerations at a switch of a piecewise-constant profile: either side's value holds.

A trapezoidal (or triangular) time law has a piecewise-constant acceleration. When a sample
time falls on a switch (accelerate -> cruise, cruise -> decelerate, accelerate -> decelerate),
the acceleration there is discontinuous and both one-sided values are right: which one a
target reports is decided by ``t < ta`` on the last bits of ``ta``, so two correct targets whose
inputs differ by one rounding (an IK answer 1e-15 apart) can report different ones.

An entry ``(i, j)`` whose accelerations differ beyond the tolerance is on a switch when
``0 < i < M - 1`` and:

* the neighbours agree across the targets: ``left = acc[i-1, j]`` and ``right = acc[i+1, j]``,
  each within the tolerance on both sides;
* one target reports ``left`` at ``i`` and the other ``right`` (within the tolerance);
* on each target the velocities follow ``left`` up to ``i`` and ``right`` after it:
  ``|v[i] - v[i-1] - left (t[i] - t[i-1])|`` and ``|v[i+1] - v[i] - right (t[i+1] - t[i])|``
  are at most ``SWITCH_TIME * |left - right| + VELOCITY_ROUNDING``, which holds only when the
  switch is within ``SWITCH_TIME`` of ``t[i]``: a switch anywhere inside an interval leaves a
  residual of ``|left - right|`` times its distance to the sample.

A target that reports a switch one sample early or late (its switch strictly between two
samples) fails the velocity check and still diverges.
"""

from __future__ import annotations

import numpy as np

ACCELERATION_TOLERANCE = 1e-6
"""Trajectory accelerations (rad/s^2 or m/s^2): the scenario oracle's tolerance on them."""
SWITCH_TIME = 1e-9
"""A sample this close to a switch of the acceleration is on it (s)."""
VELOCITY_ROUNDING = 1e-12
"""Rounding allowed in the velocity checks (rad/s or m/s)."""

Profile = tuple[np.ndarray, np.ndarray, np.ndarray]
"""time_from_start (M,), velocities (M, dof), accelerations (M, dof) of one target."""


def _follows(times: np.ndarray, v: np.ndarray, i: int, left: float, right: float) -> bool:
    allow = SWITCH_TIME * abs(left - right) + VELOCITY_ROUNDING
    before = v[i] - v[i - 1] - left * (times[i] - times[i - 1])
    after = v[i + 1] - v[i] - right * (times[i + 1] - times[i])
    return bool(abs(before) <= allow and abs(after) <= allow)


def on_switch(a: Profile, b: Profile, limit: float) -> np.ndarray:
    """Mask (M, dof) of the acceleration entries that differ beyond ``limit`` only by the side
    of a switch each target took (module docstring).

    Parameters
    ----------
    a, b : Profile
        Each target's ``time_from_start`` (M,) in s, velocities and accelerations (M, dof).
    limit : float
        Acceleration tolerance (rad/s^2 or m/s^2).
    """
    (ta, va, aa), (tb, vb, ab) = a, b
    explained = np.zeros(aa.shape, dtype=bool)
    m = aa.shape[0]
    for i, j in np.argwhere(~(np.abs(aa - ab) <= limit)):
        if not 0 < i < m - 1:
            continue
        left, right = float(aa[i - 1, j]), float(aa[i + 1, j])
        if not (abs(ab[i - 1, j] - left) <= limit and abs(ab[i + 1, j] - right) <= limit):
            continue
        x, y = float(aa[i, j]), float(ab[i, j])
        sides = (abs(x - left) <= limit and abs(y - right) <= limit) or (
            abs(x - right) <= limit and abs(y - left) <= limit
        )
        explained[i, j] = sides and all(
            _follows(t, v[:, j], int(i), left, right) for t, v in ((ta, va), (tb, vb))
        )
    return explained


def canonical(a: Profile, b: Profile, limit: float) -> np.ndarray:
    """``b``'s accelerations (M, dof) with each entry on a switch replaced by ``a``'s."""
    return np.where(on_switch(a, b, limit), a[2], b[2])
