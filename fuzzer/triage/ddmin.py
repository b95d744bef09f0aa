"""Delta debugging (Zeller and Hildebrandt's ddmin) of a list: how a scenario's steps are
shrunk (``fuzzer.triage.minimize``)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

_T = TypeVar("_T")

__all__ = ["ddmin"]


def _chunks(items: list[int], n: int) -> list[list[int]]:
    """``items`` cut into ``n`` contiguous chunks of near-equal size (the first ones larger)."""
    size, extra = divmod(len(items), n)
    out, start = [], 0
    for k in range(n):
        end = start + size + (k < extra)
        out.append(items[start:end])
        start = end
    return out


def ddmin(
    items: list[_T], holds: Callable[[list[_T]], bool], budget: Callable[[], bool]
) -> tuple[list[_T], int]:
    """Delta debugging (Zeller and Hildebrandt's ddmin) of a non-empty list.

    Parameters
    ----------
    items : list, shape (N,)
        The list to shrink (kept in order; never empty).
    holds : callable
        ``holds(subset)``: whether the subset still shows the failure. Never called twice with
        the same subset, nor with an empty one.
    budget : callable
        ``budget()``: whether another call of ``holds`` may be made.

    Returns
    -------
    tuple
        ``(kept, reductions)``: the shrunk list, 1-minimal when the budget did not run out
        (removing any one item of it makes ``holds`` false), and how many reductions were kept.
    """
    kept = list(range(len(items)))
    seen: dict[tuple[int, ...], bool] = {}
    reductions, n = 0, 2

    def test(subset: list[int]) -> bool | None:
        key = tuple(subset)
        if key not in seen:
            if not budget():
                return None
            seen[key] = holds([items[i] for i in subset])
        return seen[key]

    while len(kept) >= 2:
        chunks = _chunks(kept, min(n, len(kept)))
        complements = [[i for i in kept if i not in chunk] for chunk in chunks] if len(chunks) > 2 else []
        reduced = False
        for candidate, is_chunk in [*((c, True) for c in chunks), *((c, False) for c in complements)]:
            verdict = test(candidate)
            if verdict is None:
                return [items[i] for i in kept], reductions
            if verdict:
                kept, reduced, reductions = candidate, True, reductions + 1
                n = 2 if is_chunk else max(len(chunks) - 1, 2)
                break
        if not reduced:
            if len(chunks) >= len(kept):
                break
            n = min(2 * len(chunks), len(kept))
    return [items[i] for i in kept], reductions
