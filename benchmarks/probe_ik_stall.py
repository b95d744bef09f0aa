"""Would a stall rule in the twin's IK change its answers? (issue 11; a rule tried on paper, rejected)

The twin's Newton-Raphson (``python_impl.kinematics._ik``) runs all ``IK_MAX_ITERATIONS``
iterations of a failing solve, as KDL's ``ChainIkSolverPos_NR_JL`` does. Many failing solves
settle against a joint limit long before the last iteration, their steps down to a few ulps.
A *stall rule* would stop such a solve early: the iterate moved by at most ``STEP`` (inf-norm,
rad or m) in each of the last ``WINDOW`` iterations while the error twist stayed above ``FAR``
(every iteration after that looks the same, so the answer would be the same to a few ulps).

This probe runs the documented loop to the end on random problems and asks, for each solve the
rule would have stopped: did the full run converge later (a status the rule would flip), and
did any later step exceed ``ESCAPE`` (the iterate left its stall)? Problems, per robot and in
turn: a reachable target from a random seed; the same target 1.5 times farther from the base
(mostly out of reach); a reachable target from a seed of limits or of zeros clamped into them.

    .venv/bin/python -m benchmarks.probe_ik_stall probot_anno ur5 --problems 3000 --seed 7

One JSON line per robot. Measured in docs/benchmarks-log.md ("A stall rule for the twin's IK, measured
and rejected").
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Sequence

import numpy as np

from python_impl import kinematics as kin
from python_impl.chain import Chain
from python_impl.model import RobotModel
from robot_api import robots
from robot_api.constants import IK_MAX_ITERATIONS
from robot_api.errors import RobotAPIError

STEP = 1e-12
WINDOW = 5
FAR = 1e-3
ESCAPE = 1e-10


def solve(
    chain: Chain, target: np.ndarray, seed: np.ndarray, link: int, nvars: int
) -> tuple[bool, list[float], list[float], list[np.ndarray]] | None:
    """The documented loop, every iteration: (converged, steps, largest twist component per
    iterate, iterates), or None for a non-finite iterate."""
    lower = np.array([lim.lower for lim in chain.limits[:nvars]])
    upper = np.array([lim.upper for lim in chain.limits[:nvars]])
    q = seed.astype(np.float64).copy()
    movable = kin.movable_segments(chain, link)
    steps: list[float] = []
    twists: list[float] = []
    iterates: list[np.ndarray] = []
    for _ in range(IK_MAX_ITERATIONS):
        current, jac = kin.fk_and_jacobian(chain, q, link, nvars, movable)
        twist = kin.error_twist(current, target)
        twists.append(float(np.abs(twist).max()))
        iterates.append(q.copy())
        if kin.is_small(twist):
            return True, steps, twists, iterates
        if not (np.isfinite(twist).all() and np.isfinite(jac).all()):
            return None
        new = np.minimum(np.maximum(q[:nvars] + kin.pinv_step(jac, twist), lower), upper)
        steps.append(float(np.abs(new - q[:nvars]).max()))
        q[:nvars] = new
    iterates.append(q.copy())
    return False, steps, twists, iterates


def stall(steps: Sequence[float], twists: Sequence[float]) -> int | None:
    """The iterate the rule would stop at, or None."""
    still = 0
    for k, s in enumerate(steps):
        still = still + 1 if s <= STEP and twists[k] > FAR else 0
        if still >= WINDOW:
            return k + 1
    return None


def probe(robot: str, problems: int, seed: int) -> dict[str, object]:
    model = RobotModel(robots.resolve(robot))
    chain = model.chain
    tip = len(chain.link_names) - 1
    nvars = model._ik_variables(tip)
    lo = np.array([max(lim.lower, -math.pi) for lim in chain.limits])
    hi = np.array([min(lim.upper, math.pi) for lim in chain.limits])
    rng = np.random.default_rng(seed)
    failed = iterations = stopped = saved = flips = escapes = 0
    largest_after, largest_change = 0.0, 0.0
    for i in range(problems):
        goal, start = rng.uniform(lo, hi), rng.uniform(lo, hi)
        target = kin.fk(chain, goal, tip).copy()
        if i % 3 == 1:
            target[:3, 3] *= 1.5
        elif i % 3 == 2 and i % 2:
            start = np.zeros(len(start)).clip(lo, hi)
        elif i % 3 == 2:
            start = np.where(rng.random(len(start)) < 0.5, lo, hi)
        run = solve(chain, target, start, tip, nvars)
        if run is None:
            continue
        converged, steps, twists, iterates = run
        iterations += len(twists)
        failed += not converged
        k = stall(steps, twists)
        if k is None or k >= len(twists):
            continue
        stopped += 1
        saved += len(twists) - k
        flips += converged
        after = max(steps[k:], default=0.0)
        escapes += after > ESCAPE
        largest_after = max(largest_after, after)
        largest_change = max(largest_change, float(np.abs(iterates[k] - iterates[-1]).max()))
    return {
        "robot": robot,
        "problems": problems,
        "seed": seed,
        "failed": failed,
        "iterations": iterations,
        "stopped": stopped,
        "iterations_saved": saved,
        "status_flips": flips,
        "escapes": escapes,
        "largest_step_after_stop": largest_after,
        "largest_answer_change": largest_change,
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robots", nargs="+", choices=robots.known_robots(), metavar="ROBOT")
    parser.add_argument("--problems", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args(argv)
    if args.problems < 1:
        parser.error(f"--problems must be at least 1, got {args.problems}")
    if args.seed < 0:
        parser.error(f"--seed must be 0 or more (numpy's generators take no negative seed), got {args.seed}")
    for robot in args.robots:
        try:
            result = probe(robot, args.problems, args.seed)
        except RobotAPIError as exc:  # a named robot whose package is missing
            parser.error(f"robot {robot!r}: {exc}")
        print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
