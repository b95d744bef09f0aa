"""The ROS transport's messages (``fuzzer.ros.transport``): a request or answer as it travels on
a ``std_msgs/String`` topic, ``"<id>\n<JSON>"``, and the outcome an answer carries.

The JSON is plain JSON (RFC 8259): a non-finite float travels as ``{"$float": "nan" | "inf" |
"-inf"}``. What a node sends is data: :func:`decode` parses it, never evaluates it.
"""

from __future__ import annotations

import json
import math
from typing import Any

from fuzzer.execution.records import Outcome, Status
from robot_api.errors import error_class


def _tagged(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return {"$float": "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")}
    if isinstance(value, dict):
        return {k: _tagged(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_tagged(v) for v in value]
    return value


def _untag(obj: dict[str, Any]) -> Any:
    if len(obj) == 1 and obj.get("$float") in ("nan", "inf", "-inf"):
        return float(obj["$float"])
    return obj


def encode(ident: int, payload: dict[str, Any]) -> str:
    """A request or answer as sent: ``"<id>\n<JSON>"`` (plain JSON, non-finite floats tagged)."""
    return f"{ident}\n" + json.dumps(_tagged({"id": ident, **payload}), allow_nan=False)


def decode(text: str) -> dict[str, Any]:
    """Read what :func:`encode` wrote (data only).

    Raises
    ------
    ValueError
        Not a message of the protocol.
    """
    _, _, body = text.partition("\n")
    data = json.loads(body, object_hook=_untag)
    if not isinstance(data, dict) or not isinstance(data.get("id"), int):
        raise ValueError("not a request or answer of the ROS transport")
    return data


def outcome_of(answer: dict[str, Any]) -> Outcome:
    """The outcome a node's answer carries; a malformed one is a ``crashed:BadAnswer`` outcome
    (one ended the campaign with a traceback, exit 77). A rejection with the contract's code
    only (the C++ node) gets its class's name (``robot_api.errors.error_class``)."""
    try:
        outcome = Outcome.from_json(answer["outcome"])
    except (KeyError, TypeError, ValueError, RecursionError) as exc:
        said = f"the target's node answered what is not an outcome ({type(exc).__name__}: {exc})"
        return Outcome(Status.CRASHED, "BadAnswer", None, said[:500])
    if outcome.status == Status.REJECTED and not outcome.error and outcome.code is not None:
        outcome = Outcome(outcome.status, error_class(outcome.code).__name__, outcome.code, outcome.message)
    return outcome


__all__ = ["decode", "encode", "outcome_of"]
