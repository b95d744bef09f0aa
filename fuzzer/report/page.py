"""The report as one self-contained HTML page: inline CSS, images as data: URIs, no script.

Every string that comes from a file (logs, sidecars, file names, messages) goes
through :func:`fuzzer.report.markup.esc` (:func:`html.escape`). The bucket section is
:mod:`fuzzer.report.bucket_section`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from fuzzer.report.arm import ArmView
from fuzzer.report.bucket_section import buckets_section
from fuzzer.report.data import RUN_GAP_SECONDS, ReportData
from fuzzer.report.figures import MAX_RUNS
from fuzzer.report.markup import esc, figure, pct, utc
from fuzzer.report.tables import TABLE_III_RULES, CloserRow, TableRow

CSS = """
body { font-family: "DejaVu Sans", Arial, Helvetica, sans-serif; color: #1d2733; background: #f4f6f9;
       margin: 0; font-size: 15px; line-height: 1.45; }
main { max-width: 1180px; margin: 0 auto; padding: 18px 28px 40px; background: #ffffff; }
h1 { font-size: 26px; margin: 8px 0 2px; }
h2 { font-size: 21px; margin: 34px 0 10px; padding-bottom: 4px; border-bottom: 2px solid #d8dee6; }
h3 { font-size: 17px; margin: 0 0 8px; }
.sub { color: #5a6573; margin: 0 0 14px; }
.cards { display: flex; flex-wrap: wrap; gap: 10px; margin: 12px 0; }
.card { flex: 1 1 150px; background: #eef3fa; border-radius: 6px; padding: 10px 14px; }
.card b { display: block; font-size: 24px; color: #12345a; }
.card span { color: #4a5563; font-size: 13px; }
table { border-collapse: collapse; margin: 8px 0; font-size: 14px; }
th, td { border: 1px solid #cfd6df; padding: 4px 10px; text-align: left; vertical-align: top; }
th { background: #eef1f5; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.total td { font-weight: bold; background: #f7f9fb; }
tr.hot td { background: #fff1e0; }
dl.facts { display: grid; grid-template-columns: max-content auto; gap: 3px 16px; margin: 8px 0; }
dl.facts dt { color: #4a5563; } dl.facts dd { margin: 0; }
.note { color: #3d4752; font-size: 13.5px; background: #f7f9fb; border-left: 3px solid #b8c3cf;
        padding: 6px 12px; margin: 6px 0 12px; }
.warn { background: #fff6e0; border-left: 3px solid #e8a200; padding: 8px 12px; margin: 12px 0; }
.empty { background: #eef3fa; border-left: 3px solid #1f5fbf; padding: 14px; font-size: 16px; }
figure { margin: 10px 0 18px; }
figure img { max-width: 100%; border: 1px solid #e3e7ec; }
figcaption { font-size: 13.5px; color: #3d4752; margin-top: 4px; }
code, pre { font-family: "DejaVu Sans Mono", Consolas, monospace; font-size: 12.5px; }
pre { background: #f3f5f8; padding: 8px 10px; white-space: pre-wrap; word-break: break-all; margin: 4px 0; }
article.bucket { border: 1px solid #d8dee6; border-radius: 6px; padding: 14px 16px; margin: 16px 0; }
.badge { display: inline-block; border-radius: 10px; padding: 1px 9px; font-size: 12.5px; color: #fff;
         margin-right: 6px; }
.k-crash { background: #c00000; } .k-status { background: #6a51a3; } .k-value { background: #1f5fbf; }
.k-representation { background: #e8710a; } .k-other { background: #7f7f7f; }
.cols { display: flex; flex-wrap: wrap; gap: 16px; }
.cols > div { flex: 1 1 460px; min-width: 0; }
nav.toc ol { display: flex; flex-wrap: wrap; gap: 4px 22px; padding-left: 20px; font-size: 14px; }
nav.buckets ol { font-size: 14px; }
.a { color: #1f5fbf; font-weight: bold; } .b { color: #e8710a; font-weight: bold; }
"""


CONTENTS = (
    ("table3", "Table III"),
    ("table4", "Table IV"),
    ("fig6", "Fig. 6"),
    ("fig7", "Fig. 7"),
    ("fig8", "Fig. 8"),
    ("time", "Over time"),
    ("buckets", "Buckets"),
)


# -- sections -----------------------------------------------------------------------------------------


def _summary(data: ReportData, generated: str) -> str:
    s = data.summary
    cards = [
        (f"{s.executions:,}", "executions (all processes)"),
        (f"{s.divergent:,}", "divergent executions"),
        (pct(s.rate), "divergence rate"),
        (f"{s.signatures}", "unique signatures"),
        (f"{s.buckets}", "buckets (distinct problems)"),
    ]
    span = "n/a"
    if s.first is not None and s.last is not None:
        span = f"{utc(s.first)} to {utc(s.last)} ({s.last - s.first:,.1f} s)"
    kinds = ", ".join(f"{esc(k)} {n:,}" for k, n in s.by_kind.items()) or "none"
    facts = [
        ("artifacts folder", f"<code>{esc(data.directory)}</code>"),
        ("robots", esc(", ".join(s.robots) or "n/a")),
        ("operations", esc(", ".join(s.ops) or "n/a")),
        ("targets (a vs b)", esc("; ".join(s.targets) or "n/a")),
        ("tolerance", esc("; ".join(s.tolerances) or "n/a")),
        ("time span", esc(span)),
        ("campaign processes", f"{s.processes}"),
        (
            "inputs not evaluated",
            f"{s.filtered:,} filtered (NaN, inf, |x| &gt; 1e6), {s.malformed:,} malformed",
        ),
        ("divergences by kind", kinds),
    ]
    return (
        "<h1>RROSFuzz differential fuzzing report</h1>"
        f'<p class="sub">Generated {esc(generated)}. Robots, operations, targets and tolerance come from the '
        "crash files' sidecars; counts from the campaign logs.</p>"
        '<div class="cards">'
        + "".join(f"<div class='card'><b>{v}</b><span>{esc(label)}</span></div>" for v, label in cards)
        + '</div><dl class="facts">'
        + "".join(f"<dt>{esc(k)}</dt><dd>{v}</dd>" for k, v in facts)
        + "</dl>"
    )


def _notes(notes: Sequence[str]) -> str:
    if not notes:
        return ""
    return (
        '<div class="warn"><b>About the data</b><ul>'
        + "".join(f"<li>{esc(n)}</li>" for n in notes)
        + "</ul></div>"
    )


def _table_iii(rows: Sequence[TableRow]) -> str:
    body = []
    for i, row in enumerate(rows):
        css = ' class="total"' if row.group == "total" else ""
        first = i == 0 or rows[i - 1].group != row.group
        span = sum(1 for r in rows if r.group == row.group)
        group = (
            "" if not first else f"<td rowspan='{span}'>{esc('' if row.group == 'total' else row.group)}</td>"
        )
        body.append(
            f"<tr{css}>{group}<td>{esc(row.label)}</td><td class='num'>{row.count:,}</td>"
            f"<td class='num'>{pct(row.proportion)}</td><td class='num'>{pct(row.share)}</td></tr>"
        )
    return (
        '<h2 id="table3">Table III: difference statistics</h2>'
        "<table><tr><th>Difference</th><th>Row</th><th class='num'>Numbers</th>"
        "<th class='num'>Proportion of executions</th><th class='num'>Share of divergences</th></tr>"
        + "".join(body)
        + "</table><div class='note'><b>Row rules.</b><ul>"
        + "".join(f"<li>{esc(rule)}</li>" for rule in TABLE_III_RULES)
        + "</ul></div>"
    )


def _table_iv(rows: Sequence[CloserRow]) -> str:
    head = '<h2 id="table4">Table IV: which implementation ends closer to the commanded target</h2>'
    if not rows:
        return head + "<p class='note'>No divergent executions.</p>"
    body = []
    for r in rows:
        n = r.compared
        body.append(
            f"<tr><td><span class='a'>a</span> {esc(r.target_a)}<br>"
            f"<span class='b'>b</span> {esc(r.target_b)}</td>"
            f"<td class='num'>{r.a:,}<br>{pct(r.a / n if n else None)}</td>"
            f"<td class='num'>{r.b:,}<br>{pct(r.b / n if n else None)}</td>"
            f"<td class='num'>{r.tie:,}<br>{pct(r.tie / n if n else None)}</td>"
            f"<td class='num'>{r.excluded:,}</td></tr>"
        )
    excluded = sum(r.excluded for r in rows)
    return (
        head + "<table><tr><th>Targets</th><th class='num'>Closer to a</th><th class='num'>Closer to b</th>"
        "<th class='num'>Tie</th><th class='num'>Excluded (n/a)</th></tr>"
        + "".join(body)
        + "</table><div class='note'>For each divergent <code>move</code> with a full joint command, the "
        "implementation whose final joint values have the smaller sum of |final - commanded| over the "
        "joints, compared as raw numbers (so a continuous joint reported as θ + 2π counts 2π away); "
        "'tie' within 1e-12. Percentages are of the compared executions. "
        f"{excluded:,} divergent execution(s) are excluded (n/a): status or crash divergences, fk, ik, "
        "or commands naming only some joints. Targets are attributed through the crash files' "
        "configurations; lines that cannot be attributed appear as 'target a' / 'target b'.</div>"
    )


def _fig6(data: ReportData, png: bytes | None) -> str:
    return '<h2 id="fig6">Fig. 6: divergences by mutation strategy</h2>' + figure(
        png,
        "Divergences per mutation strategy",
        "Left: divergent executions by the strategy that produced the test case (the last mutator of its "
        "lineage; 'seed' is an unmutated generated seed). Blue: the paper's strategies, grey: RROSFuzz's "
        "other mutators. Right: the same count divided by the evaluated test cases that strategy produced "
        "(filtered inputs not counted), so strategies can be compared fairly.",
        "No divergences and no per-strategy executions recorded.",
    )


def _fig7(data: ReportData, png: bytes | None) -> str:
    nz = data.near_zero
    total = sum(nz.evaluated.values())
    fewer = sum(n for k, n in nz.evaluated.items() if k < 3)
    share = (
        f" {100 * fewer / total:.1f}% of the evaluated test cases have fewer than three joints close to zero "
        "(the paper reports 80%)."
        if total
        else ""
    )
    return '<h2 id="fig7">Fig. 7: test cases by number of joints close to zero</h2>' + figure(
        png,
        "Test cases by joints close to zero",
        f"How many joint values of each evaluated move or fk test case lie within {nz.threshold} rad (or m) "
        f"of zero; blue over all evaluated test cases, orange over the divergent ones (IK test cases have "
        f"no joint values and are not counted).{esc(share)}",
        "No move or fk test case was evaluated.",
    )


def _fig8(data: ReportData, png: bytes | None) -> str:
    d = data.differences
    return '<h2 id="fig8">Fig. 8: difference information</h2>' + figure(
        png,
        "Histogram of log10 differences",
        "Left: the size of each value or representation divergence on a log scale (metres for positions, "
        "radians for angles and revolute joints; a representation difference of 2π shows at 0.8). Dashed "
        "lines: Table III's 1e-2 and 1e-1 limits. Right: divergences without a size in metres or radians: "
        f"a different status or error ({d.status:,}), a crash ({d.crash:,}), other kinds ({d.other:,}), "
        f"value divergences in other units, a duration, a velocity or a count ({d.other_units:,}), "
        f"and value divergences whose difference is zero or not finite ({d.zero + d.nonfinite:,}).",
        "No divergences.",
    )


def _timeline(data: ReportData, png: bytes | None) -> str:
    more = len(data.runs) - MAX_RUNS
    extra = f" Only the latest {MAX_RUNS} of {len(data.runs)} runs are drawn." if more > 0 else ""
    return '<h2 id="time">Executions and divergences over time</h2>' + figure(
        png,
        "Executions and divergences over time",
        "Cumulative executions (left) and divergent executions (right) from stats.jsonl, summed over the "
        "processes of each run and stacked by configuration (the top edge is the total). Processes less than "
        f"{RUN_GAP_SECONDS:.0f} s apart form one run; each run has its own time axis.{esc(extra)}",
        "No stats.jsonl snapshots: executions over time are unknown.",
    )


def render(
    data: ReportData,
    figures: Mapping[str, bytes],
    arms: Mapping[str, ArmView],
    generated: str,
    scenarios: Mapping[str, str] | None = None,
) -> str:
    """The whole page.

    Parameters
    ----------
    data : ReportData
    figures : mapping
        PNG bytes by name: ``fig6``, ``fig7``, ``fig8``, ``timeline`` (a missing one is
        replaced by a note).
    arms : mapping
        The 3D view of each bucket, by bucket key.
    generated : str
        When the page was made (the only non-deterministic text).
    scenarios : mapping, optional
        For scenario buckets, by bucket key: the HTML of their steps and trajectory figures
        (:func:`fuzzer.report.scenario.section`, which escapes what it shows).
    """
    parts = [_summary(data, generated), _notes(data.notes)]
    if data.empty:
        parts.append(
            "<div class='empty'><b>Nothing to show.</b> This folder has no crash files and no campaign logs "
            "(divergences.jsonl, stats.jsonl). Run a campaign with "
            "<code>--artifacts=&lt;this folder&gt;</code> "
            "and build the report again.</div>"
        )
    else:
        parts += [
            "<nav class='toc'><b>Contents</b><ol>"
            + "".join(f"<li><a href='#{anchor}'>{name}</a></li>" for anchor, name in CONTENTS)
            + "</ol></nav>",
            _table_iii(data.table_iii),
            _table_iv(data.table_iv),
            _fig6(data, figures.get("fig6")),
            _fig7(data, figures.get("fig7")),
            _fig8(data, figures.get("fig8")),
            _timeline(data, figures.get("timeline")),
            buckets_section(data, arms, scenarios or {}),
        ]
    title = f"RROSFuzz report: {data.directory.name or data.directory}"
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<title>{esc(title)}</title><style>{CSS}</style></head><body><main>"
        + "".join(parts)
        + "</main></body></html>\n"
    )
