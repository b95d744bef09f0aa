"""Coverage instrumentation of the Python targets and the oracle (Atheris), for libFuzzer's
selection: each edge and comparison of the named modules becomes a coverage feature.

``instrument`` imports the targets and the oracle under ``atheris.instrument_imports`` and then
patches, in place, whatever that import hook left alone (``instrument_loaded``): a module found
by another finder (the editable install's redirect loads ``fuzzer``, ``python_impl``...) comes in
through that finder's loader, and Atheris only warns about a "custom loader".
"""

from __future__ import annotations

import contextlib
import sys
import types
from typing import Any

from fuzzer.execution.session import RunConfig
from fuzzer.execution.targets import module_of


def instrument(config: RunConfig) -> None:
    """Import the Python targets and the oracle with Atheris coverage instrumentation."""
    import atheris

    names = sorted({module_of(spec) for spec in config.targets} - {"native"} | {"fuzzer.execution.oracle"})
    # a malformed spec (":x", "a..b") is left to load_target, which reports it by name
    fresh = [n for n in names if n not in sys.modules and all(s.isidentifier() for s in n.split("."))]
    if fresh:
        with atheris.instrument_imports(include=fresh):
            for name in fresh:
                with contextlib.suppress(Exception):  # a bad target is reported when it is loaded
                    __import__(name)
    instrument_loaded(names)


def instrument_loaded(names: list[str]) -> int:
    """Instrument, in place, the functions of the modules ``names`` and their submodules that
    Atheris' import hook left as they were; returns how many it patched.

    ``atheris.instrument_imports`` rewrites code as its loader reads it, but a module found by
    another finder (the editable install's redirect: ``fuzzer``, ``python_impl``...) comes in
    through that finder's loader: Atheris warns about a "custom loader" and the code stays
    uninstrumented, so no edge and no comparison of it would reach libFuzzer. Each function,
    method, static/class method and property of those modules gets
    ``atheris.instrument_func`` (nested functions and lambdas with it; code already
    instrumented is left alone)."""
    import atheris

    prefixes = tuple(f"{n}." for n in names)
    patched = 0
    for modname, module in list(sys.modules.items()):
        if module is None or not (modname in names or modname.startswith(prefixes)):
            continue
        for obj in list(vars(module).values()):
            for func in _own_functions(obj, modname):
                if "__ATHERIS_INSTRUMENTED__" not in func.__code__.co_consts:
                    atheris.instrument_func(func)
                    patched += 1
    return patched


def _own_functions(obj: Any, modname: str) -> list[Any]:
    """The Python functions defined by module ``modname`` in ``obj`` (a function or a class)."""
    if isinstance(obj, types.FunctionType):
        return [obj] if obj.__module__ == modname else []
    if not isinstance(obj, type) or obj.__module__ != modname:
        return []
    out = []
    for member in vars(obj).values():
        if isinstance(member, staticmethod | classmethod):
            member = member.__func__
        if isinstance(member, property):
            out += [f for f in (member.fget, member.fset, member.fdel) if isinstance(f, types.FunctionType)]
        elif isinstance(member, types.FunctionType):
            out.append(member)
    return out
