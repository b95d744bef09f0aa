"""Float comparisons of instrumented Python code become distance-to-flip features."""

from __future__ import annotations

import sys
import types

import atheris
import numpy as np

from fuzzer.selection.floatcmp import FLOAT_CMP, FloatCompareTracer
from fuzzer.selection.guidance import Features


def _instrumented() -> types.ModuleType:
    name = "tests.plugins.float_branch"
    if name not in sys.modules:
        with atheris.instrument_imports(include=[name]):
            __import__(name)
    return sys.modules[name]


def test_float_comparisons_of_instrumented_code_are_traced_with_their_distance() -> None:
    module = _instrumented()
    features = Features(enabled=False)
    tracer = FloatCompareTracer(features)
    tracer.install()
    try:
        assert module.branch(0.5, 1.0) == 0
        far = set(features.seen)
        assert far and all(key.startswith(f"({FLOAT_CMP}, ") for key in far)
        assert module.branch(0.07, 1.0) == 0  # 0.14 vs 0.1234: closer, a new exponent
        closer = set(features.seen) - far
        assert closer
        assert module.branch(0.01, 5) == 1  # the branch flipped: the other side
        assert len(tracer.sites) == 2 and tracer.traced == 5
    finally:
        atheris._trace_cmp = tracer.inner


def test_nearer_names_the_sites_an_input_brought_nearer_their_flip_than_any_before() -> None:
    """``nearer`` (the walk's preferred parents, ``fuzzer.generation.walk``): per input, the
    sites whose distance reached a smaller exponent than every earlier input's, on either side."""
    module = _instrumented()
    tracer = FloatCompareTracer(Features(enabled=False))
    try:
        runs = []
        inputs = ((0.5, 1.0), (0.6, 1.0), (0.07, 1.0), (0.07, 2.5), (0.5, 1.0), (0.0617, 1.0), (0.061, 9.0))
        for x, y in inputs:
            tracer.install()  # the harness's call before each input: a fresh list
            module.branch(x, y)
            runs.append(list(tracer.nearer))
        x_site, y_site = runs[0]
        # (0.6, 1.0): 1.2 vs 0.1234 is farther and y's gap is the same; (0.07, 1.0): x nearer;
        # (0.07, 2.5): y nearer; (0.5, 1.0): nothing new; (0.0617, 1.0): x's gap 0 exactly;
        # (0.061, 9.0): x flipped (its gap larger again), y is past 3 and farther
        assert runs[1:] == [[], [x_site], [y_site], [], [x_site], []]
    finally:
        atheris._trace_cmp = tracer.inner


def test_install_is_idempotent_and_follows_a_swap() -> None:
    calls: list[tuple[object, ...]] = []

    def first(*args: object) -> bool:
        calls.append(("first", *args))
        return True

    def second(*args: object) -> bool:
        calls.append(("second", *args))
        return False

    fake = types.SimpleNamespace(_trace_cmp=first)
    tracer = FloatCompareTracer(Features(enabled=False), fake)
    tracer.install()
    tracer.install()
    assert tracer.inner is first
    assert fake._trace_cmp(1, 2, 0, 9, False) is True  # int-int: Atheris traces it
    fake._trace_cmp = second  # Atheris swaps in its real function when fuzzing starts
    tracer.install()
    assert tracer.inner is second and fake._trace_cmp(1, 2, 0, 9, False) is False
    assert [c[0] for c in calls] == ["first", "second"]


def test_non_float_comparisons_are_left_alone_and_special_floats_bucketed() -> None:
    features = Features(enabled=False)
    tracer = FloatCompareTracer(features, types.SimpleNamespace(_trace_cmp=lambda *a: None))
    tracer.install()
    tracer.trace(1, 2, 0, 1, False)
    tracer.trace("a", "b", 2, 2, False)
    assert tracer.traced == 0
    tracer.trace(float("nan"), 1.0, 0, 3, False)
    tracer.trace(2.0, 2.0, 2, 4, False)
    tracer.trace(float("inf"), 1, 4, 5, False)
    assert tracer.traced == 3 and len(features.seen) == 3
    uninstalled = FloatCompareTracer(features, types.SimpleNamespace())
    assert uninstalled.trace(1.0, 2.0, 0, 6, False) is True  # compares itself when never installed


def test_the_campaign_instruments_the_targets_and_the_oracle_it_names() -> None:
    """The editable install's finder loads ``fuzzer`` and ``python_impl`` with its own loader,
    which Atheris' import hook leaves uninstrumented ("custom loader"): ``instrument``
    must patch them in place, or no comparison of theirs reaches libFuzzer. In a subprocess
    (instrumentation rewrites the code of the running process)."""
    import subprocess

    script = (
        "import dis\n"
        "from fuzzer.selection import instrument\n"
        "from fuzzer.execution.session import RunConfig\n"
        "instrument.instrument(RunConfig(op='fk', targets=('native', 'python')))\n"
        "import fuzzer.execution.oracle as o, python_impl.model as m\n"
        "calls = lambda f: {i.argval for i in dis.get_instructions(f)}\n"
        "print('_trace_cmp' in calls(o.compare), '_trace_cmp' in calls(m.RobotModel.check_vector))\n"
        "print(instrument.instrument_loaded(['fuzzer.execution.oracle', 'python_impl']))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=True
    )
    assert done.stdout.split() == ["True", "True", "0"], done.stdout + done.stderr


def test_the_tracer_steps_aside_after_its_budget_until_the_next_input() -> None:
    calls: list[str] = []

    def atheris_own(*args: object) -> bool:
        calls.append("own")
        return True

    fake = types.SimpleNamespace(_trace_cmp=atheris_own)
    tracer = FloatCompareTracer(Features(enabled=False), fake)
    tracer.install(budget=3)
    for i in range(5):
        assert fake._trace_cmp(0.5 + i, 2.5, 0, 7, False) is (0.5 + i < 2.5)
    assert tracer.traced == 3 and calls == []  # floats: Atheris only compares them, so we do
    assert fake._trace_cmp is tracer.guard
    assert fake._trace_cmp(3, 4, 0, 7, False) is True and calls == ["own"]  # int-int still traced
    tracer.install(budget=3)  # the next input: traced again
    fake._trace_cmp(0.25, 2.5, 0, 7, False)
    assert tracer.traced == 4 and fake._trace_cmp == tracer.trace


def _results_alive(compare: object, n: int) -> int:
    """How many of ``n`` array comparison results are still referenced after the calls."""
    import gc
    import weakref

    class Bools(np.ndarray):  # ndarray itself cannot be weakly referenced
        pass

    refs = []
    a = np.arange(100.0).view(Bools)
    for _ in range(n):
        refs.append(weakref.ref(compare(a, 50.0, 0, 11, False)))  # type: ignore[operator]
    gc.collect()
    return sum(r() is not None for r in refs)


def test_atheris_leaks_array_comparison_results_and_the_guard_does_not() -> None:
    """Atheris' ``_trace_cmp`` keeps one reference too many to what it returns (a move campaign
    ran out of memory after ~100 s); the guard compares arrays itself, with the same result."""
    assert _results_alive(atheris._trace_cmp, 20) == 20  # the upstream leak, as documented
    fake = types.SimpleNamespace(_trace_cmp=atheris._trace_cmp)
    for budget in (0, 64):
        tracer = FloatCompareTracer(Features(enabled=False), fake, budget=budget)
        tracer.install()
        assert _results_alive(fake._trace_cmp, 20) == 0
        a = np.array([0.5, 2.0, np.nan, 3.0])
        for opid in range(6):
            expected = atheris._trace_cmp(a, 2.0, opid, 11, False)
            assert np.array_equal(fake._trace_cmp(a, 2.0, opid, 11, False), expected)
        assert fake._trace_cmp(b"ab", b"ac", 0, 11, False) is True
        assert fake._trace_cmp("b", "a", 4, 11, False) is True


def test_counts_and_counters_carry_over_when_atheris_swaps_its_functions() -> None:
    """``trace`` is remade when Atheris swaps ``_trace_cmp`` in: the comparisons traced before
    still count, a feature seen before is not new again, and its counter is bumped through the
    ``_trace_branch`` of the input's start (``Fuzz()`` swaps that one in too)."""
    bumped: list[tuple[str, int]] = []
    pre = types.SimpleNamespace(_trace_branch=lambda i: bumped.append(("pre", i)))
    features = Features(enabled=False)
    features.enabled, features._atheris, features._ids = True, pre, list(range(features.count))
    fake = types.SimpleNamespace(_trace_cmp=lambda *a: None)
    tracer = FloatCompareTracer(features, fake)
    tracer.install()
    fake._trace_cmp(0.5, 1.0, 0, 3, False)
    fake._trace_cmp(0.5, 1.0, 0, 3, False)  # the same feature again: a bump
    assert tracer.traced == 2 and len(features.seen) == 1 and len(bumped) == 2
    features._atheris = types.SimpleNamespace(_trace_branch=lambda i: bumped.append(("fuzz", i)))
    fake._trace_cmp = lambda *a: None  # Fuzz() starts
    tracer.install()
    assert fake._trace_cmp == tracer.trace
    fake._trace_cmp(0.5, 1.0, 0, 3, False)
    assert tracer.traced == 3 and len(features.seen) == 1
    assert [who for who, _ in bumped] == ["pre", "pre", "fuzz"] and len({i for _, i in bumped}) == 1
