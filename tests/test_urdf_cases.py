"""URDF edge cases: native (urdfdom + expat guard) and twin (expat guard + mirrored rules)
accept and reject the same documents, with the same error class and code."""

from __future__ import annotations

import numpy as np
import pytest

import native
import python_impl
from robot_api import ErrorCode, URDFError
from tests.support import outcome
from tests.urdf_cases import all_cases

CASES = dict(all_cases())

# Known, documented divergences (docs/api.md, "Known divergences"): urdfdom's
# TinyXML keeps raw tabs and newlines inside attribute values, while expat
# normalizes them to spaces as XML 1.0 requires (section 3.3.3). So "1<TAB>2<TAB>3"
# is three numbers to the twin and one bad number to urdfdom.
KNOWN_DIVERGENCES = {"xyz_tab_separated", "xyz_newline_separated"}

# Inputs that crash urdfdom 3.0.1 itself; the native guard must turn them into errors.
URDFDOM_CRASHERS = {
    "xyz_printf_format",
    "xyz_printf_percent_n",
    "xyz_printf_many_s",
    "deep_nesting_100k",
    "big_chain_20000",
}


def load(impl, text: str):  # type: ignore[no-untyped-def]
    return outcome(lambda: impl.RobotModel(text))


@pytest.mark.parametrize("name", sorted(set(CASES) - KNOWN_DIVERGENCES))
def test_same_verdict(name: str) -> None:
    a = load(native, CASES[name])
    b = load(python_impl, CASES[name])
    if a[0] == "ok" or b[0] == "ok":
        assert a[0] == b[0] == "ok", (a, b)
        ma, mb = a[1], b[1]
        assert (ma.name, ma.root_link, ma.tip_link, ma.joint_names, ma.link_names) == (
            mb.name,
            mb.root_link,
            mb.tip_link,
            mb.joint_names,
            mb.link_names,
        )
        assert ma.joint_limits == mb.joint_limits and ma.mimic_joints == mb.mimic_joints
        if ma.dof:
            q = np.random.default_rng(0).uniform(-2, 2, size=(50, ma.dof))
            assert np.max(np.abs(ma.forward_kinematics_batch(q) - mb.forward_kinematics_batch(q))) <= 1e-9
    else:
        assert a == b


@pytest.mark.parametrize("name", sorted(URDFDOM_CRASHERS))
def test_inputs_that_crash_urdfdom_are_errors(name: str) -> None:
    for impl in (native, python_impl):
        with pytest.raises(URDFError) as err:
            impl.RobotModel(CASES[name])
        assert err.value.code in (ErrorCode.URDF_INVALID, ErrorCode.URDF_UNSUPPORTED)


@pytest.mark.parametrize("name", sorted(KNOWN_DIVERGENCES))
def test_known_divergence_still_diverges(name: str) -> None:
    """If this starts failing, the divergence is gone: update docs/api.md and the set."""
    assert load(native, CASES[name])[0] == "URDFError"
    assert load(python_impl, CASES[name])[0] == "ok"


def test_verdicts_for_a_few_landmarks() -> None:
    expect = {
        "baseline_2joint": "ok",
        "revolute_missing_axis": "ok",  # axis defaults to (1, 0, 0)
        "limit_lower_gt_upper": ErrorCode.URDF_INVALID,  # the contract's rule
        "axis_0_0_0": ErrorCode.URDF_INVALID,
        "billion_laughs": ErrorCode.URDF_INVALID,
        "floating_joint": ErrorCode.URDF_UNSUPPORTED,
        "mimic_of_mimic": ErrorCode.URDF_UNSUPPORTED,
        "link_with_two_parents": ErrorCode.URDF_INVALID,
        "cycle_with_root": ErrorCode.URDF_INVALID,
        "big_chain_2000": "ok",
        "big_chain_20000": ErrorCode.URDF_UNSUPPORTED,
        "limit_upper_nan": ErrorCode.URDF_INVALID,
        "xyz_1e400": ErrorCode.URDF_INVALID,
    }
    for name, verdict in expect.items():
        for impl in (native, python_impl):
            got = load(impl, CASES[name])
            assert (got[0] == "ok") if verdict == "ok" else (got == ("URDFError", verdict)), (name, impl, got)
