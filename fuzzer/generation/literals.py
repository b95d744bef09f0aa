"""Numbers the Python targets compare against, read from their source: AFL++'s autodictionary
and libFuzzer's ``-dict``, for floats. The source is parsed (``ast``), never run.

``compared_numbers`` collects the numeric operands of every comparison (``4.0 <= v < 4.05``:
4.0 and 4.05), a module-level name bound to a number standing for it (``LOW <= v``, with
``LOW = 0.86131``); ``band_middles`` the middle of each band a chained comparison bounds on
both sides (4.025): inside it as far from both edges as can be, where the oracle's nudges of a
state (``fuzzer.execution.ik_check.IK_PERTURBATIONS``) do not carry it out, as the ``compared``
mutator's middle of two thresholds (``fuzzer.mutation.leaves``); ``literal_configurations``
puts numbers into joint configurations inside the limits. The full engine's dry run evaluates
the first ``fuzzer.dry_run.LITERALS`` of them, bands' middles first
(``fuzzer.generation.corpus.literal_cases``; a scenario's first uniform scripts start at them:
``corpus.literal_scripts``). ``parsed`` keeps what a module's text gives in a cache, so a
campaign's dry run does not parse it again. Only each target's own module is read (the
module of its spec, ``benchmarks.zoo.deep`` for ``benchmarks.zoo.deep:wrap_past_pi``), not
its submodules or what it imports.
"""

from __future__ import annotations

import ast
import hashlib
import json
import math
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path


def _number(node: ast.AST, names: dict[str, float]) -> float | None:
    """The finite number ``node`` stands for: a literal, a negated one, or a module-level name."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        value = _number(node.operand, names)
        return None if value is None else (-value if isinstance(node.op, ast.USub) else value)
    if isinstance(node, ast.Name):
        return names.get(node.id)
    if (
        isinstance(node, ast.Constant)
        and isinstance(node.value, (int, float))
        and not isinstance(node.value, bool)
    ):
        value = float(node.value)
        return value if math.isfinite(value) else None
    return None


def _module_names(tree: ast.Module) -> dict[str, float]:
    """Module-level ``NAME = number`` and ``A, B = number, number`` bindings."""
    names: dict[str, float] = {}
    for stmt in tree.body:
        if not isinstance(stmt, ast.Assign):
            continue
        for target in stmt.targets:
            pairs: list[tuple[ast.AST, ast.AST]] = [(target, stmt.value)]
            if isinstance(target, ast.Tuple) and isinstance(stmt.value, ast.Tuple):
                pairs = list(zip(target.elts, stmt.value.elts, strict=False))
            for name, value in pairs:
                number = _number(value, {})
                if isinstance(name, ast.Name) and number is not None:
                    names[name.id] = number
    return names


def _comparisons(source: str) -> list[list[float | None]]:
    """The operands of each comparison in Python ``source``, in the order met, each the number
    it stands for or None (none when it does not parse)."""
    try:
        tree = ast.parse(source)
    except (SyntaxError, ValueError):
        return []
    names = _module_names(tree)
    return [
        [_number(operand, names) for operand in (node.left, *node.comparators)]
        for node in ast.walk(tree)
        if isinstance(node, ast.Compare)
    ]


def _numbers(comparisons: list[list[float | None]]) -> list[float]:
    found = {value: None for operands in comparisons for value in operands if value is not None}
    return list(found)


def _middles(comparisons: list[list[float | None]]) -> list[float]:
    found: dict[float, None] = {}
    for operands in comparisons:
        if len(operands) == 3:
            low, middle, high = operands
            if low is not None and high is not None and middle is None and math.isfinite(low + high):
                found.setdefault((low + high) / 2.0, None)
    return list(found)


def compared_numbers(source: str) -> list[float]:
    """The numbers compared against in Python ``source``, in the order met (none when it does
    not parse)."""
    return _numbers(_comparisons(source))


def band_middles(source: str) -> list[float]:
    """The middles of the bands Python ``source`` tests with a chained comparison between two
    numbers (``a <= x < b``, ``LOW < f(q) <= HIGH``: ``(a + b) / 2``), in the order met (none
    when it does not parse)."""
    return _middles(_comparisons(source))


def _sources(modules: Iterable[str]) -> Iterable[str]:
    """The source text of each loaded module of ``modules`` read from a ``.py`` file (a module
    not loaded, or not from such a file, or unreadable, has none)."""
    for name in modules:
        module = sys.modules.get(name)
        path = getattr(module, "__file__", None)
        if not isinstance(path, str) or not path.endswith(".py"):
            continue
        try:
            yield Path(path).read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError):
            continue


def module_numbers(modules: Iterable[str], bands: bool = False) -> list[float]:
    """``compared_numbers`` of the source files of the loaded ``modules`` (a module not loaded,
    or not from a ``.py`` file, has none); with ``bands``, each file's ``band_middles`` before
    its numbers. Each file's from the cache when an earlier process read the same text
    (``parsed``)."""
    found: dict[float, None] = {}
    from fuzzer.selection.instrument_cache import folder

    cache = folder()
    for source in _sources(modules):
        middles, numbers = parsed(source, cache)
        for value in (*(middles if bands else ()), *numbers):
            found.setdefault(value, None)
    return list(found)


def parsed(source: str, cache: Path | None) -> tuple[list[float], list[float]]:
    """(``band_middles``, ``compared_numbers``) of Python ``source``, parsed once for both.

    Parsing a target's module takes a few milliseconds (3-8 ms for ``benchmarks.zoo.deep``,
    370 lines), which the dry run's child spends before its literal configurations, right
    after its first inputs; so the two lists are kept in a small JSON file named by a digest
    of the text, in the folder of ``fuzzer.selection.instrument_cache`` (``build/``, or
    ``RROSFUZZ_INSTRUMENT_CACHE``; ``off`` turns both off), and the next process that reads
    the same text loads them. The file is data: read as JSON, used only if it holds two lists
    of finite numbers, else the source is parsed and the file written again. ``cache``: the
    folder (``instrument_cache.folder()``; None: no cache)."""
    if cache is None:
        comparisons = _comparisons(source)
        return _middles(comparisons), _numbers(comparisons)
    digest = hashlib.sha256(f"{CACHE_MAGIC}\0{source}".encode("utf-8", "surrogatepass")).hexdigest()
    path = cache / f"{CACHE_PREFIX}{digest[:40]}.json"
    loaded = _load(path)
    if loaded is not None:
        return loaded
    comparisons = _comparisons(source)
    middles, numbers = _middles(comparisons), _numbers(comparisons)
    _store(cache, path, middles, numbers)
    return middles, numbers


CACHE_MAGIC = "rrosfuzz-compared-numbers-v1"
"""Names the cache files' format (in their digest and their content)."""
CACHE_PREFIX = "literals-"
CACHE_KEEP = 64
"""Cache files kept (one per version of a target module's text), the oldest removed first."""


def _load(path: Path) -> tuple[list[float], list[float]] | None:
    """The (middles, numbers) of a cache file, or None when there is none or it does not fit."""
    try:
        entry = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):  # a cache: a bad file means parsing
        return None
    if not (isinstance(entry, list) and len(entry) == 3 and entry[0] == CACHE_MAGIC):
        return None
    lists = entry[1:]
    if not all(isinstance(values, list) for values in lists):
        return None
    if not all(type(v) in (int, float) and math.isfinite(v) for values in lists for v in values):
        return None
    return [float(v) for v in lists[0]], [float(v) for v in lists[1]]


def _store(cache: Path, path: Path, middles: list[float], numbers: list[float]) -> None:
    """Write the file at once and keep the newest ``CACHE_KEEP``; a folder that cannot be
    written only means no cache."""
    from fuzzer.artifacts.store import atomic_write
    from fuzzer.selection.instrument_cache import keep_newest

    try:
        cache.mkdir(parents=True, exist_ok=True)
        atomic_write(path, json.dumps([CACHE_MAGIC, middles, numbers]).encode("utf-8"), durable=False)
    except (OSError, ValueError):
        return
    keep_newest(cache, f"{CACHE_PREFIX}*.json", CACHE_KEEP)


def literal_configurations(
    numbers: Sequence[float], lower: Sequence[float], upper: Sequence[float], limit: int
) -> list[tuple[float, ...]]:
    """Configurations with joints at the ``numbers``: first one per number, every joint whose
    limits hold it at it (the others in the middle of the joint box, 0 when unlimited), then
    one per (number, joint); 0 is left out (the aligned configurations have it); at most
    ``limit``, numbers in order."""
    middle = tuple(
        0.0 if not (math.isfinite(lo) and math.isfinite(hi)) else (lo + hi) / 2
        for lo, hi in zip(lower, upper, strict=True)
    )
    values = [v for v in numbers if v != 0.0]
    inside = [[j for j, (lo, hi) in enumerate(zip(lower, upper, strict=True)) if lo < v < hi] for v in values]
    out: list[tuple[float, ...]] = []
    for value, joints in zip(values, inside, strict=True):
        if joints:
            out.append(tuple(value if j in joints else m for j, m in enumerate(middle)))
    for value, joints in zip(values, inside, strict=True):
        if len(joints) > 1:
            out += [(*middle[:j], value, *middle[j + 1 :]) for j in joints]
    return out[: max(0, limit)]
