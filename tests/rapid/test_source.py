"""Source decoding keeps every byte: encodings, BOMs, line endings."""

from __future__ import annotations

import pytest

from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid import parse_program
from rapidfix.rapid.source import decode_source, dominant_newline

BODY = "MODULE M\n! Schweißnaht, 90°\nPROC main()\n  TPWrite \"Grüße\";\nENDPROC\nENDMODULE"


@pytest.mark.parametrize("encoding,bom,expected", [
    ("utf-8", b"", "utf-8"),
    ("utf-8", b"\xef\xbb\xbf", "utf-8"),
    ("cp1252", b"", "cp1252"),
    ("utf-16-le", b"\xff\xfe", "utf-16-le"),
])
@pytest.mark.parametrize("newline", ["\n", "\r\n", "\r"])
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
    assert program.kept_bytes is None  # the text gives them back: not held twice
    string = program.routines[0].syntax.body[0].args[0].value.value
    assert string == "Grüße"


def test_latin1_fallback_keeps_undefined_cp1252_bytes():
    data = b"MODULE M\n! \x81\x8d\x8f\x90\x9d\xe9\nENDMODULE\n"
    program = parse_program(data)
    assert program.encoding == "latin-1"
    assert program.source.encode() == data


def test_bytes_the_text_does_not_give_back_are_kept(monkeypatch):
    """A file whose decoded text would not encode back to exactly its bytes keeps them
    (none is known: the rule is a guard), so `original` and an output without edits
    are still the file as read; a string's text is checked once, when it is read."""
    from rapidfix.rapid.edit import Editor
    from rapidfix.rapid.parse import decode_for_model
    from rapidfix.rapid.source import SourceText

    data = b"MODULE M\nVAR num a;\nENDMODULE\n"
    monkeypatch.setattr(SourceText, "encode", lambda self, text=None: b"other")
    decoded, kept = decode_for_model(data, "x.mod")
    assert kept is data and decoded.text == data.decode()
    program = parse_program(data, "x.mod")
    assert program.kept_bytes is data and program.original is data
    assert Editor(program).render() is data
    monkeypatch.undo()
    with pytest.raises(RapidSyntaxError, match="cannot be written"):
        parse_program("MODULE M\n! \ud800\nENDMODULE\n", "s.mod")


def test_mixed_newlines():
    text = "MODULE M\r\nVAR num a;\nVAR num b;\nENDMODULE\r\n"
    source = decode_source(text.encode())
    assert source.newline == "\n"
    assert dominant_newline("a\r\nb\r\nc\n") == "\r\n"
    program = parse_program(text.encode())
    assert [d.span.line for d in program.declarations] == [2, 3]


def test_lone_cr_lines_are_read_as_lines():
    """A file whose lines all end in a lone CR (old Mac editors): its text has LF there,
    so a comment ends with its line and errors name the line an editor shows."""
    text = "MODULE M\r  ! a comment\r  VAR num a;\r  VAR num b;\rENDMODULE\r"
    source = decode_source(text.encode())
    assert source.newline == "\r" and source.text_newline == "\n"
    assert source.text == text.replace("\r", "\n")
    assert source.encode() == text.encode()
    program = parse_program(text.encode())
    assert [d.span.line for d in program.declarations] == [3, 4]
    with pytest.raises(RapidSyntaxError) as err:
        parse_program(text.replace("VAR num b;", "VAR num b").encode(), "cr.mod")
    assert (err.value.line, err.value.column) == (5, 1)
    with pytest.raises(RapidSyntaxError) as err:  # a binary byte: its line too
        parse_program(text.replace("VAR num b;", "VAR num b;\x01").encode(), "cr.mod")
    assert err.value.line == 4
    legacy = text.replace("a comment", "Schweißnaht")  # not UTF-8: CP1252
    source = decode_source(legacy.encode("cp1252"))
    assert source.encoding == "cp1252" and source.newline == "\r"
    with pytest.raises(RapidSyntaxError) as err:  # a character the encoding lacks
        source.encode(source.text.replace("num b", "num \u4e00"))
    assert (err.value.line, err.value.column) == (4, 11)
    # one LF anywhere: the file's CRs are not line ends but whitespace, as the grammar says
    mixed = "MODULE M\r  VAR num a;\n  VAR num b;\rENDMODULE\n"
    assert decode_source(mixed.encode()).text == mixed


def test_line_column_of_offsets():
    source = decode_source("ab\ncd\r\nef")
    assert source.line_column(0) == (1, 1)
    assert source.line_column(4) == (2, 2)
    assert source.line_column(8) == (3, 2)
    assert source.line_start(4) == 3
    assert source.line_end(4) == 7
