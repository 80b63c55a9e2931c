"""Source decoding keeps every byte: encodings, BOMs, line endings."""

from __future__ import annotations

import pytest

from rapidfix.rapid import parse_program
from rapidfix.rapid.source import decode_source, dominant_newline

BODY = "MODULE M\n! Schweißnaht, 90°\nPROC main()\n  TPWrite \"Grüße\";\nENDPROC\nENDMODULE"


@pytest.mark.parametrize("encoding,bom,expected", [
    ("utf-8", b"", "utf-8"),
    ("utf-8", b"\xef\xbb\xbf", "utf-8"),
    ("cp1252", b"", "cp1252"),
    ("utf-16-le", b"\xff\xfe", "utf-16-le"),
])
@pytest.mark.parametrize("newline", ["\n", "\r\n"])
@pytest.mark.parametrize("final", ["", "\n"])
def test_round_trip_bytes(encoding, bom, expected, newline, final):
    text = (BODY + final).replace("\n", newline)
    data = bom + text.encode(encoding)
    program = parse_program(data, "x.mod")
    assert program.encoding == expected
    assert program.bom == bom
    assert program.newline == newline
    assert program.to_bytes() == data
    assert program.source.encode() == data
    string = program.routines[0].syntax.body[0].args[0].value.value
    assert string == "Grüße"


def test_latin1_fallback_keeps_undefined_cp1252_bytes():
    data = b"MODULE M\n! \x81\x8d\x8f\x90\x9d\xe9\nENDMODULE\n"
    program = parse_program(data)
    assert program.encoding == "latin-1"
    assert program.source.encode() == data


def test_mixed_newlines():
    text = "MODULE M\r\nVAR num a;\nVAR num b;\nENDMODULE\r\n"
    source = decode_source(text.encode())
    assert source.newline == "\n"
    assert dominant_newline("a\r\nb\r\nc\n") == "\r\n"
    program = parse_program(text.encode())
    assert [d.span.line for d in program.declarations] == [2, 3]


def test_line_column_of_offsets():
    source = decode_source("ab\ncd\r\nef")
    assert source.line_column(0) == (1, 1)
    assert source.line_column(4) == (2, 2)
    assert source.line_column(8) == (3, 2)
    assert source.line_start(4) == 3
    assert source.line_end(4) == 7
