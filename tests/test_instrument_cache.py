"""The cache of Atheris-instrumented code (``fuzzer.selection.instrument_cache``): a hit gives
the code instrumenting would give and leaves Atheris' counters where instrumenting would; a
file that does not fit is a miss, never an error."""

from __future__ import annotations

import subprocess
import sys
import types
from pathlib import Path

import pytest

from fuzzer.selection import instrument_cache
from fuzzer.selection.instrument_cache import instrument_functions


class FakeAtheris(types.ModuleType):
    """Counters from ``start``; ``instrument_func`` adds itself (a module constant, which
    marshal cannot write), two counters and the marker to a function's constants."""

    def __init__(self, start: int = 0, refuse: bool = False) -> None:
        super().__init__("atheris")
        self.next, self.refuse, self.instrumented = start, refuse, 0

    def _reserve_counter(self) -> int:
        self.next += 1
        return self.next - 1

    def instrument_func(self, func: types.FunctionType) -> None:
        if self.refuse:
            raise AssertionError("instrumented although the cache had it")
        self.instrumented += 1
        extra = (self, self._reserve_counter(), self._reserve_counter(), "__ATHERIS_INSTRUMENTED__")
        func.__code__ = func.__code__.replace(co_consts=func.__code__.co_consts + extra)


def _functions() -> list[types.FunctionType]:
    """Fresh function objects with the same code each call."""
    namespace: dict[str, object] = {}
    exec(compile("def f(x):\n    return x + 1\n\ndef g(y):\n    return [y, 'g']\n", "<t>", "exec"), namespace)
    return [namespace["f"], namespace["g"]]  # type: ignore[list-item]


def test_a_hit_gives_the_same_code_and_counters_without_instrumenting(tmp_path: Path) -> None:
    first, fake = _functions(), FakeAtheris(start=7)
    assert instrument_functions(first, fake, tmp_path) is False
    assert fake.instrumented == 2 and len(list(tmp_path.glob("*.bin"))) == 1
    again, other = _functions(), FakeAtheris(start=7, refuse=True)
    assert instrument_functions(again, other, tmp_path) is True
    assert other.next == fake.next  # the counters stand where instrumenting leaves them
    for old, new in zip(first, again, strict=True):
        assert new.__code__.co_code == old.__code__.co_code
        consts = new.__code__.co_consts
        assert consts[-4] is other  # the module constant is this process's module
        assert consts[:-4] + consts[-3:] == old.__code__.co_consts[:-4] + old.__code__.co_consts[-3:]
    assert again[1](3) == [3, "g"]


def test_counters_elsewhere_or_no_cache_mean_instrumenting(tmp_path: Path) -> None:
    instrument_functions(_functions(), FakeAtheris(start=7), tmp_path)
    moved = FakeAtheris(start=8)
    assert instrument_functions(_functions(), moved, tmp_path) is False and moved.instrumented == 2
    assert len(list(tmp_path.glob("*.bin"))) == 2  # one file per first counter
    off = FakeAtheris(start=7)
    assert instrument_functions(_functions(), off, None) is False
    assert off.next == 7 + 2 + 2 * 2  # the pair around the rewriting is reserved all the same


@pytest.mark.parametrize("damage", [b"", b"garbage", b"\xe3\x00\x00"])
def test_a_damaged_file_is_a_miss_and_is_rewritten(tmp_path: Path, damage: bytes) -> None:
    instrument_functions(_functions(), FakeAtheris(start=3), tmp_path)
    (cached,) = tmp_path.glob("*.bin")
    cached.write_bytes(damage)
    fake = FakeAtheris(start=3)
    assert instrument_functions(_functions(), fake, tmp_path) is False and fake.instrumented == 2
    assert instrument_functions(_functions(), FakeAtheris(start=3, refuse=True), tmp_path) is True


def test_a_file_for_other_functions_is_not_used(tmp_path: Path) -> None:
    instrument_functions(_functions(), FakeAtheris(start=3), tmp_path)
    (cached,) = tmp_path.glob("*.bin")
    fewer = _functions()[:1]  # another set of functions has another name; a renamed file misfits
    cached.rename(tmp_path / f"{instrument_cache._digest(fewer, FakeAtheris(), 3)}.bin")
    fake = FakeAtheris(start=3)
    assert instrument_functions(fewer, fake, tmp_path) is False and fake.instrumented == 1


def test_an_unwritable_folder_only_means_no_cache(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    fake = FakeAtheris()
    assert instrument_functions(_functions(), fake, blocker / "cache") is False
    assert fake.instrumented == 2


def test_only_the_newest_files_are_kept(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(instrument_cache, "KEEP", 2)
    for start in range(4):
        instrument_functions(_functions(), FakeAtheris(start=start), tmp_path)
    assert len(list(tmp_path.glob("*.bin"))) == 2


def test_the_folder_follows_the_environment(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv(instrument_cache.ENV, raising=False)
    assert instrument_cache.folder() == instrument_cache.DEFAULT
    monkeypatch.setenv(instrument_cache.ENV, str(tmp_path))
    assert instrument_cache.folder() == tmp_path
    monkeypatch.setenv(instrument_cache.ENV, "off")
    assert instrument_cache.folder() is None


SCRIPT = """
import dis, hashlib, sys, types
import atheris
from fuzzer.execution.session import RunConfig
from fuzzer.selection import instrument
import fuzzer.execution.oracle, python_impl  # loaded first: only instrument_loaded patches them
if sys.argv[1:] == ['refuse']:  # a hit must not instrument anything
    atheris.instrument_func = None
low = atheris._reserve_counter()
patched = instrument.instrument_loaded(['fuzzer.execution.oracle', 'python_impl'])
high = atheris._reserve_counter()

def stream(code):  # the instructions, each counter (an id in (low, high)) as 'C'
    out = []
    for ins in dis.get_instructions(code):
        value = ins.argval
        if isinstance(value, int) and not isinstance(value, bool) and low < value < high:
            value = 'C'
        elif isinstance(value, types.CodeType):
            value = stream(value)
        elif isinstance(value, types.ModuleType):
            value = value.__name__
        out.append((ins.opname, repr(value)))
    return out

h = hashlib.sha256()
for name in sorted(m for m in sys.modules if m == 'fuzzer.execution.oracle' or m.startswith('python_impl')):
    for obj in vars(sys.modules[name]).values():
        for func in instrument._own_functions(obj, name):
            h.update(repr((name, func.__qualname__, stream(func.__code__))).encode())
print(patched, high - low, h.hexdigest())
"""


def test_cached_code_is_what_atheris_makes_up_to_the_counters_order(tmp_path: Path) -> None:
    """The real thing, in subprocesses: the twin and the oracle instrumented with the cache off,
    into an empty cache, and from it. Atheris numbers a function's counters in an order that
    changes from process to process, so the code is compared with each counter as 'C'; the
    number of counters reserved must be the same."""
    import os

    def run(cache: str, *args: str) -> list[str]:
        done = subprocess.run(
            [sys.executable, "-c", SCRIPT, *args],
            capture_output=True,
            text=True,
            timeout=120,
            check=True,
            env={**os.environ, instrument_cache.ENV: cache},
        )
        return done.stdout.split()

    off = run("off")
    cache = tmp_path / "cache"
    filled = run(str(cache))
    assert len(list(cache.glob("*.bin"))) == 1
    hit = run(str(cache), "refuse")
    assert int(off[0]) > 100  # the twin's and the oracle's functions
    assert off == filled == hit
