"""RROSFuzz: differential fuzzing of robot motion software (README.md, docs/engine.md)."""

import os

# A campaign process runs on one core by design (libFuzzer's -jobs / -fork run more processes),
# and nothing in it gains from a multi-threaded BLAS (the batched sweeps' rate is the same).
# OpenBLAS otherwise starts a thread per core when numpy loads; with a second process busy on
# the other core every engine then reaches its first input about 0.06 s later (docs/benchmarks-log.md,
# "One BLAS thread"). Set before numpy is imported; a user's own setting wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
