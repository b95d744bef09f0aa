"""Shrinking a divergent input to the simplest one with the same signature.

Like Hypothesis' shrinker: a fixed sequence of passes, each proposing simpler
candidates, keeping a candidate only when it still reproduces the *same*
signature, until a whole round changes nothing (or the budget of evaluations
runs out). Simpler means, in this order of passes:

1. shorter arrays (fewer names, positions, velocities...);
2. leaves set to their zero: 0, 0.0, '', false, time zero;
3. floats replaced by integers, then by the fewest significant digits
   (``3.141617`` -> ``3.1416``... as long as it still diverges the same way);
4. floats and ints moved toward zero by halving, when that is no longer to write;
5. strings cut to shorter prefixes.

Deterministic: no randomness, leaves visited in message order. The non-zero
joint values that remain are the joints that matter.

A scenario (``--op scenario``: the message is ``{"steps": [...]}``) first loses
steps: delta debugging (Zeller's ddmin) over the steps list, keeping the same
signature, leaves a 1-minimal list (removing any single step changes the
divergence). The passes above then shrink the values inside the remaining
steps' messages (topics are left alone), each round starting with a
remove-one-step pass, so a value made simpler never leaves a step that no
longer matters.
"""

from __future__ import annotations

import copy
import functools
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from typing import Any

from fuzzer.execution.evaluate import Verdict
from fuzzer.execution.session import Session
from fuzzer.input.testcase import TestCase
from fuzzer.scenario.steps import MSG_TYPE as SCENARIO
from fuzzer.triage.ddmin import ddmin

Loc = tuple[Any, ...]
JOINTS = "/joint_target"
"""The scenario topic whose messages carry joint values."""


@dataclass(frozen=True)
class Shrunk:
    """The result of minimizing one test case."""

    case: TestCase
    evaluations: int
    accepted: int
    complete: bool
    """False when the budget ran out before a round changed nothing."""


def _leaves(node: Any, loc: Loc = ()) -> Iterator[tuple[Loc, Any]]:
    if isinstance(node, dict):
        if set(node) == {"secs", "nsecs"}:
            yield loc, node
            return
        for key, value in node.items():
            yield from _leaves(value, (*loc, key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _leaves(value, (*loc, i))
    else:
        yield loc, node


def _arrays(node: Any, loc: Loc = ()) -> Iterator[Loc]:
    if isinstance(node, dict):
        for key, value in node.items():
            yield from _arrays(value, (*loc, key))
    elif isinstance(node, list):
        yield loc
        for i, value in enumerate(node):
            yield from _arrays(value, (*loc, i))


def _get(message: Any, loc: Loc) -> Any:
    for step in loc:
        message = message[step]
    return message


def _with(message: dict[str, Any], loc: Loc, value: Any) -> dict[str, Any]:
    out = copy.deepcopy(message)
    _get(out, loc[:-1])[loc[-1]] = value
    return out


def _zero(value: Any) -> Any:
    if isinstance(value, bool):
        return False
    if isinstance(value, int):
        return 0
    if isinstance(value, float):
        return 0.0
    if isinstance(value, str):
        return ""
    if isinstance(value, dict):
        return {"secs": 0, "nsecs": 0}
    return value


def _simpler_floats(x: float) -> Iterator[float]:
    """Integer, then fewer significant digits, shortest first."""
    if not math.isfinite(x):
        return
    if abs(x) < 2**53:
        yield float(math.trunc(x))
    for digits in range(1, 17):
        candidate = float(f"{x:.{digits}g}")
        if candidate != x:
            yield candidate


def _toward_zero(x: Any) -> Iterator[Any]:
    if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
        return
    y = x
    for _ in range(64):
        y = y / 2 if isinstance(y, float) else int(y / 2)
        if y == 0:
            return
        yield y


def _simplicity(value: Any) -> tuple[int, float]:
    """Lower is simpler: (length of its shortest repr, magnitude)."""
    if isinstance(value, float):
        return (len(repr(value)), abs(value) if math.isfinite(value) else math.inf)
    if isinstance(value, int) and not isinstance(value, bool):
        return (len(str(value)), abs(value))
    return (0, 0.0)


class Minimizer:
    """Shrinks test cases under one session (targets, robot, op)."""

    def __init__(self, session: Session, budget: int = 2000, history: list[Any] | None = None) -> None:
        self.session = session
        self.budget = budget
        self.history = list(history or [])
        """A state_dependent divergence's call history (``fuzzer.execution.evaluate.history_of``):
        each candidate runs on fresh targets after those calls (none: on fresh targets alone)."""

    def _key(self, case: TestCase) -> str | None:
        # Judged as ``replay`` judges a file: a new evaluator on fresh targets. One evaluator for
        # every candidate ran each on the targets the one before had moved, and skipped the
        # confirmations and ill-conditioning re-runs of signatures it had seen (a campaign's
        # shortcuts): it kept scenario candidates that replay filed under another signature.
        ev = self.session.evaluator().evaluate(case, history=self.history)
        if ev.verdict != Verdict.EVALUATED or ev.signature is None:
            return None
        key: str = ev.signature.key
        return key

    def minimize(self, case: TestCase, key: str | None = None) -> Shrunk:
        """Shrink ``case``, keeping the signature ``key`` (default: its current one).

        Raises
        ------
        ValueError
            ``case`` does not diverge, or not with the signature ``key`` (a crash file whose bug
            was fixed, or replayed under other targets or tolerances): every candidate would be
            measured against a signature the input itself no longer has.
        """
        first = self.session.evaluator().evaluate(case, history=self.history)
        if first.verdict != Verdict.EVALUATED:  # as replay says it: not that the bug is gone
            raise ValueError(f"skipped ({first.verdict}: {first.reason}): nothing to minimize")
        current: str | None = first.signature.key if first.signature is not None else None
        if current is None:
            now = "" if key is None else f"with its signature {key[:12]} or any other "
            raise ValueError(f"the input does not diverge {now}now: nothing to minimize")
        if key is not None and current != key:
            said = f"it no longer diverges with its signature {key[:12]} (now {current[:12]})"
            raise ValueError(f"{said}: nothing to minimize")
        target = current
        message = copy.deepcopy(case.message)
        evaluations, accepted = 1, 0

        def holds(candidate: dict[str, Any]) -> bool:
            nonlocal evaluations
            evaluations += 1
            return self._key(replace(case, message=candidate)) == target

        passes: list[Pass] = [
            _shorter_arrays,
            _zeros,
            _simpler_numbers,
            _halved,
            _shorter_strings,
        ]
        if case.msg_type == SCENARIO and is_scenario(message):
            before = message

            def steps_hold(kept: list[Any]) -> bool:
                return holds({**before, "steps": kept})

            steps, reductions = ddmin(message["steps"], steps_hold, lambda: evaluations < self.budget)
            message, accepted = {**message, "steps": steps}, reductions
            passes = [_fewer_steps, *(_within_steps(shrink) for shrink in passes)]
        complete = False
        while evaluations < self.budget:
            changed = exhausted = False
            for shrink_pass in passes:
                for edit in shrink_pass(message):
                    if evaluations >= self.budget:
                        exhausted = True
                        break
                    candidate = edit(message)  # applied to the message as it is now
                    if candidate is not None and candidate != message and holds(candidate):
                        message, changed = candidate, True
                        accepted += 1
            if not changed and not exhausted:  # a whole round without progress: done
                complete = True
                break
        shrunk = replace(
            case,
            message=message,
            origin="minimized",
            lineage=(*case.lineage, "minimize")[-64:],
            lineage_length=case.lineage_length + 1,
        )
        return Shrunk(shrunk, evaluations, accepted, complete)


# -- scenarios: steps first (ddmin), then values inside the steps' messages ------------------------


def is_scenario(message: Any) -> bool:
    """Whether ``message`` is a scenario (``{"steps": [...]}`` with at least one step)."""
    return isinstance(message, dict) and isinstance(message.get("steps"), list) and bool(message["steps"])


def _fewer_steps(message: dict[str, Any]) -> Iterator[Edit]:
    """Remove one step (last first); never the only one."""
    for i in reversed(range(len(message["steps"]))):

        def edit(current: dict[str, Any], i: int = i) -> dict[str, Any] | None:
            steps = current["steps"]
            if len(steps) <= 1 or i >= len(steps):
                return None
            return {**current, "steps": steps[:i] + steps[i + 1 :]}

        yield edit


def _within_steps(shrink_pass: Pass) -> Pass:
    """``shrink_pass`` applied to each step's message (``steps[i].msg``), topics untouched."""

    def scoped(message: dict[str, Any]) -> Iterator[Edit]:
        for i, step in enumerate(list(message["steps"])):
            if isinstance(step, dict) and isinstance(step.get("msg"), dict):
                for inner in shrink_pass(step["msg"]):
                    yield _step_edit(i, inner)

    return scoped


def _step_edit(i: int, inner: Edit) -> Edit:
    """``inner`` applied to the message of step ``i``."""

    def edit(message: dict[str, Any]) -> dict[str, Any] | None:
        steps = message["steps"]
        if i >= len(steps) or not isinstance(steps[i], dict) or not isinstance(steps[i].get("msg"), dict):
            return None
        msg = inner(steps[i]["msg"])
        if msg is None:
            return None
        return {**message, "steps": [*steps[:i], {**steps[i], "msg": msg}, *steps[i + 1 :]]}

    return edit


# -- passes: each yields edits; an edit maps the current message to a candidate (or None when its
#    location no longer exists), so an accepted change is never undone by a later edit --------------

Edit = Callable[[dict[str, Any]], "dict[str, Any] | None"]
Pass = Callable[[dict[str, Any]], Iterator[Edit]]


def _exists(message: Any, loc: Loc) -> bool:
    try:
        _get(message, loc)
    except (KeyError, IndexError, TypeError):
        return False
    return True


def _set_edit(loc: Loc, make: Callable[[Any], Any]) -> Edit:
    def edit(message: dict[str, Any]) -> dict[str, Any] | None:
        if not _exists(message, loc):
            return None
        value = make(_get(message, loc))
        return None if value is None else _with(message, loc, value)

    return edit


def _without(array: Any, i: int) -> list[Any] | None:
    return array[:i] + array[i + 1 :] if isinstance(array, list) and i < len(array) else None


def _shorter_arrays(message: dict[str, Any]) -> Iterator[Edit]:
    for loc in list(_arrays(message)):
        yield _set_edit(loc, lambda a: [] if isinstance(a, list) and a else None)
        for i in reversed(range(len(_get(message, loc)))):
            yield _set_edit(loc, functools.partial(_without, i=i))


def _zeros(message: dict[str, Any]) -> Iterator[Edit]:
    for loc, _ in list(_leaves(message)):

        def make(v: Any) -> Any:
            z = _zero(v)
            changes = z != v or (isinstance(v, float) and math.copysign(1, v) < 0)
            return z if changes else None

        yield _set_edit(loc, make)


def _simpler_numbers(message: dict[str, Any]) -> Iterator[Edit]:
    for loc, value in list(_leaves(message)):
        if isinstance(value, float):
            for rank in range(17):  # the integer, then 1..16 significant digits

                def make(v: Any, rank: int = rank) -> Any:
                    if not isinstance(v, float):
                        return None
                    options = list(_simpler_floats(v))
                    if rank >= len(options) or not _simplicity(options[rank]) < _simplicity(v):
                        return None
                    return options[rank]

                yield _set_edit(loc, make)


def _halved(message: dict[str, Any]) -> Iterator[Edit]:
    """Each number halved, when that is simpler (``_simplicity``: no longer to write, smaller):
    halving whatever still diverged took a joint from -1.81 to -2.5e-94 and never converged (any
    negative value diverged), every run ending on the budget with a longer file."""

    def halve(v: Any) -> Any:
        y = next(_toward_zero(v), None)
        return y if y is not None and _simplicity(y) < _simplicity(v) else None

    for loc, _ in list(_leaves(message)):
        yield _set_edit(loc, halve)


def _shorter_strings(message: dict[str, Any]) -> Iterator[Edit]:
    for loc, value in list(_leaves(message)):
        if isinstance(value, str) and value:
            yield _set_edit(loc, lambda v: v[: len(v) // 2] if isinstance(v, str) and v else None)
            yield _set_edit(loc, lambda v: v[:-1] if isinstance(v, str) and v else None)


def joints_that_matter(case: TestCase, joint_names: tuple[str, ...]) -> list[str]:
    """After minimization: the joints whose values stayed non-zero (for a scenario, in any of
    its joint targets; each joint named once, in order of appearance)."""
    messages = [case.message]
    if case.msg_type == SCENARIO and is_scenario(case.message):
        messages = [
            s["msg"] for s in case.message["steps"] if isinstance(s, dict) and s.get("topic") == JOINTS
        ]
    found: dict[str, None] = {}
    for message in messages:
        values = message.get("position", message.get("data", []))
        names = message.get("name") or list(joint_names)
        for n, v in zip(names, values, strict=False):
            if isinstance(v, float | int) and v != 0:
                found[str(n)] = None
    return list(found)
