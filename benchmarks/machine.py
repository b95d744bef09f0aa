"""How fast this machine runs Python right now: one fixed workload's time, printed beside
throughput figures so that figures of different days can be set side by side.

The VMs these benchmarks run on are shared, and their speed changes from day to day for the
same CPU model: ``bench_engine`` measured 7ab8b30's ``fk`` at 1,706 single inputs a second on
2026-12-02 and at 719 on 2026-12-04 (AMD EPYC both days, nothing else running). The model name
(``journal.cpu_model``) does not tell those days apart; the reference shows how fast the machine
was around a figure. It moves within minutes too (10.7 ms before and 15.1 ms after one 4-min run
on 2026-12-04), so it dates a figure and does not correct it: compare only figures measured in
turn on the same day. It is interpreted Python (a generator and integer arithmetic, no I/O, no
numpy), as most of a campaign's time is.
"""

from __future__ import annotations

import timeit

REFERENCE = "sum(i * i for i in range(200_000))"
"""The workload: a generator over integers, summed (about 10-30 ms on the VMs of 2026)."""

REPEAT = 7
"""Timings taken; the reference is the fastest (the least disturbed)."""


def reference_ms(repeat: int = REPEAT) -> float:
    """The fastest of ``repeat`` timings of :data:`REFERENCE`, in milliseconds."""
    if repeat < 1:
        raise ValueError(f"repeat must be at least 1, not {repeat}")
    return min(timeit.repeat(REFERENCE, number=1, repeat=repeat)) * 1000.0


def reference_line(when: str) -> str:
    """A comment line for a benchmark's output: the reference measured now, labelled ``when``
    (e.g. "before", "after"); lower is a faster machine."""
    ms = reference_ms()
    return f"# machine reference {when}: {ms:.1f} ms (fastest of {REPEAT}: {REFERENCE}; lower is faster)"
