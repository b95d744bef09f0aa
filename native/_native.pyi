"""Type stub of the private compiled module (native/src/bindings)."""

from typing import Any

constants: dict[str, float]

def __getattr__(name: str) -> Any: ...
