"""The C heap of a scenario campaign: large blocks go back to the system when freed.

A scenario's plans may hold up to 60,001 points (``MAX_TRAJECTORY_DURATION`` at
``TRAJECTORY_DT``), each field of each a float64 array of up to a few MB, on both targets, and
the planners' temporaries are as large. glibc serves a block that large with its own ``mmap``
and unmaps it when it is freed, but its threshold for that is dynamic: each such block freed
raises it to the block's size (up to 32 MiB on 64-bit), so after the first long plan the next
ones come from the heap. There they are freed into holes that the small, long-lived objects an
input leaves behind (a decode-cache entry, a pool entry) keep from going back to the system, and
a campaign's resident memory grows a step at each rare input with a long plan (BENCHMARKS.md,
"Memory"). libFuzzer's ``-rss_limit_mb`` reads the peak, so those steps end a long campaign.

:func:`give_back_large_blocks` fixes the threshold at glibc's default (128 KiB), which also
stops the dynamic rule, as ``MALLOC_MMAP_THRESHOLD_=131072`` in the environment would, for this
process and the children it forks. A scenario campaign calls it; ``fk`` and ``move`` campaigns
levelled off without it, and a batched FK sweep's 1,024 x 4 x 4 float64 temporaries (128 KiB)
would each be a new mapping under it.
"""

from __future__ import annotations

import ctypes

M_MMAP_THRESHOLD = -3
"""``mallopt``'s parameter number for the mmap threshold (glibc's ``malloc.h``)."""
THRESHOLD = 128 * 1024
"""Bytes from which a block gets a mapping of its own: glibc's default, kept fixed."""


def give_back_large_blocks(threshold: int = THRESHOLD) -> bool:
    """Fix glibc's mmap threshold at ``threshold`` bytes for this process: every block at least
    that large is mapped on its own and unmapped when freed.

    Returns
    -------
    bool
        True if glibc took the setting; False where the C library is not glibc (no ``mallopt``)
        or refused it, and nothing changed.
    """
    try:
        mallopt = ctypes.CDLL(None).mallopt  # the C library the interpreter runs on (numpy has ctypes loaded)
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    return bool(mallopt(M_MMAP_THRESHOLD, threshold))
