"""The scenario oracle's shortcuts give what the plain path gives.

* ``pairs_apart`` / ``apart_rows`` compare only the joint vectors that differ as numbers beyond
  the tolerance; the answer must be that of ``joints_apart`` on every pair.
* ``records.floats`` keeps a step's trajectory as a read-only float64 array only; it must still
  behave as a tuple of floats in every way that counts (equality, hash, repr, iteration, JSON
  through ``Outcome.to_json``), without a Python float per value.
* ``oracle_timing.reference_duration`` remembers its answers, keyed by the bits of its inputs.
* ``compare_step`` gives the single-call oracle's verdict on a step's statuses and pose values.
"""

from __future__ import annotations

import json
import math
import tracemalloc
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fuzzer.execution import oracle
from fuzzer.execution.records import Comparison, Floats, Kind, Outcome, Status, as_array, floats
from fuzzer.execution.tolerance import Tolerance
from fuzzer.scenario import oracle_timing
from fuzzer.scenario.oracle import TIMES, compare_step
from fuzzer.scenario.oracle_facts import Context, JointSpec, ScenarioFacts
from fuzzer.scenario.oracle_ik import apart_rows, joints_apart, pairs_apart
from fuzzer.scenario.oracle_timing import limits_of, reference_duration
from python_impl.trajectory import plan_trajectory, time_parameterize

TOL = Tolerance(metres=1e-5, radians=1e-6)
SPECS = {
    "revolute": JointSpec("revolute", -3.0, 3.0, 1.0),
    "continuous": JointSpec("continuous", -math.inf, math.inf, 2.0),
    "prismatic": JointSpec("prismatic", -0.5, 0.5, 0.3),
}
BASE = [0.0, 0.25, -1.0, math.pi, -math.pi, math.pi - 5e-7, -math.pi + 5e-7, 0.4, 3.0]
"""Values near the canonical range's boundary, a limit and zero, where the oracle's rules act."""
SHIFTS = [0.0, 0.0, 0.0, 5e-7, -5e-7, 2e-6, -2e-5, 2.0 * math.pi, -2.0 * math.pi, 1e-300, 0.3]
"""Gaps within and beyond either tolerance, whole turns, and nothing."""
SPECIAL = [math.nan, math.inf, -math.inf]


Pair = tuple[tuple[float, ...], tuple[float, ...]]


@st.composite
def robots_and_pairs(draw: st.DrawFn) -> tuple[ScenarioFacts, list[Pair]]:
    kinds = draw(st.lists(st.sampled_from(sorted(SPECS)), min_size=1, max_size=4))
    facts = ScenarioFacts(tuple(SPECS[k] for k in kinds))

    def value() -> st.SearchStrategy[float]:
        return st.one_of(st.sampled_from(BASE), st.sampled_from(SPECIAL), st.floats(-7.0, 7.0))

    def pair() -> st.SearchStrategy[Pair]:
        def shifted(x: float, shift: float, other: float) -> float:
            return other if shift == 1e-300 else x + shift  # 1e-300: an unrelated value

        return st.lists(
            st.tuples(value(), st.sampled_from(SHIFTS), value()), min_size=len(kinds), max_size=len(kinds)
        ).map(lambda cols: (tuple(c[0] for c in cols), tuple(shifted(*c) for c in cols)))

    return facts, draw(st.lists(pair(), min_size=1, max_size=6))


@settings(max_examples=300, deadline=None)
@given(robots_and_pairs())
def test_pairs_apart_is_joints_apart_on_every_pair(case: tuple[ScenarioFacts, list]) -> None:
    facts, pairs = case
    plain = [(x, y) for x, y in pairs if joints_apart("", x, y, TOL, facts) is not None]
    assert pairs_apart(pairs, TOL, facts) == plain
    # and no row apart_rows leaves out is apart
    x, y = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
    kept = set(apart_rows(x, y, TOL, facts).tolist())
    assert all(i in kept for i, (p, q) in enumerate(pairs) if joints_apart("", p, q, TOL, facts) is not None)


def test_apart_rows_leaves_out_rows_within_tolerance_and_keeps_whole_turns_and_nan() -> None:
    facts = ScenarioFacts((SPECS["revolute"], SPECS["continuous"], SPECS["prismatic"]))
    x = np.array([[0.1, 0.2, 0.3]] * 5)
    y = x.copy()
    y[1, 0] += 5e-7  # within 1e-6 rad
    y[2, 2] += 5e-6  # within 1e-5 m
    y[3, 1] += 2.0 * math.pi  # the same angle, another number: a representation divergence
    y[4, 0] = math.nan
    assert apart_rows(x, y, facts=facts, tol=TOL).tolist() == [3, 4]
    y[2, 2] += 1e-5  # now beyond the prismatic joint's limit
    assert apart_rows(x, y, facts=facts, tol=TOL).tolist() == [2, 3, 4]


def test_pairs_of_unequal_lengths_are_compared_one_by_one() -> None:
    facts = ScenarioFacts((SPECS["revolute"], SPECS["revolute"]))
    pairs = [((0.0, 0.0), (0.0, 0.0)), ((0.0,), (0.0, 0.0))]
    assert pairs_apart(pairs, TOL, facts) == [pairs[1]]  # a length mismatch is a divergence


def test_floats_is_a_tuple_in_every_way_that_counts() -> None:
    source = np.array([[0.1, -0.0], [math.inf, 2.5]])
    made = floats(source)
    plain = (0.1, -0.0, math.inf, 2.5)
    assert isinstance(made, Floats) and isinstance(made, Sequence) and not isinstance(made, tuple)
    assert made == plain and plain == made and hash(made) == hash(plain) and made == floats(plain)
    assert made != list(plain) and made != (0.1, -0.0, math.inf) and made != (0.1, 0.0, math.inf, 2.6)
    assert repr(made) == repr(plain) and len(made) == 4 and list(made) == list(plain)
    assert all(type(x) is float for x in made) and type(made[3]) is float and made[-1] == 2.5
    assert made[1:3] == plain[1:3] and made + (1.0,) == plain + (1.0,) and (1.0,) + made == (1.0, *plain)  # noqa: RUF005
    assert {plain: 1}[made] == 1
    assert Outcome(Status.OK, values={"v": made}) == Outcome(Status.OK, values={"v": plain})
    data = Outcome(Status.OK, values={"v": made}).to_json()
    assert json.dumps(data["values"]) == json.dumps({"v": list(plain)})
    assert Outcome.from_json(json.loads(json.dumps(data))) == Outcome(Status.OK, values={"v": plain})
    source[0, 0] = 9.0  # the target's array changing later changes nothing kept
    assert made[0] == 0.1 and as_array(made)[0] == 0.1 and np.asarray(made)[0] == 0.1
    with pytest.raises(ValueError, match="read-only"):
        as_array(made)[0] = 1.0
    assert np.signbit(as_array(made)[1])  # -0.0 kept as it is
    assert np.asarray(made) is made.array and np.asarray(made, dtype=np.float32).dtype == np.float32
    copied = np.array(made)  # numpy's copy: a new array, writeable
    copied[0] = 5.0
    assert made[0] == 0.1


def test_a_long_trajectory_is_kept_without_a_python_float_per_value() -> None:
    # a 60,001-point plan of 6 joints, as a plan at acceleration scaling 3.75e-5 gives: kept as a
    # tuple of Python floats beside its array it took 32 bytes more per value (BENCHMARKS.md, "Memory")
    rows = np.linspace(0.0, 1.0, 60_001 * 6)
    tracemalloc.start()
    try:
        made = floats(rows)
        kept, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert len(made) == rows.size and kept < rows.nbytes + 4096


def test_as_array_reads_any_tuple_of_floats() -> None:
    made = floats([1.0, 2.0])
    assert as_array(made) is made.array
    plain = as_array((1.0, 2.0))
    assert plain.dtype == np.float64 and plain.tolist() == [1.0, 2.0] and plain.flags.writeable
    assert as_array(()).shape == (0,)


def test_a_step_compares_the_same_from_floats_and_from_tuples() -> None:
    facts = ScenarioFacts((SPECS["revolute"], SPECS["continuous"]))
    times, rows = [0.0, 0.5, 1.0], [[0.0, 0.0], [0.1, 3.0], [0.2, math.pi - 2e-7]]
    field = "plan.trajectory.positions"
    cases = {
        ("agree", "", ()): [[0.0, 0.0], [0.1, 3.0], [0.2, -math.pi + 2e-7]],  # the boundary's other side
        ("value", field, (0,)): [[0.0, 0.0], [0.1 + 1e-3, 3.0], [0.2, math.pi - 2e-7]],
        ("representation", field, (1,)): [[0.0, 0.0], [0.1, 3.0 - 2 * math.pi], [0.2, math.pi - 2e-7]],
    }
    as_tuple = lambda v: tuple(np.asarray(v, dtype=float).ravel().tolist())  # noqa: E731 - the old way
    for expected, other in cases.items():
        found = []
        for make in (floats, as_tuple):
            a, b = (
                Outcome(Status.OK, values={TIMES: make(times), "trajectory.positions": make(r)})
                for r in (rows, other)
            )
            found.append(compare_step("plan", a, b, TOL, facts))
        assert found[0] == found[1]
        assert (found[0].kind.value, found[0].field, found[0].joints) == expected


def test_reference_duration_is_remembered_by_the_bits_of_its_inputs() -> None:
    facts = ScenarioFacts((SPECS["revolute"], SPECS["continuous"]))
    rows = np.array([[0.0, 0.0], [0.3, 0.1], [0.7, -0.2]])
    before = Context(velocity_scaling=0.5, acceleration_scaling=0.25)
    oracle_timing._duration.cache_clear()
    first = reference_duration("cartesian_path", rows, before, facts)
    assert first == float(time_parameterize(limits_of(facts), rows.tolist(), 0.5, 0.25).time_from_start[-1])
    assert reference_duration("cartesian_path", rows.copy(), before, facts) == first
    info = oracle_timing._duration.cache_info()
    assert (info.hits, info.misses) == (1, 1)
    # 0.0 and -0.0 are equal as numbers but are different questions (the bits differ)
    moved = rows.copy()
    moved[0, 0] = -0.0
    assert reference_duration("cartesian_path", moved, before, facts) == first
    assert oracle_timing._duration.cache_info().misses == 2
    # a question the contract refuses is remembered as refused
    assert reference_duration("cartesian_path", rows, Context(velocity_scaling=0.0), facts) is None
    assert reference_duration("cartesian_path", rows, Context(velocity_scaling=0.0), facts) is None
    assert oracle_timing._duration.cache_info().misses == 3


def test_a_plans_reference_duration_is_remembered_by_its_two_ends() -> None:
    """A plan's duration is that of its first and last points (``plan_trajectory``): its key keeps
    only those, so a long plan leaves no megabytes in the cache, and plans that part only in
    between share the answer."""
    facts = ScenarioFacts((SPECS["revolute"], SPECS["continuous"]))
    before = Context(velocity_scaling=0.5, acceleration_scaling=0.25)
    long = np.linspace([0.0, 0.0], [0.7, -0.2], 60_001)
    oracle_timing._duration.cache_clear()
    first = reference_duration("plan", long, before, facts)
    reference = plan_trajectory(limits_of(facts), [0.0, 0.0], [0.7, -0.2], 0.5, 0.25)
    assert first == float(reference.time_from_start[-1])
    bent = long.copy()
    bent[1:-1] += 0.01
    assert reference_duration("plan", bent, before, facts) == first
    assert reference_duration("plan", long[[0, -1]], before, facts) == first
    info = oracle_timing._duration.cache_info()
    assert (info.hits, info.misses) == (2, 1)


POSE_PARTS = {"joint_values": 3, "position": 3, "orientation": 4}


@st.composite
def pose_pairs(draw: st.DrawFn) -> tuple[dict[str, tuple[float, ...]], dict[str, tuple[float, ...]]]:
    """Two steps' pose values: some fields equal (finite or not), some a little or far apart."""
    number = st.one_of(st.sampled_from([0.0, -0.0, 0.5, math.pi, -math.pi, *SPECIAL]), st.floats(-4.0, 4.0))
    a, b = {}, {}
    for key, size in POSE_PARTS.items():
        if not draw(st.booleans()):
            continue
        x = tuple(draw(st.lists(number, min_size=size, max_size=size)))
        shifts = draw(
            st.lists(st.sampled_from([0.0, 0.0, 5e-7, 2e-6, 2.0 * math.pi]), min_size=size, max_size=size)
        )
        a[key], b[key] = x, tuple(v + s for v, s in zip(x, shifts, strict=True))
    return a, b


@settings(max_examples=400, deadline=None)
@given(pose_pairs())
def test_a_step_s_pose_values_give_the_single_call_oracle_s_verdict(pair: tuple[dict, dict]) -> None:
    """``compare_step``'s verdict on a step's pose values is the single-call oracle's on all of them
    (inf on both sides is a divergence of a position). 09c9d70 left out the fields equal as
    numbers and finite, with the same verdicts, and was reverted: fewer calls of the instrumented
    oracle slowed the search (BENCHMARKS.md, "The scenario oracle's share, cut")."""
    facts = ScenarioFacts((SPECS["revolute"], SPECS["continuous"], SPECS["prismatic"]))
    a, b = pair
    step = compare_step("go", Outcome(Status.OK, values=a), Outcome(Status.OK, values=b), TOL, facts)
    whole = oracle.compare(
        Outcome(Status.OK, values=a),
        Outcome(Status.OK, values=b),
        TOL,
        facts.prismatic,
        continuous=facts.continuous,
    )
    assert step == (replace(whole, field=f"go.{whole.field}") if whole.divergent else Comparison(Kind.AGREE))


def test_statuses_are_compared_only_when_they_differ_or_one_crashed() -> None:
    facts = ScenarioFacts((SPECS["revolute"],))
    ok = Outcome(Status.OK, values={"joint_values": (0.1,)})
    failed = Outcome(Status.FAILED, values={"joint_values": (0.1,)})
    crashed = Outcome(Status.CRASHED, "ZeroDivisionError", values={})
    assert compare_step("go", ok, ok, TOL, facts) == Comparison(Kind.AGREE)
    assert (
        compare_step("go", ok, failed, TOL, facts).kind,
        compare_step("go", ok, failed, TOL, facts).field,
    ) == (
        Kind.STATUS,
        "go.status",
    )
    assert compare_step("go", crashed, crashed, TOL, facts).kind is Kind.CRASH
