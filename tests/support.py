"""Shared helpers of the test suite: implementations, robots, sampling, references."""

from __future__ import annotations

import hashlib
import json
import math
import os
import subprocess
import sys
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import native
import python_impl
from robot_api import robots
from robot_api.records import JointType

IMPLEMENTATIONS = {"native": native, "python": python_impl}

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = str(ROOT / "fuzz_diff.py")


def fuzz(
    *args: str,
    cwd: Path = ROOT,
    timeout: float = 120,
    path: Sequence[Path] = (),
    env: Mapping[str, str] | None = None,
    preexec_fn: Callable[[], None] | None = None,
) -> subprocess.CompletedProcess[str]:
    """``fuzz_diff.py ARGS`` in a subprocess (PYTHONPATH: the repository, then ``path``; ``env``:
    more variables; ``preexec_fn``: run in the child before the exec)."""
    return subprocess.run(
        [sys.executable, SCRIPT, *args],
        cwd=cwd,
        env=dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), *map(str, path)]), **(env or {})),
        preexec_fn=preexec_fn,
        text=True,
        capture_output=True,
        timeout=timeout,
        check=False,
    )


def sidecar_describes(crash: Path) -> Path:
    """Make the sidecar beside ``crash`` describe the file as it is now (its ``sha1``): a test that
    edits a crash file keeps its sidecar, which the tools refuse as another input's otherwise."""
    side = crash.with_name(crash.name + ".json")
    data = json.loads(side.read_text())
    data["sha1"] = hashlib.sha1(crash.read_bytes()).hexdigest()
    side.write_text(json.dumps(data))
    return crash


def python(program: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """``python -c program`` in a fresh interpreter, with the repository importable."""
    return subprocess.run(
        [sys.executable, "-c", program],
        cwd=ROOT,
        env=dict(os.environ, PYTHONPATH=str(ROOT)),
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )


# (robot name, tip link or None for the default tip)
AGREEMENT_ROBOTS = [
    ("probot_anno", None),
    ("ur5", None),
    ("ur5", "tool0"),
    ("panda", None),
    ("panda", "panda_leftfinger"),
    ("panda", "panda_rightfinger"),  # mimic joint whose master is off the chain
    ("kinova", None),  # continuous joints
    ("xarm7", None),
    ("z1", None),
    ("so100", None),
]


def robot_path(name: str) -> Path:
    return robots.resolve(name)


def robot_id(case: tuple[str, str | None]) -> str:
    return case[0] if case[1] is None else f"{case[0]}:{case[1]}"


def sample_configurations(model: Any, n: int, seed: int, margin: float = 0.0) -> np.ndarray:
    """n configurations, uniform within limits widened by ``margin`` (continuous: [-2pi, 2pi])."""
    rng = np.random.default_rng(seed)
    lows, highs = [], []
    for lim in model.joint_limits:
        if lim.type == JointType.CONTINUOUS:
            lows.append(-2 * math.pi)
            highs.append(2 * math.pi)
        else:
            lows.append(lim.lower - margin)
            highs.append(lim.upper + margin)
    return rng.uniform(lows, highs, size=(n, len(lows)))


def outcome(call: Any) -> tuple[str, Any]:
    """('ok', value) or (exception class name, error code) of a call."""
    try:
        return ("ok", call())
    except Exception as exc:  # noqa: BLE001 - recording any failure is the point
        return (type(exc).__name__, getattr(exc, "code", None))


@dataclass
class PinocchioReference:
    """Forward kinematics of pinocchio on the same URDF, fed our joint vectors."""

    model: Any
    data: Any
    columns: list[tuple[int, int, int]]  # (our variable, idx_q, nq)

    @classmethod
    def load(cls, path: Path, joint_names: tuple[str, ...]) -> PinocchioReference:
        import pinocchio as pin

        model = pin.buildModelFromUrdf(str(path), mimic=True)
        columns = []
        for i, name in enumerate(joint_names):
            jid = model.getJointId(name)
            joint = model.joints[jid]
            columns.append((i, joint.idx_q, joint.nq))
        return cls(model, model.createData(), columns)

    def q(self, values: np.ndarray) -> np.ndarray:
        import pinocchio as pin

        q = pin.neutral(self.model)
        for i, idx, nq in self.columns:
            if nq == 2:  # continuous joint: (cos, sin)
                q[idx], q[idx + 1] = math.cos(values[i]), math.sin(values[i])
            else:
                q[idx] = values[i]
        return q

    def transform(self, values: np.ndarray, link: str) -> np.ndarray:
        import pinocchio as pin

        pin.framesForwardKinematics(self.model, self.data, self.q(values))
        return np.array(self.data.oMf[self.model.getFrameId(link)].homogeneous)


def pose_matrices(poses: Iterator[Any]) -> np.ndarray:
    return np.array([p.matrix for p in poses])


REQUIRE_ADAPTERS = "RROSFUZZ_REQUIRE_ADAPTERS"


def skip_or_fail(reason: str) -> None:
    """Skip a test whose optional library is missing, or fail under ``RROSFUZZ_REQUIRE_ADAPTERS=1``.

    ``make test`` (and so CI) installs the ``adapters`` extra and sets the
    variable, so a missing library there is a failure, not a silent skip.
    """
    import os

    import pytest

    if os.environ.get(REQUIRE_ADAPTERS) == "1":
        pytest.fail(f"{reason} ({REQUIRE_ADAPTERS}=1: optional libraries are required)")
    pytest.skip(reason)


def import_or_skip(module: str) -> Any:
    """``pytest.importorskip``, but a failure under ``RROSFUZZ_REQUIRE_ADAPTERS=1``."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as exc:
        skip_or_fail(f"{module} is not installed: {exc}")


# The poses of the controls' two false positives on 312c459 (benchmarks/results/control-fp-312c459/):
# just out of reach with joints at a limit or at pi; both IK solvers stall about IK_EPS short,
# KDL's error just inside its tolerance and the twin's just outside on an AMD EPYC (the split
# depends on the CPU's rounding). (robot, position in m, orientation as x, y, z, w)
KNIFE_EDGE_POSES = (
    (
        "probot_anno",
        (-0.22499999999392847, -2.3639033373344096e-07, 0.5458553500026021),
        (-2.8000036732051035, -0.9999999999915672, -1.8365948965779296e-06, 6.746245984502051e-12),
    ),
    (
        "kinova",
        (-0.009799999999878066, 0.13504567046898047, 0.29329889484134397),
        (-4.552628843617489e-13, -0.16504760586081785, 0.986285601537208, 9.999999999999999e-06),
    ),
)
