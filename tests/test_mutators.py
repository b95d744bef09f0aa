"""Unit tests of the seed mutators (fuzzer/mutation/mutators.py): registry, type safety,
per-mutator semantics."""

from __future__ import annotations

import math
import random
import re
import struct
from collections.abc import Callable, Mapping
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fuzzer.mutation import base, paper
from fuzzer.mutation import mutators as m
from fuzzer.mutation.mutators import (
    MUTATORS,
    NOOP,
    WEIGHTS,
    LeafOp,
    MutationContext,
    NotApplicable,
    crossover,
    mutate,
)
from fuzzer.selection.compared import ComparedValues

Message = dict[str, Any]

EXPECTED_NAMES = {
    "bit_flip", "arithmetic", "interesting", "comb1", "comb2", "comb3", "comb4",
    "dictionary", "havoc", "splice", "libfuzzer", "compared",
    "sign_flip", "wrap_2pi", "array_insert", "array_delete", "array_duplicate", "string_swap", "zero",
}  # fmt: skip
ALL_NAMES = sorted(EXPECTED_NAMES)
ITERATIONS = 300
RESET_EVERY = 25  # chained mutations, restarted from the seed now and then
DICTIONARY: tuple[str | float, ...] = ("joint_1", "tool0", 3.5, "42", -7, "1e400", 10**30)
ENGINE_FLOATS = (2.9671 + 1e-9, -2.9671 - 1e-9)

# ----------------------------------------------------------------------------------------------------------
# Message factories
# ----------------------------------------------------------------------------------------------------------

JS_TYPES = {
    "header.seq": "uint32",
    "header.stamp": "time",
    "header.frame_id": "string",
    "name": "string[]",
    "position": "float64[]",
    "velocity": "float64[]",
    "effort": "float64[]",
}


def joint_state(
    seq: int = 3,
    names: tuple[str, ...] = ("joint_1", "joint_2"),
    position: tuple[float, ...] = (0.1, -2.0),
    velocity: tuple[float, ...] = (),
    effort: tuple[float, ...] = (),
    frame: str = "",
) -> Message:
    return {
        "header": {"seq": seq, "stamp": {"secs": 1, "nsecs": 5}, "frame_id": frame},
        "name": list(names),
        "position": list(position),
        "velocity": list(velocity),
        "effort": list(effort),
    }


ALL_TYPES = {
    "flag": "bool",
    "i8": "int8",
    "u8": "uint8",
    "i16": "int16",
    "u16": "uint16",
    "i32": "int32",
    "u32": "uint32",
    "i64": "int64",
    "u64": "uint64",
    "by": "byte",
    "ch": "char",
    "f32": "float32",
    "f64": "float64",
    "text": "string",
    "short": "string<=8",
    "stamp": "time",
    "span": "duration",
    "matrix": "float64[9]",
    "triple": "int8[3]",
    "f32s": "float32[]",
    "stamps": "time[]",
    "spans": "duration[2]",
    "bounded": "int16[<=4]",
    "data": "uint8[]",
    "bools": "bool[]",
    "names": "string[]",
    "nested": "pkg/Nested",
    "nested.x": "float64",
    "nested.label": "string",
    "points": "pkg/Point[]",
    "points.x": "float64",
    "points.y": "float32",
    "corners": "pkg/Point[2]",
    "corners.x": "float64",
    "corners.y": "float32",
}


def all_types(variant: int = 0) -> Message:
    """A message with every builtin type; ``variant=1`` differs in every value (same shapes)."""
    s = -1 if variant else 1
    return {
        "flag": bool(variant),
        "i8": 5 * s,
        "u8": 200 + variant,
        "i16": -300 * s,
        "u16": 60000 + variant,
        "i32": 123456 * s,
        "u32": 4000000000 + variant,
        "i64": -(2**40) * s,
        "u64": 2**63 + variant,
        "by": -3 * s,
        "ch": 65 + variant,
        "f32": 1.5 * s,
        "f64": 0.25 * s,
        "text": f"hello{variant}",
        "short": f"abc{variant}",
        "stamp": {"secs": 10 + variant, "nsecs": 999_999_000 + variant},
        "span": {"secs": -5 * s, "nsecs": 7 + variant},
        "matrix": [float(i) * s + 0.5 for i in range(9)],
        "triple": [1 * s, -2 * s, 3 * s],
        "f32s": [0.5 * s, -0.25 * s],
        "stamps": [{"secs": 1 + variant, "nsecs": 2}],
        "spans": [{"secs": -1 * s, "nsecs": 0}, {"secs": 2 * s, "nsecs": 500 + variant}],
        "bounded": [1 + variant, 2, 3],
        "data": [0, 255 - variant, 7],
        "bools": [True, bool(variant)],
        "names": [f"a{variant}", f"b{variant}"],
        "nested": {"x": 3.0 * s, "label": f"lbl{variant}"},
        "points": [{"x": 1.0 * s, "y": 2.0 * s}],
        "corners": [{"x": 0.0, "y": -1.0 * s}, {"x": 4.0 * s, "y": 0.5 * s}],
        "untyped": 5,
    }


def fake_libfuzzer(data: bytes, max_size: int) -> bytes:
    """Deterministic stand-in for atheris.Mutate: random bytes of a random length, sometimes NaN bytes."""
    rng = random.Random(data + max_size.to_bytes(4, "little"))
    if rng.random() < 0.1:
        return b"\xff" * max_size
    return rng.randbytes(rng.randint(0, max_size + 3))


THRESHOLDS = (0.3, 4.05)


def thresholds() -> ComparedValues:
    """A table that has seen ``x < 0.3`` and ``x < 4.05`` at two sites, x varying."""
    table = ComparedValues()
    for site, threshold in enumerate(THRESHOLDS):
        for x in (0.0, 1.0):
            table.watch(site, x, threshold, x < threshold)
    return table


def make_ctx(seed: int, types: Mapping[str, str], **kwargs: Any) -> MutationContext:
    return MutationContext(rng=random.Random(seed), field_types=types, **kwargs)


def full_ctx(seed: int, types: Mapping[str, str], other: Message | None, **kwargs: Any) -> MutationContext:
    """A context where every mutator can apply."""
    options: dict[str, Any] = {
        "interesting_floats": ENGINE_FLOATS,
        "dictionary": DICTIONARY,
        "libfuzzer_mutate": fake_libfuzzer,
        "other": other,
        "compared": thresholds(),
    }
    options.update(kwargs)
    return make_ctx(seed, types, **options)


CASES: dict[str, tuple[Callable[[int], Message], Mapping[str, str]]] = {
    "joint_state": (lambda v: joint_state(seq=3 + v, position=(0.1 + v, -2.0), velocity=(0.5,)), JS_TYPES),
    "all_types": (all_types, ALL_TYPES),
}

# ----------------------------------------------------------------------------------------------------------
# An independent type checker
# ----------------------------------------------------------------------------------------------------------

INT_RANGES = {
    "int8": (-(2**7), 2**7 - 1),
    "uint8": (0, 2**8 - 1),
    "int16": (-(2**15), 2**15 - 1),
    "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
    "byte": (-(2**7), 2**7 - 1),
    "char": (0, 2**8 - 1),
}
TYPE_RE = re.compile(r"^(?P<base>[^\[]+)(?:\[(?P<le><=)?(?P<n>\d*)\])?$")


def check_float(value: Any, base: str, allow_special: bool) -> str | None:
    if type(value) is not float:
        return f"{value!r} is not a float"
    if math.isnan(value) or math.isinf(value):
        return None if allow_special else f"special {value!r}"
    if base == "float32" and struct.unpack("<f", struct.pack("<f", value))[0] != value:
        return f"{value!r} is not a float32"
    return None


def check_scalar(value: Any, base: str, allow_special: bool) -> str | None:
    if base in ("time", "duration"):
        if not isinstance(value, dict) or list(value) != ["secs", "nsecs"]:
            return f"{value!r} is not a time"
        secs = check_scalar(value["secs"], "uint32" if base == "time" else "int32", allow_special)
        nsecs_ok = type(value["nsecs"]) is int and 0 <= value["nsecs"] <= 999_999_999
        return secs or (None if nsecs_ok else f"bad nsecs {value['nsecs']!r}")
    if base in INT_RANGES:
        lo, hi = INT_RANGES[base]
        return None if type(value) is int and lo <= value <= hi else f"{value!r} is not a {base}"
    if base in ("float32", "float64"):
        return check_float(value, base, allow_special)
    if base == "bool":
        return None if type(value) is bool else f"{value!r} is not a bool"
    bounded = re.fullmatch(r"string<=(\d+)", base)
    if base == "string" or bounded:
        too_long = bounded is not None and isinstance(value, str) and len(value) > int(bounded[1])
        return None if type(value) is str and not too_long else f"{value!r} is not a {base}"
    return f"unexpected base {base}"


def problems(
    msg: Any, template: Message, types: Mapping[str, str], allow_special: bool, prefix: str = ""
) -> list[str]:
    """Every way ``msg`` violates the shape of ``template`` and the types of ``types``."""
    if not isinstance(msg, dict) or list(msg) != list(template):
        return [f"{prefix}: keys {list(msg) if isinstance(msg, dict) else msg!r} != {list(template)}"]
    out: list[str] = []
    for key, tval in template.items():
        name = f"{prefix}.{key}" if prefix else key
        value = msg[key]
        text = types.get(name)
        if text is None:
            if isinstance(tval, dict):
                out += problems(value, tval, types, allow_special, name)
            elif value != tval:
                out.append(f"{name}: untyped field changed to {value!r}")
            continue
        match = TYPE_RE.match(text)
        assert match is not None
        base = match["base"]
        if not text.endswith("]"):
            out += [f"{name}: {p}" for p in check_element(value, base, tval, types, allow_special, name)]
            continue
        if not isinstance(value, list):
            out.append(f"{name}: {value!r} is not a list")
            continue
        size = int(match["n"]) if match["n"] else None
        if size is not None and not match["le"] and len(value) != size:
            out.append(f"{name}: fixed length {size} became {len(value)}")
        if size is not None and match["le"] and len(value) > size:
            out.append(f"{name}: bound {size} exceeded by {len(value)}")
        for item in value:
            out += [
                f"{name}[]: {p}"
                for p in check_element(item, base, tval[0] if tval else None, types, allow_special, name)
            ]
    return out


def check_element(
    value: Any, base: str, template: Any, types: Mapping[str, str], allow_special: bool, name: str
) -> list[str]:
    if "/" in base:
        return problems(value, template, types, allow_special, name)
    problem = check_scalar(value, base, allow_special)
    return [] if problem is None else [problem]


def leaves(value: Any) -> list[Any]:
    if isinstance(value, dict):
        return [leaf for item in value.values() for leaf in leaves(item)]
    if isinstance(value, list):
        return [leaf for item in value for leaf in leaves(item)]
    return [value]


def run_one(name: str, msg: Message, ctx: MutationContext) -> Any:
    """The value of the only field ``x`` after mutating with ``name`` (which must apply)."""
    out, used = mutate(msg, ctx, name)
    assert used == name
    return out["x"]


# ----------------------------------------------------------------------------------------------------------
# Self-test of the checker (so a lenient checker cannot hide broken mutators)
# ----------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("i8", 128),
        ("u64", -1),
        ("flag", 1),
        ("u8", True),
        ("f64", 1),
        ("f32", 0.1),
        ("f64", math.nan),
        ("short", "123456789"),
        ("stamp", {"secs": 1, "nsecs": 10**9}),
        ("span", {"secs": 2**31, "nsecs": 0}),
        ("matrix", [0.0] * 8),
        ("bounded", [1, 2, 3, 4, 5]),
        ("untyped", 6),
    ],
)
def test_checker_rejects_bad_values(field: str, value: Any) -> None:
    msg = all_types()
    msg[field] = value
    assert problems(msg, all_types(), ALL_TYPES, allow_special=False)


def test_checker_accepts_seeds() -> None:
    for factory, types in CASES.values():
        assert problems(factory(0), factory(0), types, allow_special=False) == []
        assert problems(factory(1), factory(0), types, allow_special=False) == []


# ----------------------------------------------------------------------------------------------------------
# Registry and dispatcher
# ----------------------------------------------------------------------------------------------------------


def test_registry_names_weights_and_docs() -> None:
    assert set(MUTATORS) == EXPECTED_NAMES
    assert set(WEIGHTS) == set(MUTATORS)
    assert all(weight > 0 for weight in WEIGHTS.values())
    assert m.PAPER_STRATEGIES == ("bit_flip", "arithmetic", "interesting", "comb1", "comb2", "comb3", "comb4")
    assert m.FUTURE_WORK == ("dictionary", "havoc", "splice")
    assert set(m.PAPER_STRATEGIES) | set(m.FUTURE_WORK) <= set(MUTATORS)
    for name, fn in MUTATORS.items():
        assert fn.__doc__ and len(fn.__doc__) > 20, name


def test_register_rejects_duplicates() -> None:
    with pytest.raises(ValueError, match="already registered"):
        m.register("bit_flip")(lambda message, ctx: message)


def test_mutate_unknown_name() -> None:
    with pytest.raises(KeyError):
        mutate(joint_state(), make_ctx(0, JS_TYPES), "no_such_mutator")


def test_weighted_choice_reaches_every_mutator() -> None:
    seen: dict[str, int] = {}
    for seed in range(1500):
        _, used = mutate(joint_state(position=(0.1, 0.2)), full_ctx(seed, JS_TYPES, joint_state(seq=9)))
        seen[used] = seen.get(used, 0) + 1
    assert set(seen) == EXPECTED_NAMES
    # weights matter: arithmetic (2.0) is picked more often than sign_flip (0.5)
    assert seen["arithmetic"] > seen["sign_flip"]


def test_mutate_falls_back_and_reports_the_name_used() -> None:
    msg = {"text": "abc", "names": ["a", "b"]}
    types = {"text": "string", "names": "string[]"}
    used_names = set()
    for seed in range(60):
        out, used = mutate(msg, make_ctx(seed, types), "bit_flip")
        assert used != "bit_flip"
        assert used in MUTATORS
        used_names.add(used)
        assert problems(out, msg, types, allow_special=False) == []
    assert used_names <= {
        "interesting",
        "havoc",
        "string_swap",
        "array_insert",
        "array_delete",
        "array_duplicate",
    }


def test_mutate_without_any_mutable_field_is_a_noop() -> None:
    msg = {"untyped": 1.5, "nested": {"also": "x"}}
    out, used = mutate(msg, make_ctx(0, {}))
    assert used == NOOP
    assert out == msg
    assert out is not msg


@pytest.mark.parametrize("name", ALL_NAMES)
def test_not_applicable_is_raised_by_direct_calls(name: str) -> None:
    with pytest.raises(NotApplicable):
        MUTATORS[name]({"untyped": 1}, make_ctx(0, {}))


# ----------------------------------------------------------------------------------------------------------
# Properties of every mutator
# ----------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("name", ALL_NAMES)
def test_determinism(name: str, case: str) -> None:
    factory, types = CASES[case]
    for seed in range(15):
        first = mutate(factory(0), full_ctx(seed, types, factory(1)), name)
        second = mutate(factory(0), full_ctx(seed, types, factory(1)), name)
        assert first == second


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("name", ALL_NAMES)
def test_no_in_place_mutation(name: str, case: str) -> None:
    factory, types = CASES[case]
    seed_msg, other = factory(0), factory(1)
    for seed in range(30):
        ctx = full_ctx(seed, types, other)
        out, _ = mutate(seed_msg, ctx, name)
        direct = MUTATORS[name](seed_msg, full_ctx(seed, types, other))
        assert seed_msg == factory(0)
        assert other == factory(1)
        assert out is not seed_msg and direct is not seed_msg


@pytest.mark.parametrize("allow_special", [False, True])
@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("name", ALL_NAMES)
def test_types_and_widths_are_preserved(name: str, case: str, allow_special: bool) -> None:
    factory, types = CASES[case]
    seed_msg = factory(0)
    ctx = full_ctx(1234, types, factory(1), allow_special=allow_special)
    msg = seed_msg
    applied = 0
    iterations = ITERATIONS if not allow_special else ITERATIONS // 3
    for i in range(iterations):
        if i % RESET_EVERY == 0:
            msg = seed_msg
        msg, used = mutate(msg, ctx, name)
        applied += used == name
        found = problems(msg, seed_msg, types, allow_special)
        assert found == [], (used, i, found[:3])
    assert applied > iterations // 10, f"{name} rarely applied"


@pytest.mark.parametrize("name", ALL_NAMES)
def test_no_special_floats_unless_allowed(name: str) -> None:
    """Every leaf is checked, with engine values and dictionary tokens that include inf/NaN."""
    types = {"x": "float64", "y": "float32", "v": "float64[]"}
    seed_msg = {"x": 1.0, "y": -2.5, "v": [0.0, 3.0]}
    ctx = full_ctx(
        7,
        types,
        {"x": -1.0, "y": 2.5, "v": [1.0]},
        interesting_floats=(math.nan, math.inf, 1.25),
        dictionary=("inf", "nan", 2.0),
    )
    msg = seed_msg
    for i in range(ITERATIONS):
        if i % RESET_EVERY == 0:
            msg = seed_msg
        msg, _ = mutate(msg, ctx, name)
        assert all(math.isfinite(v) for v in leaves(msg)), msg


def test_interesting_produces_specials_when_allowed() -> None:
    seen = set()
    for seed in range(600):
        value = run_one("interesting", {"x": 1.0}, make_ctx(seed, {"x": "float64"}, allow_special=True))
        if not math.isfinite(value):
            seen.add("nan" if math.isnan(value) else value)
    assert seen == {"nan", math.inf, -math.inf}


def test_focus_is_preferred() -> None:
    hits = 0
    runs = 200
    for seed in range(runs):
        ctx = make_ctx(seed, JS_TYPES, focus=["position"])
        before = joint_state()
        out, _ = mutate(before, ctx, "arithmetic")
        hits += out["position"] != before["position"]
    assert hits >= 0.8 * runs
    assert hits < runs  # the rest of the message is still reachable


# ----------------------------------------------------------------------------------------------------------
# bit_flip
# ----------------------------------------------------------------------------------------------------------


def is_flip_mask(mask: int, width: int) -> bool:
    """Whether ``mask`` is 1, 2 or 4 consecutive set bits within ``width`` bits."""
    if mask <= 0 or mask >= 1 << width:
        return False
    low = (mask & -mask).bit_length() - 1
    run = mask >> low
    return run in (0b1, 0b11, 0b1111)


@pytest.mark.parametrize("x", [0.25, 0.5, -2.75, 3.0, -0.0, 100.125, 1e-3, -3.9212])
def test_bit_flip_changes_only_the_integer_part(x: float) -> None:
    whole, fraction = math.trunc(x), x - math.trunc(x)
    exact = (fraction * 8).is_integer()  # dyadic fractions survive exactly, others up to rounding
    for seed in range(150):
        r = run_one("bit_flip", {"x": x}, make_ctx(seed, {"x": "float64"}))
        if exact:
            assert r - math.trunc(r) == fraction
        else:
            assert abs((r - math.trunc(r)) - fraction) <= math.ulp(r)
        assert math.copysign(1.0, r) == math.copysign(1.0, x) or math.trunc(r) == 0
        assert is_flip_mask(abs(math.trunc(r)) ^ abs(whole), base.FLOAT_FLIP_WINDOW), (x, r)


def test_bit_flip_turns_half_into_one_and_a_half() -> None:
    results = {run_one("bit_flip", {"x": 0.5}, make_ctx(seed, {"x": "float64"})) for seed in range(100)}
    assert 1.5 in results
    assert {r - math.trunc(r) for r in results} == {0.5}


@given(
    x=st.floats(min_value=-(2.0**40), max_value=2.0**40, allow_nan=False, allow_infinity=False),
    seed=st.integers(0, 2**32),
)
@settings(max_examples=200, deadline=None, database=None, derandomize=True)
def test_bit_flip_fraction_property(x: float, seed: int) -> None:
    r = run_one("bit_flip", {"x": x}, make_ctx(seed, {"x": "float64"}))
    assert abs((r - math.trunc(r)) - (x - math.trunc(x))) <= math.ulp(r)
    assert is_flip_mask(abs(math.trunc(r)) ^ abs(math.trunc(x)), base.FLOAT_FLIP_WINDOW)


@pytest.mark.parametrize(
    ("ros_type", "value", "width"), [("int8", 127, 8), ("uint8", 0, 8), ("int16", -1, 16)]
)
def test_bit_flip_ints_two_complement(ros_type: str, value: int, width: int) -> None:
    lo, hi = INT_RANGES[ros_type]
    signs = set()
    for seed in range(200):
        r = run_one("bit_flip", {"x": value}, make_ctx(seed, {"x": ros_type}))
        assert type(r) is int and lo <= r <= hi
        mask = (1 << width) - 1
        assert is_flip_mask((r & mask) ^ (value & mask), width)
        signs.add(r < 0)
    if lo < 0:
        assert signs == {False, True}  # the sign bit is reachable


def test_bit_flip_reaches_high_bits_of_uint64_and_keeps_nsecs_in_range() -> None:
    tops = [run_one("bit_flip", {"x": 0}, make_ctx(seed, {"x": "uint64"})) for seed in range(200)]
    assert max(tops) >= 2**60
    for seed in range(200):
        out, _ = mutate({"t": {"secs": 0, "nsecs": 999_999_999}}, make_ctx(seed, {"t": "time"}), "bit_flip")
        assert 0 <= out["t"]["nsecs"] <= 999_999_999 and 0 <= out["t"]["secs"] < 2**32


def test_bit_flip_toggles_bools() -> None:
    assert run_one("bit_flip", {"x": True}, make_ctx(0, {"x": "bool"})) is False


# ----------------------------------------------------------------------------------------------------------
# arithmetic
# ----------------------------------------------------------------------------------------------------------


def test_arithmetic_float_deltas_are_bounded_and_span_magnitudes() -> None:
    deltas = []
    for seed in range(400):
        r = run_one("arithmetic", {"x": 1.0}, make_ctx(seed, {"x": "float64"}))
        delta = r - 1.0
        assert 0 < abs(delta) <= m.ARITH_MAX + 1e-12
        deltas.append(abs(delta))
    assert min(deltas) < 1e-6 and max(deltas) > 1.0
    signs = {
        math.copysign(1.0, run_one("arithmetic", {"x": 0.0}, make_ctx(s, {"x": "float64"})))
        for s in range(50)
    }
    assert signs == {1.0, -1.0}


@given(
    x=st.floats(min_value=-1e15, max_value=1e15, allow_nan=False, allow_infinity=False),
    seed=st.integers(0, 2**32),
)
@settings(max_examples=200, deadline=None, database=None, derandomize=True)
def test_arithmetic_delta_property(x: float, seed: int) -> None:
    r = run_one("arithmetic", {"x": x}, make_ctx(seed, {"x": "float64"}))
    assert abs(r - x) <= m.ARITH_MAX + 2 * math.ulp(abs(x) + m.ARITH_MAX)


def test_arithmetic_ints_wrap_within_width() -> None:
    wrapped = False
    for seed in range(300):
        r = run_one("arithmetic", {"x": 250}, make_ctx(seed, {"x": "uint8"}))
        assert type(r) is int and 0 <= r <= 255
        delta = (r - 250) % 256
        assert 1 <= delta <= m.ARITH_MAX or 256 - m.ARITH_MAX <= delta <= 255
        wrapped |= r < 250 - m.ARITH_MAX
    assert wrapped
    values = {run_one("arithmetic", {"x": -128}, make_ctx(s, {"x": "int8"})) for s in range(100)}
    assert any(v > 90 for v in values)  # -128 - k wraps to 128 - k


def test_arithmetic_wraps_nsecs() -> None:
    values = []
    for seed in range(200):
        out, _ = mutate(
            {"t": {"secs": 3, "nsecs": 999_999_990}}, make_ctx(seed, {"t": "duration"}), "arithmetic"
        )
        values.append(out["t"]["nsecs"])
    assert all(0 <= v <= 999_999_999 for v in values)
    assert any(v < 100 for v in values)


def test_arithmetic_skips_bools_and_strings() -> None:
    _, used = mutate({"b": True, "s": "x"}, make_ctx(0, {"b": "bool", "s": "string"}), "arithmetic")
    assert used != "arithmetic"


# ----------------------------------------------------------------------------------------------------------
# interesting
# ----------------------------------------------------------------------------------------------------------


def bits(x: float) -> bytes:
    return struct.pack("<d", x)


def test_interesting_floats_come_from_the_tables() -> None:
    allowed = {bits(v) for v in (*m.INTERESTING_FLOATS, *ENGINE_FLOATS)}
    seen = set()
    for seed in range(400):
        ctx = make_ctx(seed, {"x": "float64"}, interesting_floats=ENGINE_FLOATS)
        r = run_one("interesting", {"x": 1.0}, ctx)
        assert bits(r) in allowed
        seen.add(bits(r))
    assert {bits(v) for v in ENGINE_FLOATS} <= seen
    assert {bits(-0.0), bits(5e-324), bits(1.7976931348623157e308), bits(math.pi + 1e-9)} <= seen


def test_interesting_float_table_contents() -> None:
    table = {bits(v) for v in m.INTERESTING_FLOATS}
    expected = [0.0, -0.0, 1e-9, -1e-9, math.pi, -math.pi, math.pi / 2, 2 * math.pi, -3 * math.pi,
                5e-324, 2.2250738585072014e-308, 1e-300, 1e300, 1.7976931348623157e308,
                2.0**31, 2.0**53, 2.0**63, base.FLOAT32_MAX]  # fmt: skip
    assert {bits(v) for v in expected} <= table
    assert all(math.isfinite(v) for v in m.INTERESTING_FLOATS)


def test_interesting_float32_stays_in_range() -> None:
    seen = set()
    for seed in range(300):
        r = run_one("interesting", {"x": 1.0}, make_ctx(seed, {"x": "float32"}))
        assert abs(r) <= base.FLOAT32_MAX and struct.unpack("<f", struct.pack("<f", r))[0] == r
        seen.add(r)
    assert base.FLOAT32_MAX in seen


@pytest.mark.parametrize(
    ("ros_type", "must_see"),
    [("int8", {-128, 127, 0, -1}), ("uint16", {0, 65535, 4096}), ("int64", {-(2**63), 2**63 - 1, 2**31 - 1})],
)
def test_interesting_ints_are_filtered_by_width(ros_type: str, must_see: set[int]) -> None:
    lo, hi = INT_RANGES[ros_type]
    seen = set()
    for seed in range(400):
        r = run_one("interesting", {"x": 1}, make_ctx(seed, {"x": ros_type}))
        assert type(r) is int and lo <= r <= hi
        seen.add(r)
    assert must_see <= seen


def test_interesting_strings_and_times() -> None:
    strings = set()
    for seed in range(300):
        ctx = make_ctx(seed, {"x": "string"}, dictionary=("panda_link7",))
        strings.add(run_one("interesting", {"x": "abc"}, ctx))
    assert {"", "panda_link7", "%s%n%s%n"} <= strings
    assert max(len(s) for s in strings) >= 1000
    assert any(any(ord(c) > 127 for c in s) for s in strings)
    secs, nsecs = set(), set()
    for seed in range(400):
        out, _ = mutate({"t": {"secs": 1, "nsecs": 1}}, make_ctx(seed, {"t": "time"}), "interesting")
        secs.add(out["t"]["secs"])
        nsecs.add(out["t"]["nsecs"])
    assert {0, 2**32 - 1} <= secs and {0, 999_999_999} <= nsecs
    assert max(nsecs) <= 999_999_999


def test_bounded_strings_are_truncated() -> None:
    for seed in range(100):
        r = run_one("interesting", {"x": "ab"}, make_ctx(seed, {"x": "string<=3"}))
        assert len(r) <= 3


# ----------------------------------------------------------------------------------------------------------
# Combinations
# ----------------------------------------------------------------------------------------------------------


def spy_on(monkeypatch: pytest.MonkeyPatch, calls: list[tuple[str, Any]], names: tuple[str, ...]) -> None:
    for name in names:
        op = m.LEAF_OPS[name]

        def apply(value: Any, leaf: Any, message: Any, ctx: Any, _name: str = name, _op: LeafOp = op) -> Any:
            calls.append((_name, leaf.loc))
            return _op.apply(value, leaf, message, ctx)

        monkeypatch.setitem(m.LEAF_OPS, name, LeafOp(op.kinds, apply, op.accepts))


@pytest.mark.parametrize(
    ("comb", "parts"),
    [
        ("comb1", ("bit_flip", "arithmetic")),
        ("comb2", ("interesting", "bit_flip")),
        ("comb3", ("interesting", "arithmetic")),
        ("comb4", ("interesting", "bit_flip", "arithmetic")),
    ],
)
def test_combinations_apply_their_parts_to_one_leaf(
    monkeypatch: pytest.MonkeyPatch, comb: str, parts: tuple[str, ...]
) -> None:
    calls: list[tuple[str, Any]] = []
    spy_on(monkeypatch, calls, ("bit_flip", "arithmetic", "interesting"))
    for seed in range(50):
        calls.clear()
        _, used = mutate(all_types(), make_ctx(seed, ALL_TYPES), comb)
        assert used == comb
        assert tuple(name for name, _ in calls) == parts
        assert len({loc for _, loc in calls}) == 1


def test_comb3_is_an_interesting_value_plus_a_bounded_delta() -> None:
    table = {bits(v) for v in m.INTERESTING_FLOATS}
    off_table = 0
    for seed in range(200):
        r = run_one("comb3", {"x": 0.7}, make_ctx(seed, {"x": "float64"}))
        assert any(abs(r - v) <= m.ARITH_MAX * (1 + 1e-9) for v in m.INTERESTING_FLOATS)
        off_table += bits(r) not in table  # tiny deltas vanish on huge values
    assert off_table > 100


def test_comb_skips_a_part_that_cannot_apply(monkeypatch: pytest.MonkeyPatch) -> None:
    op = m.LEAF_OPS["interesting"]
    monkeypatch.setitem(m.LEAF_OPS, "interesting", LeafOp(op.kinds, lambda *args: math.nan, op.accepts))
    calls: list[tuple[str, Any]] = []
    spy_on(monkeypatch, calls, ("bit_flip",))
    r = run_one("comb2", {"x": 1.0}, make_ctx(0, {"x": "float64"}, allow_special=True))
    assert math.isnan(r) and calls == []
    # without allow_special the NaN is rejected and another mutator is used
    _, used = mutate({"x": 1.0}, make_ctx(0, {"x": "float64"}), "comb2")
    assert used != "comb2"


# ----------------------------------------------------------------------------------------------------------
# Future work: dictionary, havoc, splice
# ----------------------------------------------------------------------------------------------------------


def test_dictionary_replaces_and_inserts_typed_tokens() -> None:
    types = {"label": "string", "names": "string[]", "x": "float64", "n": "int8", "u": "uint8"}
    seed_msg = {"label": "a", "names": ["j1"], "x": 0.0, "n": 0, "u": 0}
    inserted = replaced = False
    for seed in range(300):
        ctx = make_ctx(seed, types, dictionary=("tok", 3.5, "42", 1000, -7))
        out, used = mutate(seed_msg, ctx, "dictionary")
        assert used == "dictionary"
        assert problems(out, seed_msg, types, allow_special=False) == []
        assert out["x"] in (0.0, 3.5, 42.0, 1000.0, -7.0)
        assert out["n"] in (0, 42, -7)  # 1000 does not fit an int8
        assert out["u"] in (0, 42)
        assert out["label"] in ("a", "tok", "42")
        inserted |= len(out["names"]) == 2
        replaced |= out["names"] == ["tok"] or out["label"] != "a"
    assert inserted and replaced


def test_dictionary_not_applicable_without_tokens() -> None:
    with pytest.raises(NotApplicable):
        MUTATORS["dictionary"](joint_state(), make_ctx(0, JS_TYPES))


def test_havoc_stacks_two_to_sixteen_mutations(monkeypatch: pytest.MonkeyPatch) -> None:
    counts: list[int] = []

    def spy(message: Message, ctx: MutationContext) -> Message:
        counts[-1] += 1
        return message

    monkeypatch.setattr(paper, "WEIGHTS", {"havoc": 1.0, "splice": 1.0, "spy": 1.0})  # what havoc draws from
    monkeypatch.setitem(m.MUTATORS, "spy", spy)
    monkeypatch.setitem(m.MUTATORS, "splice", lambda message, ctx: pytest.fail("havoc must not splice"))
    for seed in range(200):
        counts.append(0)
        MUTATORS["havoc"](joint_state(), make_ctx(seed, JS_TYPES, other=joint_state()))
    assert min(counts) == base.HAVOC_MIN_STACK and max(counts) == base.HAVOC_MAX_STACK


def test_havoc_changes_the_message() -> None:
    changed = sum(
        mutate(joint_state(), make_ctx(s, JS_TYPES), "havoc")[0] != joint_state() for s in range(100)
    )
    assert changed >= 95


def distinct_parents() -> tuple[Message, Message]:
    a = joint_state(seq=1, names=("a1", "a2", "a3", "a4"), position=(1.0, 2.0, 3.0, 4.0), frame="a")
    b = joint_state(
        seq=2,
        names=tuple(f"b{i}" for i in range(6)),
        position=(-1.0, -2.0, -3.0, -4.0, -5.0, -6.0),
        frame="b",
    )
    b["header"]["stamp"] = {"secs": 9, "nsecs": 9}
    return a, b


def test_splice_uses_both_parents() -> None:
    a, b = distinct_parents()
    seqs = set()
    for seed in range(100):
        child, used = mutate(a, make_ctx(seed, JS_TYPES, other=b), "splice")
        assert used == "splice"
        assert child != a and child != b
        assert problems(child, a, JS_TYPES, allow_special=False) == []
        for field in ("name", "position"):
            assert 4 <= len(child[field]) <= 6
            for index, item in enumerate(child[field]):  # aligned: element i comes from a[i] or b[i]
                assert item in [p[field][index] for p in (a, b) if index < len(p[field])]
        assert child["header"]["stamp"] in (a["header"]["stamp"], b["header"]["stamp"])
        seqs.add(child["header"]["seq"])
    assert seqs == {1, 2}


def test_splice_keeps_fixed_lengths_and_types() -> None:
    a, b = all_types(0), all_types(1)
    mixed = False
    for seed in range(100):
        child, _ = mutate(a, make_ctx(seed, ALL_TYPES, other=b), "splice")
        assert problems(child, a, ALL_TYPES, allow_special=False) == []
        mixed |= (
            any(x != y for x, y in zip(child["matrix"], a["matrix"], strict=True))
            and child["matrix"] != b["matrix"]
        )
    assert mixed


def test_splice_needs_other() -> None:
    with pytest.raises(NotApplicable):
        MUTATORS["splice"](joint_state(), make_ctx(0, JS_TYPES))
    _, used = mutate(joint_state(), make_ctx(0, JS_TYPES), "splice")
    assert used != "splice"


def test_crossover() -> None:
    for factory, types in CASES.values():
        for seed in range(20):
            assert crossover(factory(0), factory(0), make_ctx(seed, types)) == factory(0)
    a, b = distinct_parents()
    children = []
    for seed in range(20):
        child = crossover(a, b, make_ctx(seed, JS_TYPES))
        assert problems(child, a, JS_TYPES, allow_special=False) == []
        children.append(child)
    assert (a, b) == distinct_parents()
    assert all(child not in (a, b) for child in children)


# ----------------------------------------------------------------------------------------------------------
# libfuzzer
# ----------------------------------------------------------------------------------------------------------


class FakeMutate:
    """Records calls and returns a fixed output."""

    def __init__(self, output: bytes) -> None:
        self.output = output
        self.calls: list[tuple[bytes, int]] = []

    def __call__(self, data: bytes, max_size: int) -> bytes:
        self.calls.append((data, max_size))
        return self.output


@pytest.mark.parametrize(
    ("output", "expected"),
    [
        (struct.pack("<d", 42.0), 42.0),
        (struct.pack("<d", 42.0)[:3], struct.unpack("<d", struct.pack("<d", 42.0)[:3] + b"\0" * 5)[0]),
        (struct.pack("<d", -7.5) + b"tail", -7.5),
    ],
)
def test_libfuzzer_float64(output: bytes, expected: float) -> None:
    fake = FakeMutate(output)
    r = run_one("libfuzzer", {"x": 1.5}, make_ctx(0, {"x": "float64"}, libfuzzer_mutate=fake))
    assert fake.calls == [(struct.pack("<d", 1.5), 8)]
    assert r == expected


def test_libfuzzer_float32_and_string() -> None:
    fake = FakeMutate(struct.pack("<f", 0.75))
    assert run_one("libfuzzer", {"x": 2.0}, make_ctx(0, {"x": "float32"}, libfuzzer_mutate=fake)) == 0.75
    assert fake.calls == [(struct.pack("<f", 2.0), 4)]
    fake = FakeMutate(b"\xff\xfeok")
    assert (
        run_one("libfuzzer", {"x": "jo"}, make_ctx(0, {"x": "string"}, libfuzzer_mutate=fake))
        == "\ufffd\ufffdok"
    )
    assert fake.calls[0][0] == b"jo" and fake.calls[0][1] >= 2


def test_libfuzzer_rejects_special_results_unless_allowed() -> None:
    fake = FakeMutate(struct.pack("<d", math.inf))
    _, used = mutate({"x": 1.5}, make_ctx(0, {"x": "float64"}, libfuzzer_mutate=fake), "libfuzzer")
    assert used != "libfuzzer" and len(fake.calls) == base.LIBFUZZER_ATTEMPTS
    r = run_one(
        "libfuzzer", {"x": 1.5}, make_ctx(0, {"x": "float64"}, libfuzzer_mutate=fake, allow_special=True)
    )
    assert r == math.inf


def test_libfuzzer_needs_the_callable() -> None:
    with pytest.raises(NotApplicable):
        MUTATORS["libfuzzer"]({"x": 1.5}, make_ctx(0, {"x": "float64"}))


# ----------------------------------------------------------------------------------------------------------
# Robotics-aware mutators
# ----------------------------------------------------------------------------------------------------------


def test_sign_flip_wrap_2pi_and_zero() -> None:
    assert run_one("sign_flip", {"x": 1.25}, make_ctx(0, {"x": "float64"})) == -1.25
    assert math.copysign(1.0, run_one("sign_flip", {"x": 0.0}, make_ctx(0, {"x": "float64"}))) == -1.0
    shifts = set()
    for seed in range(100):
        r = run_one("wrap_2pi", {"x": 0.3}, make_ctx(seed, {"x": "float64"}))
        shifts.add(round(r - 0.3, 9))
    assert shifts == {round(v, 9) for v in (math.pi, -math.pi, 2 * math.pi, -2 * math.pi)}
    out, _ = mutate({"x": 2.5, "n": 0}, make_ctx(0, {"x": "float64", "n": "int32"}), "zero")
    assert out == {"x": 0.0, "n": 0} and type(out["x"]) is float
    _, used = mutate({"x": 0.0, "n": 0}, make_ctx(0, {"x": "float64", "n": "int32"}), "zero")
    assert used != "zero"


def lengths(msg: Message) -> dict[str, int]:
    return {key: len(value) for key, value in msg.items() if isinstance(value, list)}


def test_array_insert_and_delete_change_one_variable_array_by_one() -> None:
    seed_msg = all_types()
    before = lengths(seed_msg)
    fixed = {"matrix", "triple", "spans", "corners"}
    for name, step in (("array_insert", 1), ("array_delete", -1)):
        for seed in range(100):
            out, used = mutate(seed_msg, make_ctx(seed, ALL_TYPES), name)
            assert used == name
            diff = {k: v - before[k] for k, v in lengths(out).items() if v != before[k]}
            assert len(diff) == 1 and next(iter(diff.values())) == step
            assert not set(diff) & fixed


def test_array_insert_respects_bounds_and_empty_message_arrays() -> None:
    types = {"bounded": "int16[<=2]", "points": "pkg/Point[]", "points.x": "float64"}
    msg: Message = {"bounded": [1, 2], "points": []}
    _, used = mutate(msg, make_ctx(0, types), "array_insert")
    assert used != "array_insert"
    msg = {"bounded": [1], "points": [{"x": 1.0}]}
    for seed in range(50):
        out, _ = mutate(msg, make_ctx(seed, types), "array_insert")
        assert len(out["bounded"]) <= 2 and all(p.keys() == {"x"} for p in out["points"])


def test_array_duplicate() -> None:
    types = {"v": "float64[]", "f": "float64[3]"}
    for seed in range(100):
        out, _ = mutate({"v": [1.0, 2.0], "f": [4.0, 5.0, 6.0]}, make_ctx(seed, types), "array_duplicate")
        if len(out["v"]) == 3:
            assert out["v"] in ([1.0, 1.0, 2.0], [1.0, 2.0, 2.0]) and out["f"] == [4.0, 5.0, 6.0]
        else:
            assert out["v"] == [1.0, 2.0] and len(out["f"]) == 3 and len(set(out["f"])) == 2


def test_string_swap_uses_siblings_and_dictionary() -> None:
    seen = set()
    for seed in range(100):
        out, used = mutate(joint_state(), make_ctx(seed, JS_TYPES, dictionary=("tool0",)), "string_swap")
        assert used == "string_swap"
        seen.update(out["name"])
        seen.add(out["header"]["frame_id"])
    assert seen == {"joint_1", "joint_2", "tool0", ""}
    _, used = mutate({"s": "only"}, make_ctx(0, {"s": "string"}), "string_swap")
    assert used != "string_swap"


def test_compared_writes_a_threshold_or_a_value_just_either_side() -> None:
    near = {
        t + d
        for t in THRESHOLDS
        for d in (0.0, 1e-6 * max(1.0, t), -1e-6 * max(1.0, t), 1e-3 * max(1.0, t), -1e-3 * max(1.0, t))
    } | {math.nextafter(t, d) for t in THRESHOLDS for d in (math.inf, -math.inf)}
    written = set()
    for seed in range(200):
        seed_msg = joint_state(position=(0.1, 0.2))
        out = MUTATORS["compared"](seed_msg, full_ctx(seed, JS_TYPES, None))
        moved = [b for a, b in zip(seed_msg["position"], out["position"], strict=True) if a != b]
        assert len(moved) == 1 and moved[0] in near
        written.add(moved[0])
    assert written == near  # every neighbour of both thresholds comes up


def test_compared_writes_past_the_threshold_into_the_leaf_a_comparison_saw() -> None:
    """Input-to-state: ``x < 0.31`` only ever saw x = 1.2 and 0.5; the leaf holding 1.2 gets 0.31
    or a value just below it (the side never reached), three times in four."""
    table = ComparedValues()
    for x in (0.5, 1.2):
        table.watch(1, x, 0.31, False)
    below = {0.31, math.nextafter(0.31, -math.inf), 0.31 - 1e-6, 0.31 - 1e-3}
    crossed, written = 0, set()
    for seed in range(400):
        out = MUTATORS["compared"](joint_state(position=(0.1, 1.2)), make_ctx(seed, JS_TYPES, compared=table))
        if out["position"][0] == 0.1 and out["position"][1] in below:
            crossed += 1
            written.add(out["position"][1])
    assert written == below
    share = crossed / 400  # 0.75 by input-to-state, plus the random leaf's draws that land there
    assert 0.75 <= share <= 0.75 + 0.25 * 0.5 * 4 / 7 + 0.05
    unseen = [
        MUTATORS["compared"](joint_state(position=(0.1, 0.9)), make_ctx(s, JS_TYPES, compared=table))
        for s in range(400)
    ]
    random_leaf = 0.5 * 4 / 7  # no leaf matches: either leaf, then 4 of the 7 values near 0.31
    assert abs(sum(o["position"][1] in below for o in unseen) / 400 - random_leaf) < 0.06


def test_compared_crosses_from_a_leaf_on_the_threshold_to_the_side_never_reached() -> None:
    """``x < 0.31`` saw x = 1.2, then x = 0.31 (a leaf the mutator had set to the threshold): the
    leaf holding 0.31 gets a value below it, never one above (before: always above)."""
    table = ComparedValues()
    for x in (1.2, 0.31):
        table.watch(1, x, 0.31, x < 0.31)
    below = {math.nextafter(0.31, -math.inf), 0.31 - 1e-6, 0.31 - 1e-3}
    written = []
    for seed in range(200):
        out = MUTATORS["compared"](
            joint_state(position=(0.1, 0.31)), make_ctx(seed, JS_TYPES, compared=table)
        )
        if out["position"][0] == 0.1:
            written.append(out["position"][1])
    assert set(written) & below == below
    down = sum(v in below for v in written)
    up = sum(0.31 < v <= 0.31 + 1e-3 for v in written)  # only the random leaf's draws (1 in 8)
    assert down >= 0.7 * 200 and up <= 0.15 * 200, (down, up)


def test_compared_takes_a_leaf_at_a_band_edge_deeper_into_the_band() -> None:
    """``x < 0.31`` saw 1.2 (false), then 0.30999999999999994 (true, within ``EDGE``: not
    counted): the leaf at the edge gets 0.31 - 1e-3 whenever input-to-state picks it, never the
    threshold, the next float or 1e-6 below it (each of which left it at the edge, judged
    ill-conditioned by the scenario oracle, or undid the crossing)."""
    at_edge = math.nextafter(0.31, -math.inf)
    table = ComparedValues()
    for x in (1.2, at_edge):
        table.watch(1, x, 0.31, x < 0.31)
    written = []
    for seed in range(200):
        out = MUTATORS["compared"](
            joint_state(position=(0.1, at_edge)), make_ctx(seed, JS_TYPES, compared=table)
        )
        if out["position"][0] == 0.1:
            written.append(out["position"][1])
    deeper = sum(v == 0.31 - 1e-3 for v in written)
    at_the_edge = sum(v in (at_edge, 0.31 - 1e-6) for v in written)  # the random leaf's draws only
    assert deeper >= 0.7 * len(written) and at_the_edge <= 0.1 * len(written), (deeper, at_the_edge)


def _scaled_to_the_ratio_threshold(table: ComparedValues) -> float:
    """Share of 400 ``compared`` mutations of a (0.4, 0.8) message that scale a leaf by 1.001 /
    2.0 or just below it (the selected input compared a ratio of 2.0 with 1.001)."""
    below = {1.001, math.nextafter(1.001, -math.inf), 1.001 - 1e-6 * 1.001, 1.001 - 1e-3 * 1.001}
    scaled = 0
    for seed in range(400):
        out = MUTATORS["compared"](joint_state(position=(0.4, 0.8)), make_ctx(seed, JS_TYPES, compared=table))
        for before, after in zip((0.4, 0.8), out["position"], strict=True):
            if after != before and any(after == before * (t / 2.0) for t in below):
                scaled += 1
    return scaled / 400


def test_compared_scales_a_leaf_so_a_value_in_proportion_to_it_lands_past_the_threshold() -> None:
    """No leaf holds what ``ratio < 1.001`` compared (a ratio computed from the input: 2.0 for
    this parent): three times in four a leaf is scaled by 1.001 / 2.0 (or just below), so a ratio
    proportional to that leaf lands right past the threshold."""
    table = ComparedValues()
    table.watch(9, 3.0, 1.001, False)
    table.begin()
    table.watch(9, 2.0, 1.001, False)
    table.end(b"parent")
    table.select(b"parent")
    assert abs(_scaled_to_the_ratio_threshold(table) - 0.75) < 0.07
    table.select(b"another")  # an input that compared nothing there: the random leaf only
    outs = [
        MUTATORS["compared"](joint_state(position=(0.4, 0.8)), make_ctx(s, JS_TYPES, compared=table))
        for s in range(100)
    ]
    assert not any(
        a != b and a == b * (1.001 / 2.0)
        for o in outs
        for a, b in zip(o["position"], (0.4, 0.8), strict=True)
    )


def test_compared_scales_by_no_value_0() -> None:
    """``gap > 1e-6`` that compared 0.0 (an oracle's exact agreement) beside ``ratio < 1.001``
    at 2.0: no factor takes 0.0 past 1e-6, so 0.0 is no operand and the scaling step always uses
    the ratio, three times in four as with the ratio alone."""
    table = ComparedValues()
    table.watch(8, 0.5, 1e-6, True)
    table.watch(9, 3.0, 1.001, False)
    table.begin()
    table.watch(8, 0.0, 1e-6, True)
    table.watch(9, 2.0, 1.001, False)
    table.end(b"parent")
    table.select(b"parent")
    assert {t for t, _, _ in table.operands()} == {1.001}  # no operand of value 0
    assert abs(_scaled_to_the_ratio_threshold(table) - 0.75) < 0.07


def test_compared_writes_the_middle_of_a_band_a_value_was_compared_against() -> None:
    """``0.3 <= x < 0.31`` (two sites) only ever saw x = 1.2 and 0.5: the leaf holding 1.2 gets
    the band's middle, 0.305, half the times input-to-state picks it, a value past one edge
    otherwise; one threshold alone never gives a middle."""
    table = ComparedValues()
    for x in (0.5, 1.2):
        table.watch(1, 0.3, x, x >= 0.3)  # always true: unsolved
        table.watch(2, x, 0.31, x < 0.31)  # always false: unsolved
    middles = 0
    for seed in range(400):
        out = MUTATORS["compared"](joint_state(position=(0.1, 1.2)), make_ctx(seed, JS_TYPES, compared=table))
        middles += out["position"][1] == pytest.approx(0.305, abs=1e-15)
    share = middles / 400  # input-to-state (0.75), then the middle (0.5)
    assert abs(share - 0.75 * 0.5) < 0.07
    single = ComparedValues()
    for x in (0.5, 1.2):
        single.watch(2, x, 0.31, x < 0.31)
    outs = [
        MUTATORS["compared"](joint_state(position=(0.1, 1.2)), make_ctx(s, JS_TYPES, compared=single))
        for s in range(200)
    ]
    assert not any(o["position"][1] == pytest.approx(0.305, abs=1e-9) for o in outs)


def test_compared_does_not_apply_without_a_known_threshold() -> None:
    for table in (None, ComparedValues()):
        with pytest.raises(NotApplicable):
            MUTATORS["compared"](joint_state(position=(0.1, 0.2)), make_ctx(0, JS_TYPES, compared=table))
