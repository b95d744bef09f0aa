#!/usr/bin/env python3
"""RROSFuzz: differential fuzzing of robot motion software.

    python fuzz_diff.py corpus/ -max_total_time=60      # fuzz the default robot
    python fuzz_diff.py artifacts/crash-<sha1>           # replay one crash file
    python fuzz_diff.py --help

See README.md and docs/engine.md. This file is executable so that libFuzzer's
-fork, -jobs, -merge and -minimize_crash can re-run it.
"""

import sys

from fuzzer.cli import main

if __name__ == "__main__":
    sys.exit(main())
