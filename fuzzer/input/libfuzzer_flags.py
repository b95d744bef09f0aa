"""libFuzzer's own options, checked before a campaign hands them over: what libFuzzer or Atheris
would otherwise take in silently, crash on, or refuse only after start-up with an exit status the
campaign's summary cannot tell from its own."""

from __future__ import annotations

import string
from pathlib import Path

INT_FLAGS: dict[str, tuple[int, int]] = {
    **dict.fromkeys(
        (
            "-max_len", "-len_control", "-timeout", "-max_total_time", "-fork", "-jobs", "-workers",
            "-rss_limit_mb", "-malloc_limit_mb", "-verbosity", "-print_final_stats", "-use_value_profile",
            "-minimize_crash", "-shrink", "-reduce_inputs", "-close_fd_mask", "-report_slow_units",
            "-prefer_small", "-only_ascii", "-use_counters", "-cross_over", "-detect_leaks", "-entropic",
            "-keep_seed", "-reload", "-error_exitcode", "-timeout_exitcode", "-ignore_crashes",
        ),
        (0, 2**31 - 1),
    ),
    "-seed": (0, 2**32 - 1),  # an unsigned int; 0 draws one
    "-runs": (-1, 2**63 - 1),  # -1: no limit
    "-mutate_depth": (1, 2**31 - 1),
}  # fmt: skip
"""libFuzzer's integer flags that a campaign checks before handing them over, with their ranges.
libFuzzer reads them with ``atoi``-like parsing (``-jobs=abc`` is 0) and Atheris some with
``std::stoul`` (``-seed=abc`` raised from ``atheris.Fuzz`` and then crashed the interpreter);
``-jobs=-1`` started jobs without end and ``-max_len=-1`` was ``std::bad_alloc``."""


def check_int_flags(flags: tuple[str, ...]) -> None:
    """Raise ValueError naming the first flag of :data:`INT_FLAGS` among ``flags`` whose value is
    not a decimal integer in its range."""
    for flag in flags:
        name, sep, value = flag.partition("=")
        if name not in INT_FLAGS:
            continue
        low, high = INT_FLAGS[name]
        digits = value[1:] if value.startswith("-") else value
        if (
            not sep
            or not (digits.isascii() and digits.isdecimal())
            or len(digits) > 20
            or not low <= int(value) <= high
        ):
            raise ValueError(f"{flag}: libFuzzer's {name} takes an integer from {low} to {high}")


MAX_DICTIONARY_BYTES = 16 << 20
"""The largest ``-dict`` file read for the check (libFuzzer reads a file of any size)."""


def dictionary_entry_ok(line: bytes) -> bool:
    """Whether libFuzzer's ``ParseOneDictionaryEntry`` accepts ``line`` (``name="value"`` or
    ``"value"``; inside the quotes printable bytes or spaces, and the escapes ``\\\\``, ``\\"``
    and ``\\xAB``)."""
    text = line.strip(_SPACE)
    if len(text) < 3 or not text.endswith(b'"'):
        return False
    opening = text.find(b'"')
    if opening >= len(text) - 2:  # the value between the quotes may not be empty
        return False
    body, pos = text[opening + 1 : -1], 0
    while pos < len(body):
        byte = body[pos]
        if byte not in _PRINTABLE:
            return False
        if byte == 0x5C:  # a backslash
            if body[pos + 1 : pos + 2] in (b"\\", b'"'):
                pos += 2
                continue
            if (
                body[pos + 1 : pos + 2] == b"x"
                and len(body[pos + 2 : pos + 4]) == 2
                and all(c in _HEX for c in body[pos + 2 : pos + 4])
            ):
                pos += 4
                continue
            return False
        pos += 1
    return True


_SPACE = b" \t\n\v\f\r"
_PRINTABLE = frozenset(string.printable.encode("ascii"))  # C's isprint or isspace, in ASCII
_HEX = frozenset(string.hexdigits.encode("ascii"))


def check_dictionary(path: Path) -> None:
    """Raise ValueError naming the first line of the ``-dict`` file ``path`` that libFuzzer's
    ``ParseDictionaryFile`` would refuse (blank lines and lines starting with ``#`` are skipped;
    an empty file is refused), or a file that cannot be read."""
    try:
        if path.stat().st_size > MAX_DICTIONARY_BYTES:
            raise ValueError(f"-dict={path}: larger than {MAX_DICTIONARY_BYTES} bytes")
        data = path.read_bytes()
    except OSError as exc:
        raise ValueError(f"-dict={path}: cannot be read ({exc.strerror or exc})") from None
    if not data:
        raise ValueError(f"-dict={path}: an empty file (libFuzzer refuses it)")
    for number, line in enumerate(data.split(b"\n"), 1):
        stripped = line.lstrip(_SPACE)
        if not stripped or stripped.startswith(b"#"):
            continue
        if not dictionary_entry_ok(line):
            shown = line[:80].decode("utf-8", "replace")
            raise ValueError(
                f"-dict={path}: line {number} is not a libFuzzer dictionary entry "
                f'(name="value" or "value", no comment after it): {shown!r}'
            )
