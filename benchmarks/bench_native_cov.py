"""Native-coverage mode against in-process mode, on the same budget (issue 16).

    .venv/bin/python -m benchmarks.bench_native_cov --seeds 5 --budget 20 --write-md

Both modes run the whole engine (``fuzz_diff.py``, structured mutators) on the same
configurations: the control (the unmodified twin) and a few zoo bugs. ``native`` mode
is what ``make fuzz-native`` runs: the clang + ASan build of the C++ target, Atheris'
``asan_with_fuzzer.so`` and the custom-mutator shim preloaded (build it first with
``make native-cov``). Per run: valid executions per second (executions that reached
both targets: not malformed, not filtered), libFuzzer's coverage points at the end
(``cov:``, which in native mode include the C++ edges), the share of malformed
inputs, and the time to first detection. Modes are compared per configuration with
Mann-Whitney U and Vargha-Delaney A12 (``scipy.stats``), as FuzzBench does.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from scipy.stats import mannwhitneyu

from benchmarks import cli
from benchmarks.bench_zoo import command
from benchmarks.trials import NOT_DETECTIONS
from benchmarks.zoo import BY_NAME, CONTROL
from benchmarks.zoo_tables import replace_section
from fuzzer.artifacts.divlog import DIVERGENCES, STATS, read_lines

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
MODES = ("inprocess", "native")
CONFIGS = (CONTROL.name, "silent_clamp", "wrap_positive", "off_by_tolerance")
COV = re.compile(r"cov: (\d+) ft: (\d+)")
MARKS = ("<!-- bench_native_cov:begin -->", "<!-- bench_native_cov:end -->")


@dataclass(frozen=True)
class Run:
    config: str
    mode: str
    seed: int
    valid_per_s: float
    execs: int
    malformed: int
    cov: int
    ft: int
    detected_at: float | None
    mutators: int


def native_env() -> dict[str, str]:
    """The environment `make fuzz-native` gives its campaign."""
    import atheris  # only where the benchmark runs

    build = ROOT / "build" / "coverage"
    modules = sorted(build.glob("_native*.so"))
    shim = build / "librrosfuzz_mutator_shim.so"
    if not modules or not shim.is_file():
        raise SystemExit("bench_native_cov: build the coverage flavour first: make native-cov")
    preload = f"{Path(atheris.path()) / 'asan_with_fuzzer.so'} {shim}"
    return {
        "LD_PRELOAD": preload,
        "ASAN_OPTIONS": "detect_leaks=0",
        "RROSFUZZ_NATIVE_MODULE": str(modules[0]),
    }


def run_one(config: str, mode: str, seed: int, budget: float) -> Run:
    bug = BY_NAME[config]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    if mode == "native":
        env.update(native_env())
    with tempfile.TemporaryDirectory(prefix="rrosfuzz-ncov-") as tmp:
        workdir = Path(tmp)
        started = time.time()
        done = subprocess.run(
            [*command(bug, "full", seed, budget, workdir), "--verbose"],  # libFuzzer's cov: lines
            cwd=ROOT,
            env=env,
            capture_output=True,
            text=True,
            timeout=budget + 180,
            check=False,
        )
        artifacts = workdir / "artifacts"
        hits = [r for r in read_lines(artifacts / DIVERGENCES) if r.get("kind") not in NOT_DETECTIONS]
        stats = list(read_lines(artifacts / STATS))
    last = stats[-1] if stats else {}
    execs, malformed = int(last.get("execs", 0)), int(last.get("malformed", 0))
    valid = execs - malformed - int(last.get("filtered", 0))
    elapsed = float(last.get("elapsed", budget)) or budget
    found = COV.findall(done.stderr + done.stdout)
    cov, ft = (int(found[-1][0]), int(found[-1][1])) if found else (0, 0)
    return Run(
        config,
        mode,
        seed,
        valid / elapsed,
        execs,
        malformed,
        cov,
        ft,
        min((float(r["t"]) - started for r in hits), default=None),
        len(last.get("executed_by_strategy", {})),
    )


def a12(xs: list[float], ys: list[float]) -> float:
    """Vargha-Delaney A12: probability that a value of xs exceeds one of ys (ties count half)."""
    wins = sum((x > y) + 0.5 * (x == y) for x in xs for y in ys)
    return wins / (len(xs) * len(ys))


def _test(xs: list[float], ys: list[float]) -> tuple[float, float]:
    if len(set(xs) | set(ys)) <= 1:
        return 1.0, 0.5
    return float(mannwhitneyu(xs, ys, alternative="two-sided").pvalue), a12(xs, ys)


def markdown(runs: list[Run], seeds: int, budget: float, cmd: str) -> str:
    lines = [
        f"{seeds} seeds x {budget:.0f} s per configuration and mode, one run at a time on "
        f"{os.cpu_count()} CPUs ({platform.machine()}, Python {platform.python_version()}). "
        f"Command: `{cmd}`. Medians; p: Mann-Whitney U (two-sided), A12: Vargha-Delaney "
        "(native over in-process; 0.5 = no difference).",
        "",
        "| configuration | valid exec/s in-process | valid exec/s native | p | A12 "
        "| cov in-process | cov native | p | A12 | malformed native "
        "| detected in-process | detected native |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for config in CONFIGS:
        by = {m: [r for r in runs if r.config == config and r.mode == m] for m in MODES}
        if not all(by.values()):
            continue
        speed = {m: [r.valid_per_s for r in by[m]] for m in MODES}
        cov = {m: [float(r.cov) for r in by[m]] for m in MODES}
        p_s, a_s = _test(speed["native"], speed["inprocess"])
        p_c, a_c = _test(cov["native"], cov["inprocess"])
        bad = statistics.median(r.malformed / max(r.execs, 1) for r in by["native"])

        def det(rs: list[Run]) -> str:
            ts = [r.detected_at for r in rs if r.detected_at is not None]
            return f"{len(ts)}/{len(rs)}" + (f", median {statistics.median(ts):.1f} s" if ts else "")

        lines.append(
            f"| {config} | {statistics.median(speed['inprocess']):,.0f} "
            f"| {statistics.median(speed['native']):,.0f} "
            f"| {p_s:.3g} | {a_s:.2f} | {statistics.median(cov['inprocess']):.0f} "
            f"| {statistics.median(cov['native']):.0f} | {p_c:.3g} | {a_c:.2f} | {bad:.1%} "
            f"| {det(by['inprocess'])} | {det(by['native'])} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--budget", type=float, default=20.0)
    parser.add_argument("--configs", default=",".join(CONFIGS))
    parser.add_argument("--write-md", action="store_true")
    args = parser.parse_args(argv)
    cli.check_sizes(parser, seeds=args.seeds)
    cli.check_campaign_seconds(parser, budget=args.budget)
    configs = [c for c in args.configs.split(",") if c]
    unknown = [c for c in configs if c not in CONFIGS]
    if unknown or not configs:  # the table has a row for each of CONFIGS only
        parser.error(
            f"--configs: unknown configuration(s) {', '.join(unknown) or '(none given)'}; "
            f"known: {', '.join(CONFIGS)}"
        )
    cli.check_unique(parser, configs=configs)
    native_env()  # fail early when the coverage build is missing
    runs: list[Run] = []
    for seed in range(args.seeds):
        for config in configs:
            for mode in MODES:
                run = run_one(config, mode, seed, args.budget)
                print(json.dumps(asdict(run)), flush=True)
                runs.append(run)
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "native-cov.json").write_text(json.dumps([asdict(r) for r in runs], indent=1))
    cmd = "python -m benchmarks.bench_native_cov " + " ".join(argv if argv is not None else sys.argv[1:])
    text = markdown(runs, args.seeds, args.budget, cmd.strip())
    print(text)
    if args.write_md:
        replace_section(text, MARKS, "## Native-coverage mode against in-process mode")


if __name__ == "__main__":
    main()
