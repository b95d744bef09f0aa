"""The twin's IK answers a problem it solved recently from memory (``kinematics.IK_MEMO``).

Newton-Raphson is deterministic, so the memory must never change an answer: an answer from
memory equals solving again, bit for bit; problems that differ in any bit are different
problems; the same robot loaded again shares answers; a chain changed by
``dataclasses.replace`` is a different chain; and the oracle's model of KDL's dead zone, which
replaces ``error_twist``, is never answered from memory.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import python_impl
from python_impl import kinematics
from tests.support import robot_path, sample_configurations


@pytest.fixture(autouse=True)
def _empty_memo():  # type: ignore[no-untyped-def]
    kinematics.IK_MEMO.clear()
    yield
    kinematics.IK_MEMO.clear()


def _problems(robot: str, n: int, seed: int):  # type: ignore[no-untyped-def]
    model = python_impl.RobotModel(robot_path(robot))
    chain, tip = model.chain, len(model.chain.link_names) - 1
    nvars = model._ik_variables(tip)
    rng = np.random.default_rng(seed)
    out = []
    for q in sample_configurations(model, n, seed=seed):
        target = kinematics.fk(chain, q, tip).copy()
        target[:3, 3] += rng.normal(0.0, 0.2, 3)  # some within reach, some not
        start = model._ik_start(model.forward_kinematics(q), q + rng.normal(0.0, 0.3, len(q)), None)[2]
        out.append((model, chain, target, list(start), tip, nvars))
    return out


@pytest.mark.parametrize("robot", ["ur5", "probot_anno"])
def test_an_answer_from_memory_is_the_answer_of_solving_again(robot: str) -> None:
    for _, chain, target, seed, tip, nvars in _problems(robot, 25, seed=3):
        with np.errstate(all="ignore"):
            solved = kinematics._ik(chain, target, list(seed), tip, nvars, None)
        first = kinematics.ik(chain, target, list(seed), tip, nvars)
        hits = kinematics.IK_MEMO.hits
        again = kinematics.ik(chain, target, list(seed), tip, nvars)
        assert kinematics.IK_MEMO.hits == hits + 1
        assert first == again == solved
        assert again[1] is not first[1]  # a list of its own: the caller may change it


def test_problems_that_differ_in_one_bit_are_different_problems() -> None:
    model, chain, target, seed, tip, nvars = _problems("ur5", 1, seed=8)[0]
    kinematics.ik(chain, target, seed, tip, nvars)
    seed0 = list(seed)
    seed0[0] = np.nextafter(seed0[0], np.inf)
    moved = target.copy()
    moved[0, 3] = np.nextafter(moved[0, 3], -np.inf)
    positive_zero, negative_zero = list(seed), list(seed)
    positive_zero[1], negative_zero[1] = 0.0, -0.0
    kinematics.ik(chain, target, positive_zero, tip, nvars)
    for t, s in ((target, seed0), (moved, seed), (target, negative_zero)):
        misses = kinematics.IK_MEMO.misses
        kinematics.ik(chain, t, s, tip, nvars)
        assert kinematics.IK_MEMO.misses == misses + 1
    misses = kinematics.IK_MEMO.misses
    kinematics.ik(chain, target, seed, tip - 1, model._ik_variables(tip - 1))
    assert kinematics.IK_MEMO.misses == misses + 1


def test_the_same_robot_loaded_again_shares_answers_and_a_changed_chain_does_not() -> None:
    _, chain, target, seed, tip, nvars = _problems("ur5", 1, seed=9)[0]
    again = python_impl.RobotModel(robot_path("ur5")).chain
    assert again is not chain and again.key == chain.key
    kinematics.ik(chain, target, seed, tip, nvars)
    hits = kinematics.IK_MEMO.hits
    kinematics.ik(again, target, seed, tip, nvars)
    assert kinematics.IK_MEMO.hits == hits + 1
    offset = chain.offset.copy()
    offset[0] += 0.5
    changed = dataclasses.replace(chain, offset=offset)
    assert changed.key != chain.key
    answer = kinematics.ik(changed, target, seed, tip, nvars)
    with np.errstate(all="ignore"):
        assert answer == kinematics._ik(changed, target, list(seed), tip, nvars, None)
    with pytest.raises(ValueError):
        chain.a0[0, 0, 0] = 2.0  # read-only: the key cannot go stale


def test_the_dead_zone_model_and_traces_are_never_answered_from_memory() -> None:
    from fuzzer.execution.dead_zone import twin_with_kdl_dead_zone

    _, chain, target, seed, tip, nvars = _problems("ur5", 1, seed=10)[0]
    kinematics.ik(chain, target, seed, tip, nvars)
    lookups = kinematics.IK_MEMO.hits + kinematics.IK_MEMO.misses
    with twin_with_kdl_dead_zone() as swapped:
        assert swapped
        kinematics.ik(chain, target, seed, tip, nvars)
    trace: list[float] = []
    kinematics.ik(chain, target, seed, tip, nvars, trace)
    assert trace
    assert kinematics.IK_MEMO.hits + kinematics.IK_MEMO.misses == lookups


def test_the_memory_keeps_the_most_recent_problems() -> None:
    memo = kinematics.IkMemo(2)
    memo.put(b"a", (True, (1.0,), 0.0, 0.0))
    memo.put(b"b", (True, (2.0,), 0.0, 0.0))
    assert memo.get(b"a") is not None  # now the most recent
    memo.put(b"c", (True, (3.0,), 0.0, 0.0))
    assert len(memo) == 2 and memo.get(b"b") is None and memo.get(b"a") is not None
    assert memo.kept == 2  # the count a stats snapshot reads (not ``len``: instrumented code)
    memo.clear()
    assert (len(memo), memo.kept, memo.hits, memo.misses) == (0, 0, 0, 0)


def test_a_forked_child_keeps_the_answers_and_counts_its_own_lookups() -> None:
    """``stats.jsonl`` snapshots are per process and the report sums them: a dry-run stage
    (a forked child) must not report the lookups its parent made before the fork."""
    import os

    _, chain, target, seed, tip, nvars = _problems("ur5", 1, seed=11)[0]
    first = kinematics.ik(chain, target, seed, tip, nvars)
    kinematics.ik(chain, target, seed, tip, nvars)
    assert (kinematics.IK_MEMO.hits, kinematics.IK_MEMO.misses) == (1, 1)
    pid = os.fork()
    if pid == 0:  # the child: one lookup, answered from the memory it inherited
        code = 1
        try:
            again = kinematics.ik(chain, target, seed, tip, nvars)
            memo = kinematics.IK_MEMO
            code = 0 if (again == first and (memo.hits, memo.misses) == (1, 0)) else 3
        finally:
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0, "the child counted its parent's lookups or lost answers"
    assert (kinematics.IK_MEMO.hits, kinematics.IK_MEMO.misses) == (1, 1), "the parent's counts are its own"
