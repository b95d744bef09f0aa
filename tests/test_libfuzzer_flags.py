"""libFuzzer's options checked before a campaign hands them over
(``fuzzer.input.libfuzzer_flags``): the integer flags' ranges and the ``-dict`` grammar of
libFuzzer's ``ParseDictionaryFile`` (the hostile command lines run them end to end)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzer.input.libfuzzer_flags import check_dictionary, check_int_flags, dictionary_entry_ok


@pytest.mark.parametrize(
    "flags", [(), ("-runs=-1", "-seed=0", "-jobs=2", "-max_len=0"), ("-seed=4294967295",), ("-only_ascii=1",)]
)
def test_integer_flags_in_range_pass(flags: tuple[str, ...]) -> None:
    check_int_flags(flags)


@pytest.mark.parametrize(
    ("flag", "says"),
    [
        ("-seed=abc", "-seed takes an integer from 0"),
        ("-seed=-3", "-seed takes an integer from 0"),
        ("-seed=4294967296", "to 4294967295"),
        ("-runs=-2", "-runs takes an integer from -1"),
        ("-runs=4294967296", "-runs takes an integer from -1 to 2147483647"),  # libFuzzer ran 0
        ("-use_cmp=abc", "-use_cmp takes an integer"),  # libFuzzer read 0: tracing off, silently
        ("-mutate_depth=0", "-mutate_depth takes an integer from 1"),
        ("-jobs", "-jobs takes an integer"),  # no value at all
        ("-jobs=", "-jobs takes an integer"),
        ("-workers=2.5", "-workers takes an integer"),
        ("-timeout=" + "9" * 5000, "-timeout takes an integer"),  # past int()'s 4,300 digits
        ("-max_len=١٢", "-max_len takes an integer"),  # Unicode digits: isdecimal, not C's
    ],
)
def test_integer_flags_out_of_range_or_not_integers_are_named(flag: str, says: str) -> None:
    with pytest.raises(ValueError, match=says):
        check_int_flags(("-runs=3", flag))


@pytest.mark.parametrize(
    "line",
    [b'"a"', b'kw="a"', b'  kw = "a b"  ', b'"\\x41"', b'"\\\\"', b'"\\""', b'"say \\"hi\\""', b'"\t"'],
)
def test_entries_libfuzzer_takes(line: bytes) -> None:
    assert dictionary_entry_ok(line)


@pytest.mark.parametrize(
    "line",
    [
        b'""',  # an empty value
        b'kw=""',
        b'"a" # a comment after it',
        b"a",
        b'"a',
        b'a"',
        b'"\\q"',  # an unknown escape
        b'"\\t"',  # so is \t (a tab itself is taken)
        b'"\\x4"',  # half a hex escape
        b'"\\xZZ"',
        b'"caf\xc3\xa9"',  # bytes past ASCII: not isprint in the C locale
        b'"\x01"',
    ],
)
def test_entries_libfuzzer_refuses(line: bytes) -> None:
    assert not dictionary_entry_ok(line)


def test_a_dictionary_file_is_checked_line_by_line(tmp_path: Path) -> None:
    path = tmp_path / "d.dict"
    path.write_bytes(b'# comment\n\n   \n  # indented comment\nkw="1"\n"2"\r\n')
    check_dictionary(path)
    path.write_bytes(b'"1"\n"2" junk\n')
    with pytest.raises(ValueError, match="line 2 is not a libFuzzer dictionary entry"):
        check_dictionary(path)
    path.write_bytes(b"")
    with pytest.raises(ValueError, match="an empty file"):
        check_dictionary(path)
    with pytest.raises(ValueError, match="cannot be read"):
        check_dictionary(tmp_path)
