"""The mutator registry and dispatcher, in the style of libFuzzer's ``MutationDispatcher``.

:func:`register` adds a named mutator with a weight; :func:`mutate` picks one by weight (or
by name) and falls back to another one while the chosen one does not apply. The mutators
themselves are in :mod:`fuzzer.mutation.paper` and :mod:`fuzzer.mutation.robotics`;
:mod:`fuzzer.mutation.mutators` imports both (in that order, which is the order of
:data:`WEIGHTS` and so of the weighted draws) and is what the rest of the fuzzer imports.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from random import Random
from typing import Any

from fuzzer.mutation.base import (
    NOOP,
    Message,
    MutationContext,
    Mutator,
    NotApplicable,
)
from fuzzer.mutation.fields import (
    clone,
)
from fuzzer.mutation.structure import splice_both

# ----------------------------------------------------------------------------------------------------------
# Registry
# ----------------------------------------------------------------------------------------------------------

MUTATORS: dict[str, Mutator] = {}
"""Registered mutators by name.  Each one works on a deep copy and raises :class:`NotApplicable`."""
WEIGHTS: dict[str, float] = {}
"""Relative selection weights of :data:`MUTATORS` (same keys)."""


def register(name: str, weight: float = 1.0) -> Callable[[Mutator], Mutator]:
    """Register an in-place mutator under ``name``; the registered function works on a deep copy.

    Parameters
    ----------
    name : str
        Unique mutator name.
    weight : float
        Relative weight for :func:`mutate`'s random choice.

    Returns
    -------
    Callable
        A decorator returning the copying wrapper.
    """

    def decorator(fn: Mutator) -> Mutator:
        if name in MUTATORS:
            raise ValueError(f"mutator {name!r} is already registered")

        @functools.wraps(fn)
        def wrapper(message: dict[str, Any], ctx: MutationContext) -> dict[str, Any]:
            copied = clone(message)
            outer = ctx.memo.get("_source")
            ctx.memo["_source"] = (copied, message)  # lets _inventory reuse the input's inventory
            try:
                return fn(copied, ctx)
            finally:
                ctx.memo["_source"] = outer

        MUTATORS[name] = wrapper
        WEIGHTS[name] = weight
        return wrapper

    return decorator


def weighted_choice(pool: Mapping[str, float], rng: Random) -> str:
    """A name of ``pool`` drawn with probability proportional to its weight."""
    names = [name for name, weight in pool.items() if weight > 0]
    if not names:
        raise NotApplicable("no mutator left")
    return rng.choices(names, weights=[pool[name] for name in names])[0]


def dispatch(
    message: Message, ctx: MutationContext, pool: dict[str, float], first: str | None
) -> tuple[Message, str]:
    """Run ``first`` (or a weighted pick), falling back through ``pool`` while mutators do not apply."""
    name = first if first is not None else weighted_choice(pool, ctx.rng)
    while True:
        try:
            return MUTATORS[name](message, ctx), name
        except NotApplicable:
            pool.pop(name, None)
            name = weighted_choice(pool, ctx.rng)


# ----------------------------------------------------------------------------------------------------------
# Entry points
# ----------------------------------------------------------------------------------------------------------


def mutate(
    message: dict[str, Any], ctx: MutationContext, name: str | None = None
) -> tuple[dict[str, Any], str]:
    """Mutate a copy of ``message`` with the named mutator, or one picked by :data:`WEIGHTS`.

    Parameters
    ----------
    message : dict
        The seed; never modified.
    ctx : MutationContext
        Randomness, types and options.
    name : str, optional
        Mutator to try first; when it does not apply, others are tried by weight.

    Returns
    -------
    tuple[dict, str]
        The new message and the name of the mutator actually used (:data:`NOOP` and an unchanged copy
        when none applies).

    Raises
    ------
    KeyError
        If ``name`` is not a registered mutator.
    """
    if name is not None and name not in MUTATORS:
        raise KeyError(f"unknown mutator {name!r}; known: {sorted(MUTATORS)}")
    try:
        return dispatch(message, ctx, dict(WEIGHTS), name)
    except NotApplicable:
        return clone(message), NOOP


def crossover(a: dict[str, Any], b: dict[str, Any], ctx: MutationContext) -> dict[str, Any]:
    """Splice two messages of the same type (for libFuzzer's custom crossover); inputs are not modified.

    Parameters
    ----------
    a, b : dict
        Parents; the child has the shape and field order of ``a``.
    ctx : MutationContext
        Randomness and field types (``ctx.other`` is ignored).

    Returns
    -------
    dict
        The child; equal to ``a`` when ``a == b``.
    """
    return splice_both(a, b, ctx)
