"""KDL's rotation dead zone, put into the twin for one re-run: does it explain a divergence?

KDL's ``diff``/``Rotation::GetRot`` returns exactly zero for a rotation whose off-diagonal
asymmetries are all below its epsilon (1e-6), about 5e-7 rad (docs/api.md, "Known
divergences"). The twin (``python_impl``) takes an exact logarithm. Newton-Raphson's first
step toward a pose whose orientation the seed already holds to within that band then differs:
KDL corrects the position only, the twin also the 1e-8 rad of rotation left. Near a wrist
singularity the pseudo-inverse turns those 1e-8 rad into a joint step of 1e-6 rad or more
along the near-singular direction, and a joint that sits a few 1e-6 rad inside its limit is
clamped on one side and not on the other. The clamped iterates then stall with a rotation
error above the tolerance, and a Cartesian path stops there on one target while it goes on
on the other. Both follow the documented algorithm; only the dead zone parts them.

:func:`twin_with_kdl_dead_zone` makes the twin's IK use KDL's rule for the duration of a
``with`` block (in this process: an in-process twin, or a target built on it such as the
zoo's variants; a plugin is unaffected, so the divergence stands). A target in a ROS node is
asked to do the same in its own process for the calls made inside the block (:func:`active`;
``fuzzer.ros.transport``: the rospy node swaps its twin; the C++ node has none): before, over
ROS the swap changed nothing, and a divergence explained in process was counted there. The twin's
own code is untouched: the oracle swaps the one function that computes the error twist
(``python_impl.kinematics.error_twist``), as this module is the oracle's model of KDL, not
part of the twin.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any

import numpy as np

KDL_EPSILON = 1e-6
"""KDL's ``epsilon``: the asymmetry below which ``GetRotAngle`` reports no rotation."""


def within_dead_zone(relative: Any) -> bool:
    """Whether KDL's ``GetRotAngle`` reports the rotation matrix ``relative`` (3 x 3) as the
    identity: every off-diagonal asymmetry below ``KDL_EPSILON`` and the diagonal within ten
    times that of ones (KDL's test; the half-turn case it also has is not taken here)."""
    r = np.asarray(relative, dtype=np.float64)
    asymmetric = max(abs(r[0, 1] - r[1, 0]), abs(r[0, 2] - r[2, 0]), abs(r[1, 2] - r[2, 1]))
    if not asymmetric < KDL_EPSILON:
        return False
    symmetric = max(abs(r[0, 1] + r[1, 0]), abs(r[0, 2] + r[2, 0]), abs(r[1, 2] + r[2, 1]))
    return bool(symmetric < 10 * KDL_EPSILON and abs(np.trace(r) - 3.0) < 10 * KDL_EPSILON)


_ACTIVE: list[bool] = []


def active() -> bool:
    """Whether a :func:`twin_with_kdl_dead_zone` block is running (its calls to a target in a
    ROS node ask the node for the same swap)."""
    return bool(_ACTIVE)


@contextlib.contextmanager
def twin_with_kdl_dead_zone() -> Iterator[bool]:
    """While active, the twin's error twist has no rotation part when KDL would report none.
    Yields False (and changes nothing) when the twin cannot be imported."""
    try:
        from python_impl import kinematics
    except ImportError:
        yield False
        return
    exact = kinematics.error_twist

    def with_dead_zone(current: Any, target: Any) -> Any:
        twist = exact(current, target)
        if within_dead_zone(current[:3, :3].T @ target[:3, :3]):
            twist = twist.copy()
            twist[3:] = 0.0
        return twist

    kinematics.error_twist = with_dead_zone
    _ACTIVE.append(True)
    try:
        yield True
    finally:
        _ACTIVE.pop()
        kinematics.error_twist = exact
