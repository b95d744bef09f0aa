"""Speed of the two targets (issue: two targets, one API).

    .venv/bin/python -m benchmarks.bench_targets [--rounds 5] [--repeat 7] [--robot probot_anno]

Single-call FK (us per call), batch FK (configurations per second, 100,000
rows) and ``go()`` (us per call, alternating between two targets). Each round
takes the median of ``--repeat`` timings; the table gives the median over
``--rounds`` rounds and, in brackets, the lowest and highest round (the
machine is a shared VM: expect noise). Run it under ``taskset -c 0`` for
one-core figures.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import timeit
from collections.abc import Callable

import numpy as np

import native
import python_impl
from benchmarks import cli
from robot_api import robots
from robot_api.errors import URDFError


def median_time(func: Callable[[], object], number: int, repeat: int) -> float:
    """Median over ``repeat`` runs of the time (s) of one call."""
    return statistics.median(t / number for t in timeit.repeat(func, number=number, repeat=repeat))


def measure(impl: object, urdf: str, repeat: int) -> dict[str, float]:
    model = impl.RobotModel(urdf)  # type: ignore[attr-defined]
    rng = np.random.default_rng(0)
    q = rng.uniform(-1.0, 1.0, model.dof).tolist()
    rows = rng.uniform(-1.0, 1.0, (100_000, model.dof))
    group = impl.MoveGroup(model)  # type: ignore[attr-defined]
    targets = [[0.5] * model.dof, [-0.5] * model.dof]
    state = {"i": 0}

    def go() -> None:
        state["i"] ^= 1
        group.go(targets[state["i"]])

    return {
        "fk_us": median_time(lambda: model.forward_kinematics(q), 20_000, repeat) * 1e6,
        "batch_per_s": len(rows) / median_time(lambda: model.forward_kinematics_batch(rows), 1, repeat),
        "go_us": median_time(go, 200, repeat) * 1e6,
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--robot", default=robots.DEFAULT_ROBOT)
    args = parser.parse_args()
    cli.check_sizes(parser, rounds=args.rounds, repeat=args.repeat)
    try:
        urdf = str(robots.resolve(args.robot))
        for impl in (native, python_impl):  # a URDF either target refuses: named before any timing
            impl.RobotModel(urdf)
    except URDFError as exc:
        parser.error(f"--robot {args.robot}: {exc}")
    cpus = len(os.sched_getaffinity(0))
    print(
        f"# {platform.machine()}, {cpus} CPU(s) available, robot {args.robot}, "
        f"median of {args.rounds} rounds x {args.repeat} timings [min-max of rounds]"
    )
    print("| target | single FK (us/call) | batch FK (configs/s) | go() (us/call) |")
    print("|---|---|---|---|")
    for name, impl in (("native", native), ("python", python_impl)):
        rounds = [measure(impl, urdf, args.repeat) for _ in range(args.rounds)]

        def cell(key: str, fmt: str, rounds: list[dict[str, float]] = rounds) -> str:
            values = [r[key] for r in rounds]
            return f"{statistics.median(values):{fmt}} [{min(values):{fmt}}-{max(values):{fmt}}]"

        print(f"| {name} | {cell('fk_us', '.2f')} | {cell('batch_per_s', ',.0f')} | {cell('go_us', '.1f')} |")


if __name__ == "__main__":
    main()
