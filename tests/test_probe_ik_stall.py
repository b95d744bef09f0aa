"""``benchmarks.probe_ik_stall`` measures the twin's own loop, and its stall rule stops where it says."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks import probe_ik_stall as probe
from python_impl import kinematics
from python_impl.model import RobotModel
from tests.support import robot_path


def test_the_stall_rule_needs_a_window_of_small_steps_far_from_the_goal() -> None:
    small, far = probe.STEP / 2, probe.FAR * 2
    steps = [1.0] + [small] * probe.WINDOW
    assert probe.stall(steps, [far] * len(steps)) == probe.WINDOW + 1
    assert probe.stall(steps[:-1], [far] * len(steps)) is None, "one step short of the window"
    assert probe.stall(steps, [probe.FAR / 2] * len(steps)) is None, "close to the goal: no stall"
    broken = [small, small, 1.0] + [small] * (probe.WINDOW - 1)
    assert probe.stall(broken, [far] * len(broken)) is None, "a large step starts the count again"


@pytest.mark.parametrize("robot", ["probot_anno", "ur5"])
def test_the_probe_runs_the_twins_loop(robot: str) -> None:
    """Its status and last iterate are those of ``kinematics._ik`` (which ends cycles early,
    bit for bit), on reachable and unreachable targets."""
    model = RobotModel(robot_path(robot))
    chain, tip = model.chain, len(model.chain.link_names) - 1
    nvars = model._ik_variables(tip)
    rng = np.random.default_rng(2)
    lo = np.array([lim.lower for lim in chain.limits])
    hi = np.array([lim.upper for lim in chain.limits])
    for i in range(12):
        target = kinematics.fk(chain, rng.uniform(lo, hi), tip).copy()
        target[:3, 3] *= 1.5 if i % 2 else 1.0
        seed = rng.uniform(lo, hi)
        run = probe.solve(chain, target, seed, tip, nvars)
        assert run is not None
        converged, steps, twists, iterates = run
        ok, values, _, _ = kinematics._ik(chain, target, seed.tolist(), tip, nvars, None)
        assert converged == ok
        assert iterates[-1].tolist() == values
        assert len(steps) == len(twists) - converged and len(iterates) == len(twists) + (not converged)


def test_the_probe_refuses_an_empty_run(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as stop:
        probe.main(["probot_anno", "--problems", "0"])
    assert stop.value.code == 2
    assert "--problems must be at least 1" in capsys.readouterr().err
