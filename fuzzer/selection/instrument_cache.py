"""A cache of Atheris-instrumented code, so a campaign's start does not redo the rewriting.

``atheris.instrument_func`` rewrites a function's bytecode in pure Python: about 3 ms a
function, 0.5 s for the twin (``python_impl``) and the oracle, paid before every campaign's
first input. The result depends only on the function's code, on Atheris and Python, and on
the coverage counters Atheris hands out (``atheris._reserve_counter()``: consecutive integers
from one per process counter, baked into the rewritten code as constants). So the rewritten
code objects of one :func:`instrument_functions` call are kept in a file named by a digest
of all of that, and the next process that would produce the same code loads them instead.

The counters are what makes reuse exact. Every call, cached or not, first reserves one
counter (``first``) and, after instrumenting, one more (``last``): the counters in between
are those the rewritten code uses. The digest includes ``first``, so a file is only ever used
by a process whose counter stands where it stood when the file was written; a hit reserves
``last - first`` counters, leaving the process exactly where instrumenting would have left
it, and checks that the last one is ``last``. Anything unexpected (an unreadable, truncated
or foreign file, a count that does not match) is a miss: the functions are instrumented as
usual and the file is rewritten. The two counters reserved around the rewriting are never
hit; a wasted pair keeps the cached and the uncached code identical.

Atheris' code holds the ``atheris`` module itself as a constant, which ``marshal`` cannot
write: it is stored as a placeholder string and put back on load.

The files are code this program runs, like Python's own ``__pycache__``: they live in the
repository's ``build/`` folder (``RROSFUZZ_INSTRUMENT_CACHE`` names another folder, which
only you should be able to write, or ``off`` turns the cache off), never in a folder a
campaign was pointed at (corpus, artifacts: untrusted data). At most
``KEEP`` files are kept, the oldest removed first.
"""

from __future__ import annotations

import contextlib
import hashlib
import marshal
import os
import sys
import types
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

ENV = "RROSFUZZ_INSTRUMENT_CACHE"
DEFAULT = Path(__file__).resolve().parents[2] / "build" / "instrument-cache"
KEEP = 32
"""Cache files kept (each is one configuration of targets and one version of their code)."""
MAGIC = "rrosfuzz-instrumented-code-v1"
PLACEHOLDER = "__rrosfuzz_atheris_module_3f9c1e7a__"
"""Stands for the ``atheris`` module among a cached code object's constants."""


def folder() -> Path | None:
    """Where the cache lives, or None when ``RROSFUZZ_INSTRUMENT_CACHE=off``."""
    chosen = os.environ.get(ENV, "")
    if chosen.lower() in ("off", "0", "no", "false"):
        return None
    return Path(chosen) if chosen else DEFAULT


def instrument_functions(functions: Sequence[types.FunctionType], atheris: Any, cache: Path | None) -> bool:
    """Give every function of ``functions`` its Atheris-instrumented code: from ``cache``
    when a file there matches, else with ``atheris.instrument_func`` (and write the file).

    Parameters
    ----------
    functions : sequence of function
        Distinct function objects, none instrumented yet, in a deterministic order.
    atheris : module
        ``atheris`` (or a stand-in with ``_reserve_counter`` and ``instrument_func``).
    cache : Path or None
        The cache folder; None instruments without a cache (the same counters are reserved).

    Returns
    -------
    bool
        Whether the code came from the cache.
    """
    from fuzzer.selection import cmp_gap

    cmp_gap.install(atheris)  # the comparisons Atheris' own pass leaves untraced
    first = int(atheris._reserve_counter())
    key = _digest(functions, atheris, first) if cache is not None else None
    codes = _load(cache / f"{key}.bin", first, len(functions)) if cache is not None and key else None
    if codes is not None:
        last = first
        for _ in range(codes[0] - first):
            last = int(atheris._reserve_counter())
        if last == codes[0]:
            for func, code in zip(functions, codes[1], strict=True):
                func.__code__ = _restore(code, atheris)
            return True
        key = None  # another thread took counters meanwhile: instrument, and keep no file
    for func in functions:
        atheris.instrument_func(func)
    last = int(atheris._reserve_counter())
    if cache is not None and key:
        _store(cache, key, first, last, [_portable(f.__code__, atheris) for f in functions])
    return False


def _digest(functions: Sequence[types.FunctionType], atheris: Any, first: int) -> str | None:
    """What the rewritten code depends on: Python, Atheris' rewriter, the first counter, and
    each function's module, name and code (None if a code object cannot be serialized)."""
    h = hashlib.sha256(f"{MAGIC}\0{sys.version}\0{first}\0".encode())
    for source in _rewriter_files(atheris):
        with contextlib.suppress(OSError):
            h.update(source.read_bytes())
    for func in functions:
        h.update(f"\0{func.__module__}\0{func.__qualname__}\0".encode())
        try:
            h.update(marshal.dumps(func.__code__, 2))  # no references: the same bytes in every process
        except ValueError:
            return None
    return h.hexdigest()


def _rewriter_files(atheris: Any) -> list[Path]:
    """Atheris' bytecode rewriter (its version is in its code) and this program's addition to
    it (``fuzzer.selection.cmp_gap``), if ``atheris`` is the real one."""
    where = getattr(atheris, "__file__", None)
    if not where:
        return []
    base = Path(where).parent
    ours = Path(__file__).resolve().with_name("cmp_gap.py")
    return [base / "instrument_bytecode.py", base / "version_dependent.py", base / "__init__.py", ours]


def _portable(code: types.CodeType, atheris: Any) -> types.CodeType:
    """``code`` with the ``atheris`` module among its constants (nested code too) replaced by
    :data:`PLACEHOLDER`."""
    return _map_constants(code, lambda c: PLACEHOLDER if c is atheris else c)


def _restore(code: types.CodeType, atheris: Any) -> types.CodeType:
    """The inverse of :func:`_portable`."""
    return _map_constants(code, lambda c: atheris if isinstance(c, str) and c == PLACEHOLDER else c)


def _map_constants(code: types.CodeType, change: Callable[[Any], Any]) -> types.CodeType:
    consts = tuple(
        _map_constants(c, change) if isinstance(c, types.CodeType) else change(c) for c in code.co_consts
    )
    return code.replace(co_consts=consts)


def _load(path: Path, first: int, count: int) -> tuple[int, list[types.CodeType]] | None:
    """(last counter, code objects) of a cache file made for these functions from counter
    ``first``; None when there is none or it does not fit."""
    try:
        entry = marshal.loads(path.read_bytes())
    except (OSError, ValueError, EOFError, TypeError):  # a cache: a bad file means instrumenting
        return None
    if not (isinstance(entry, tuple) and len(entry) == 4 and entry[0] == MAGIC and entry[1] == first):
        return None
    last, codes = entry[2], entry[3]
    if not (isinstance(last, int) and last > first and isinstance(codes, tuple) and len(codes) == count):
        return None
    if not all(isinstance(c, types.CodeType) for c in codes):
        return None
    return last, list(codes)


def _store(cache: Path, key: str, first: int, last: int, codes: list[types.CodeType]) -> None:
    """Write the file (all at once: a process reading it sees the old one or the new one) and
    keep the newest :data:`KEEP`. A folder that cannot be written only means no cache."""
    from fuzzer.artifacts.store import atomic_write

    try:
        atomic_write(cache / f"{key}.bin", marshal.dumps((MAGIC, first, last, tuple(codes))))
    except (OSError, ValueError):
        return
    keep_newest(cache, "*.bin", KEEP)


def keep_newest(cache: Path, pattern: str, keep: int) -> None:
    """Remove all but the newest ``keep`` files of ``cache`` matching ``pattern`` (a file that
    cannot be listed or removed stays: it is only a cache)."""
    try:
        files = sorted(cache.glob(pattern), key=lambda p: p.stat().st_mtime, reverse=True)
    except OSError:
        return
    for old in files[keep:]:
        with contextlib.suppress(OSError):
            old.unlink()
