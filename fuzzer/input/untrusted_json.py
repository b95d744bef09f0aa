"""JSON from files anyone may have written (sidecars, manifests, campaign logs): numbers a float
can hold.

Python's ``json`` reads an integer of any length up to 4,300 digits (past that, a ValueError),
and code that then takes it as a float (a tolerance, a difference, a timestamp) raised an
OverflowError from 309 digits on: a traceback instead of "not valid JSON" naming the file.
:func:`loads` refuses such an integer as bad JSON, a ``ValueError`` every reader of these files
already turns into its message (or a skipped log line).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

MAX_DIGITS = 308
"""The longest integer :func:`bounded_int` parses without checking it: every integer of 308 digits
or fewer is below 1e308, within a float's range (about 1.8e308)."""


def bounded_int(text: str) -> int:
    """``json``'s ``parse_int`` for untrusted files: the integer ``text``, if a float can hold it.

    Raises
    ------
    ValueError
        An integer beyond a float's range (longer than 309 characters, or above about 1.8e308).
    """
    digits = len(text.lstrip("-"))
    beyond = f"an integer of {digits} digits, beyond the range of a float"
    if digits > MAX_DIGITS + 1:  # refused before int() parses it
        raise ValueError(beyond)
    value = int(text)
    if digits > MAX_DIGITS:  # 309 digits: 1e308 fits, 2e308 does not
        try:
            float(value)
        except OverflowError:
            raise ValueError(beyond) from None
    return value


def loads(text: str | bytes, **options: Any) -> Any:
    """``json.loads`` with :func:`bounded_int` (``options``: any other of its hooks).

    Raises
    ------
    ValueError
        Not JSON, or an integer beyond a float's range; RecursionError for deep nesting, as
        ``json.loads``.
    """
    return json.loads(text, parse_int=bounded_int, **options)


MAX_LINE = 1 << 20
"""The longest line of a campaign log (characters) a reader parses; a longer one is skipped
without being held in memory (a log's lines are under 10 kB; a 2 GB sparse "log" was one line,
which took 4.2 GB to read)."""


def jsonl_records(path: Path) -> Iterator[Any]:
    """The values of the JSON Lines file ``path``, in order: None for a line that is not JSON
    (or longer than :data:`MAX_LINE`), nothing for a blank line. A missing file has none.

    Raises
    ------
    OSError
        The file cannot be read.
    """
    if not path.is_file():
        return
    with open(path, encoding="utf-8", errors="replace") as handle:
        while line := handle.readline(MAX_LINE):
            if len(line) == MAX_LINE and not line.endswith("\n"):  # too long: read past the rest
                while (rest := handle.readline(MAX_LINE)) and not rest.endswith("\n"):
                    pass
                yield None
                continue
            if not line.strip():
                continue
            try:
                yield loads(line)
            except (ValueError, RecursionError):  # bad JSON, an int past a float's range, nesting
                yield None
