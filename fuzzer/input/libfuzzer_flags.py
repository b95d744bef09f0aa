"""libFuzzer's own options, checked before a campaign hands them over: what libFuzzer or Atheris
would otherwise take in silently, crash on, or refuse only after start-up with an exit status the
campaign's summary cannot tell from its own; and the argv it hands over (``libfuzzer_argv``)."""

from __future__ import annotations

import contextlib
import os
import shlex
import string
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from fuzzer.processes import CHILD_ENV, absolute_flag, absolute_option, flag_value, int_flag, one_campaign

if TYPE_CHECKING:
    from fuzzer.campaign import CampaignOptions

DEFAULT_FLAGS = {"-max_len": "16384", "-timeout": "20"}
"""libFuzzer flags a campaign sets unless given: inputs up to 16 KiB (a scenario's: room for its
steps, :func:`default_max_len`), a 20-s timeout."""

SCENARIO_STEP_BYTES = 1024
"""Room per step in a scenario campaign's default ``-max_len``. At ``--max-steps 256`` on the
default robot the Hypothesis seeds took up to 407 bytes a step (31,677 in all) and the uniform
scripts 162 (37,004): 20 of 32 seeds were longer than 16 KiB, and libFuzzer, given
``-max_len=16384``, cut them short into malformed inputs, unrun and unsaid."""


def default_max_len(op: str, max_steps: int) -> int:
    """The ``-max_len`` a campaign sets unless given (bytes): 16 KiB, or for ``--op scenario``
    :data:`SCENARIO_STEP_BYTES` a step if that is more, at most a test case's ``MAX_BYTES``."""
    from fuzzer.input.testcase import MAX_BYTES

    base = int(DEFAULT_FLAGS["-max_len"])
    return max(base, min(MAX_BYTES, SCENARIO_STEP_BYTES * max_steps)) if op == "scenario" else base


INT_FLAGS: dict[str, tuple[int, int]] = {
    **dict.fromkeys(
        (
            "-max_len", "-len_control", "-timeout", "-max_total_time", "-fork", "-jobs", "-workers",
            "-rss_limit_mb", "-malloc_limit_mb", "-verbosity", "-print_final_stats", "-use_value_profile",
            "-minimize_crash", "-shrink", "-reduce_inputs", "-close_fd_mask", "-report_slow_units",
            "-prefer_small", "-only_ascii", "-use_counters", "-cross_over", "-detect_leaks", "-entropic",
            "-keep_seed", "-reload", "-error_exitcode", "-timeout_exitcode", "-ignore_crashes",
            "-use_cmp", "-print_pcs", "-print_corpus_stats", "-use_memmem",
        ),
        (0, 2**31 - 1),
    ),
    "-seed": (0, 2**32 - 1),  # an unsigned int; 0 draws one
    "-runs": (-1, 2**31 - 1),  # -1: no limit; an int in libFuzzer (2**32 became 0 runs, silently)
    "-mutate_depth": (1, 2**31 - 1),
}  # fmt: skip
"""libFuzzer's integer flags that a campaign checks before handing them over, with their ranges.
libFuzzer reads them with ``atoi``-like parsing (``-jobs=abc`` is 0) and Atheris some with
``std::stoul`` (``-seed=abc`` raised from ``atheris.Fuzz`` and then crashed the interpreter);
``-jobs=-1`` started jobs without end and ``-max_len=-1`` was ``std::bad_alloc``."""


def check_int_flags(flags: tuple[str, ...]) -> None:
    """Raise ValueError naming the first flag of :data:`INT_FLAGS` among ``flags`` whose value is
    not a decimal integer in its range."""
    for flag in flags:
        name, sep, value = flag.partition("=")
        if name not in INT_FLAGS:
            continue
        low, high = INT_FLAGS[name]
        digits = value[1:] if value.startswith("-") else value
        if (
            not sep
            or not (digits.isascii() and digits.isdecimal())
            or len(digits) > 20
            or not low <= int(value) <= high
        ):
            raise ValueError(f"{flag}: libFuzzer's {name} takes an integer from {low} to {high}")


MAX_DICTIONARY_BYTES = 16 << 20
"""The largest ``-dict`` file read for the check (libFuzzer reads a file of any size)."""


def dictionary_entry_ok(line: bytes) -> bool:
    """Whether libFuzzer's ``ParseOneDictionaryEntry`` accepts ``line`` (``name="value"`` or
    ``"value"``; inside the quotes printable bytes or spaces, and the escapes ``\\\\``, ``\\"``
    and ``\\xAB``)."""
    text = line.strip(_SPACE)
    if len(text) < 3 or not text.endswith(b'"'):
        return False
    opening = text.find(b'"')
    if opening >= len(text) - 2:  # the value between the quotes may not be empty
        return False
    body, pos = text[opening + 1 : -1], 0
    while pos < len(body):
        byte = body[pos]
        if byte not in _PRINTABLE:
            return False
        if byte == 0x5C:  # a backslash
            if body[pos + 1 : pos + 2] in (b"\\", b'"'):
                pos += 2
                continue
            if (
                body[pos + 1 : pos + 2] == b"x"
                and len(body[pos + 2 : pos + 4]) == 2
                and all(c in _HEX for c in body[pos + 2 : pos + 4])
            ):
                pos += 4
                continue
            return False
        pos += 1
    return True


_SPACE = b" \t\n\v\f\r"
_PRINTABLE = frozenset(string.printable.encode("ascii"))  # C's isprint or isspace, in ASCII
_HEX = frozenset(string.hexdigits.encode("ascii"))


def check_dictionary(path: Path) -> None:
    """Raise ValueError naming the first line of the ``-dict`` file ``path`` that libFuzzer's
    ``ParseDictionaryFile`` would refuse (blank lines and lines starting with ``#`` are skipped;
    an empty file is refused), or a file that cannot be read."""
    try:
        if path.stat().st_size > MAX_DICTIONARY_BYTES:
            raise ValueError(f"-dict={path}: larger than {MAX_DICTIONARY_BYTES} bytes")
        data = path.read_bytes()
    except OSError as exc:
        raise ValueError(f"-dict={path}: cannot be read ({exc.strerror or exc})") from None
    if not data:
        raise ValueError(f"-dict={path}: an empty file (libFuzzer refuses it)")
    for number, line in enumerate(data.split(b"\n"), 1):
        stripped = line.lstrip(_SPACE)
        if not stripped or stripped.startswith(b"#"):
            continue
        if not dictionary_entry_ok(line):
            shown = line[:80].decode("utf-8", "replace")
            raise ValueError(
                f"-dict={path}: line {number} is not a libFuzzer dictionary entry "
                f'(name="value" or "value", no comment after it): {shown!r}'
            )


def cut_seeds(flags: tuple[str, ...], sizes: Sequence[int]) -> str | None:
    """A warning when a given ``-max_len`` is shorter than some seeds (``sizes``: their encoded
    lengths, bytes): libFuzzer cuts them short into malformed inputs, never run (at
    ``-max_len=1`` a campaign tested nothing and exited 0); None otherwise."""
    limit = int_flag(flags, "-max_len", 0)
    longer = [size for size in sizes if size > limit]
    if limit <= 0 or not longer:
        return None
    return (
        f"{len(longer)} of {len(sizes)} seeds are longer than -max_len={limit}: libFuzzer cuts them "
        f"short into malformed inputs, which are never run (the longest is {max(longer)} bytes)"
    )


def _unwritable(folder: Path) -> str | None:
    """Why no file can be created in ``folder`` (a read-only mount, /proc), or None."""
    try:
        fd, probe = tempfile.mkstemp(prefix=".tmp-probe-", dir=folder)
    except OSError as exc:
        return str(exc.strerror or exc)
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(probe)
    return None


def check_path_flags(flags: tuple[str, ...]) -> None:
    """Raise ValueError naming a path flag that libFuzzer would refuse after start-up, exiting
    with its status 1 (which a campaign reads as "new divergences"): an ``-artifact_prefix``,
    ``-exact_artifact_path`` or ``-merge_control_file`` whose folder does not exist, an
    ``-exact_artifact_path`` that is a folder (the crash file written "to" it was lost), a
    ``-seed_inputs=@FILE`` whose file does not exist; and a folder no file can be written into
    (a read-only mount, ``/proc/1/``: libFuzzer said "Test unit written to ..." and the input
    that killed a target was nowhere)."""

    def folder_of(value: str) -> Path:
        return Path(value) if value.endswith("/") else Path(value).parent

    for name in ("-artifact_prefix", "-exact_artifact_path", "-merge_control_file"):
        value = flag_value(flags, name)
        if not value:
            continue
        folder = folder_of(value)
        if folder.is_file() or any(p.is_file() for p in folder.parents):
            blocker = folder if folder.is_file() else next(p for p in folder.parents if p.is_file())
            raise ValueError(f"{name}={value}: {blocker} is a file, not a folder")
        if not folder.is_dir():
            raise ValueError(f"{name}={value}: the folder {folder} does not exist")
        if name != "-artifact_prefix" and Path(value).is_dir():
            raise ValueError(f"{name}={value}: a folder; give a file's path")
        problem = _unwritable(folder)
        if problem is not None:  # libFuzzer said "Test unit written to ..." and wrote nothing
            from fuzzer.input.paths import FolderUnwritable  # exit 74, as any folder that takes no file

            raise FolderUnwritable(f"{name}={value}: cannot write into the folder {folder}: {problem}")
    seeds = flag_value(flags, "-seed_inputs")
    if seeds and seeds.startswith("@") and not Path(seeds[1:]).is_file():
        raise ValueError(f"-seed_inputs={seeds}: no such file {seeds[1:]}")


def libfuzzer_argv(options: CampaignOptions) -> list[str]:
    """argv for Atheris: our script (absolute, for re-execution), libFuzzer flags with our
    defaults, our options as --name=value tokens, the corpus folders.

    Without ``--verbose``, ``-verbosity=0`` hides libFuzzer's per-input lines (NEW, REDUCE,
    pulse); its crash, timeout and -fork reports still show. One process (no ``-jobs``, no
    ``-fork``, not their worker: ``CHILD_ENV``) gets ``-reload=0`` unless given: libFuzzer's
    reread of the folder, which nothing else writes, made runs of one command differ
    (docs/engine.md, "Reproducing a campaign"). ``-jobs=N`` without ``-workers`` gets
    ``-workers=N`` (libFuzzer's default, half the cores, runs the jobs one at a time on small
    machines). With ``-jobs`` the campaign runs in its artifacts folder
    (libFuzzer writes ``fuzz-<job>.log`` into the working folder), so paths are made absolute.

    Raises
    ------
    ValueError
        A word that a ``-fork`` (merge, crash minimization) parent would pass to its jobs
        through a shell unquoted: a path with a space or a shell character.
    """
    script = os.path.abspath(sys.argv[0])
    flags = list(options.libfuzzer_flags)
    for name, value in DEFAULT_FLAGS.items():
        if flag_value(options.libfuzzer_flags, name) is None:
            flags.append(f"{name}={options.max_len if name == '-max_len' else value}")
    if flag_value(options.libfuzzer_flags, "-artifact_prefix") is None:
        flags.append(f"-artifact_prefix={options.artifacts.resolve()}/")
    if not options.verbose and flag_value(options.libfuzzer_flags, "-verbosity") is None:
        flags.append("-verbosity=0")
    jobs = int_flag(options.libfuzzer_flags, "-jobs", 0)
    fork = int_flag(options.libfuzzer_flags, "-fork", 0)
    alone = not jobs and fork <= 0 and os.environ.get(CHILD_ENV) != "1"  # not a -jobs/-fork worker either
    if alone and flag_value(options.libfuzzer_flags, "-reload") is None:
        flags.append("-reload=0")
    ours = one_campaign(options.libfuzzer_flags) or jobs > 0 or fork > 0  # (their workers get it too)
    if ours and flag_value(options.libfuzzer_flags, "-handle_term") is None:
        flags.append("-handle_term=0")  # signals.on_signal: the summary, not libFuzzer's _Exit(72)
    if flag_value(options.libfuzzer_flags, "-handle_xfsz") is None:
        # a file size limit (ulimit -f) fails a write with EFBIG, which the campaign says and
        # ends with 74; libFuzzer's own SIGXFSZ handler made it a crash (77), input unsaved
        flags.append("-handle_xfsz=0")
    forwarded = list(options.forwarded)
    corpus = [str(c) for c in options.corpus]
    if jobs > 0:
        if flag_value(options.libfuzzer_flags, "-workers") is None:
            flags.append(f"-workers={jobs}")
        flags = [absolute_flag(f) for f in flags]
        forwarded = [absolute_option(o) for o in forwarded]
        corpus = [str(Path(c).resolve()) for c in corpus]
    rest = [*flags, *forwarded, *corpus]
    if not one_campaign(options.libfuzzer_flags) and os.environ.get(CHILD_ENV) != "1":
        # libFuzzer runs each job as `sh -c "<argv> > log"`, its words joined unquoted; a Ctrl-C
        # killed that shell, and a job killed by SIGINT made a -jobs supervisor read a null
        # Fuzzer (a segfault): exec'd, the job is the shell's process, with its own status
        script = "exec " + shlex.quote(script)
        if jobs > 0:  # a -jobs supervisor reads its flags only, none of them a path
            rest = [shlex.quote(word) for word in rest]
        else:  # -fork, a merge...: the parent reads the same words as its jobs
            rest = [shell_word(word) for word in rest]  # a working folder "/home/me/My robots"
            unsafe = next((word for word in rest if shlex.quote(word) != word), None)
            if unsafe is not None:
                raise ValueError(
                    f"{unsafe!r}: libFuzzer hands this to its jobs through a shell, unquoted "
                    "(-fork, -merge, -minimize_crash), which would split or expand it; use paths "
                    "without spaces or shell characters here (-jobs quotes them)"
                )
    return [script, *rest]


def shell_word(word: str) -> str:
    """``word``, or the same path relative to the working folder where only that form is a word a
    shell keeps whole (no space, no shell character): for the words a ``-fork`` or merge parent
    hands its jobs, which run in the same working folder. ``word`` is a path or ``-name=path``;
    what is not an absolute path, or stays unsafe, is returned as it is."""
    if shlex.quote(word) == word:
        return word
    head, sep, value = word.partition("=") if word.startswith("-") else ("", "", word)
    if not os.path.isabs(value):
        return word
    try:
        relative = os.path.relpath(value) + ("/" if value.endswith("/") else "")
    except (OSError, ValueError):  # no working folder
        return word
    candidate = head + sep + relative
    return candidate if shlex.quote(candidate) == candidate else word
