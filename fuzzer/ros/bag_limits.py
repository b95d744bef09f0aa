"""Bounds on reading a bag: rosbag decompresses a chunk whole, so a chunk that lies about its
size filled the memory (an 8 KB bz2 bag declaring 600 MB took 1.3 GB). While a bag is read,
rosbag's ``bz2.decompress`` and ``roslz4.decompress`` are swapped for ones that stop past a
limit (``fuzzer.ros.bags.MAX_CHUNK_BYTES``)."""

from __future__ import annotations

import bz2
import contextlib
import types
from collections.abc import Iterator
from typing import Any

LZ4_PIECE = 4096
"""Compressed bytes fed to the LZ4 decompressor at a time (each gives at most one block, 1 MiB)."""


class ChunkTooLargeError(Exception):
    """A chunk that decompresses past ``limit``, whatever its header declared."""


def bounded_bz2(data: bytes, limit: int) -> bytes:
    """``bz2.decompress(data)`` (every stream of it), stopping once past ``limit`` bytes.

    Raises
    ------
    ChunkTooLargeError
        More than ``limit`` bytes would come out.
    ValueError, OSError
        As ``bz2.decompress``: data cut short, or not bz2.
    """
    out = bytearray()
    while data:
        stream = bz2.BZ2Decompressor()
        out += stream.decompress(data, max_length=limit + 1 - len(out))
        if len(out) > limit:
            raise ChunkTooLargeError(limit)
        if not stream.eof:
            raise ValueError("compressed data ended before the end-of-stream marker was reached")
        data = stream.unused_data
    return bytes(out)


def bounded_lz4(roslz4: Any, data: bytes, limit: int) -> bytes:
    """``roslz4.decompress(data)``, fed :data:`LZ4_PIECE` bytes at a time, stopping once past
    ``limit`` bytes (:class:`ChunkTooLargeError`)."""
    stream = roslz4.LZ4Decompressor()
    out = bytearray()
    for start in range(0, len(data), LZ4_PIECE):
        out += stream.decompress(data[start : start + LZ4_PIECE])
        if len(out) > limit:
            raise ChunkTooLargeError(limit)
    return bytes(out)


@contextlib.contextmanager
def bounded_chunks(rosbag: Any, limit: int) -> Iterator[None]:
    """While reading: rosbag's ``bz2.decompress`` and ``roslz4.decompress`` (module globals of
    ``rosbag.bag``, looked up at each chunk) replaced by bounded ones, so a chunk that lies
    about its size stops at ``limit`` instead of filling the memory."""
    module = rosbag.bag
    saved = {name: getattr(module, name) for name in ("bz2", "roslz4") if hasattr(module, name)}
    module.bz2 = types.SimpleNamespace(decompress=lambda data: bounded_bz2(data, limit))
    if "roslz4" in saved:
        lz4 = saved["roslz4"]
        module.roslz4 = types.SimpleNamespace(
            decompress=lambda data: bounded_lz4(lz4, data, limit),
            LZ4Compressor=lz4.LZ4Compressor,
            LZ4Decompressor=lz4.LZ4Decompressor,
        )
    try:
        yield
    finally:
        for name, value in saved.items():
            setattr(module, name, value)
