"""Line and branch coverage of the Python twin over a corpus (coverage.py).

Each corpus input is mapped onto its call and run on ``python_impl`` only,
under coverage.py with branch measurement; the HTML report shows which parts
of the twin the corpus never reached.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

from fuzzer.execution.session import RunConfig
from fuzzer.input.mapping import MappingError, mapping_for
from fuzzer.input.msgdef import MessageRegistry
from fuzzer.input.testcase import TestCaseError, read_case
from robot_api import robots


@dataclass(frozen=True)
class CoverageTotals:
    inputs: int
    skipped: int
    lines: int
    lines_covered: int
    branches: int
    branches_covered: int
    html: Path

    def line(self) -> str:
        lp = 100.0 * self.lines_covered / max(self.lines, 1)
        bp = 100.0 * self.branches_covered / max(self.branches, 1)
        return (
            f"python_impl coverage over {self.inputs} inputs ({self.skipped} skipped): lines "
            f"{self.lines_covered}/{self.lines} ({lp:.1f}%), branches {self.branches_covered}/"
            f"{self.branches} ({bp:.1f}%); HTML: {self.html / 'index.html'}"
        )


def measure(corpus: list[Path], config: RunConfig, html: Path) -> CoverageTotals:
    """Run every input of ``corpus`` (files or folders) on the twin under coverage."""
    import coverage

    from fuzzer.input.paths import contained
    from fuzzer.reporting import warn

    files = []
    for p in corpus:
        for f in sorted(p.iterdir()) if p.is_dir() else [p]:
            if not f.is_file() or f.name.startswith(".") or f.name.endswith(".json"):
                continue
            if p.is_dir() and f.is_symlink() and not contained(p, f):  # it ran what the link led to
                warn(f"corpus file {f} is a link to a file outside the corpus folder {p}: not read")
                continue
            files.append(f)
    cov = coverage.Coverage(branch=True, source_pkgs=["python_impl"], data_file=None)
    cov.start()
    try:
        from fuzzer.execution.session import ConfigError
        from fuzzer.execution.targets import Runner
        from robot_api.errors import RobotAPIError

        try:
            runner = Runner.create("python", robots.resolve(config.robot), config.tip_link)
        except RobotAPIError as exc:  # a robot that does not load, a tip link not in it
            tip = f", --tip-link {config.tip_link}" if config.tip_link else ""
            raise ConfigError(f"--robot {config.robot}{tip}: {type(exc).__name__}: {exc}") from None
        registry = MessageRegistry(config.msg_path)
        msg_type = config.message_type
        try:
            mapping = mapping_for(config.op, msg_type)
        except MappingError as exc:  # a manifest's or --msg-type's type the op cannot use: a traceback
            raise ConfigError(str(exc)) from None
        run = skipped = 0
        for path in files:
            try:
                case = read_case(path)
                if config.op == "scenario":
                    from fuzzer.scenario.steps import validate as validate_scenario

                    validate_scenario(case.message, registry, config.max_steps)
                else:
                    registry.validate(msg_type, case.message)
            except (OSError, TestCaseError, ValueError):
                skipped += 1
                continue
            runner.run(mapping(case.message))
            run += 1
    finally:
        cov.stop()
    html.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=".tmp-coverage-", dir=html))
    try:  # written aside, then each page renamed into place: a FIFO there blocked coverage.py,
        try:  # and a link there was written through
            cov.html_report(directory=str(staging))
        except OSError as exc:  # a full disk said "No space left on device", naming no folder
            from fuzzer.input.paths import WRITE_FAILURES, FolderUnwritable

            problem = f"--html {html}: cannot write the report: {exc.strerror or exc}"
            raise (FolderUnwritable if exc.errno in WRITE_FAILURES else ConfigError)(problem) from None
        for page in sorted(staging.iterdir()):
            try:
                os.replace(page, html / page.name)
            except OSError as exc:  # a folder under a page's name
                raise ConfigError(f"--html {html}: cannot hold {page.name}: {exc.strerror or exc}") from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "coverage.json"
        cov.json_report(outfile=str(out))
        totals = json.loads(out.read_text())["totals"]
    return CoverageTotals(
        run,
        skipped,
        totals["num_statements"],
        totals["covered_lines"],
        totals["num_branches"],
        totals["covered_branches"],
        html,
    )
