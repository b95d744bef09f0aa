"""Run a function when the process ends, including libFuzzer's own exit, and let it
choose the exit status.

libFuzzer ends a campaign (-max_total_time, -runs, the end of -fork) by calling C
``exit(status)``, which skips Python's ``atexit``; Python's ``atexit`` covers the
other endings (Python exceptions, Ctrl-C). So the callback is registered both
with ``atexit`` and with glibc's ``on_exit`` (through ctypes; ``__cxa_atexit``
where ``on_exit`` is missing), and runs once. ``on_exit`` hands over the status
libFuzzer exits with; a callback that returns another status ends the process
with it (``os._exit``, after flushing Python's and C's output). Timeouts and
deadly signals end the process with ``_Exit`` or a signal, without either hook:
their status is libFuzzer's.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import os
import sys
from collections.abc import Callable
from typing import Any

_keep_alive: list[Any] = []

ExitCallback = Callable[[int | None], int | None]
"""Called with the exit status (None when unknown: Python's atexit, which Atheris also
runs when it ends the process itself); returns the status the process should end with,
or None to keep it (with an unknown status, a returned 0 is not applied either)."""


def flush_all() -> None:
    """Flush Python's streams and C stdio (before ``os._exit``)."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    with contextlib.suppress(Exception):
        ctypes.CDLL(None).fflush(None)


def on_exit(callback: ExitCallback) -> Callable[[int | None], int | None]:
    """Call ``callback`` once at process exit, however normal exit happens.

    Returns the once-only wrapper, so that a caller ending the process itself
    (``os._exit``) can run the callback first.
    """
    done = False

    def once(status: int | None) -> int | None:
        nonlocal done
        if done:
            return None
        done = True
        try:
            return callback(status)
        except Exception:  # noqa: BLE001 - nothing useful can be done at exit
            return None

    def python_exit() -> None:
        code = once(None)
        if code:  # the status is unknown here: only a non-zero choice is applied
            flush_all()
            os._exit(code)

    atexit.register(python_exit)

    def c_exit(status: int, _arg: object) -> None:
        code = once(status)
        if code is not None and code != status:
            flush_all()
            os._exit(code)

    def c_exit_unknown(_arg: object) -> None:
        once(None)

    libc = None
    with contextlib.suppress(OSError):
        libc = ctypes.CDLL(None)
    if libc is not None and hasattr(libc, "on_exit"):
        c_callback: Any = ctypes.CFUNCTYPE(None, ctypes.c_int, ctypes.c_void_p)(c_exit)
        libc.on_exit(c_callback, None)
        _keep_alive.append(c_callback)
    elif libc is not None and hasattr(libc, "__cxa_atexit"):  # not glibc: no status, no override
        c_callback = ctypes.CFUNCTYPE(None, ctypes.c_void_p)(c_exit_unknown)
        libc.__cxa_atexit(c_callback, None, None)
        _keep_alive.append(c_callback)
    return once
