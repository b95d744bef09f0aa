"""Hostile inputs to the tool commands, from a helper's probe (sixty-second session): each row
was a traceback, a read outside the folder pointed at, or a message a file could forge lines
into. Every one now gets a clear error and a documented status."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from fuzzer import reporting
from fuzzer.input.testcase import TestCase
from tests.support import sidecar_describes
from tests.test_hostile_files import AGREE, cli, copy_crash


def _status_of_outcome_0(value: Any) -> Any:
    def edit(sidecar: dict[str, Any]) -> None:
        sidecar["outcomes"][0]["status"] = value

    return edit


def test_an_outcome_status_that_is_a_list_is_a_damaged_sidecar_not_a_traceback(tmp_path: Path) -> None:
    """``status not in {...}`` raised "unhashable type: 'list'" in triage, replay, minimize,
    promote and export-bag: one hostile sidecar ended triage of the whole folder."""
    for value in ([], {}):
        crash = copy_crash(tmp_path, edit=_status_of_outcome_0(value))
        run = cli("replay", str(crash), cwd=tmp_path)
        assert run.returncode == 2 and "'outcomes[0].status' must be a string" in run.stderr, run.stderr[
            -800:
        ]
        run = cli("triage", str(crash.parent), cwd=tmp_path)
        assert run.returncode == 0 and "damaged sidecar" in run.stdout, run.stderr[-800:]
        assert "Traceback" not in run.stderr


def test_report_skips_a_damaged_sidecar_instead_of_ending(tmp_path: Path) -> None:
    """``config.targets`` a number: "'int' object is not iterable" ended the report (exit 1)."""

    def edit(sidecar: dict[str, Any]) -> None:
        sidecar["config"]["targets"] = 5

    crash = copy_crash(tmp_path, edit=edit)
    run = cli("report", str(crash.parent), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert run.returncode == 0 and "Traceback" not in run.stderr, run.stderr[-800:]
    assert (tmp_path / "out" / "report.html").is_file()


def test_replay_does_not_follow_a_sidecar_link_out_of_the_folder(tmp_path: Path) -> None:
    """The link's target (a sidecar naming the builtins) was used in place of the crash file's,
    and a link to /proc/self/environ was opened; triage refused it already."""
    work = tmp_path / "work"
    work.mkdir()
    crash = copy_crash(work)
    outside = tmp_path / "outside.json"
    sidecar = crash.with_name(crash.name + ".json")
    outside.write_text(sidecar.read_text())
    sidecar.unlink()
    sidecar.symlink_to(outside)
    run = cli("replay", str(crash), cwd=work)
    assert run.returncode == 2 and "a link to a file outside" in run.stderr, run.stderr[-800:]
    inside = work / "art" / "kept.json"  # a link within the folder is read as before
    inside.write_text(outside.read_text())
    sidecar.unlink()
    sidecar.symlink_to(inside)
    assert cli("replay", str(crash), cwd=work).returncode == 0


def test_coverage_refuses_what_it_cannot_use_with_a_clear_error(tmp_path: Path) -> None:
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    case = TestCase("sensor_msgs/JointState", json.loads(AGREE.read_text())["message"])
    (corpus / "one").write_bytes(case.encode())
    run = cli("coverage", str(corpus), "--msg-type", "std_msgs/String", "--html", "h1", cwd=tmp_path)
    assert run.returncode == 2 and "cannot use std_msgs/String" in run.stderr, run.stderr[-800:]
    assert "Traceback" not in run.stderr  # it was MappingError's traceback, exit 1
    assert not (tmp_path / "h1").exists(), "a refused run leaves no empty --html folder"
    (tmp_path / "a-file").write_text("x")
    run = cli("coverage", str(corpus), "--html", "a-file/h", cwd=tmp_path)
    assert run.returncode == 2 and "a-file is a file" in run.stderr, run.stderr[-800:]  # it said 74
    (tmp_path / "elsewhere").write_bytes(case.encode())
    (corpus / "link").symlink_to(tmp_path / "elsewhere")
    run = cli("coverage", str(corpus), "--html", "h2", cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-800:]
    assert "is a link to a file outside the corpus folder" in run.stderr
    assert "coverage over 1 inputs" in run.stdout, "the link out of the folder was run"


def test_export_bag_refuses_a_message_not_of_its_type_or_of_no_type_we_fuzz(tmp_path: Path) -> None:
    crash = copy_crash(tmp_path)
    message = json.loads(AGREE.read_text())["message"]
    crash.write_bytes(TestCase("sensor_msgs/JointState", {**message, "header": 5}).encode())
    sidecar_describes(crash)
    run = cli("export-bag", str(crash), "-o", str(tmp_path / "a.bag"), cwd=tmp_path)
    assert run.returncode == 2 and "is not a sensor_msgs/JointState" in run.stderr, run.stderr[-800:]
    assert "Traceback" not in run.stderr  # a header of 5 was an AttributeError's traceback
    crash.write_bytes(TestCase("os/system", message).encode())
    sidecar_describes(crash)
    run = cli("export-bag", str(crash), "-o", str(tmp_path / "b.bag"), cwd=tmp_path)
    assert run.returncode == 2 and "'os/system' is none a campaign fuzzes" in run.stderr, run.stderr[-800:]
    assert not (tmp_path / "b.bag").exists(), "a bag of the sidecar's states alone was written"


def test_minimize_names_the_file_whose_configuration_cannot_be_opened(tmp_path: Path) -> None:
    def edit(sidecar: dict[str, Any]) -> None:
        sidecar["config"]["tip_link"] = "no_such_link"

    crash = copy_crash(tmp_path, edit=edit)
    run = cli("minimize", str(crash), "--budget", "5", cwd=tmp_path)
    assert run.returncode == 2, run.stderr[-800:]
    assert f"{crash}: cannot minimize under the configuration from its sidecar" in run.stderr


def test_a_message_s_line_breaks_indent_and_its_lines_are_bounded() -> None:
    """A file named ``crash-x<newline>FAKE LINE`` printed a line of its own; a sidecar's 2 MB
    robot path made a 2,000,254-byte error line."""
    text = reporting.message("t5/crash-\x1b[31mRED\nfuzz_diff.py: error: forged")
    assert text == "t5/crash-\\x1b[31mRED\n    fuzz_diff.py: error: forged"
    long = reporting.message("robot '" + "x" * 2_000_000 + "' is not a file")
    assert len(long) < 2 * reporting.MESSAGE_LINE_CHARS + 100
    assert long.startswith("robot 'xxx") and long.endswith("' is not a file")
    assert f"({2_000_000 + 22 - reporting.MESSAGE_LINE_CHARS} characters left out)" in long
    many = reporting.message("\n".join(str(i) for i in range(100)))
    assert many.count("\n") == reporting.MESSAGE_LINES - 1 and many.endswith("... (61 more lines)")


def test_a_refused_campaign_leaves_no_configuration_line_in_a_folder_that_was_there(tmp_path: Path) -> None:
    """Its line made every later campaign on other targets warn of "crash files of a campaign on
    another configuration" in a folder that held none."""
    (tmp_path / "art").mkdir()
    run = cli("corpus", "--targets", "native,tests.no_such_module:api", "--artifacts", "art", cwd=tmp_path)
    assert run.returncode == 2 and "cannot import tests.no_such_module" in run.stderr, run.stderr[-800:]
    assert list((tmp_path / "art").iterdir()) == [] and not (tmp_path / "corpus").exists()


def test_a_target_whose_import_calls_exit_is_a_clear_error(tmp_path: Path) -> None:
    """``SystemExit`` from a library's import went past the import check: the command ended with
    the library's status and not a word."""
    modules = tmp_path / "modules"
    modules.mkdir()
    (modules / "quitter.py").write_text("import sys\nsys.exit(3)\n")
    run = cli("corpus", "--targets", "native,quitter:api", "-runs=1", cwd=tmp_path, extra_path=modules)
    assert run.returncode == 2, run.stderr[-800:]
    assert "target 'quitter:api': importing quitter called exit(3)" in run.stderr


def test_help_1_prints_libfuzzer_s_flags_and_does_nothing_else(tmp_path: Path) -> None:
    """``-help=1`` needed a corpus, and with one it wrote seeds, ran the dry run and wrote crash
    files before libFuzzer printed its list."""
    run = cli("-help=1", cwd=tmp_path)
    assert run.returncode == 0 and "Usage:" in run.stderr and "max_len" in run.stderr, run.stderr[-800:]
    run = cli("corpus", "-help=1", "--artifacts", "art", cwd=tmp_path)
    assert run.returncode == 0 and "Usage:" in run.stderr
    assert list(tmp_path.iterdir()) == [], "nothing is written"


def test_malloc_limit_mb_is_said_to_do_nothing(tmp_path: Path) -> None:
    run = cli("corpus", "-malloc_limit_mb=300", "-runs=0", "--artifacts", "art", cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-800:]
    assert "-malloc_limit_mb=300 does nothing here" in run.stderr


def test_a_verdict_line_is_bounded(capsys: Any) -> None:
    """A sidecar's 1.5 MB target name came back whole in "replayed with ... (the campaign's: ...)"."""
    reporting.verdict(
        "crash-x", "now agrees", "replayed with targets a,b (the campaign's: a," + "x" * 100_000 + ")"
    )
    line = capsys.readouterr().out
    assert len(line) < 2 * reporting.MESSAGE_LINE_CHARS + 100 and "characters left out" in line


def test_an_empty_dict_path_is_named_as_empty(tmp_path: Path) -> None:
    run = cli("corpus", "-dict=", "-runs=0", "--artifacts", "art", cwd=tmp_path)
    assert run.returncode == 2 and "-dict=: an empty path" in run.stderr, run.stderr[-800:]  # "is a folder"
