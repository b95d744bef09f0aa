"""Keeping a sidecar's recorded outcomes small enough to read back.

A scenario records every step's return values on both targets, trajectories
included, and one ``/plan`` at a low acceleration scaling can return tens of
thousands of points (a 600-s trajectory sampled every 10 ms has 60,000). Written
in full, one such step made a 37 MB sidecar, larger than every reader accepts
(:data:`MAX_SIDECAR_BYTES`): replay refused the file and
the campaign counted a ``known_limitation`` as a finding.

:func:`fit_outcomes` keeps the numbers of all recorded outcomes of one sidecar
under :data:`MAX_OUTCOME_NUMBERS`. It shortens the longest series first, all to
one common length (the largest that fits), and leaves everything else exact:

* a trajectory (``trajectory.time_from_start`` with M points and the other
  ``trajectory.*`` vectors of M rows each) keeps that many of its points, spread
  evenly from the first to the last, with whole rows, so the report still plots it;
* any other vector keeps its first entries.

An outcome that was shortened says so in ``shortened`` (a sentence, e.g.
``trajectory: 3000 of 35450 points kept, evenly spaced, first and last included``).
The comparison, the difference and the signature are computed before this and are
not affected; replaying the crash file runs the targets again and has every point.
:func:`encode_sidecar` is what the writers call (:mod:`fuzzer.artifacts.store`); if
a sidecar is still larger than :data:`MAX_SIDECAR_BYTES` (a plug-in target returning
a huge number of values), its outcomes keep their statuses and lose their values.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any, NamedTuple

MAX_SIDECAR_BYTES = 32 * 1024 * 1024
"""The largest sidecar (or manifest) a reader accepts, and so the largest a writer writes."""
MAX_OUTCOME_NUMBERS = 100_000
"""Numbers kept over all recorded outcomes of one sidecar (about 3 MB of indented JSON)."""
TRAJECTORY = "trajectory."
TIME = "trajectory.time_from_start"
NOTE = "shortened"


class Series(NamedTuple):
    """Vectors of one outcome record shortened together."""

    names: tuple[str, ...]
    points: int
    width: int
    """Numbers per point, over all of ``names``."""
    trajectory: bool


def _records(outcomes: list[Any]) -> Iterator[dict[str, Any]]:
    """Every outcome record: each target's outcome and its step outcomes."""
    for outcome in outcomes:
        if not isinstance(outcome, dict):
            continue
        yield outcome
        for step in outcome.get("steps") or ():
            if isinstance(step, dict):
                yield step


def _series(record: dict[str, Any]) -> list[Series]:
    """The record's series. A trajectory whose vectors all hold whole rows for its time
    points is one series; every other vector is a series of its own."""
    values = record.get("values")
    if not isinstance(values, dict):
        return []
    vectors = {k: v for k, v in values.items() if isinstance(v, list)}
    out: list[Series] = []
    time = vectors.get(TIME)
    grouped: set[str] = set()
    if time:
        m = len(time)
        names = tuple(k for k in vectors if k.startswith(TRAJECTORY))
        if all(len(vectors[k]) % m == 0 for k in names):
            out.append(Series(names, m, sum(len(vectors[k]) // m for k in names), True))
            grouped.update(names)
    out.extend(Series((k,), len(v), 1, False) for k, v in vectors.items() if k not in grouped)
    return out


def _cost(series: list[Series], cap: int) -> int:
    return sum(min(s.points, cap) * s.width for s in series)


def _evenly(points: int, keep: int) -> list[int]:
    """``keep`` indices from 0 to ``points - 1``, evenly spaced, both ends included
    (only the last for ``keep == 1``)."""
    if keep == 1:
        return [points - 1]
    return sorted({round(i * (points - 1) / (keep - 1)) for i in range(keep)})


def _shorten(record: dict[str, Any], series: list[Series], cap: int) -> dict[str, Any]:
    values = dict(record["values"])
    notes = []
    for s in series:
        if s.points <= cap:
            continue
        if s.trajectory:
            rows = _evenly(s.points, cap)
            for name in s.names:
                vector = values[name]
                per = len(vector) // s.points
                values[name] = [x for r in rows for x in vector[r * per : (r + 1) * per]]
            notes.append(
                f"trajectory: {len(rows)} of {s.points} points kept, evenly spaced, first and last included"
            )
        else:
            values[s.names[0]] = values[s.names[0]][:cap]
            notes.append(f"{s.names[0]}: first {cap} of {s.points} numbers kept")
    return {**record, "values": values, NOTE: "; ".join(notes)}


def fit_outcomes(outcomes: list[Any], limit: int = MAX_OUTCOME_NUMBERS) -> list[Any]:
    """``outcomes`` (a sidecar's ``outcomes``: JSON records) with at most ``limit`` numbers
    in all, if shortening every series to one point can get there.

    Returns the list itself when it fits, else a copy in which the longest series are
    shortened to one common number of points (see the module's docstring); records
    that were not shortened are the same objects.
    """
    records = list(_records(outcomes))
    series = [_series(r) for r in records]
    longest = max((s.points for group in series for s in group), default=0)
    if sum(_cost(group, longest) for group in series) <= limit:
        return outcomes
    low, high = 1, longest  # the largest cap that fits (1 if none does)
    while low < high:
        mid = (low + high + 1) // 2
        if sum(_cost(group, mid) for group in series) <= limit:
            low = mid
        else:
            high = mid - 1
    done = {
        id(r): _shorten(r, group, low)
        for r, group in zip(records, series, strict=True)
        if any(s.points > low for s in group)
    }
    out: list[Any] = []
    for outcome in outcomes:
        if not isinstance(outcome, dict):
            out.append(outcome)
            continue
        fitted = done.get(id(outcome), outcome)
        steps = outcome.get("steps")
        if isinstance(steps, list):
            fitted = {**fitted, "steps": [done.get(id(s), s) for s in steps]}
        out.append(fitted)
    return out


def _without_values(outcomes: list[Any]) -> list[Any]:
    note = f"values not recorded: the sidecar would be larger than {MAX_SIDECAR_BYTES} bytes"
    out: list[Any] = []
    for outcome in outcomes:
        if not isinstance(outcome, dict):
            out.append(outcome)
            continue
        bare = {**outcome, "values": {}, NOTE: note}
        if isinstance(outcome.get("steps"), list):
            bare["steps"] = [
                {**s, "values": {}, NOTE: note} if isinstance(s, dict) else s for s in outcome["steps"]
            ]
        out.append(bare)
    return out


def _dump(sidecar: dict[str, Any]) -> bytes:
    return json.dumps(sidecar, indent=1, sort_keys=True).encode()


def encode_sidecar(sidecar: dict[str, Any]) -> bytes:
    """The sidecar as written (indented JSON, sorted keys), its outcomes fitted with
    :func:`fit_outcomes`, and without their values if it would still be larger than
    :data:`MAX_SIDECAR_BYTES`."""
    outcomes = sidecar.get("outcomes")
    if not isinstance(outcomes, list):
        return _dump(sidecar)
    fitted = fit_outcomes(outcomes)
    data = _dump(sidecar if fitted is outcomes else {**sidecar, "outcomes": fitted})
    if len(data) > MAX_SIDECAR_BYTES:
        data = _dump({**sidecar, "outcomes": _without_values(outcomes)})
    return data
