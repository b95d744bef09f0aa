"""Atheris' edge callback without pybind11's dispatch (the facade of ``_fastcov``).

Every edge of an instrumented module (the Python targets, the oracle) calls
``atheris._trace_branch(index)``, looked up on the ``atheris`` module at each edge. Once
``atheris.Fuzz()`` has started, that is a pybind11 function of Atheris' core module around
``atheris::_trace_branch``, and pybind11's argument dispatch costs about 150 ns a call, where a
C builtin of one argument costs about 25 (an ``fk`` evaluation makes 139 such calls, a ``move``
499: BENCHMARKS.md, "Instrumentation's cost, split"). :func:`install` puts in its place a
builtin of ``_fastcov`` that calls the same C++ function of the same loaded library: the same
counters bumped, so libFuzzer sees the same coverage (``tests/test_fastcov.py`` checks a
campaign keeps the same corpus with it as without).

Where it cannot (Atheris not fuzzing yet, another Atheris whose core has no such symbol, the
module not built), Atheris' own function stays and :func:`install` says why.
"""

from __future__ import annotations

import sys
from typing import Any

CORE_MODULES = ("atheris.core_with_libfuzzer", "atheris.core_without_libfuzzer")
"""Atheris' core modules; ``atheris.Fuzz()`` imports one and takes ``_trace_branch`` from it."""


def install(atheris: Any = None) -> str | None:
    """Swap ``atheris._trace_branch`` for ``_fastcov.trace_branch`` once ``atheris.Fuzz()`` has
    put its core module's function there.

    Returns
    -------
    str or None
        None once installed (or already); else why not (Atheris' function is left in place).
    """
    if atheris is None:
        import atheris as module

        atheris = module
    try:
        from fuzzer.selection import _fastcov  # type: ignore[attr-defined]
    except ImportError as exc:
        return f"the _fastcov module is not built ({exc})"
    current = getattr(atheris, "_trace_branch", None)
    if current is _fastcov.trace_branch:
        return None
    core = next(
        (sys.modules[n] for n in CORE_MODULES if getattr(sys.modules.get(n), "_trace_branch", 0) is current),
        None,
    )
    if core is None:
        return "atheris._trace_branch is not its core module's (atheris.Fuzz() has not started)"
    try:
        _fastcov.bind(str(core.__file__))
    except (LookupError, TypeError, UnicodeError) as exc:
        return str(exc)
    atheris._trace_branch = _fastcov.trace_branch
    return None
