"""benchmarks.probe_mutator: one mutator's children of one tutorial script, counted."""

from __future__ import annotations

import pytest

from benchmarks import probe_mutator


def test_it_counts_the_children_by_lineage_and_the_detections() -> None:
    import atheris

    before = atheris._trace_cmp
    result = probe_mutator.main(["--bug", "profile_switch_band", "--children", "3", "--warm-seeds", "1"])
    assert result["parent"] and sum(result["children"].values()) == 3
    assert set(result["detected"]) <= set(result["children"])
    assert all(len(operand) == 3 for operand in result["operands"])
    assert atheris._trace_cmp is before  # the probe's frozen comparisons do not outlive it


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--bug", "narrow_band"], "not a deep scenario bug"),
        (["--bug", "plan_start_band", "--children", "0"], "at least 1"),
        (["--bug", "plan_start_band", "--parent", "999", "--warm-seeds", "1"], "--parent must be in"),
        (["--bug", "plan_start_band", "--mutator", "nope", "--warm-seeds", "1"], "unknown sequence mutator"),
    ],
)
def test_bad_arguments_are_named(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        probe_mutator.main(argv)
    assert exit_info.value.code == 2 and message in capsys.readouterr().err
