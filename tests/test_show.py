"""``fuzz_diff.py show FILE``: a crash file's test case as JSON, read as data (issue 11)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from fuzzer.input.testcase import MAX_BYTES, decode
from tests.support import ROOT, fuzz

REGRESSIONS = ROOT / "tests" / "regressions"
CRASH = REGRESSIONS / "crash-364397c4d569c4ab0b32ab7ec9ef57821af1a621"


def test_show_prints_the_test_case_as_json() -> None:
    done = fuzz("show", str(CRASH))
    assert done.returncode == 0, done.stderr
    shown = json.loads(done.stdout)
    assert shown == decode(CRASH.read_bytes()).to_json()
    assert shown["msg_type"] == "sensor_msgs/JointState" and shown["lineage"]


def test_show_of_a_folder_keys_each_case_by_its_path() -> None:
    done = fuzz("show", str(REGRESSIONS))
    assert done.returncode == 0, done.stderr
    shown = json.loads(done.stdout)
    files = sorted(p for p in REGRESSIONS.iterdir() if p.is_file() and p.suffix != ".json")
    assert sorted(shown) == [str(p) for p in files] and len(files) >= 2


def test_show_never_imports_what_a_sidecar_names(tmp_path: Path) -> None:
    crash = tmp_path / CRASH.name
    shutil.copy(CRASH, crash)
    sidecar = json.loads(CRASH.with_name(CRASH.name + ".json").read_text())
    sidecar["config"]["targets"] = ["native", "evil_show_module:api"]
    crash.with_name(crash.name + ".json").write_text(json.dumps(sidecar))
    marker = tmp_path / "imported"
    (tmp_path / "evil_show_module.py").write_text(f"open({str(marker)!r}, 'w').close()\napi = None\n")
    done = fuzz("show", crash.name, cwd=tmp_path, path=[tmp_path])
    assert done.returncode == 0, done.stderr
    assert not marker.exists()
    assert json.loads(done.stdout)["message"]["position"]


def test_show_of_what_is_not_a_test_case_exits_2_naming_the_file(tmp_path: Path) -> None:
    text = tmp_path / "notes.txt"
    text.write_text("hello")
    big = tmp_path / "big"
    big.write_bytes(b" " * (MAX_BYTES + 10))
    wrong = tmp_path / "wrong"
    wrong.write_text('{"rrosfuzz": 99, "msg_type": "x", "message": {}}')
    cases = [
        (text, "not an RROSFuzz test case: not JSON"),
        (big, "larger than"),
        (wrong, "not an RROSFuzz test case (format 1)"),
        (tmp_path / "missing", "no such file"),
        (CRASH.with_name(CRASH.name + ".json"), "only sidecars"),
    ]
    for path, message in cases:
        done = fuzz("show", str(path))
        assert done.returncode == 2 and message in done.stderr and "Traceback" not in done.stderr, (
            path,
            done,
        )
        assert done.stdout == ""


def test_a_file_among_corpus_folders_is_a_usage_error_not_a_campaign(tmp_path: Path) -> None:
    folder = tmp_path / "corpus"
    done = fuzz(str(folder), str(CRASH), "-max_total_time=5")
    assert done.returncode == 2, done
    assert "a file among corpus folders" in done.stderr and "fuzz_diff.py show FILE" in done.stderr
    assert not folder.exists()


def test_a_lone_surrogate_is_shown_as_json_s_escape(tmp_path: Path) -> None:
    # "\ud800" is valid JSON but no UTF-8 text: printing it raised UnicodeEncodeError
    path = tmp_path / "crash-surrogate"
    path.write_text(
        '{"rrosfuzz":1,"msg_type":"sensor_msgs/JointState","sequence":0,"origin":"hypothesis",'
        '"lineage":[],"lineage_length":0,"message":{"name":["\\ud800"],"position":[0.0]}}'
    )
    done = fuzz("show", str(path))
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr[-800:]
    assert "\\ud800" in done.stdout and json.loads(done.stdout)["message"]["name"] == ["\ud800"]
