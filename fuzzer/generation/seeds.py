"""Deterministic initial seed generation (Algorithm 1, line 10 of the RROSFuzz paper).

As in the paper, a function decorated with :func:`hypothesis.given` is called and its
``max_examples`` setting bounds the number of test cases; here the function only collects
what Hypothesis draws. ``@hypothesis.seed`` fixes the random choices, so the same call
returns the same seeds in every run and every process.

One more input has to be pinned for that: recent Hypothesis versions (6.13x+) mix into
generation the literals found in the source of every *local* module currently imported
(``hypothesis.internal.conjecture.providers._get_local_constants``). Seeds would then change
with the set of project modules a process happens to have imported (the CLI, pytest with its
conftest, ...) and with any edit adding a literal anywhere in the project. While seeds are
generated, that pool is replaced by an empty one (see :func:`_without_local_constants`).
"""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import hypothesis
from hypothesis import HealthCheck, Phase, Verbosity, given, settings
from hypothesis.strategies import SearchStrategy

from fuzzer.signals import stop_requested

__all__ = ["MAX_ATTEMPTS", "canonical_json", "generate_seeds", "smallest_fits"]

#: Hypothesis runs (with seeds ``seed``, ``seed + 1``, ...) tried before giving up on ``n``.
MAX_ATTEMPTS = 10


def canonical_json(value: Any) -> str:
    """Return the canonical text of a message value (sorted keys), used for de-duplication.

    ``nan`` and the infinities are kept (as ``NaN``/``Infinity``), ``-0.0`` stays distinct
    from ``0.0``; objects JSON cannot encode fall back to their ``repr``.
    """
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=False, default=repr)


_PATCH_LOCK = threading.RLock()


@contextmanager
def _without_local_constants() -> Iterator[None]:
    """Keep Hypothesis from drawing literals mined from the imported local modules.

    This touches private Hypothesis internals; when they are missing (other versions) it
    does nothing, and ``test_seeds_deterministic_across_processes`` notices if determinism
    breaks again.
    """
    from hypothesis.internal.conjecture import providers

    get_local = getattr(providers, "_get_local_constants", None)
    constants_cls = getattr(providers, "Constants", None)
    clear_cache = getattr(getattr(getattr(providers, "CONSTANTS_CACHE", None), "cache", None), "clear", None)
    if get_local is None or constants_cls is None or clear_cache is None:
        yield
        return
    empty = constants_cls()
    with _PATCH_LOCK:
        # The cache holds (global, local) constant pools per choice kind; drop pools built
        # with the local constants before, and ours after.
        clear_cache()
        setattr(providers, "_get_local_constants", lambda: empty)  # noqa: B010
        try:
            yield
        finally:
            setattr(providers, "_get_local_constants", get_local)  # noqa: B010
            clear_cache()


def smallest_fits(strategy: SearchStrategy[Any]) -> bool:
    """Whether the simplest value of ``strategy`` fits in one Hypothesis test case.

    Hypothesis checks the same first (its ``large_base_example`` health check, suppressed here),
    but with the check suppressed it goes on drawing until hundreds of test cases have overrun:
    for a chain of 1,300 joints, 42 s before :class:`~hypothesis.errors.Unsatisfiable`. The
    simplest value is drawn here alone, from Hypothesis' "simplest" choice template, as its
    engine draws it; that takes no random choice, so the seeds drawn after are the same.

    This touches private Hypothesis internals; when they are missing or changed (other
    versions) it answers True and the slow path still ends in ``Unsatisfiable``.
    """
    try:
        from hypothesis.control import BuildContext
        from hypothesis.errors import StopTest
        from hypothesis.internal.conjecture.choice import ChoiceTemplate
        from hypothesis.internal.conjecture.data import ConjectureData, Status

        data = ConjectureData.for_choices((ChoiceTemplate("simplest", count=None),))
        context = BuildContext(data, is_final=False, wrapped_test=lambda: None)
    except (ImportError, AttributeError, TypeError):
        return True
    try:
        with context:
            data.draw(strategy)
    except StopTest:
        return data.status != Status.OVERRUN
    except Exception:  # noqa: BLE001 - not this check's to report: the real run raises it
        return True
    return True


def _draw(strategy: SearchStrategy[Any], max_examples: int, seed: int) -> list[Any]:
    """Run one Hypothesis generate phase with ``seed`` and return every example it drew."""
    drawn: list[Any] = []

    @hypothesis.seed(seed)
    @settings(
        max_examples=max_examples,
        database=None,
        derandomize=False,
        phases=[Phase.generate],
        deadline=None,
        suppress_health_check=list(HealthCheck),
        verbosity=Verbosity.quiet,
        print_blob=False,
    )
    @given(strategy)
    def collect(value: Any) -> None:
        if stop_requested():  # a kept Ctrl-C or SIGTERM: 100,000 seeds were all drawn first (6 min)
            raise KeyboardInterrupt
        drawn.append(value)

    with _without_local_constants():
        collect()
    return drawn


def generate_seeds(strategy: SearchStrategy[dict[str, Any]], n: int, seed: int) -> list[dict[str, Any]]:
    """Generate up to ``n`` distinct initial seeds, deterministically for ``seed``.

    Parameters
    ----------
    strategy : SearchStrategy
        Strategy of message values, e.g. from :func:`fuzzer.generation.strategies.strategy_for`.
    n : int
        Number of distinct seeds wanted.
    seed : int
        Seed of the first Hypothesis run; when it yields fewer than ``n`` distinct values,
        runs with ``seed + 1``, ``seed + 2``, ... follow (at most :data:`MAX_ATTEMPTS` runs in
        all; a run over a tiny, exhausted space costs only as many calls as it has values).

    Returns
    -------
    list of dict
        Distinct values (by :func:`canonical_json`) in the order drawn, each as drawn (field
        order kept). Shorter than ``n`` only if the value space is (nearly) exhausted.

    Raises
    ------
    ValueError
        If ``n`` is negative.
    TypeError
        If ``strategy`` is not a Hypothesis strategy.
    hypothesis.errors.Unsatisfiable
        If even the simplest value is larger than a Hypothesis test case (a chain of 1,300
        joints), or no value can be drawn.
    hypothesis.errors.FailedHealthCheck
        If called inside another ``@given`` test whose settings do not suppress
        ``HealthCheck.nested_given`` (Hypothesis checks the outer test's settings).
    """
    if n < 0:
        raise ValueError(f"n must be >= 0, got {n}")
    if not isinstance(strategy, SearchStrategy):
        raise TypeError(f"strategy must be a hypothesis strategy, got {type(strategy).__name__}")
    if n and not smallest_fits(strategy):
        from hypothesis.errors import Unsatisfiable

        raise Unsatisfiable("even the simplest value is larger than one Hypothesis test case may be")
    seen: set[str] = set()
    seeds: list[dict[str, Any]] = []
    for attempt in range(MAX_ATTEMPTS):
        if len(seeds) >= n:
            break
        for value in _draw(strategy, n, seed + attempt):
            key = canonical_json(value)
            if key not in seen:
                seen.add(key)
                seeds.append(value)
    return seeds[:n]
