"""Tables, plots and BENCHMARKS.md sections of the zoo benchmark (``benchmarks.bench_zoo``).

``summarize`` and ``summarize_ops`` reduce a sweep's runs to cells per (bug, engine) or (bug,
op); ``markdown``, ``controls_markdown`` and ``ops_markdown`` render them; ``plot`` draws the
time-to-detection figure; ``write_markdown`` and ``replace_section`` put a table between its
marks in BENCHMARKS.md. ``benchmarks.bench_zoo`` runs the sweeps.
"""

from __future__ import annotations

import statistics
from collections.abc import Iterable
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from benchmarks.zoo import BY_NAME

if TYPE_CHECKING:
    from benchmarks.bench_zoo import Run

ROOT = Path(__file__).resolve().parents[1]
MARK_BEGIN, MARK_END = "<!-- bench_zoo:begin -->", "<!-- bench_zoo:end -->"


def summarize(runs: list[Run], engines: tuple[str, ...], bugs: tuple[str, ...]) -> dict[str, Any]:
    cells: dict[str, dict[str, Any]] = {}
    for bug in bugs:
        for engine in engines:
            mine = [r for r in runs if r.bug == bug and r.engine == engine]
            if not mine:
                continue
            times = sorted(r.detected_at if r.detected_at is not None else float("inf") for r in mine)
            median = statistics.median(times)
            cells[f"{bug}/{engine}"] = {
                "detected": sum(r.detected_at is not None for r in mine),
                "runs": len(mine),
                "median_ttd": None if median == float("inf") else median,
                "median_signatures": statistics.median(r.signatures for r in mine),
                "median_exec_per_s": statistics.median(r.executions / r.elapsed for r in mine),
                "divergences": sum(r.divergences for r in mine),
                "minutes": sum(r.elapsed for r in mine) / 60.0,
            }
    return cells


def _fmt_ttd(cell: dict[str, Any], budget: float) -> str:
    ttd = "-" if cell["median_ttd"] is None else f"{cell['median_ttd']:.1f}"
    if cell["median_ttd"] is None and cell["detected"]:
        ttd = f">{budget:.0f}"
    return f"{ttd} ({cell['detected']}/{cell['runs']})"


MARGIN, MARGIN_S = 0.10, 0.25


def compare_times(mine: float, other: float) -> str:
    """'faster', 'slower' or 'tie' (not found by either, or within the margins)."""
    if mine == other:
        return "tie"
    if other == float("inf"):
        return "faster"
    if mine == float("inf"):
        return "slower"
    if abs(mine - other) <= max(MARGIN * min(mine, other), MARGIN_S):
        return "tie"
    return "faster" if mine < other else "slower"


def is_config_control(name: str) -> bool:
    return name.startswith("control@")


def buckets_per_bug(result: dict[str, Any], engine: str = "full") -> dict[str, float]:
    """Median unique signatures (buckets) per zoo bug that the engine detected."""
    out = {}
    for bug in result["bugs"]:
        cell = result["cells"].get(f"{bug}/{engine}")
        if cell and not BY_NAME[bug].is_control and cell["detected"]:
            out[bug] = cell["median_signatures"]
    return out


def controls_markdown(result: dict[str, Any]) -> list[str]:
    """The false-positive table: every control run of the full engine."""
    runs = [r for r in result["runs"] if BY_NAME[r["bug"]].is_control and r["engine"] == "full"]
    if not runs:
        return []
    lines = [
        "False positives: the unmodified twin against native (full engine). A control run that reports "
        "any divergence counting as a detection is a false positive.",
        "",
        "| control configuration | op | runs reporting a divergence | divergences per minute |",
        "|---|---|---|---|",
    ]
    for bug in result["bugs"]:
        mine = [r for r in runs if r["bug"] == bug]
        if not mine:
            continue
        minutes = sum(r["elapsed"] for r in mine) / 60.0
        found = sum(r.get("divergences", 0) for r in mine)
        reporting = sum(1 for r in mine if r.get("divergences", 0) or r["detected_at"] is not None)
        rate = found / minutes if minutes else 0.0
        lines.append(f"| {bug} | {BY_NAME[bug].op} | {reporting}/{len(mine)} | {rate:.1f} |")
    minutes = sum(r["elapsed"] for r in runs) / 60.0
    reporting = sum(1 for r in runs if r.get("divergences", 0) or r["detected_at"] is not None)
    total = sum(r.get("divergences", 0) for r in runs)
    lines += [
        "",
        f"False-positive rate: {reporting} of {len(runs)} control runs reported a divergence; "
        f"{total} divergences in {minutes:.1f} min ({total / minutes if minutes else 0.0:.1f} per minute).",
    ]
    return lines


def summarize_ops(runs: list[Run], bugs: tuple[str, ...], ops: tuple[str, ...]) -> dict[str, Any]:
    """Per ``bug/op``: the cells of :func:`summarize` (one engine), keyed by the op run."""
    cells = {}
    for op in ops:
        mine = [replace(r, engine=op) for r in runs if r.op == op]
        for key, cell in summarize(mine, (op,), bugs).items():
            cells[key] = cell
    return cells


def _largest_by_field(runs: Iterable[dict[str, Any]]) -> list[str]:
    """``--op OP kind field: largest difference unit`` over the runs' ``fields``, one per field."""
    largest: dict[tuple[str, str], tuple[float, str]] = {}
    for run in runs:
        for entry in run.get("fields", ()):
            name, _, rest = entry.partition(": ")
            number, _, unit = rest.partition(" ")
            key = (str(run["op"]), name)
            if key not in largest or float(number) > largest[key][0]:
                largest[key] = (float(number), unit)
    return [f"`--op {op}` {name}: {d:.2g} {u}".rstrip() for (op, name), (d, u) in sorted(largest.items())]


def seed_count(result: dict[str, Any]) -> str:
    """The seeds of ``result``: "5 seed(s)", named when they do not start at 1 ("10 seed(s) (11-20)"; a
    result from before ``--first-seed`` holds seeds from 1)."""
    count, first = int(result["seeds"]), int(result.get("first_seed") or 1)
    return f"{count} seed(s)" + (f" ({first}-{first + count - 1})" if first != 1 else "")


def ops_markdown(result: dict[str, Any]) -> str:
    """The table of ``--mode ops``: which op detects each stateful bug."""
    ops, budget, cells = result["ops"], result["budget"], result["cells"]
    lines = [
        "Each stateful zoo bug (`benchmarks/zoo/stateful.py`: it needs a second call on a live group, or "
        "shows only in a trajectory) against native, full engine, under each op: "
        f"{seed_count(result)} x {budget:.0f} s per (bug, op), "
        f"{result['jobs']} runs at a time on {result['cpus']} CPUs. "
        f"Command: `{result['command']}`.",
        "",
        "Median time to first detection in seconds from launch (runs that detected it); `-`: not detected. "
        "Expected: `--op move` (one call on a fresh group) misses every one, `--op scenario` finds them; "
        "the `control@` rows (the unmodified twin) give the false positives of the same campaigns.",
        "",
        "| bug | robot | " + " | ".join(f"`--op {op}`" for op in ops) + " | median buckets (scenario) "
        "| what was found (all runs; kind field: largest difference) |",
        "|---|---|" + "---|" * len(ops) + "---|---|",
    ]
    for bug in result["bugs"]:
        row = [cells.get(f"{bug}/{op}") for op in ops]
        scenario = cells.get(f"{bug}/scenario")
        buckets = f"{scenario['median_signatures']:g}" if scenario and scenario["detected"] else "-"
        cols = " | ".join(_fmt_ttd(c, budget) if c else "" for c in row)
        what = _largest_by_field(r for r in result["runs"] if r["bug"] == bug)
        lines.append(
            f"| {bug} | {Path(BY_NAME[bug].robot).stem} | {cols} | {buckets} | {'; '.join(what) or '-'} |"
        )
    lines.append("")
    bugs = [b for b in result["bugs"] if not BY_NAME[b].is_control]
    for op in ops:
        hit = sum(1 for b in bugs if (cells.get(f"{b}/{op}") or {}).get("detected"))
        lines.append(f"- `--op {op}`: {hit} of {len(bugs)} stateful bugs detected in at least one run.")
    if result.get("load"):
        lines.append(
            f"\nLoad average (1, 5, 15 min) before / after the sweep: {result['load']} "
            f"on {result['cpus']} CPUs "
            "(above the CPU count, other work shared the machine: times to detection are longer than idle)."
        )
    return "\n".join(lines)


def markdown(result: dict[str, Any]) -> str:
    if result.get("ops"):
        return ops_markdown(result)
    engines, budget = result["engines"], result["budget"]
    bugs = [b for b in result["bugs"] if not is_config_control(b)]
    cells = result["cells"]
    lines = [
        f"Mode `{result['mode']}`: {len(bugs)} bugs x {len(engines)} engines x {seed_count(result)}, "
        f"{budget:.0f} s each, {result['jobs']} runs at a time on {result['cpus']} CPUs "
        f"({result['machine']}). Command: `{result['command']}`.",
    ]
    configs = len(result["bugs"]) - len(bugs)
    if not bugs:
        return "\n".join(
            [lines[0].replace("0 bugs", f"{configs} control configurations"), "", *controls_markdown(result)]
        )
    lines += [
        "",
        "Median time to first detection in seconds from launch (startup included), and runs that detected it "
        "(`-`: not detected within the budget by at least half the runs).",
        "",
        "| bug | op | " + " | ".join(engines) + " |",
        "|---|---|" + "---|" * len(engines),
    ]
    verdicts = {e: {"faster": 0, "tie": 0, "slower": 0} for e in engines if e != "full"}
    for bug in bugs:
        row = [cells.get(f"{bug}/{e}") for e in engines]
        op = BY_NAME[bug].op
        lines.append(f"| {bug} | {op} | " + " | ".join(_fmt_ttd(c, budget) if c else "" for c in row) + " |")
        full = cells.get(f"{bug}/full")
        if BY_NAME[bug].is_control or not full:
            continue
        full_t = full["median_ttd"] if full["median_ttd"] is not None else float("inf")
        for e, tally in verdicts.items():
            other = cells.get(f"{bug}/{e}")
            if other is None:  # a bug the baseline has not run (no scenario op): no verdict
                continue
            other_t = other["median_ttd"] if other["median_ttd"] is not None else float("inf")
            tally[compare_times(full_t, other_t)] += 1
    lines += [
        "",
        "The full engine against each baseline over the bugs both ran (faster / tie / slower; "
        f"a difference counts when it is over {MARGIN:.0%} and over {MARGIN_S} s):",
        "",
    ]
    lines += [
        f"- vs {e}, {sum(t.values())} bugs: {t['faster']} faster, {t['tie']} tie, {t['slower']} slower"
        for e, t in verdicts.items()
    ]
    lines.append("")
    lines += [
        "Median unique signatures found within the budget:",
        "",
        "| bug | " + " | ".join(engines) + " |",
        "|---|" + "---|" * len(engines),
    ]
    for bug in bugs:
        row = [cells.get(f"{bug}/{e}") for e in engines]
        lines.append(
            f"| {bug} | " + " | ".join(f"{c['median_signatures']:g}" if c else "" for c in row) + " |"
        )
    lines += [
        "",
        "Throughput (median exec/s over every run of that op):",
        "",
        "| op | " + " | ".join(engines) + " |",
        "|---|" + "---|" * len(engines),
    ]
    for op in ("fk", "move", "ik", "scenario"):
        values = []
        for e in engines:
            rates = [
                c["median_exec_per_s"]
                for k, c in cells.items()
                if k.endswith(f"/{e}") and BY_NAME[k.rsplit("/", 1)[0]].op == op
            ]
            values.append(f"{statistics.median(rates):,.0f}" if rates else "")
        lines.append(f"| {op} | " + " | ".join(values) + " |")
    per_bug = buckets_per_bug(result)
    if per_bug:
        counts = list(per_bug.values())
        worst = max(per_bug, key=lambda b: per_bug[b])
        lines += [
            "",
            f"One bug, one bucket: buckets (unique signatures) per detected zoo bug, full engine: "
            f"median {statistics.median(counts):g}, max {max(counts):g} ({worst}) over {len(counts)} bugs "
            "(goal: median 1, at most 3).",
        ]
    replayed = [r for r in result["runs"] if r.get("replayed")]
    if replayed:
        files = sum(r["replayed"] for r in replayed)
        same = sum(r["replay_same"] for r in replayed)
        lines += [
            "",
            f"Replay fidelity: {same} of {files} crash files ({same / files:.0%}) replayed in a new process "
            "with the same signature.",
        ]
        lines += [f"- not replayed, {r['bug']}: {m}" for r in replayed for m in r["replay_misses"]]
    control_lines = controls_markdown(result)
    if control_lines:
        lines += ["", *control_lines]
    return "\n".join(lines)


def plot(result: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    engines, bugs, budget, cells = result["engines"], result["bugs"], result["budget"], result["cells"]
    bugs = [b for b in bugs if not BY_NAME[b].is_control]
    if not bugs or result.get("ops"):
        return
    fig = Figure(figsize=(10, 0.45 * len(bugs) + 1.8))
    ax = fig.add_subplot()
    height = 0.8 / len(engines)
    for i, engine in enumerate(engines):
        ys, xs = [], []
        for j, bug in enumerate(bugs):
            c = cells.get(f"{bug}/{engine}")
            ttd = c["median_ttd"] if c and c["median_ttd"] is not None else budget * 1.5
            ys.append(j + i * height)
            xs.append(ttd)
        ax.barh(ys, xs, height=height, label=engine)
    ax.axvline(budget, color="black", linestyle="--", linewidth=1)
    ax.set_yticks([j + 0.4 - height / 2 for j in range(len(bugs))], bugs)
    ax.set_xscale("log")
    ax.set_xlabel(
        f"median time to first detection (s, log); bars past the dashed line: not found in {budget:.0f} s"
    )
    ax.invert_yaxis()
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


SECTIONS = {
    "controls": "## False positives (controls, short sweep)",
    "buckets": "## One bug, one bucket, and replay fidelity (short sweep)",
    "ops": "## Which ops detect the stateful bugs",
}


def write_markdown(text: str, path: Path = ROOT / "BENCHMARKS.md", mode: str = "full") -> None:
    """Replace this mode's marked section of BENCHMARKS.md (``full``: the main one; the
    short ``controls`` and ``buckets`` sweeps have sections of their own)."""
    begin, end = MARK_BEGIN, MARK_END
    if mode in SECTIONS:
        begin, end = f"<!-- bench_zoo_{mode}:begin -->", f"<!-- bench_zoo_{mode}:end -->"
    replace_section(text, (begin, end), SECTIONS.get(mode, "## Bug-finding power (the bug zoo)"), path)


def replace_section(
    text: str, marks: tuple[str, str], title: str, path: Path = ROOT / "BENCHMARKS.md"
) -> None:
    """Put ``text`` between the ``marks`` comments of ``path``; append it under ``title`` if absent."""
    begin, end = marks
    content = path.read_text(encoding="utf-8")
    block = f"{begin}\n{text}\n{end}"
    if begin in content:
        head, rest = content.split(begin, 1)
        content = head + block + rest.split(end, 1)[1]
    else:
        content = content.rstrip() + f"\n\n{title}\n\n" + block + "\n"
    path.write_text(content, encoding="utf-8")
