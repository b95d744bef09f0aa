"""Leaf operations on the targets' comparison thresholds (``fuzzer.selection.compared``): the
values ``compared`` and input-to-state write, a threshold or a value just past it."""

from __future__ import annotations

import math
from random import Random
from typing import Any

from fuzzer.mutation.base import Message, MutationContext, NotApplicable
from fuzzer.mutation.fields import Leaf
from fuzzer.selection.compared import edge


def _has_thresholds(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> bool:
    """Guard: the campaign has learned a comparison threshold."""
    return ctx.compared is not None and len(ctx.compared) > 0


def _past(threshold: float, value: float, rng: Random, way: float = 0.0) -> float:
    """``threshold``, or the next float, a relative 1e-6 or 1e-3 (at least that much absolute)
    beyond it, on the side ``way`` (+1.0 up, -1.0 down; 0.0: away from ``value``, and either
    way, drawn, from a value on the threshold). A ``value`` already past it on that side, by
    no more than ``EDGE`` (``fuzzer.selection.compared``: an input there does not solve the
    site), gets the 1e-3 step: the next float and 1e-6 would leave it at the edge, where the
    scenario oracle judges a divergence ill-conditioned, and the threshold itself undoes it."""
    if way == 0.0:
        way = -1.0 if value > threshold else 1.0 if value < threshold else rng.choice((-1.0, 1.0))
    step = max(1.0, abs(threshold))
    if 0.0 < (value - threshold) * way <= edge(threshold):
        return threshold + way * 1e-3 * step
    near = (
        threshold,
        math.nextafter(threshold, way * math.inf),
        threshold + way * 1e-6 * step,
        threshold + way * 1e-3 * step,
    )
    return rng.choice([v for v in near if v != value])


def _compared(value: Any, leaf: Leaf, message: Message, ctx: MutationContext) -> Any:
    """A comparison threshold of the targets or a value just either side of it: the next float
    either way, or a relative step of 1e-6 or 1e-3 (at least that much absolute)."""
    assert ctx.compared is not None
    threshold = ctx.compared.pick(ctx.rng)
    if threshold is None:
        raise NotApplicable("no comparison threshold known yet")
    step = max(1.0, abs(threshold))
    near = (
        threshold,
        math.nextafter(threshold, math.inf),
        math.nextafter(threshold, -math.inf),
        threshold + 1e-6 * step,
        threshold - 1e-6 * step,
        threshold + 1e-3 * step,
        threshold - 1e-3 * step,
    )
    return ctx.rng.choice([v for v in near if v != value])  # never the value it has
