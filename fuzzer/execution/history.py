"""The call history of a ``state_dependent`` divergence: the calls made on the campaign's
targets before it, stored in its sidecar as plain JSON data and read back, validated, for replay
(``Evaluator.evaluate(case, history=...)``)."""

from __future__ import annotations

from typing import Any

from fuzzer.input.mapping import Call, call_from_json, call_to_json
from fuzzer.scenario.steps import ScenarioCall, ScenarioError, to_call, to_message

HISTORY = 32
"""Calls on the campaign's targets kept for a ``state_dependent`` divergence's sidecar."""

AnyCall = Call | ScenarioCall

__all__ = ["HISTORY", "AnyCall", "history_of", "stored_call"]


def stored_call(call: AnyCall, seed: tuple[float, ...] | None = None) -> dict[str, Any]:
    """A call as plain JSON data (a scenario as its message)."""
    if isinstance(call, ScenarioCall):
        return {"kind": "ScenarioCall", "message": to_message(call)}
    return call_to_json(call, seed)


def history_of(sidecar: dict[str, Any] | None) -> list[tuple[AnyCall, tuple[float, ...] | None]]:
    """The call history a sidecar records (``[]`` without one).

    Raises
    ------
    ValueError
        When it is not a list of calls (``fuzzer.input.mapping.CallError`` names the field).
    """
    raw = sidecar.get("history", []) if isinstance(sidecar, dict) else []
    if not isinstance(raw, list):
        raise ValueError("'history' must be a list of calls")
    if len(raw) > 10 * HISTORY:
        raise ValueError(f"'history' holds {len(raw)} calls, more than {10 * HISTORY}")
    return [_stored(item) for item in raw]


def _stored(item: Any) -> tuple[AnyCall, tuple[float, ...] | None]:
    if isinstance(item, dict) and item.get("kind") == "ScenarioCall":
        from fuzzer.input.msgdef import MessageRegistry
        from fuzzer.scenario.steps import MAX_STEPS_LIMIT, validate

        try:
            validate(item.get("message"), MessageRegistry(), MAX_STEPS_LIMIT)
        except ScenarioError as exc:
            raise ValueError(f"a stored scenario in 'history': {exc}") from None
        return to_call(item["message"]), None
    return call_from_json(item)
