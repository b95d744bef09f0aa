"""The API under memory pressure and threads (a helper's probe of the sixty-second session):
an array whose float64 copy cannot be made is the argument's error in both twins (native
segfaulted), and a batch FK beside single FK on one model in another thread stays right."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import numpy as np
import pytest

import native
import python_impl
from robot_api.errors import URDFError
from tests.support import robot_path

ROOT = Path(__file__).resolve().parents[1]
ROBOT = robot_path("probot_anno")

PROGRAM = textwrap.dedent(
    """
    import json, resource, sys
    import numpy as np
    import native, python_impl
    from robot_api.records import RobotTrajectory
    with open("/proc/self/status") as status:
        size = next(int(line.split()[1]) for line in status if line.startswith("VmSize:")) << 10
    limit = size + (1 << 30)  # 1 GiB more than the process has mapped: every copy below fails
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    impl = {"native": native, "python": python_impl}[sys.argv[2]]
    model = impl.RobotModel(sys.argv[1])
    group = impl.MoveGroup(model)
    rows = np.broadcast_to(np.zeros(6), (10**9, 6))  # 48 bytes of data, 48 GB as float64
    long = np.broadcast_to(np.zeros(1), (10**10,))
    calls = {
        "forward_kinematics_batch": lambda: model.forward_kinematics_batch(rows),
        "forward_kinematics": lambda: model.forward_kinematics(long),
        "set_joint_value_target": lambda: group.set_joint_value_target(long),
    }
    if impl is native:  # 50 million times (0.4 GB) fit, their positions (2.4 GB) do not
        m = 5 * 10**7
        times = np.broadcast_to(np.zeros(1), (m,))
        plan = RobotTrajectory(model.joint_names, times, rows[:m], rows[:m], rows[:m])
        calls["execute"] = lambda: group.execute(plan)
    out = {}
    for name, call in calls.items():
        try:
            call()
            out[name] = "returned"
        except Exception as exc:
            out[name] = [type(exc).__name__, getattr(getattr(exc, "code", None), "name", ""), str(exc)]
    print(json.dumps(out))
    """
)


def _under_a_memory_limit(target: str) -> dict[str, list[str]]:
    run = subprocess.run(
        [sys.executable, "-c", PROGRAM, str(ROBOT), target],
        capture_output=True, text=True, timeout=120, cwd=ROOT, check=False,
    )  # fmt: skip
    assert run.returncode == 0, f"{target}: exit {run.returncode}\n{run.stderr[-2000:]}"
    return json.loads(run.stdout.splitlines()[-1])  # type: ignore[no-any-return]


def test_an_array_whose_float64_copy_cannot_be_made_is_the_argument_s_error_in_both() -> None:
    """native segfaulted in ``forward_kinematics_batch`` and ``execute`` (a null ``ensure()``
    read), and raised pybind11's "error_already_set called while Python error indicator not
    set" for a 1-D one; the twin raised a bare ``MemoryError``. (The twin's ``execute`` is not
    tried: its list of 50 million times runs out of memory before the positions do.)"""
    native_out, twin_out = _under_a_memory_limit("native"), _under_a_memory_limit("python")
    assert {k: v for k, v in native_out.items() if k != "execute"} == twin_out
    for name, said in native_out.items():
        assert said[0] == "InvalidInputError", (name, said)
        assert said[2].endswith("cannot convert the array to float64"), (name, said)
    assert native_out["execute"][1] == "INVALID_TRAJECTORY"
    assert native_out["forward_kinematics"][1] == "INVALID_ARGUMENT"


def test_batch_fk_beside_single_fk_in_another_thread_returns_the_right_rows() -> None:
    """The batch released the GIL and then copied the chain, while single FK (holding the GIL)
    rewrote KDL's cached joint poses in it: a copy could pair a new joint value with an old pose.
    The probe saw 75 of 1,145 batches of 8,192 rows wrong, by up to 1.55, without an error."""
    model = native.RobotModel(ROBOT)
    q_a, q_b = [0.3, -0.7, 0.9, 1.1, -0.4, 2.0], [-1.2, 0.5, -0.3, 0.2, 1.3, -2.5]
    expected = model.forward_kinematics_batch(np.array([q_b]))[0]
    rows = np.tile(q_b, (8192, 1))
    stop = threading.Event()

    def single() -> None:
        while not stop.is_set():
            model.forward_kinematics(q_a)
            model.forward_kinematics(q_b)

    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-5)
    worker = threading.Thread(target=single, daemon=True)
    worker.start()
    try:
        wrong = sum(
            float(np.abs(model.forward_kinematics_batch(rows) - expected).max()) > 1e-9 for _ in range(300)
        )
    finally:
        stop.set()
        worker.join()
        sys.setswitchinterval(old)
    assert wrong == 0, f"{wrong} of 300 batches wrong"


@pytest.mark.parametrize("spec", [None, 5, b"probot_anno", ""])
def test_resolve_refuses_what_is_not_a_robot_with_a_urdf_error(spec: object) -> None:
    """``resolve(None)`` was a bare TypeError from ``os.fspath``; ``resolve("")`` said the
    working folder "is not a regular file"."""
    from robot_api import robots

    with pytest.raises(URDFError, match=r"expected a name or a path|an empty name"):
        robots.resolve(spec)  # type: ignore[arg-type]


def test_both_twins_still_convert_ordinary_arrays() -> None:
    for impl in (native, python_impl):
        model = impl.RobotModel(ROBOT)
        out = model.forward_kinematics_batch(np.zeros((3, 6), dtype=np.float32))
        assert out.shape == (3, 4, 4) and out.dtype == np.float64
