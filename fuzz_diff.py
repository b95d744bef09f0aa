#!/usr/bin/env python3
"""RROSFuzz entry point. Until the fuzzing engine lands, a self-check: both
targets load the default robot and agree on FK and on a few go() moves."""

from __future__ import annotations

import sys

import numpy as np

import native
import python_impl
from robot_api import robots


def main() -> int:
    urdf = robots.default_robot_path()
    a, b = native.RobotModel(urdf), python_impl.RobotModel(urdf)
    lower = [lim.lower for lim in a.joint_limits]
    upper = [lim.upper for lim in a.joint_limits]
    q = np.random.default_rng(0).uniform(lower, upper, (1000, a.dof))
    fk_gap = float(np.max(np.abs(a.forward_kinematics_batch(q) - b.forward_kinematics_batch(q))))
    ga, gb = native.MoveGroup(a), python_impl.MoveGroup(b)
    for row in q[:50]:
        ga.go(row.tolist())
        gb.go(row.tolist())
    move_gap = float(
        np.max(np.abs(np.subtract(ga.get_current_joint_values(), gb.get_current_joint_values())))
    )
    ok = fk_gap <= 1e-9 and move_gap <= 1e-12
    sys.stdout.write(
        f"self-check on {a.name}: FK gap {fk_gap:.2e}, go() gap {move_gap:.2e}: {'ok' if ok else 'FAIL'}\n"
    )
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
