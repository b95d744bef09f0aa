"""Tokens of a libFuzzer dictionary file (``-dict``) for the ``dictionary`` mutator."""

from __future__ import annotations

from pathlib import Path


def parse_dictionary(path: str) -> list[str | float]:
    """Tokens of a libFuzzer -dict file (``name="value"`` or ``"value"`` lines)."""
    tokens: list[str | float] = []
    for raw in Path(path).read_text(encoding="utf-8", errors="replace").splitlines():
        line = raw.strip()
        if not line or line.startswith("#") or '"' not in line:
            continue
        body = line[line.index('"') + 1 : line.rindex('"')]
        text = body.encode("latin-1", "backslashreplace").decode("unicode_escape", "replace")
        try:
            tokens.append(float(text))
        except ValueError:
            tokens.append(text)
    return tokens
