"""``fuzz_diff.py show FILE...``: a crash or corpus file's test case, printed as JSON.

The file is read as data (at most ``MAX_BYTES`` + 1 bytes, then parsed:
``fuzzer.input.testcase.read_case``); nothing it names is imported or run, and its
sidecar is not read. One file prints its test case (``msg_type``, ``message``,
``origin``, ``lineage``...) as one indented JSON object, ready for ``jq``; several
print one object keyed by path. NaN and infinities print as JSON's usual
extensions (``NaN``, ``Infinity``), as the files store them.

Exit status: 0 when every file is a test case, 2 (with a message naming the
file and the problem) when one is not, or cannot be read.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from fuzzer import reporting
from fuzzer.execution.session import ConfigError
from fuzzer.input.paths import PathError, crash_inputs, given_path
from fuzzer.input.testcase import TestCaseError, read_case


def load(path: Path) -> dict[str, Any]:
    """The test case in ``path`` as its JSON object.

    Raises
    ------
    ConfigError
        Naming the file and the problem (``fuzz_diff.py`` prints it and exits 2).
    """
    try:
        return read_case(path).to_json()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except TestCaseError as exc:
        raise ConfigError(f"{path}: not an RROSFuzz test case: {exc}") from None


def show_main(argv: Sequence[str]) -> int:
    """``fuzz_diff.py show FILE...``."""
    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py show",
        description="print crash or corpus files' test cases as JSON (read as data: nothing is run)",
    )
    parser.add_argument("files", type=given_path, nargs="+", help="crash or corpus files, or folders of them")
    args = parser.parse_args(argv)
    try:
        paths = crash_inputs(args.files)
    except PathError as exc:
        raise ConfigError(str(exc)) from None
    cases = {str(p): load(p) for p in paths}
    shown: Any = next(iter(cases.values())) if len(cases) == 1 else cases
    text = json.dumps(shown, indent=1, ensure_ascii=False)
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:  # a lone surrogate ("\ud800" in the file): JSON's own escape for it
        text = json.dumps(shown, indent=1)
    reporting.out(text)
    return 0
