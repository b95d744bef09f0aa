"""Trace the comparisons Atheris 3.0.0 leaves untraced: those it takes for two constants, and
those inside comprehensions and generator expressions.

``atheris.instrument_func`` turns each ``COMPARE_OP`` into a call of ``atheris._trace_cmp``
(``Instrumentor.trace_data_flow``), unless both operands are constants. It decides that by
walking the bytecode in a straight line and remembering the stack slots where ``LOAD_CONST``
pushed, without following ``SWAP``, ``COPY`` or jumps. A chained comparison with a literal
first bound in a condition, ``if 0.3 <= x < 0.31:`` (``SWAP``, ``COPY``, a jump, then
``LOAD_CONST 0.31``), leaves a stale mark on ``x``'s slot, so its second comparison is taken
for ``0.31`` against a constant and is never traced: the float tracer and the comparison
table (``fuzzer.selection.compared``) never see the band's upper edge. The same shape as a
``return`` value is traced.

Atheris also leaves the code of comprehensions and generator expressions
(``<listcomp>``, ``<genexpr>``, ``<setcomp>``, ``<dictcomp>``: separate code objects in Python
3.11; from 3.12 only generator expressions are, PEP 709 inlines the others) uninstrumented:
``patch_code`` recurses only into nested functions and lambdas. A band
``4.0 <= v < 4.05`` tested per joint inside a list comprehension was invisible to the float
tracer. :func:`install` also wraps ``patch_code``: before Atheris patches a code object, the
comprehensions among its constants get their comparisons traced (data flow only, both
Atheris' pass and the one below; no edge counters, so a comprehension's loop costs one call
per comparison and element, not one per basic block: a float comparison's traced side is
already a feature, ``fuzzer.selection.floatcmp``).

:func:`install` wraps ``trace_data_flow``: after Atheris' own pass, each ``COMPARE_OP`` still
in the code gets the same call Atheris would insert. An operand counts as a constant only when
it is plainly one: the comparison's right operand when the instruction just before it is a
``LOAD_CONST`` and nothing jumps to the comparison; its left operand when, besides, the
instruction before that is a ``LOAD_CONST`` followed by a plain load. Two constants are left
alone, as Atheris does. Everything Atheris traced stays as it was. The rewritten code is
cached with this file's text in the cache key (``fuzzer.selection.instrument_cache``).
"""

from __future__ import annotations

import dis
import types
from collections.abc import Callable
from typing import Any, Final

_PLAIN_LOADS: Final = frozenset({"LOAD_CONST", "LOAD_FAST", "LOAD_DEREF", "LOAD_CLOSURE", "LOAD_NAME"})
"""Instructions that push exactly one value and pop none (``LOAD_GLOBAL`` may push two)."""
_MARK: Final = "_rrosfuzz_traces_skipped_comparisons"
_COMPREHENSIONS: Final = frozenset({"<listcomp>", "<genexpr>", "<setcomp>", "<dictcomp>"})
_INSTRUMENTED: Final = "__ATHERIS_INSTRUMENTED__"


def install(atheris: Any) -> bool:
    """Wrap ``atheris.instrument_bytecode.Instrumentor.trace_data_flow`` and
    ``atheris.instrument_bytecode.patch_code`` once; False when ``atheris`` has no such
    rewriter (a stand-in)."""
    rewriter = getattr(atheris, "instrument_bytecode", None)
    instrumentor = getattr(rewriter, "Instrumentor", None)
    original = getattr(instrumentor, "trace_data_flow", None)
    patch = getattr(rewriter, "patch_code", None)
    if rewriter is None or instrumentor is None or original is None or patch is None:
        return False
    if not getattr(original, _MARK, False):

        def trace_data_flow(self: Any) -> None:
            original(self)
            trace_skipped(self, rewriter)

        setattr(trace_data_flow, _MARK, True)
        trace_data_flow.__wrapped__ = original  # type: ignore[attr-defined]
        instrumentor.trace_data_flow = trace_data_flow
    if not getattr(patch, _MARK, False):

        def patch_code(
            code: types.CodeType, trace_dataflow: bool, trace_control_flow: bool = True, nested: bool = False
        ) -> types.CodeType:
            if trace_dataflow:
                code = with_comprehensions_traced(code, patch_code)
            return patch(code, trace_dataflow, trace_control_flow, nested)  # type: ignore[no-any-return]

        setattr(patch_code, _MARK, True)
        patch_code.__wrapped__ = patch  # type: ignore[attr-defined]
        rewriter.patch_code = patch_code  # Atheris' own recursion looks it up here too
    return True


def with_comprehensions_traced(code: types.CodeType, patch: Callable[..., types.CodeType]) -> types.CodeType:
    """``code`` with the comprehensions among its constants patched by ``patch`` (the wrapped
    ``patch_code``, which comes back here for comprehensions nested in them) for data flow
    only; unchanged when Atheris already instrumented it or it has none."""
    if any(isinstance(c, str) and c == _INSTRUMENTED for c in code.co_consts):
        return code
    consts = tuple(
        patch(c, True, False, True) if isinstance(c, types.CodeType) and c.co_name in _COMPREHENSIONS else c
        for c in code.co_consts
    )
    if all(a is b for a, b in zip(consts, code.co_consts, strict=True)):
        return code
    return code.replace(co_consts=consts)


def trace_skipped(inst: Any, rewriter: Any) -> int:
    """Insert Atheris' ``_trace_cmp`` call before every comparison its pass left; returns how many."""
    shift = rewriter.CMP_OP_SHIFT_AMOUNT
    left = [i for i in inst.instructions if i.mnemonic == "COMPARE_OP" and (i.arg >> shift) < len(dis.cmp_op)]
    traced = 0
    for instr in left:
        at = inst.instructions.index(instr)
        before = inst.instructions[at - 1] if at >= 1 else None
        before2 = inst.instructions[at - 2] if at >= 2 else None
        entered = bool(instr.referers)  # reached by a jump too: its operands are not known here
        right_const = not entered and before is not None and before.mnemonic == "LOAD_CONST"
        left_const = (
            not entered
            and before is not None
            and before2 is not None
            and before.mnemonic in _PLAIN_LOADS
            and not before.referers
            and before2.mnemonic == "LOAD_CONST"
        )
        if right_const and left_const:
            continue  # two literals: nothing to learn, as Atheris decides
        coerce = rewriter.requires_bool_coersion(instr.arg)
        if right_const or left_const:
            code = inst._generate_const_cmp_invocation(instr.arg, instr, right_const, coerce)
        else:
            code = inst._generate_cmp_invocation(instr.arg, instr, coerce)
        inst._insert_at(code, instr)
        instr.make_nop()
        traced += 1
    return traced
