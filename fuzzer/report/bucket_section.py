"""The report page's bucket section: one article per bucket, most severe first, with its
signature, outcomes, joints, lineage, replay commands, 3D view and test case.

Every string that comes from a file (sidecars, file names, messages) goes through
:func:`fuzzer.report.markup.esc`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from fuzzer.report.arm import ArmView
from fuzzer.report.buckets import BucketView
from fuzzer.report.data import ReportData, config_label, tolerance_label
from fuzzer.report.markup import esc, img, kind_class, num


def _vector(values: Sequence[float]) -> str:
    return "(" + ", ".join(num(v) for v in values) + ")"


def _outcomes(view: BucketView) -> str:
    rows = []
    for side, o in zip("ab", view.outcomes, strict=False):
        values = "<br>".join(f"{esc(k)} = {esc(_vector(v))}" for k, v in sorted(o.values.items())) or "-"
        message = f"<br><small>{esc(o.message)}</small>" if o.message else ""
        rows.append(
            f"<tr><td><span class='{side}'>{side}</span> {esc(o.target)}</td><td>{esc(o.label)}{message}</td>"
            f"<td><code>{values}</code></td></tr>"
        )
    return (
        "<table><tr><th>Target</th><th>Outcome</th><th>Values (m, rad, quaternion x y z w)</th></tr>"
        + "".join(rows)
        + "</table>"
    )


def _command(view: BucketView) -> list[float] | None:
    call = view.call or {}
    positions, names = call.get("positions"), call.get("names")
    if call.get("kind") != "MoveCall" or not isinstance(positions, list):
        return None
    if names is None and len(positions) == len(view.joint_names):
        return [float(x) for x in positions]
    if (
        isinstance(names, list)
        and sorted(map(str, names)) == sorted(view.joint_names)
        and len(names) == len(positions)
    ):
        given = dict(zip(map(str, names), positions, strict=True))
        return [float(given[n]) for n in view.joint_names]
    return None


def _joints(view: BucketView) -> str:
    finals = [o.values.get("joint_values") for o in view.outcomes]
    command = _command(view)
    if not view.joint_names or (not any(finals) and command is None):
        return ""
    differing = set((view.signature or {}).get("joints") or [])
    head = "<tr><th>Joint</th>" + ("<th class='num'>commanded</th>" if command else "")
    head += "".join(f"<th class='num'><span class='{s}'>{s}</span> final</th>" for s in "ab")
    head += "<th class='num'>|a - b|</th></tr>"
    rows = []
    for i, name in enumerate(view.joint_names):
        cells = [f"<td>{esc(name)}</td>"]
        if command:
            cells.append(f"<td class='num'>{num(command[i])}</td>")
        got = [f[i] if f and i < len(f) else None for f in [*finals, None, None][:2]]
        cells += [f"<td class='num'>{'-' if v is None else num(v)}</td>" for v in got]
        delta = abs(got[0] - got[1]) if got[0] is not None and got[1] is not None else None
        cells.append(f"<td class='num'>{'-' if delta is None else num(delta)}</td>")
        css = " class='hot'" if i in differing else ""
        rows.append(f"<tr{css}>{''.join(cells)}</tr>")
    return (
        "<table>" + head + "".join(rows) + "</table><p class='note'>Joint values in rad (m for prismatic "
        "joints), as the sidecar recorded them; highlighted rows are the joints the signature names.</p>"
    )


def _subcommand(replay: str, command: str) -> str:
    """The replay command line turned into another subcommand on the same file (``view`` and
    ``export-bag`` draw from the sidecar's outcomes and take no ``--targets``)."""
    return replay.split(" --targets ", 1)[0].replace(" fuzz_diff.py ", f" fuzz_diff.py {command} ", 1)


def _bucket(index: int, view: BucketView, arm: ArmView | None, steps: str = "") -> str:
    badge = f"<span class='badge {kind_class(view.kind)}'>{esc(view.kind)}</span>"
    title = (
        f"<h3 id='bucket-{esc(view.key)}'>{index}. {badge}<code>{esc(view.key)}</code> "
        f"{esc(view.description)}</h3>"
    )
    files = f"<code>{esc(view.representative)}</code>"
    if view.minimized:
        files += f"<br>minimized: <code>{esc(view.minimized)}</code>"
    if not view.has_sidecar:
        if view.note:  # a sidecar beside it that could not be used (damaged, another input's...)
            why = f"its sidecar was not used ({esc(view.note)})"
            said = "<p>Replay names what is wrong with the sidecar. "
        else:
            why = "there is no sidecar to record them"
            said = "<p>libFuzzer wrote this file itself: a target died (native crash) or hung (timeout). "
        return (
            f"<article class='bucket'>{title}<dl class='facts'>"
            f"<dt>file</dt><dd>{files} ({view.size:,} bytes)</dd>"
            f"<dt>replay</dt><dd><code>{esc(view.replay)}</code> plus the campaign's options (--robot, --op, "
            f"--targets): {why}.</dd></dl>"
            f"{said}First bytes:</p><pre>{esc(view.preview) or '(empty)'}</pre></article>"
        )
    sig = view.signature or {}
    sig_rows = "".join(
        f"<tr><th>{esc(k)}</th><td>{esc(sig.get(k))}</td></tr>"
        for k in ("op", "kind", "field", "outcome_a", "outcome_b", "joint_types", "target")
    )
    lineage = " → ".join(esc(s) for s in view.lineage) or "(none: a generated seed)"
    if view.lineage_length > len(view.lineage):
        lineage = f"... ({view.lineage_length - len(view.lineage)} earlier) → " + lineage
    facts = [
        ("divergent executions", f"{view.count:,}"),
        ("configuration", esc(config_label(view.config))),
        ("tolerance", esc(tolerance_label(view.config or {}))),
        ("difference", "n/a" if view.difference is None else esc(f"{num(view.difference)} {view.unit}")),
        ("files", files),
        ("replay", f"<code>{esc(view.replay)}</code>"),
        ("in RViz", f"<code>{esc(_subcommand(view.replay, 'view'))}</code>"),
        ("as a bag", f"<code>{esc(_subcommand(view.replay, 'export-bag'))}</code>"),
        ("lineage", f"seed #{esc(view.sequence)} ({esc(view.origin)}) → {lineage}"),
        ("written", esc(view.written)),
    ]
    if arm is None:
        picture = ""
    else:
        notes = "".join(f"<li>{esc(n)}</li>" for n in arm.notes if n)
        if arm.png is not None:
            picture = (
                f"<figure>{img(arm.png, 'arm of both targets for ' + view.key)}"
                "<figcaption>Where each target "
                "leaves the arm after re-running this test case (links of each target's own model, root to "
                "tip; diamonds mark the last link). Identical arms overlap: solid a, dashed b."
                f"<ul>{notes}</ul></figcaption></figure>"
            )
        else:
            picture = f"<div class='warn'><b>No 3D view.</b><ul>{notes}</ul></div>"
    return (
        f"<article class='bucket'>{title}<div class='cols'><div>"
        "<dl class='facts'>" + "".join(f"<dt>{esc(k)}</dt><dd>{v}</dd>" for k, v in facts) + "</dl>"
        f"<table>{sig_rows}</table></div><div>{picture}</div></div>"
        f"<h3>Outcomes</h3>{_outcomes(view)}{_joints(view)}{steps}"
        f"<h3>Test case <small>({esc(view.msg_type)})</small></h3><pre>{esc(view.message)}</pre></article>"
    )


def buckets_section(data: ReportData, arms: Mapping[str, ArmView], scenarios: Mapping[str, str]) -> str:
    head = f'<h2 id="buckets">Buckets: {len(data.views)} distinct problem(s), most severe first</h2>'
    if not data.views:
        return head + "<p class='note'>No crash files in this folder: nothing to triage.</p>"
    index = (
        "<nav class='buckets'><ol>"
        + "".join(
            f"<li><a href='#bucket-{esc(v.key)}'>{esc(v.kind)} x{v.count:,}: {esc(v.description)}</a></li>"
            for v in data.views
        )
        + "</ol></nav>"
    )
    return (
        head
        + index
        + "".join(
            _bucket(i, v, arms.get(v.key), scenarios.get(v.key, "")) for i, v in enumerate(data.views, 1)
        )
    )
