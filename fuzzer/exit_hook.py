"""Run a function when the process ends, including libFuzzer's own exit.

libFuzzer ends a campaign (-max_total_time, -runs) by calling C ``exit()``,
which skips Python's ``atexit``; Python's ``atexit`` covers the other endings
(Python exceptions, Ctrl-C). So the callback is registered both with
``atexit`` and with the C library's ``__cxa_atexit`` (through ctypes), and runs
once. Timeouts and deadly signals end the process without either.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
from collections.abc import Callable
from typing import Any

_keep_alive: list[Any] = []


def on_exit(callback: Callable[[], None]) -> None:
    """Call ``callback`` once at process exit, however normal exit happens."""
    done = False

    def once(*_: object) -> None:
        nonlocal done
        if done:
            return
        done = True
        with contextlib.suppress(Exception):  # nothing useful can be done at exit
            callback()

    atexit.register(once)
    try:
        c_callback = ctypes.CFUNCTYPE(None, ctypes.c_void_p)(once)
        ctypes.CDLL(None).__cxa_atexit(c_callback, None, None)
        _keep_alive.append(c_callback)
    except (AttributeError, OSError):  # not glibc: Python's atexit still runs on most paths
        pass
