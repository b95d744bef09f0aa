#!/usr/bin/env python3
"""RROSFuzz: differential fuzzing of robot motion software.

    python fuzz_diff.py corpus/ -max_total_time=60      # fuzz the default robot
    python fuzz_diff.py artifacts/crash-<sha1>           # replay one crash file
    python fuzz_diff.py triage artifacts/                # and minimize, replay, report, promote, coverage
    python fuzz_diff.py --help                           # options, subcommands, exit statuses

A campaign exits 0 without new divergences, 1 with new ones, 2 on usage errors,
74 when a folder cannot be written (a full disk), and with libFuzzer's status for
its crashes (77) and timeouts (70). See README.md and docs/engine.md. This file
is executable so that libFuzzer's -fork, -jobs, -merge and -minimize_crash can
re-run it.
"""

import sys

try:
    from fuzzer.cli import main
except KeyboardInterrupt:  # Ctrl-C while the modules load
    sys.stderr.write("fuzz_diff.py: interrupted\n")
    sys.exit(130)

if __name__ == "__main__":
    sys.exit(main())
