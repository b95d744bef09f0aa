"""Coverage instrumentation of the Python targets and the oracle (Atheris), for libFuzzer's
selection: each edge and comparison of the named modules becomes a coverage feature.

``instrument`` imports the targets and the oracle and then gives every function, method and
property of theirs Atheris' instrumented code, in place (``instrument_loaded``). Not with
Atheris' import hook (``atheris.instrument_imports``): a module found by another finder (the
editable install's redirect loads ``fuzzer``, ``python_impl``...) comes in through that
finder's loader, which the hook leaves alone (it only warns about a "custom loader"), and the
rewritten code of the in-place path can be cached (``fuzzer.selection.instrument_cache``),
which takes about 0.5 s off the start of a campaign on the twin.
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
    names = sorted({module_of(spec) for spec in config.targets} - {"native"} | {"fuzzer.execution.oracle"})
    # a malformed spec (":x", "a..b") is left to load_target, which reports it by name
    fresh = [n for n in names if n not in sys.modules and all(s.isidentifier() for s in n.split("."))]
    for name in fresh:
        with contextlib.suppress(Exception):  # a bad target is reported when it is loaded
            __import__(name)
    instrument_loaded(names)


def instrument_loaded(names: list[str]) -> int:
    """Instrument, in place, the functions of the modules ``names`` and their submodules that
    are not instrumented yet; returns how many it patched.

    Each function, method, static/class method and property of those modules gets what
    ``atheris.instrument_func`` makes of it (nested functions and lambdas with it; code
    already instrumented is left alone), from ``fuzzer.selection.instrument_cache`` when an
    earlier process made the same."""
    import atheris

    from fuzzer.selection.instrument_cache import folder, instrument_functions

    prefixes = tuple(f"{n}." for n in names)
    functions: dict[int, types.FunctionType] = {}  # one entry per function object, in order
    for modname, module in list(sys.modules.items()):
        if module is None or not (modname in names or modname.startswith(prefixes)):
            continue
        for obj in list(vars(module).values()):
            for func in _own_functions(obj, modname):
                if "__ATHERIS_INSTRUMENTED__" not in func.__code__.co_consts:
                    functions.setdefault(id(func), func)
    if functions:
        instrument_functions(list(functions.values()), atheris, folder())
    return len(functions)


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
