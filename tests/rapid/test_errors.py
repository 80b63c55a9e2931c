"""Syntax errors: one readable message at the right line and column."""

from __future__ import annotations

import pytest

from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid import load_program, parse_program


def error_of(text: str | bytes, filename: str = "prog.mod") -> RapidSyntaxError:
    with pytest.raises(RapidSyntaxError) as info:
        parse_program(text, filename)
    return info.value


def test_missing_comma_position_and_message():
    err = error_of("MODULE M\nPROC main()\n  MoveL p10, v100 z10, tool0;\nENDPROC\nENDMODULE\n")
    assert (err.file, err.line, err.column) == ("prog.mod", 3, 19)
    text = str(err)
    assert text.startswith("prog.mod:3:19: unexpected 'z10'; expected one of ")
    assert "','" in text and "';'" in text
    assert "\n" not in text


def test_position_with_crlf_and_bom():
    data = b"\xef\xbb\xbfMODULE M\r\nPROC main()\r\n  x := 1 +;\r\nENDPROC\r\nENDMODULE"
    err = error_of(data)
    assert (err.line, err.column) == (3, 11)
    assert "unexpected ';'" in str(err)


def test_unexpected_character():
    err = error_of("MODULE M\nPROC main()\n  x := 1 @ 2;\nENDPROC\nENDMODULE")
    assert (err.line, err.column) == (3, 10)
    assert "unexpected '@'" in err.message


def test_unexpected_end_of_file():
    err = error_of("MODULE M\nPROC main()\n  x := 1;\n")
    assert err.line == 4
    assert "unexpected end of file" in err.message
    assert "'ENDPROC'" in err.message


# Placeholders where their kind may stand are RAPID (tests/rapid/test_real_world_constructs.py);
# elsewhere they are named as the error.
@pytest.mark.parametrize("placeholder,line,column", [
    ("  x := <SMT>;", 3, 8),
    ("  IF a <EXP> THEN ENDIF", 3, 8),
    ("  MoveL p1, v100, z10, tool0 <ARG>;", 3, 30),
    ("  <TDN>", 3, 3),
    ("  <FOO>;", 3, 3),
])
def test_robotstudio_placeholders_where_they_cannot_stand(placeholder, line, column):
    err = error_of(f"MODULE M\nPROC main()\n{placeholder}\nENDPROC\nENDMODULE")
    assert (err.line, err.column) == (line, column)
    assert "placeholder <" in err.message and "unfinished code" in err.message


def test_a_placeholder_that_parsed_is_not_blamed_for_a_later_error():
    err = error_of("MODULE M\nPROC main()\n  <SMT>\n  x := <EXP>; y := ;\nENDPROC\nENDMODULE")
    assert (err.line, err.column) == (4, 20)
    assert "placeholder" not in err.message and "<EXP>" not in err.message


def test_placeholder_in_string_or_comment_is_not_reported():
    err = error_of('MODULE M\nPROC main()\n  ! <SMT>\n  TPWrite "<EXP>";\n  x := ;\n'
                   "ENDPROC\nENDMODULE")
    assert "placeholder" not in err.message
    assert (err.line, err.column) == (5, 8)


def test_text_after_last_endmodule():
    err = error_of("MODULE M\nENDMODULE\n! trailing comment is fine\nPROC x()\n")
    assert (err.line, err.column) == (4, 1)
    assert err.message.startswith("text after the last ENDMODULE: 'PROC'")


def test_comment_after_endmodule_is_fine():
    program = parse_program("MODULE M\nENDMODULE\n! end of file\n\n")
    assert program.modules[0].name == "M"


def test_not_starting_with_module():
    err = error_of("PROC main()\nENDPROC\n")
    assert (err.line, err.column) == (1, 1)
    assert "starts with MODULE" in err.message


def test_empty_file():
    err = error_of("")
    assert "end of file" in err.message


def test_binary_file(tmp_path):
    path = tmp_path / "image.mod"
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR")
    with pytest.raises(RapidSyntaxError) as info:
        load_program(path)
    assert info.value.file == str(path)
    assert "not RAPID text" in str(info.value)


def test_bom_on_a_legacy_file_is_kept_not_refused():
    data = b"\xef\xbb\xbfMODULE M\n! \xe9\xb0\nENDMODULE"
    program = parse_program(data)
    assert program.encoding == "cp1252" and program.bom == b"\xef\xbb\xbf"
    assert program.source.encode() == data


def test_bad_utf16_is_not_text():
    err = error_of(b"\xff\xfeM\x00O\x00\x00\xd8")
    assert "not RAPID text" in err.message and err.file == "prog.mod"



def test_unterminated_string():
    err = error_of('MODULE M\nPROC main()\n  TPWrite "no end;\nENDPROC\nENDMODULE')
    assert (err.line, err.column) == (3, 11)
    assert err.message.startswith("unterminated string")
