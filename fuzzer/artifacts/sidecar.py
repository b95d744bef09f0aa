"""Reading a crash file's sidecar as untrusted data: a strict schema, validated field by field.

A crash file is something people mail to each other and open in CI, so its sidecar is
validated field by field (a wrong type names the file and the field) before anything in it is
used; what its settings may name (targets, robots, message folders) and where they may point
is :mod:`fuzzer.artifacts.trust`'s. The same rules apply to a corpus manifest
(:mod:`fuzzer.artifacts.manifest`).
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import re
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fuzzer.artifacts.manifest import SidecarError as SidecarError  # re-exported: where readers look for it
from fuzzer.artifacts.shorten import MAX_SIDECAR_BYTES
from fuzzer.artifacts.store import sidecar_path
from fuzzer.execution.records import Status
from fuzzer.input import untrusted_json
from fuzzer.input.mapping import OPS

BUILTIN_TARGETS = ("native", "python")
SCENARIO_OP = "scenario"
SCENARIO_CALL = "ScenarioCall"
MAX_STEPS_LIMIT = 256
"""The largest ``--max-steps``: a scenario sidecar never holds more steps (or step outcomes)."""
CONFIG_FIELDS: dict[str, type | tuple[type, ...]] = {
    "op": str,
    "max_steps": int,
    "robot": str,
    "tip_link": (str, type(None)),
    "targets": list,
    "tolerance": dict,
    "msg_type": str,
    "msg_path": list,
    "filtering": bool,
}


Fail = Callable[[str, str], SidecarError]
"""Makes the error for (field, problem)."""


def _type_name(value: Any) -> str:
    return "null" if value is None else type(value).__name__


def read_json_file(path: Path, what: str = "sidecar") -> dict[str, Any]:
    """A JSON object from a regular file of at most MAX_SIDECAR_BYTES.

    Raises
    ------
    SidecarError
        Not a regular file, unreadable, too large, not UTF-8 JSON, or not an object.
    """
    try:
        info = path.stat()
    except OSError as exc:
        raise SidecarError(f"{path}: cannot read the {what}: {exc.strerror or exc}") from None
    if not stat.S_ISREG(info.st_mode):
        raise SidecarError(f"{path}: the {what} is not a regular file")
    if info.st_size > MAX_SIDECAR_BYTES:
        raise SidecarError(f"{path}: the {what} is larger than {MAX_SIDECAR_BYTES} bytes")
    try:
        data = untrusted_json.loads(path.read_bytes().decode("utf-8"))
    except OSError as exc:
        raise SidecarError(f"{path}: cannot read the {what}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise SidecarError(f"{path}: the {what} is not UTF-8 text") from None
    except (ValueError, RecursionError) as exc:  # ValueError: bad JSON, or an int past a float's range
        raise SidecarError(f"{path}: the {what} is not valid JSON ({exc})") from None
    if not isinstance(data, dict):
        raise SidecarError(f"{path}: the {what} is a JSON {_type_name(data)}, expected an object")
    return data


def read_sidecar(crash: Path) -> dict[str, Any] | None:
    """The validated sidecar of ``crash``, or None when it has none.

    Raises
    ------
    SidecarError
        The sidecar exists but is damaged or has a field of the wrong type.
    """
    path = sidecar_path(crash)
    if not path.exists() and not path.is_symlink():
        return None
    if path.is_symlink() and _leads_somewhere(path):  # a loop or a dangling link: reading it says so
        from fuzzer.input.paths import contained

        folders = [crash.parent]
        with contextlib.suppress(OSError):  # the working folder was removed
            folders.append(Path.cwd())
        if not any(contained(folder, path) for folder in folders):  # replay used what it found there
            raise SidecarError(
                f"{path}: a link to a file outside {crash.parent} and the working folder; a sidecar "
                "is read only inside them, and this one was not opened (copy it there if you trust it)"
            )
    data = read_json_file(path)
    validate(data, path)
    of_this_file(crash, path, data)
    return data


HASHED_BYTES = 16 * 1024 * 1024
"""A crash file larger than this is not hashed against its sidecar (the tools refuse it anyway)."""


def of_this_file(crash: Path, path: Path, data: dict[str, Any]) -> None:
    """The sidecar's ``sha1`` (the input it describes) is the crash file's. A sidecar beside
    another input (copied, renamed, or the crash file edited) was read as this file's: replay
    said "now agrees" of a file that never diverged, and report drew one input's steps beside
    another's re-run."""
    recorded = data.get("sha1")
    if not isinstance(recorded, str) or not re.fullmatch(r"[0-9a-fA-F]{40}", recorded):
        return  # an older sidecar, or a hand-made one without a digest: nothing to check against
    try:
        if crash.stat().st_size > HASHED_BYTES:
            return
        actual = hashlib.sha1(crash.read_bytes()).hexdigest()
    except OSError:
        return  # the tool that reads the file names the problem
    if actual != recorded.lower():
        raise SidecarError(
            f"{path}: the sidecar of another input (its sha1 {recorded[:12]}, this file's {actual[:12]}): "
            "it does not describe this file; move it away to use the file without it"
        )


def _leads_somewhere(link: Path) -> bool:
    try:
        link.resolve(strict=True)
    except (OSError, RuntimeError):
        return False
    return True


def validate(data: dict[str, Any], path: Path) -> None:
    """Check the fields replay, minimize and triage rely on (unknown extra fields are allowed).

    Raises
    ------
    SidecarError
        Naming ``path`` and the first field that is missing or of the wrong type.
    """

    def fail(field: str, problem: str) -> SidecarError:
        return SidecarError(f"{path}: field {field!r} {problem}")

    for name in ("config", "signature"):
        if name not in data:
            raise fail(name, "is missing (not a divergence sidecar of RROSFuzz)")
        if not isinstance(data[name], dict):
            raise fail(name, f"must be an object, not {_type_name(data[name])}")
    validate_config(data["config"], path)
    signature = data["signature"]
    if not isinstance(signature.get("key"), str) or not signature["key"]:
        raise fail("signature.key", "must be a non-empty string")
    for name, kind in (("op", str), ("kind", str), ("field", str), ("outcome_a", str), ("outcome_b", str)):
        if name in signature and not isinstance(signature[name], kind):
            raise fail(f"signature.{name}", f"has the wrong type ({_type_name(signature[name])})")
    if "joints" in signature and not (
        isinstance(signature["joints"], list)
        and all(isinstance(j, int | str) and not isinstance(j, bool) for j in signature["joints"])
    ):
        raise fail("signature.joints", "must be a list of joint indices or names")
    for name in ("testcase", "comparison", "call", "versions"):
        if name in data and not isinstance(data[name], dict):
            raise fail(name, f"must be an object, not {_type_name(data[name])}")
    for name in ("lineage", "outcomes", "joint_names"):
        if name in data and not isinstance(data[name], list):
            raise fail(name, f"must be a list, not {_type_name(data[name])}")
    validate_scenario(data, path)


def validate_config(config: dict[str, Any], path: Path) -> None:
    """Check the ``config`` object of a sidecar or manifest.

    Raises
    ------
    SidecarError
        Naming ``path`` and the first field of the wrong type.
    """

    def fail(field: str, problem: str) -> SidecarError:
        return SidecarError(f"{path}: field {field!r} {problem}")

    for name, kind in CONFIG_FIELDS.items():
        if name in config and not isinstance(config[name], kind):
            raise fail(f"config.{name}", f"has the wrong type ({_type_name(config[name])})")
    ops = OPS if SCENARIO_OP in OPS else (*OPS, SCENARIO_OP)
    if "op" in config and config["op"] not in ops:
        raise fail("config.op", f"is {config['op']!r}, expected one of {', '.join(ops)}")
    steps = config.get("max_steps", 1)
    if isinstance(steps, bool) or not 1 <= steps <= MAX_STEPS_LIMIT:
        raise fail("config.max_steps", f"must be an integer from 1 to {MAX_STEPS_LIMIT}, not {steps!r}")
    targets = config.get("targets", list(BUILTIN_TARGETS))
    if len(targets) != 2 or not all(isinstance(t, str) and t for t in targets):
        raise fail("config.targets", "must be a list of two target names")
    for name in ("m", "rad"):
        value = config.get("tolerance", {}).get(name, 1e-6)
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
            or value <= 0
        ):
            raise fail(f"config.tolerance.{name}", f"must be a positive finite number, not {value!r}")
    if not all(isinstance(p, str) for p in config.get("msg_path", [])):
        raise fail("config.msg_path", "must be a list of folder names")


def validate_scenario(data: dict[str, Any], path: Path) -> None:
    """Check the scenario parts of a sidecar (``--op scenario``; other sidecars pass as they are).

    Checked: the call's steps (``{"kind", "message"}``, 1 to the bound), the test case's
    steps (``{"topic", "msg"}``), every outcome (status, error, code, values of numbers) with
    its step outcomes (at most one per step, not nested further), and the comparison's
    ``step`` (an index into the steps) and ``step_kind``. The bound is ``config.max_steps``
    when recorded, else :data:`MAX_STEPS_LIMIT`.

    Raises
    ------
    SidecarError
        Naming ``path`` and the first field that is wrong, e.g. ``outcomes[1].steps[3].status``.
    """

    def fail(field: str, problem: str) -> SidecarError:
        return SidecarError(f"{path}: field {field!r} {problem}")

    config = data["config"]
    bound = config.get("max_steps", MAX_STEPS_LIMIT)
    scenario = config.get("op") == SCENARIO_OP
    counts: list[int] = []
    call = data.get("call")
    if isinstance(call, dict) and (call.get("kind") == SCENARIO_CALL or (scenario and "kind" in call)):
        if call.get("kind") != SCENARIO_CALL:
            raise fail("call.kind", f"is {call.get('kind')!r}, expected {SCENARIO_CALL!r} for op scenario")
        counts.append(_steps(call.get("steps"), "call.steps", ("kind", str), ("message", dict), bound, fail))
    testcase = data.get("testcase")
    if isinstance(testcase, dict) and testcase.get("msg_type") == "rrosfuzz/Scenario":
        message = testcase.get("message")
        raw = message.get("steps") if isinstance(message, dict) else None
        counts.append(_steps(raw, "testcase.message.steps", ("topic", str), ("msg", dict), bound, fail))
    if len(set(counts)) > 1:
        raise fail("call.steps", f"holds {counts[0]} step(s), the test case {counts[1]}")
    limit = counts[0] if counts else bound
    for i, outcome in enumerate(data.get("outcomes", [])):
        _outcome(outcome, f"outcomes[{i}]", limit, fail)
    comparison = data.get("comparison", {})
    step = comparison.get("step")
    if step is not None and (isinstance(step, bool) or not isinstance(step, int) or not 0 <= step < limit):
        raise fail("comparison.step", f"must be a step index from 0 to {limit - 1} or null, not {step!r}")
    if not isinstance(comparison.get("step_kind", ""), str):
        raise fail("comparison.step_kind", f"must be a string, not {_type_name(comparison['step_kind'])}")


def _steps(
    raw: Any, where: str, name: tuple[str, type], body: tuple[str, type], bound: int, fail: Fail
) -> int:
    """How many steps ``raw`` holds, after checking it is a list of 1..bound step objects."""
    if not isinstance(raw, list):
        raise fail(where, f"must be a list of steps, not {_type_name(raw)}")
    if not 1 <= len(raw) <= bound:
        raise fail(where, f"holds {len(raw)} step(s), expected 1 to {bound}")
    for i, step in enumerate(raw):
        if not isinstance(step, dict):
            raise fail(f"{where}[{i}]", f"must be an object, not {_type_name(step)}")
        for key, kind in (name, body):
            if not isinstance(step.get(key), kind):
                expected = "an object" if kind is dict else "a string"
                raise fail(f"{where}[{i}].{key}", f"must be {expected}, not {_type_name(step.get(key))}")
    return len(raw)


def _outcome(raw: Any, where: str, limit: int, fail: Fail, nested: bool = False) -> None:
    """Check one recorded outcome (and its step outcomes, at most ``limit``)."""
    if not isinstance(raw, dict):
        raise fail(where, f"must be an object, not {_type_name(raw)}")
    status = raw.get("status", str(Status.OK))
    if not isinstance(status, str):  # a list or object: "not in" a set raised TypeError
        raise fail(f"{where}.status", f"must be a string, not {_type_name(status)}")
    if status not in {str(s) for s in Status}:
        raise fail(f"{where}.status", f"is {status[:80]!r}, expected one of {', '.join(map(str, Status))}")
    for key in ("target", "error", "message", "shortened"):
        if key in raw and not isinstance(raw[key], str | type(None)):
            raise fail(f"{where}.{key}", f"must be a string, not {_type_name(raw[key])}")
    code = raw.get("code")
    if code is not None and (isinstance(code, bool) or not isinstance(code, int)):
        raise fail(f"{where}.code", f"must be an integer or null, not {_type_name(code)}")
    values = raw.get("values", {})
    if not isinstance(values, dict):
        raise fail(f"{where}.values", f"must be an object, not {_type_name(values)}")
    for name, vector in values.items():
        if not isinstance(vector, list) or not all(
            isinstance(x, int | float) and not isinstance(x, bool) for x in vector
        ):
            raise fail(f"{where}.values.{name}", "must be a list of numbers")
    if "steps" not in raw:
        return
    steps = raw["steps"]
    if nested:
        raise fail(f"{where}.steps", "is not allowed in a step outcome")
    if not isinstance(steps, list) or len(steps) > limit:
        problem = f"holds {len(steps)} step outcomes" if isinstance(steps, list) else _type_name(steps)
        raise fail(f"{where}.steps", f"must be a list of at most {limit} step outcomes, not {problem}")
    for i, step in enumerate(steps):
        _outcome(step, f"{where}.steps[{i}]", limit, fail, nested=True)
