"""Hostile files and paths: crash files, sidecars, corpus folders and manifests as an attacker
(or a tired user) would hand them over. Each row runs ``fuzz_diff.py`` in a subprocess and checks
the exit status, a message naming the problem, and that no traceback escapes.

Crash files are data: a sidecar naming a module is never imported unless the command line
allows it (rows ``*-import-*`` put a module on ``PYTHONPATH`` whose import writes a marker
file; the marker must not appear).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from tests.support import sidecar_describes

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = str(ROOT / "fuzz_diff.py")
SUITE = ROOT / "tests" / "regressions"
AGREE = SUITE / "crash-364397c4d569c4ab0b32ab7ec9ef57821af1a621"  # move, probot_anno, builtins: agree
TIGHT = "tests.plugins.faults:tight_tolerance"
DIVERGE = SUITE / "minimized-34e1a33bf5c25be1ca333b3736986c6e1f2cc248"  # diverges with native vs TIGHT
MARKER_MODULE = "rrosfuzz_hostile_marker"


def cli(
    *args: str, cwd: Path, extra_path: Path | None = None, timeout: float = 150
) -> subprocess.CompletedProcess[str]:
    path = [str(ROOT)] + ([str(extra_path)] if extra_path else [])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(path))
    return subprocess.run(
        [sys.executable, SCRIPT, *args],
        cwd=cwd,
        env=env,
        text=True,
        capture_output=True,
        timeout=timeout,
        check=False,
    )


def copy_crash(tmp: Path, source: Path = AGREE, edit: Callable[[dict[str, Any]], Any] | None = None) -> Path:
    """A copy of a suite crash file and its sidecar in tmp/art; ``edit`` changes the sidecar."""
    art = tmp / "art"
    art.mkdir(exist_ok=True)
    crash = art / source.name
    shutil.copyfile(source, crash)
    sidecar = json.loads(source.with_name(source.name + ".json").read_text())
    sidecar.pop("regression", None)
    if edit is not None:
        replaced = edit(sidecar)
        if replaced is not None:
            sidecar = replaced
    side = crash.with_name(crash.name + ".json")
    if isinstance(sidecar, bytes):
        side.write_bytes(sidecar)
    else:
        side.write_text(json.dumps(sidecar))
    return crash


def marker_module(tmp: Path) -> Path:
    """A folder with a module whose import writes tmp/MARKER."""
    folder = tmp / "evil"
    folder.mkdir(exist_ok=True)
    (folder / f"{MARKER_MODULE}.py").write_text(
        f"open({str(tmp / 'MARKER')!r}, 'w').write('imported')\nRobotModel = MoveGroup = None\n"
    )
    return folder


@dataclass
class Row:
    """A hostile input: build it, run the CLI, expect a status and a message."""

    args: list[str]
    status: int
    message: str
    extra_path: Path | None = None
    stream: str = "stderr"
    not_imported: Path | None = None
    checks: list[Callable[[subprocess.CompletedProcess[str]], None]] = field(default_factory=list)


def _set(path: str, value: Any) -> Callable[[dict[str, Any]], None]:
    def edit(sidecar: dict[str, Any]) -> None:
        node = sidecar
        *parents, last = path.split(".")
        for name in parents:
            node = node[name]
        node[last] = value

    return edit


def _drop(path: str) -> Callable[[dict[str, Any]], None]:
    def edit(sidecar: dict[str, Any]) -> None:
        node = sidecar
        *parents, last = path.split(".")
        for name in parents:
            node = node[name]
        del node[last]

    return edit


def _both(*edits: Callable[[dict[str, Any]], None]) -> Callable[[dict[str, Any]], None]:
    def edit(sidecar: dict[str, Any]) -> None:
        for one in edits:
            one(sidecar)

    return edit


def _unrunnable(tmp: Path) -> Path:
    """AGREE with its positions made a string (an input the tools skip), its sidecar's sha1 its own."""
    crash = copy_crash(tmp)
    case = json.loads(crash.read_bytes())
    case["message"]["position"] = "not a list"
    crash.write_text(json.dumps(case))
    return sidecar_describes(crash)


def _report_of_another_input(tmp: Path) -> Row:
    """The report said "libFuzzer wrote this file itself" of a file whose sidecar it could not use."""
    art = copy_crash(tmp, edit=lambda _: _sidecar_of(DIVERGE)).parent
    row = Row(["report", str(art), "-o", str(tmp / "out")], 0, "")

    def page_says_why(run: subprocess.CompletedProcess[str]) -> None:
        page = (tmp / "out" / "report.html").read_text()
        assert "its sidecar was not used (damaged sidecar:" in page and "libFuzzer wrote this" not in page

    row.checks.append(page_says_why)
    return row


def _sidecar_of(crash: Path) -> dict[str, Any]:
    sidecar: dict[str, Any] = json.loads(crash.with_name(crash.name + ".json").read_text())
    sidecar.pop("regression", None)
    return sidecar


def sidecar_row(edit: Callable[[dict[str, Any]], Any], message: str) -> Callable[[Path], Row]:
    def build(tmp: Path) -> Row:
        return Row([str(copy_crash(tmp, edit=edit))], 2, message)

    return build


def _folder(path: Path) -> Path:
    path.mkdir()
    return path


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def _link(path: Path, target: Path) -> Path:
    path.symlink_to(target)
    return path


def foreign_target(
    tmp: Path, *extra: str, status: int = 2, message: str = "--trust-sidecar", stream: str = "stderr"
) -> Row:
    crash = copy_crash(tmp, edit=_set("config.targets", ["native", f"{MARKER_MODULE}:impl"]))
    return Row(
        [str(crash), *extra],
        status,
        message,
        extra_path=marker_module(tmp),
        stream=stream,
        not_imported=tmp / "MARKER",
    )


def _many_buckets(tmp: Path) -> Path:
    art = tmp / "art"
    art.mkdir()
    for i in range(1500):  # ~150 kB of triage output: more than a pipe holds
        (art / f"crash-{i:040x}").write_bytes(b"x")
    return art


def _stale_minimize(tmp: Path, crash: Path, *args: str) -> Row:
    """``minimize`` of a crash file that does not reproduce its signature: status 1, no file."""

    def nothing_written(_: subprocess.CompletedProcess[str]) -> None:
        assert sorted(p.name for p in crash.parent.iterdir()) == [crash.name, f"{crash.name}.json"]

    said = "not minimized: (the input does not diverge|it no longer diverges) with its signature"
    return Row(["minimize", str(crash), *args], 1, said, stream="stdout", checks=[nothing_written])


def _manifest_link_out(tmp: Path, link: str, command: str | None = None) -> Row:
    """A corpus whose ``link`` (its manifest's folder or file) is a symlink to a folder outside."""
    victim = tmp / "victim"
    victim.mkdir()
    corpus = tmp / "corpus"
    (corpus / ".rrosfuzz").mkdir(parents=True)
    if link == ".rrosfuzz":
        (corpus / ".rrosfuzz").rmdir()
        (corpus / ".rrosfuzz").symlink_to(victim)
    else:
        (corpus / link).symlink_to(victim / "manifest.json")

    def untouched(_: subprocess.CompletedProcess[str]) -> None:
        assert not list(victim.iterdir()), "a manifest was written outside the corpus"

    args = [command, str(corpus)] if command else [str(corpus), *CAMPAIGN, f"--artifacts={tmp / 'a'}"]
    return Row(args, 2, "leads outside the corpus folder", checks=[untouched])


def _show_folder_with_link_out(tmp: Path) -> Row:
    """``show FOLDER`` with a symlink in it to a test case outside: only the folder's own shown."""
    from fuzzer.input.testcase import TestCase

    folder = tmp / "d"
    folder.mkdir()
    shutil.copyfile(AGREE, folder / AGREE.name)
    outside = tmp / "outside"
    outside.write_bytes(TestCase("std_msgs/Float64MultiArray", {"data": [12345.678]}).encode())
    (folder / "link").symlink_to(outside)

    def not_shown(run: subprocess.CompletedProcess[str]) -> None:
        assert "12345.678" not in run.stdout, "a link out of the folder was read"

    return Row(["show", str(folder)], 0, '"msg_type"', stream="stdout", checks=[not_shown])


def _promote_through_link(tmp: Path) -> Row:
    """``promote`` into a suite where a symlink to a file outside has the crash file's name."""
    crash = copy_crash(tmp)
    victim = tmp / "victim"
    victim.write_text("precious data")
    suite = tmp / "suite"
    suite.mkdir()
    (suite / crash.name).symlink_to(victim)

    def replaced(_: subprocess.CompletedProcess[str]) -> None:
        assert victim.read_text() == "precious data", "promote wrote through the link"
        assert not (suite / crash.name).is_symlink()
        assert (suite / crash.name).read_bytes() == crash.read_bytes()

    args = ["promote", str(crash), "--fixed", "--suite", str(suite)]
    return Row(args, 0, "promoted", stream="stdout", checks=[replaced])


def _minimize_crash_foreign(tmp: Path) -> Row:
    row = foreign_target(tmp)
    row.args = ["-minimize_crash=1", "-runs=10", *row.args]
    return row


def _corpus_with_manifest(tmp: Path, **config: Any) -> Path:
    corpus = tmp / "corpus"
    (corpus / ".rrosfuzz").mkdir(parents=True)
    base = {"op": "move", "robot": "probot_anno", "msg_type": "sensor_msgs/JointState"}
    (corpus / ".rrosfuzz" / "manifest.json").write_text(json.dumps({"config": {**base, **config}}))
    return corpus


IMMUTABLE: list[Path] = []


def _read_only(tmp: Path) -> Path:
    """A folder nobody can write into: mode 555, and as root (whom modes do not stop) chattr +i."""
    folder = tmp / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    if AS_ROOT:
        done = subprocess.run(["chattr", "+i", str(folder)], capture_output=True, check=False)
        if done.returncode != 0:
            pytest.skip("root, and chattr +i is not available here")
        IMMUTABLE.append(folder)
    return folder


@pytest.fixture(autouse=True)
def _mutable_again() -> Any:
    yield
    while IMMUTABLE:
        subprocess.run(["chattr", "-i", str(IMMUTABLE.pop())], capture_output=True, check=False)


def _unreadable(tmp: Path) -> Path:
    folder = tmp / "noread"
    folder.mkdir()
    folder.chmod(0o000)
    return folder


AS_ROOT = hasattr(os, "geteuid") and os.geteuid() == 0
CAMPAIGN = ["-runs=1", "--no-progress"]


ROWS: dict[str, Callable[[Path], Row]] = {
    # -- crash paths ---------------------------------------------------------------------------
    "replay-missing-crash-path": lambda t: Row([str(t / "crash-0123abcd")], 2, "no such file"),
    "minimize-crash-missing-path": lambda t: Row(
        ["-minimize_crash=1", "-runs=10", str(t / "crash-0123abcd"), f"--artifacts={t / 'a'}"],
        2,
        "no such file",
    ),
    "replay-subcommand-missing-path": lambda t: Row(["replay", str(t / "nothing")], 2, "no such file"),
    "replay-fifo": lambda t: Row(["replay", str(_fifo(t / "crash-fifo"))], 2, "FIFO"),
    "replay-only-sidecar": lambda t: Row(["replay", str(copy_crash(t)) + ".json"], 2, "only sidecars"),
    "replay-garbage-crash": lambda t: Row(
        [str(_write(t / "crash-garbage", b"\x00\xff{"))], 0, "not a test case", stream="stdout"
    ),
    "replay-empty-crash": lambda t: Row(
        [str(_write(t / "crash-empty", b""))], 0, "not a test case", stream="stdout"
    ),
    "replay-no-sidecar-says-so": lambda t: Row(
        [str(shutil.copyfile(AGREE, t / "crash-plain"))], 0, "no sidecar"
    ),
    # -- sidecar schema -------------------------------------------------------------------------
    # another input's sidecar beside a crash file: replay said "now agrees" of a file that never
    # diverged, report drew one input's steps beside another's re-run
    "sidecar-of-another-input": sidecar_row(lambda _: _sidecar_of(DIVERGE), "the sidecar of another input"),
    "triage-sidecar-of-another-input": lambda t: Row(
        ["triage", str(copy_crash(t, edit=lambda _: _sidecar_of(DIVERGE)).parent)],
        0,
        "crash without sidecar \\(damaged sidecar: .*the sidecar of another input",
        stream="stdout",
    ),
    "report-sidecar-of-another-input": _report_of_another_input,
    "minimize-sidecar-of-another-input": lambda t: Row(
        ["minimize", str(copy_crash(t, edit=lambda _: _sidecar_of(DIVERGE))), "-o", str(t / "m")],
        2,
        "the sidecar of another input",
    ),
    "promote-sidecar-of-another-input": lambda t: Row(
        ["promote", str(copy_crash(t, edit=lambda _: _sidecar_of(DIVERGE))), "--suite", str(t / "s")],
        1,
        "the sidecar of another input",
        stream="stdout",
    ),
    # an input the tools skip (here: a joint state whose positions are not a list) is not a bug
    # that went away: minimize said "does not diverge ... now" and promote's two answers each
    # pointed at the other flag, the reason left out
    "minimize-skipped-input": lambda t: Row(
        ["minimize", str(_unrunnable(t)), "-o", str(t / "m")],
        1,
        r"not minimized: skipped \(",
        stream="stdout",
    ),
    "promote-skipped-input": lambda t: Row(
        ["promote", str(_unrunnable(t)), "--suite", str(t / "s")],
        1,
        r"skipped \(.*only a test case that runs",
        stream="stdout",
    ),
    "promote-fixed-skipped-input": lambda t: Row(
        ["promote", str(_unrunnable(t)), "--fixed", "--suite", str(t / "s")],
        1,
        r"skipped \(.*only a test case that runs",
        stream="stdout",
    ),
    "sidecar-without-config": sidecar_row(_drop("config"), "'config' is missing"),
    "sidecar-without-signature": sidecar_row(_drop("signature"), "'signature' is missing"),
    "sidecar-config-list": sidecar_row(_set("config", []), "'config' must be an object"),
    "sidecar-signature-string": sidecar_row(_set("signature", "abc"), "'signature' must be an object"),
    "sidecar-op-number": sidecar_row(_set("config.op", 5), "config.op"),
    "sidecar-op-unknown": sidecar_row(_set("config.op", "dance"), "config.op.*dance"),
    "sidecar-one-target": sidecar_row(_set("config.targets", ["native"]), "config.targets"),
    "sidecar-targets-string": sidecar_row(_set("config.targets", "native,python"), "config.targets"),
    "sidecar-targets-numbers": sidecar_row(_set("config.targets", [1, 2]), "config.targets"),
    "sidecar-tolerance-negative": sidecar_row(_set("config.tolerance.m", -1), "config.tolerance.m"),
    "sidecar-tolerance-nan-string": sidecar_row(_set("config.tolerance.rad", "nan"), "config.tolerance.rad"),
    "sidecar-tolerance-number": sidecar_row(_set("config.tolerance", 5), "config.tolerance"),
    "sidecar-robot-number": sidecar_row(_set("config.robot", 7), "config.robot"),
    "sidecar-msg-path-string": sidecar_row(_set("config.msg_path", "/usr"), "config.msg_path"),
    "sidecar-filtering-string": sidecar_row(_set("config.filtering", "no"), "config.filtering"),
    "sidecar-signature-key-number": sidecar_row(_set("signature.key", 5), "signature.key"),
    "sidecar-signature-joints": sidecar_row(_set("signature.joints", {"a": 1}), "signature.joints"),
    "sidecar-lineage-number": sidecar_row(_set("lineage", 5), "'lineage' must be a list"),
    # a damaged call history read as "skipped" with status 0 (in CI: "no longer diverges")
    "sidecar-history-string": sidecar_row(
        _set("history", "abc"), "field 'history': 'history' must be a list"
    ),
    "minimize-sidecar-history-string": lambda t: Row(
        ["minimize", str(copy_crash(t, DIVERGE, edit=_set("history", "abc"))), "--trust-sidecar"],
        2,
        "field 'history'",
    ),
    "sidecar-not-json": sidecar_row(lambda s: b"{not json", "not valid JSON"),
    "sidecar-json-list": sidecar_row(lambda s: b"[1, 2]", "expected an object"),
    "sidecar-not-utf8": sidecar_row(lambda s: b'{"config": "\xff\xfe"}', "not UTF-8"),
    "sidecar-deeply-nested": sidecar_row(lambda s: b"[" * 200000 + b"]" * 200000, "not valid JSON"),
    # (the runs' working directory is the test's folder, the crash file in its art/)
    "sidecar-robot-missing": sidecar_row(_set("config.robot", "nonexistent/robot.urdf"), "neither a shipped"),
    "sidecar-robot-folder": sidecar_row(_set("config.robot", "art"), "not a regular file"),
    "sidecar-robot-fifo": lambda t: Row(
        [str(copy_crash(t, edit=_set("config.robot", str(_fifo(t / "robot.urdf")))))], 2, "not a regular file"
    ),
    # (message folders can matter only for a type the project does not ship: one here)
    "sidecar-msg-path-missing": sidecar_row(
        _both(_set("config.msg_path", ["nonexistent/msgs"]), _set("config.msg_type", "my_msgs/Goal")),
        "is not a folder",
    ),
    # a shipped type: no folder could be read, and one the sidecar names is not looked at (a
    # relative one, recorded as typed, made the file unusable from another working directory)
    "sidecar-msg-path-of-a-shipped-type": lambda t: Row(
        [str(copy_crash(t, edit=_set("config.msg_path", ["nonexistent/msgs", "/usr/share"])))],
        0,
        "agree",
        stream="stdout",
    ),
    # -- nothing is read outside the working directory and the file's folder -----------------------
    "sidecar-robot-device": sidecar_row(_set("config.robot", "/dev/zero"), "'/dev/zero' leads outside"),
    "sidecar-robot-outside": sidecar_row(_set("config.robot", str(ROOT / "README.md")), "leads outside"),
    "sidecar-robot-missing-outside": sidecar_row(
        _set("config.robot", "/nonexistent/robot.urdf"), "leads outside"
    ),
    "sidecar-robot-dot-dot": sidecar_row(_set("config.robot", "../robot.urdf"), "leads outside"),
    "sidecar-robot-symlink-out": lambda t: Row(
        [str(copy_crash(t, edit=_set("config.robot", str(_link(t / "r.urdf", ROOT / "README.md")))))],
        2,
        "r.urdf' leads outside .* \\(symlinks followed\\)",
    ),
    "sidecar-msg-path-outside": sidecar_row(
        _both(_set("config.msg_path", ["/usr/share"]), _set("config.msg_type", "my_msgs/Goal")),
        "msg_path '/usr/share' leads",
    ),
    "sidecar-robot-outside-trusted": lambda t: Row(
        [str(copy_crash(t, edit=_set("config.robot", str(ROOT / "README.md")))), "--trust-sidecar"],
        2,
        "cannot load .*README.md: URDFError",
    ),
    "sidecar-robot-outside-given": lambda t: Row(
        [str(copy_crash(t, edit=_set("config.robot", "/nonexistent/robot.urdf"))), "--robot", "probot_anno"],
        0,
        "agree",
        stream="stdout",
    ),
    "sidecar-symlink-to-fifo": lambda t: Row([str(_sidecar_fifo(t))], 2, "not a regular file"),
    # -- crash files are data: no import of what a sidecar names -----------------------------------
    "replay-import-refused": lambda t: foreign_target(t),
    "replay-subcommand-import-refused": lambda t: _prefixed(foreign_target(t), "replay"),
    "replay-import-overridden-by-targets": lambda t: foreign_target(
        t, "--targets", "native,python", status=0, message="now agrees", stream="stdout"
    ),
    "minimize-import-refused": lambda t: _prefixed(foreign_target(t), "minimize"),
    "promote-import-refused": lambda t: _prefixed(
        foreign_target(t, "--suite", str(t / "suite"), status=1, stream="stdout"), "promote"
    ),
    "minimize-crash-import-refused": _minimize_crash_foreign,
    "report-import-refused": lambda t: _report_foreign(t),
    # -- globs that include sidecars, and pipes ----------------------------------------------------
    "replay-glob-with-sidecars": lambda t: Row(
        ["replay", *_glob(copy_crash(t, DIVERGE)), "--targets", f"native,{TIGHT}"],
        1,
        "still diverges",
        stream="stdout",
    ),
    "minimize-glob-with-sidecars": lambda t: Row(
        ["minimize", *_glob(copy_crash(t, DIVERGE)), "--trust-sidecar", "--budget", "30"],
        0,
        "minimized-34e1a33bf5c25be1ca333b3736986c6e1f2cc248: already minimal",  # read once, sidecar skipped
        stream="stdout",
    ),
    # a file that no longer reproduces its signature: each candidate was measured against it, and a
    # "minimized" file with that signature written for an input that agrees
    "minimize-stale-agrees": lambda t: _stale_minimize(
        t, copy_crash(t, DIVERGE), "--targets", "native,python"
    ),
    "minimize-stale-other-signature": lambda t: _stale_minimize(
        t, copy_crash(t, DIVERGE, edit=_set("signature.key", "0" * 40)), "--trust-sidecar"
    ),
    "minimize-no-sidecar": lambda t: Row(
        ["minimize", str(shutil.copyfile(AGREE, t / "crash-x"))], 2, "no sidecar"
    ),
    "promote-glob-with-sidecars": lambda t: Row(
        ["promote", *_glob(copy_crash(t)), "--fixed", "--suite", str(t / "suite")],
        0,
        "promoted",
        stream="stdout",
    ),
    "triage-glob-with-sidecars": lambda t: Row(
        ["triage", *_glob(copy_crash(t, DIVERGE))], 0, "1 bucket", stream="stdout"
    ),
    # art/* also matches the campaign's logs: they were listed as a bucket "stats.jsonl"
    "triage-glob-with-campaign-logs": lambda t: Row(
        ["triage", *_all(_logs(copy_crash(t, DIVERGE).parent))], 0, r"^1 bucket\(s\)", stream="stdout"
    ),
    "triage-missing-folder": lambda t: Row(["triage", str(t / "nothing")], 2, "no such file"),
    "triage-two-folders": lambda t: Row(
        ["triage", str(copy_crash(t)), str(shutil.copyfile(AGREE, t / "crash-other"))], 2, "several folders"
    ),
    "triage-damaged-sidecar": lambda t: Row(
        ["triage", str(copy_crash(t, edit=_set("config.op", 5)).parent)],
        0,
        "damaged sidecar",
        stream="stdout",
    ),
    "report-damaged-sidecar": lambda t: Row(
        ["report", str(copy_crash(t, edit=lambda s: b"[").parent), "-o", str(t / "out")],
        0,
        "report:",
        stream="stdout",
    ),
    "replay-folder-one-damaged": lambda t: _one_damaged(t),
    # a name with line breaks printed fake verdict lines; one with ESC reached the terminal raw
    "replay-name-with-line-breaks": lambda t: _odd_name(t, "replay"),
    "triage-name-with-line-breaks": lambda t: _odd_name(t, "triage"),
    # view wrote its screenshot over the crash file's sidecar (exit 0), and blocked on a FIFO
    "view-screenshot-over-the-sidecar": lambda t: _view_shot(t, "sidecar", "the crash file's own data"),
    "view-screenshot-fifo": lambda t: _view_shot(t, "fifo", "--screenshot .* is a FIFO, not a regular file"),
    "view-screenshot-folder": lambda t: _view_shot(t, "folder", "--screenshot .* is a folder"),
    "view-screenshot-missing-folder": lambda t: _view_shot(t, "missing", "its folder .* does not exist"),
    "view-fifo-crash": lambda t: Row(
        ["view", str(_fifo(t / "crash-fifo"))], 2, "is a FIFO, not a regular file"
    ),
    "export-bag-fifo-crash": lambda t: Row(
        ["export-bag", str(_fifo(t / "crash-fifo"))], 2, "is a FIFO, not a regular file"
    ),
    "error-naming-a-name-with-escapes": lambda t: Row(
        ["replay", str(t / "crash-gone\x1b[2J")], 2, r"crash-gone\\x1b\[2J: no such file"
    ),
    # a -jobs folder's worker logs were listed, each "skipped (not a test case)" with a warning
    "replay-folder-with-job-logs": lambda t: _with_job_logs(t),
    "replay-sidecar-symlink-loop": lambda t: Row([str(_sidecar_loop(t))], 2, "cannot read the sidecar"),
    "replay-crash-symlink-loop": lambda t: Row(["replay", str(_loop(t / "crash-loop"))], 2, "crash-loop"),
    "minimize-output-is-a-file": lambda t: Row(
        ["minimize", str(copy_crash(t, DIVERGE)), "-o", str(_touch(t / "file"))], 2, "--output .*is a file"
    ),
    "report-output-is-a-file": lambda t: Row(
        ["report", str(copy_crash(t).parent), "-o", str(_touch(t / "file"))], 2, "is a file"
    ),
    # coverage.py opened a FIFO under a page's name (a hang) and wrote through a link there
    "coverage-html-with-fifo-and-link": lambda t: _coverage_into_planted(t),
    "coverage-html-is-a-file": lambda t: Row(
        ["coverage", str(copy_crash(t)), "--html", str(_touch(t / "file"))], 2, "--html .*is a file"
    ),
    "promote-missing-file": lambda t: Row(["promote", str(t / "crash-gone")], 2, "no such file"),
    # a symlink planted under the crash file's name in the suite: copyfile wrote through it
    "promote-through-a-planted-link": lambda t: _promote_through_link(t),
    "show-folder-link-out": lambda t: _show_folder_with_link_out(t),
    # libFuzzer refuses these after start-up with its status 1, which read as "new divergences"
    "artifact-prefix-missing-folder": lambda t: Row(
        [str(t / "c"), *CAMPAIGN, f"-artifact_prefix={t / 'nodir'}/", f"--artifacts={t / 'a'}"],
        2,
        "-artifact_prefix=.*: the folder .*nodir does not exist",
    ),
    "exact-artifact-path-folder": lambda t: Row(
        [str(t / "c"), *CAMPAIGN, f"-exact_artifact_path={t}", f"--artifacts={t / 'a'}"],
        2,
        "-exact_artifact_path=.*: a folder; give a file's path",
    ),
    "seed-inputs-missing-list-file": lambda t: Row(
        [str(t / "c"), *CAMPAIGN, "-seed_inputs=@/nonexistent", f"--artifacts={t / 'a'}"],
        2,
        "-seed_inputs=@/nonexistent: no such file",
    ),
    "merge-control-file-missing-folder": lambda t: Row(
        [
            str(t / "m"),
            str(_folder(t / "c")),
            "-merge=1",
            "-merge_control_file=/nonexistent/ctl",
            f"--artifacts={t / 'a'}",
        ],
        2,
        "-merge_control_file=/nonexistent/ctl: the folder /nonexistent does not exist",
    ),
    # a mistyped folder to merge from was created empty, and nothing merged, without a word
    "merge-from-a-missing-folder": lambda t: Row(
        [str(t / "m"), str(t / "typo"), "-merge=1", f"--artifacts={t / 'a'}"],
        2,
        "corpus .*typo: no such folder \\(a merge reads the folders after the first\\)",
    ),
    "minimize-crash-that-does-not-crash": lambda t: Row(
        [str(copy_crash(t)), "-minimize_crash=1", "-runs=20", f"--artifacts={t / 'a'}"],
        2,
        r"exit status 2 \(libFuzzer stopped with an error",
    ),
    "coverage-html-in-its-corpus": lambda t: Row(
        ["coverage", str(_corpus_with_manifest(t)), "--html", str(t / "corpus" / "html")],
        2,
        "inside the corpus folder",
    ),
    # -- campaign paths ---------------------------------------------------------------------------
    "corpus-under-a-file": lambda t: Row(
        [str(_touch(t / "file") / "corpus"), *CAMPAIGN, f"--artifacts={t / 'a'}"], 2, "is a file"
    ),
    # entries of the artifacts folder the campaign writes: a FIFO blocked it before its first input
    # (past SIGTERM), links had it read, write and delete elsewhere (the special-files probe)
    "artifacts-stats-fifo": lambda t: _artifacts_entry(t, "stats.jsonl", "fifo", r"stats\.jsonl is a FIFO"),
    "artifacts-log-link": lambda t: _artifacts_entry(
        t, "divergences.jsonl", "link", r"divergences\.jsonl is a symbolic link"
    ),
    "artifacts-job-log-fifo": lambda t: _artifacts_entry(t, "fuzz-0.log", "fifo", r"fuzz-0\.log is a FIFO"),
    "artifacts-signatures-link": lambda t: _artifacts_entry(
        t, ".signatures", "folder-link", r"\.signatures is a symbolic link"
    ),
    "artifacts-marker-fifo": lambda t: _artifacts_entry(
        t, ".signatures/8214519f3677", "fifo", r"\.signatures/8214519f3677 is a FIFO"
    ),
    "artifacts-inside-corpus": lambda t: Row(
        [str(_mkdir(t / "c")), *CAMPAIGN, f"--artifacts={t / 'c' / 'art'}"], 2, "inside the corpus folder"
    ),
    "artifacts-equal-corpus": lambda t: Row(
        [str(_mkdir(t / "c")), *CAMPAIGN, f"--artifacts={t / 'c'}"], 2, "inside the corpus folder"
    ),
    "corpus-is-fifo": lambda t: Row([str(_fifo(t / "fifo")), *CAMPAIGN, f"--artifacts={t / 'a'}"], 2, "FIFO"),
    "corpus-is-device": lambda t: Row(["/dev/null", *CAMPAIGN, f"--artifacts={t / 'a'}"], 2, "device"),
    "artifacts-is-a-file": lambda t: Row(
        [str(t / "corpus"), *CAMPAIGN, f"--artifacts={_touch(t / 'file')}"], 2, "artifacts .*is a file"
    ),
    "artifacts-under-a-file": lambda t: Row(
        [str(t / "corpus"), *CAMPAIGN, f"--artifacts={_touch(t / 'file') / 'a'}"], 2, "is a file"
    ),
    # a folder that cannot be written exits 74, as every write that fails (it was 2 here)
    "corpus-read-only": lambda t: Row(
        [str(_read_only(t)), *CAMPAIGN, f"--artifacts={t / 'a'}"], 74, "cannot write"
    ),
    "corpus-unreadable": lambda t: Row(
        [str(_unreadable(t)), *CAMPAIGN, f"--artifacts={t / 'a'}"], 2, "cannot (read|write)"
    ),
    "artifacts-read-only": lambda t: Row(
        [str(t / "corpus"), *CAMPAIGN, f"--artifacts={_read_only(t)}"], 74, "artifacts .*cannot write"
    ),
    # -- corpus manifests -------------------------------------------------------------------------
    "corpus-of-another-op": lambda t: Row(
        [str(_corpus_with_manifest(t)), "--op", "fk", *CAMPAIGN, f"--artifacts={t / 'a'}"],
        2,
        "made for op move, not fk",
    ),
    "corpus-of-another-robot": lambda t: Row(
        [str(_corpus_with_manifest(t)), "--robot", "ur5", *CAMPAIGN, f"--artifacts={t / 'a'}"],
        2,
        "made for robot probot_anno, not ur5",
    ),
    "corpus-of-another-message-type": lambda t: Row(
        [
            str(_corpus_with_manifest(t, msg_type="std_msgs/Float64MultiArray")),
            *CAMPAIGN,
            f"--artifacts={t / 'a'}",
            "--msg-type",
            "sensor_msgs/JointState",
        ],
        2,
        "holds std_msgs/Float64MultiArray inputs",
    ),
    "corpus-manifest-damaged": lambda t: Row(
        [str(_damaged_manifest(t)), *CAMPAIGN, f"--artifacts={t / 'a'}"], 2, "manifest is not valid JSON"
    ),
    "corpus-manifest-bad-robot": lambda t: Row(
        [str(_corpus_with_manifest(t, robot="nonexistent.urdf")), *CAMPAIGN, f"--artifacts={t / 'a'}"],
        2,
        "neither a shipped robot",
    ),
    "corpus-manifest-robot-outside": lambda t: Row(
        [str(_corpus_with_manifest(t, robot=str(ROOT / "README.md"))), *CAMPAIGN, f"--artifacts={t / 'a'}"],
        2,
        "manifest.json: robot .*README.md' leads outside",
    ),
    "corpus-manifest-import-refused": lambda t: _manifest_foreign(t),
    # a .rrosfuzz (or manifest.json) symlink made a campaign read and write a manifest outside
    # prescan said "skipping" a link out of the corpus, and libFuzzer read it as an input
    "corpus-file-link-out": lambda t: Row(
        [str(_corpus_link_out(t)), *CAMPAIGN, f"--artifacts={t / 'a'}"],
        2,
        "a link to a file outside the corpus",
    ),
    "corpus-manifest-folder-link-out": lambda t: _manifest_link_out(t, ".rrosfuzz"),
    "corpus-manifest-file-link-out": lambda t: _manifest_link_out(t, ".rrosfuzz/manifest.json"),
    "coverage-manifest-link-out": lambda t: _manifest_link_out(t, ".rrosfuzz", "coverage"),
    "failed-campaign-records-no-manifest": lambda t: _no_manifest_for_a_bad_robot(t),
    "coverage-of-another-robot": lambda t: Row(
        ["coverage", str(_corpus_with_manifest(t)), "--robot", "ur5", "--html", str(t / "html")],
        2,
        "made for robot",
    ),
}


def _prefixed(row: Row, command: str) -> Row:
    row.args = [command, *row.args]
    return row


def _glob(crash: Path) -> list[str]:
    """What the shell makes of ``art/<prefix>*``: the crash file and its sidecar, sorted."""
    return sorted(str(p) for p in crash.parent.glob(crash.name.split("-")[0] + "-*"))


def _logs(art: Path) -> Path:
    """``art`` with a campaign's two logs in it."""
    (art / "stats.jsonl").write_text('{"execs": 1}\n')
    (art / "divergences.jsonl").write_text('{"sig": "x"}\n')
    return art


def _all(art: Path) -> list[str]:
    """What the shell makes of ``art/*``."""
    return sorted(str(p) for p in art.iterdir())


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _touch(path: Path) -> Path:
    path.write_text("x")
    return path


def _sidecar_fifo(tmp: Path) -> Path:
    crash = tmp / "crash-fifo-sidecar"
    shutil.copyfile(AGREE, crash)
    os.mkfifo(tmp / "fifo")
    (tmp / "crash-fifo-sidecar.json").symlink_to(tmp / "fifo")
    return crash


def _loop(path: Path) -> Path:
    path.symlink_to(path)
    return path


def _sidecar_loop(tmp: Path) -> Path:
    crash = tmp / "crash-sideloop"
    shutil.copyfile(AGREE, crash)
    _loop(tmp / "crash-sideloop.json")
    return crash


def _one_damaged(tmp: Path) -> Row:
    copy_crash(tmp)
    bad = tmp / "art" / "crash-bad"
    shutil.copyfile(AGREE, bad)
    (tmp / "art" / "crash-bad.json").write_text(json.dumps({"config": {"op": 5}, "signature": {"key": "k"}}))
    row = Row(["replay", str(tmp / "art")], 2, "crash-bad.json: field 'config.op'")

    def good_one_still_replayed(run: subprocess.CompletedProcess[str]) -> None:
        assert "now agrees" in run.stdout

    row.checks.append(good_one_still_replayed)
    return row


def _coverage_into_planted(tmp: Path) -> Row:
    html = _mkdir(tmp / "html")
    os.mkfifo(html / "index.html")
    victim = tmp / "victim.txt"
    victim.write_text("keep")
    (html / "class_index.html").symlink_to(victim)
    row = Row(["coverage", str(copy_crash(tmp)), "--html", str(html)], 0, "HTML: ", stream="stdout")

    def pages_written_in_place(run: subprocess.CompletedProcess[str]) -> None:
        assert victim.read_text() == "keep" and (html / "index.html").is_file()
        assert not (html / "class_index.html").is_symlink() and not list(html.glob(".tmp-*"))

    row.checks.append(pages_written_in_place)
    return row


def _corpus_link_out(tmp: Path) -> Path:
    corpus = _mkdir(tmp / "c")
    secret = tmp / "secret.json"
    secret.write_text('{"rrosfuzz": 1, "msg_type": "sensor_msgs/JointState", "message": {}}')
    (corpus / "seed").symlink_to(secret)
    return corpus


def _view_shot(tmp: Path, what: str, says: str) -> Row:
    crash = copy_crash(tmp)
    side = crash.with_name(crash.name + ".json")
    before = side.read_bytes()
    shot = {
        "sidecar": side,
        "fifo": _fifo(tmp / "shot.ppm") if what == "fifo" else tmp / "shot.ppm",
        "folder": tmp,
        "missing": tmp / "no" / "shot.ppm",
    }[what]
    row = Row(["view", str(crash), "--screenshot", str(shot)], 2, says)

    def sidecar_kept(run: subprocess.CompletedProcess[str]) -> None:
        assert side.read_bytes() == before

    row.checks.append(sidecar_kept)
    return row


def _odd_name(tmp: Path, command: str) -> Row:
    crash = copy_crash(tmp)
    odd = crash.with_name(crash.name + "\nfake: now agrees\x1b[31m")
    crash.rename(odd)
    crash.with_name(crash.name + ".json").rename(odd.with_name(odd.name + ".json"))
    target = odd.parent if command == "triage" else odd
    row = Row(
        [command, str(target)],
        0,
        r"\\nfake: now agrees\\x1b\[31m",
        stream="stdout",
    )

    def one_line_each(run: subprocess.CompletedProcess[str]) -> None:
        assert not any(line.startswith("fake") for line in run.stdout.splitlines()), run.stdout
        assert "\x1b" not in run.stdout + run.stderr

    row.checks.append(one_line_each)
    return row


def _mkdir(path: Path) -> Path:
    path.mkdir(parents=True, exist_ok=True)
    return path


def _artifacts_entry(tmp: Path, name: str, what: str, says: str) -> Row:
    art = _mkdir(tmp / "a")
    entry = art / name
    entry.parent.mkdir(exist_ok=True)
    outside = _mkdir(tmp / "outside")
    kept = outside / "empty-user-file"
    kept.touch()
    if what == "fifo":
        os.mkfifo(entry)
    elif what == "link":
        entry.symlink_to(outside / "log.txt")
    else:
        entry.symlink_to(outside)
    row = Row([str(_mkdir(tmp / "c")), *CAMPAIGN, f"--artifacts={art}"], 2, says)

    def nothing_outside_touched(run: subprocess.CompletedProcess[str]) -> None:
        assert sorted(p.name for p in outside.iterdir()) == ["empty-user-file"]

    row.checks.append(nothing_outside_touched)
    return row


def _with_job_logs(tmp: Path) -> Row:
    folder = copy_crash(tmp).parent
    for job in (0, 1, 12):
        (folder / f"fuzz-{job}.log").write_text("INFO: Running with entropic power schedule\n")
    row = Row(["replay", str(folder)], 0, "now agrees", stream="stdout")

    def logs_not_listed(run: subprocess.CompletedProcess[str]) -> None:
        assert "fuzz-" not in run.stdout + run.stderr and "skipped" not in run.stdout

    row.checks.append(logs_not_listed)
    return row


def _damaged_manifest(tmp: Path) -> Path:
    corpus = _corpus_with_manifest(tmp)
    (corpus / ".rrosfuzz" / "manifest.json").write_text("{")
    return corpus


def _no_manifest_for_a_bad_robot(tmp: Path) -> Row:
    row = Row(
        [str(tmp / "c"), "--robot", str(_touch(tmp / "bad.urdf")), *CAMPAIGN, f"--artifacts={tmp / 'a'}"],
        2,
        "--robot|cannot load",
    )

    def nothing_recorded(run: subprocess.CompletedProcess[str]) -> None:
        assert not (tmp / "c" / ".rrosfuzz" / "manifest.json").exists()

    row.checks.append(nothing_recorded)
    return row


def _manifest_foreign(tmp: Path) -> Row:
    corpus = _corpus_with_manifest(tmp, targets=["native", f"{MARKER_MODULE}:impl"])
    return Row(
        [str(corpus), *CAMPAIGN, f"--artifacts={tmp / 'a'}"],
        0,
        "not imported from a file",
        extra_path=marker_module(tmp),
        not_imported=tmp / "MARKER",
    )


def _report_foreign(tmp: Path) -> Row:
    crash = copy_crash(tmp, DIVERGE, _set("config.targets", ["native", f"{MARKER_MODULE}:impl"]))
    row = Row(["report", str(crash.parent), "-o", str(tmp / "out")], 0, "report:", stream="stdout")
    row.extra_path, row.not_imported = marker_module(tmp), tmp / "MARKER"

    def page_says_why(run: subprocess.CompletedProcess[str]) -> None:
        page = (tmp / "out" / "report.html").read_text()
        assert "never imported" in page and "--trust-sidecar" in page

    row.checks.append(page_says_why)
    return row


@pytest.mark.parametrize("name", sorted(ROWS))
def test_hostile_input(name: str, tmp_path: Path) -> None:
    if AS_ROOT and name == "corpus-unreadable":
        pytest.skip("nothing stops root from reading a folder")
    row = ROWS[name](tmp_path)
    run = cli(*row.args, cwd=tmp_path, extra_path=row.extra_path)
    text = run.stderr if row.stream == "stderr" else run.stdout
    assert "Traceback" not in run.stderr, run.stderr[-3000:]
    assert run.returncode == row.status, (run.returncode, run.stdout[-1500:], run.stderr[-1500:])
    assert re.search(row.message, text), (row.message, run.stdout[-1500:], run.stderr[-1500:])
    if row.not_imported is not None:
        assert not row.not_imported.exists(), "a module named by a file was imported"
    for check in row.checks:
        check(run)


def test_the_marker_module_is_imported_when_trusted(tmp_path: Path) -> None:
    """The import rows can fail: with --trust-sidecar the same file does import the module."""
    row = foreign_target(tmp_path, "--trust-sidecar")
    run = cli(*row.args, cwd=tmp_path, extra_path=row.extra_path)
    assert (tmp_path / "MARKER").read_text() == "imported"
    assert run.returncode == 2 and "has no attribute impl" in run.stderr
    assert "Traceback" not in run.stderr


def test_a_target_that_calls_sys_exit_replays_as_a_crash(tmp_path: Path) -> None:
    crash = copy_crash(tmp_path)
    run = cli(str(crash), "--targets", "native,tests.plugins.hostile:exits", cwd=tmp_path)
    assert "Traceback" not in run.stderr
    assert run.returncode == 1, (run.stdout, run.stderr)
    assert "diverges differently" in run.stdout and "crash" in run.stdout


def test_triage_piped_to_head_ends_quietly(tmp_path: Path) -> None:
    art = _many_buckets(tmp_path)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    with subprocess.Popen(
        [sys.executable, SCRIPT, "triage", str(art)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env
    ) as proc:
        assert proc.stdout is not None and proc.stderr is not None
        first = proc.stdout.readline()
        proc.stdout.close()  # like `| head -1`: the reader goes away with most output unwritten
        err = proc.stderr.read().decode()
        status = proc.wait(timeout=120)
    assert b"bucket(s)" in first
    assert "Traceback" not in err and "BrokenPipe" not in err, err[-2000:]
    assert status in (0, 141)


def test_report_never_reads_outside_the_folder(tmp_path: Path) -> None:
    secret = tmp_path / "secret"
    secret.mkdir()
    (secret / "data").write_text("SECRET-TOKEN-1")
    (secret / "side.json").write_text(json.dumps({"config": {}, "signature": {"key": "SECRET-TOKEN-2"}}))
    crash = copy_crash(tmp_path, DIVERGE)
    art = crash.parent
    (art / "crash-aaaa").symlink_to(secret / "data")
    (art / "crash-bbbb").write_bytes(b"x")
    (art / "crash-bbbb.json").symlink_to(secret / "side.json")
    (art / "divergences.jsonl").symlink_to(secret / "data")
    run = cli("report", str(art), "--trust-sidecar", cwd=tmp_path)
    assert run.returncode == 0 and "Traceback" not in run.stderr, run.stderr[-2000:]
    page = (art / "report" / "report.html").read_text()
    assert "SECRET-TOKEN" not in page
    assert "outside" in run.stderr and "lead outside it" in page


def test_report_shows_hostile_strings_as_text(tmp_path: Path) -> None:
    """Mathtext in a lineage or strategy name, HTML in a lineage: drawn and shown as plain text."""
    hostile = ["$\\frac{1}{$", "$x^$", "<script>alert(1)</script>", "$\\undefinedmacro$"]

    def edit(sidecar: dict[str, Any]) -> None:
        sidecar["lineage"] = hostile
        sidecar["testcase"]["lineage"] = hostile

    crash = copy_crash(tmp_path, DIVERGE, edit)
    art = crash.parent
    key = json.loads(crash.with_name(crash.name + ".json").read_text())["signature"]["key"]
    lines = [
        {"sig": key, "kind": "status", "field": "", "strategy": s, "t": 1.0 + i, "pid": 1}
        for i, s in enumerate(hostile)
    ]
    (art / "divergences.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
    run = cli("report", str(art), "--trust-sidecar", cwd=tmp_path)
    assert run.returncode == 0 and "Traceback" not in run.stderr, run.stderr[-3000:]
    page = (art / "report" / "report.html").read_text()
    assert "<script>alert" not in page and "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    assert (art / "report" / "fig6-strategies.png").stat().st_size > 0


IK_KINOVA = SUITE / "crash-71f78e4fcc3be2f3a2216b1111a7d9dd961c70b8"  # op ik on kinova, builtins


def test_settings_travel_with_the_corpus_and_the_crash_file(tmp_path: Path) -> None:
    """A corpus made with --op fk --robot ur5: coverage and -merge need neither option again, and
    -minimize_crash takes op and robot from the crash file's sidecar."""
    made = cli(
        "fk",
        "-runs=1",
        "--op",
        "fk",
        "--robot",
        "ur5",
        "--seeds",
        "4",
        "--no-progress",
        f"--artifacts={tmp_path / 'a'}",
        cwd=tmp_path,
    )
    assert made.returncode == 0, made.stderr[-2000:]
    recorded = json.loads((tmp_path / "fk" / ".rrosfuzz" / "manifest.json").read_text())["config"]
    assert (recorded["op"], recorded["robot"]) == ("fk", "ur5")
    replayed = cli("replay", "fk", cwd=tmp_path)  # corpus inputs have no sidecar: the manifest's settings
    # 4 seeds from Hypothesis and 4 space-filling ones
    assert replayed.returncode == 0 and replayed.stdout.count("replayed under op fk, robot ur5") == 8
    cov = cli("coverage", "fk", "--html", str(tmp_path / "html"), cwd=tmp_path)
    assert cov.returncode == 0 and "over 8 inputs (0 skipped)" in cov.stdout, cov.stderr[-2000:]
    (tmp_path / "merged").mkdir()
    merged = cli("-merge=1", "merged", "fk", "--no-progress", f"--artifacts={tmp_path / 'a'}", cwd=tmp_path)
    assert "Traceback" not in merged.stderr and "--op=fk" in merged.stderr, merged.stderr[-2000:]
    assert (
        json.loads((tmp_path / "merged" / ".rrosfuzz" / "manifest.json").read_text())["config"]["op"] == "fk"
    )
    assert any(p.is_file() for p in (tmp_path / "merged").iterdir())
    shutil.copyfile(IK_KINOVA, tmp_path / IK_KINOVA.name)
    shutil.copyfile(IK_KINOVA.with_name(IK_KINOVA.name + ".json"), tmp_path / (IK_KINOVA.name + ".json"))
    mini = cli(
        "-minimize_crash=1",
        "-runs=5",
        IK_KINOVA.name,
        "--no-progress",
        f"--artifacts={tmp_path / 'a'}",
        cwd=tmp_path,
    )
    assert "Traceback" not in mini.stderr
    assert "--op=ik" in mini.stderr and "--robot=kinova" in mini.stderr, mini.stderr[-2000:]


def test_shipped_corpus_has_the_default_campaigns_manifest() -> None:
    """`make run` (fuzz_diff.py corpus/ -max_total_time=60) must accept the shipped corpus."""
    from fuzzer.artifacts import manifest
    from fuzzer.execution.session import RunConfig

    found = manifest.read(ROOT / "corpus")
    assert found is not None
    assert manifest.check(found, RunConfig()) == []


def test_a_corpus_without_manifest_is_adopted(tmp_path: Path) -> None:
    corpus = tmp_path / "old"
    corpus.mkdir()
    shutil.copyfile(ROOT / "corpus" / "seed-00000-c94dfe6996", corpus / "seed-00000-c94dfe6996")
    run = cli(str(corpus), "-runs=2", "--no-progress", f"--artifacts={tmp_path / 'a'}", cwd=tmp_path)
    assert run.returncode == 0 and "Traceback" not in run.stderr, run.stderr[-2000:]
    assert json.loads((corpus / ".rrosfuzz" / "manifest.json").read_text())["config"]["op"] == "move"


def test_report_refuses_an_output_symlink(tmp_path: Path) -> None:
    art = copy_crash(tmp_path).parent
    (art / "report").symlink_to(tmp_path)
    run = cli("report", str(art), cwd=tmp_path)
    assert run.returncode == 2 and "symbolic link" in run.stderr and "Traceback" not in run.stderr
    assert not (tmp_path / "report.html").exists()
