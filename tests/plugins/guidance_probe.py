#!/usr/bin/env python3
"""A branch-free libFuzzer target whose only coverage is fuzzer.selection.guidance.Features.

    guidance_probe.py on|off [libFuzzer flags]

With 'on' every input reports the feature ``crc32(data) % 64``; with 'off'
nothing. libFuzzer's corpus can only grow through the features.
"""

import sys
import zlib

import atheris

from fuzzer.selection.guidance import Features

mode = sys.argv.pop(1)
features = Features(count=1024, enabled=True)


def test_one_input(data: bytes) -> None:
    if mode == "on":
        features.hit(f"probe:{zlib.crc32(data) % 64}")


atheris.Setup(sys.argv, test_one_input)
atheris.Fuzz()
