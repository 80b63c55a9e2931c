"""Span edits keep every untouched byte; formatted literals parse back to the same values."""

from __future__ import annotations

import math

import pytest

from rapidfix.rapid import load_program, parse_program
from rapidfix.rapid.edit import EditConflict, Editor
from rapidfix.rapid.format import (
    format_declaration,
    format_jointtarget,
    format_num,
    format_robtarget,
    format_string,
    format_tooldata,
    format_value,
)

UNUSED = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"
CRLF_CP1252 = (
    "MODULE M\r\n! Träger °\r\n"
    f"  CONST robtarget p10:=[[1,2,3],[0,0,1,0],[0,0,0,0],{UNUSED}];\r\n"
    "  PROC main()\r\n    MoveL p10, v100, z10, tool0;\r\n  ENDPROC\r\nENDMODULE"
).encode("cp1252")


def test_no_edits_gives_identical_bytes(rapid_samples):
    for path in rapid_samples:
        program = load_program(path)
        assert Editor(program).render() == path.read_bytes()


def test_rewrite_move_to_moveabsj_keeps_encoding_and_newlines():
    program = parse_program(CRLF_CP1252, "old.mod")
    (move,) = program.motions
    decl = program.declaration("p10")
    editor = Editor(program)
    literal = format_jointtarget([10.5, -20, 30, 0, 45.123456789, -180])
    editor.insert_declaration_after(decl, format_declaration("CONST", "jointtarget",
                                                             "jp10", literal))
    editor.replace_statement(move, "MoveAbsJ jp10, v100, z10, tool0;")
    out = editor.render()
    expected = CRLF_CP1252.replace(
        b"]];\r\n  PROC",
        b"]];\r\n  CONST jointtarget jp10:=" + literal.encode() + b";\r\n  PROC",
    ).replace(b"MoveL p10, v100, z10, tool0;", b"MoveAbsJ jp10, v100, z10, tool0;")
    assert out == expected
    assert b"Tr\xe4ger \xb0" in out
    rewritten = parse_program(out)
    assert rewritten.encoding == "cp1252" and rewritten.newline == "\r\n"
    assert rewritten.motions[0].name == "MoveAbsJ"
    assert rewritten.motions[0].target.data.robax == (10.5, -20.0, 30.0, 0.0, 45.123457,
                                                      -180.0)


def test_replace_value_and_argument_span():
    text = f"MODULE M\nCONST robtarget p:=[[1,2,3],[1,0,0,0],[0,0,0,0],{UNUSED}];\n" \
           "PROC main()\n  MoveL p, v100, z10, tool0 \\WObj:=wobj0;\nENDPROC\nENDMODULE\n"
    program = parse_program(text)
    editor = Editor(program)
    editor.replace_value(program.declaration("p"),
                         format_robtarget((4, 5, 6.25), (1, 0, 0, 0), (0, -1, 2, 0)))
    editor.replace(program.motions[0].speed.value_span, "v200")
    editor.replace(program.motions[0].wobj.span, "")
    out = parse_program(editor.render())
    assert out.declaration("p").data.trans == (4.0, 5.0, 6.25)
    assert out.declaration("p").data.robconf == (0, -1, 2, 0)
    assert out.motions[0].speed.text == "v200" and out.motions[0].wobj is None
    assert editor.text().count("\n") == text.count("\n")


def test_insert_declaration_into_module_area_and_file_without_final_newline():
    program = parse_program("MODULE M\n  PROC main()\n  ENDPROC\nENDMODULE")
    editor = Editor(program)
    editor.insert_declaration(program.modules[0], "CONST num a:=1;")
    assert editor.text() == "MODULE M\n  CONST num a:=1;\n  PROC main()\n  ENDPROC\nENDMODULE"
    program = parse_program("MODULE M\nVAR num b;\nENDMODULE")
    editor = Editor(program)
    editor.insert_declaration(program.modules[0], "VAR num c;")
    assert editor.text() == "MODULE M\nVAR num b;\nVAR num c;\nENDMODULE"
    program = parse_program("MODULE M\nVAR num b;ENDMODULE")
    editor = Editor(program)
    editor.insert_line_after(program.modules[0].span, "! end")
    assert editor.text() == "MODULE M\nVAR num b;ENDMODULE\n! end"


def test_overlapping_edits_are_refused():
    program = parse_program("MODULE M\nVAR num b := 12345;\nENDMODULE")
    editor = Editor(program)
    decl = program.declaration("b")
    editor.replace(decl.span, "VAR num b;")
    editor.replace(decl.value_span, "1")
    with pytest.raises(EditConflict):
        editor.render()


def test_insertions_at_one_offset_keep_call_order():
    program = parse_program("MODULE M\nENDMODULE")
    editor = Editor(program)
    editor.insert(9, "VAR num a;\n")
    editor.insert(9, "VAR num b;\n")
    assert editor.text() == "MODULE M\nVAR num a;\nVAR num b;\nENDMODULE"


def test_lines_after_one_anchor_code_follows_stand_together():
    """New lines after an anchor that code follows on its line go right after it, and
    that code on a line of its own: given by several calls, they stand together (no
    empty line between them), in the order of the calls, after any anchor."""
    text = (f"MODULE M\n  CONST robtarget p1:=[[1,2,3],[0,0,1,0],[0,0,0,0],{UNUSED}];"
            " PROC main() MoveL p1, v100, z10, tool0; ENDPROC ENDMODULE\n")
    program = parse_program(text)
    anchor = program.declarations[0].span
    editor = Editor(program)
    editor.insert_line_after(anchor, "CONST num a:=1;")
    editor.insert_lines_after([(anchor.start, anchor.end)], [["CONST num b:=2;", "! b"]])
    editor.insert_line_after(anchor, "CONST num c:=3;")
    rest = editor.text().partition("];\n")[2]
    assert rest == ("  CONST num a:=1;\n  CONST num b:=2;\n  ! b\n  CONST num c:=3;\n"
                    " PROC main() MoveL p1, v100, z10, tool0; ENDPROC ENDMODULE\n")
    assert len(parse_program(editor.text()).declarations) == 4


def test_text_that_cannot_be_encoded_is_a_clear_error():
    program = parse_program(CRLF_CP1252)
    editor = Editor(program)
    editor.insert(0, "! \u4e2d\n")
    with pytest.raises(Exception) as info:
        editor.render()
    assert "cp1252" in str(info.value) and info.type.__name__ == "RapidSyntaxError"


@pytest.mark.parametrize("value,text", [
    (0.0, "0"), (-0.0, "0"), (12.5, "12.5"), (-3.0, "-3"), (1e-6, "0.000001"),
    (1e-7, "0"), (9e9, "9E+09"), (-1.5e10, "-1.5E+10"), (123456.123456789, "123456.123457"),
])
def test_format_num(value, text):
    assert format_num(value) == text


def test_format_num_refuses_nan():
    with pytest.raises(ValueError):
        format_num(math.nan)


def test_formatted_values_parse_back():
    tool = format_tooldata((0.5, -1, 200), (0.7071068, 0, 0.7071068, 0), 2.5, (0, 0, 80))
    rt = format_robtarget((1.23456, -7, 1e-5), (0.5, 0.5, -0.5, 0.5), (-1, 0, 2, 1))
    quoted = format_string('a "b" c')
    text = (f"MODULE M\nCONST tooldata t:={tool};\nCONST robtarget r:={rt};\n"
            f"CONST string s:={quoted};\n"
            f"CONST num v{{2,2}}:={format_value(((1.5, True), ('x', -2.0)))};\nENDMODULE")
    program = parse_program(text)
    t = program.declaration("t").data
    assert t.tframe.trans == (0.5, -1.0, 200.0) and t.tload.mass == 2.5 and t.robhold
    r = program.declaration("r").data
    assert r.trans == (1.2346, -7.0, 0.0) and r.robconf == (-1, 0, 2, 1)
    assert r.extax == (9e9,) * 6
    assert program.declaration("s").value == 'a "b" c'
    assert program.declaration("v").value == ((1.5, True), ("x", -2.0))


def test_an_editor_renders_the_same_bytes_after_letting_the_program_go():
    """`release_program` keeps only what rendering needs (the source text, its encoding
    and line endings): the bytes are the same, and the program itself is gone."""
    import gc
    import weakref

    def edited(release: bool) -> tuple[bytes, bool]:
        program = parse_program(CRLF_CP1252)
        editor = Editor(program)
        motion = program.motions[0]
        editor.replace(motion.span, "MoveAbsJ jt_°, v100, z10, tool0;")
        editor.insert_declaration(program.modules[0], "CONST num n:=1;\n! zwei Zeilen")
        ref = weakref.ref(program)
        if release:
            editor.release_program()
        del program, motion
        return editor.render(), ref() is None

    gc.disable()  # gone by reference counts alone, as in the rewrite
    try:
        kept, kept_gone = edited(False)
        released, released_gone = edited(True)
    finally:
        gc.enable()
    assert released == kept and (kept_gone, released_gone) == (False, True)
    assert b"jt_\xb0, v100" in released
    assert b"\r\n  CONST num n:=1;\r\n  ! zwei Zeilen\r\n" in released


@pytest.mark.parametrize("source", [
    "MODULE M\n  VAR num a;\n  PROC p()\n  ENDPROC\nENDMODULE\n",
    "MODULE M\r\n\tVAR num a;\r\nENDMODULE",  # CRLF, a tab, no final line end
    "MODULE M\nENDMODULE",  # no declaration: after the MODULE line, at the end of the file
])
@pytest.mark.parametrize("lines", [
    ["CONST num b:=1;"],
    ["CONST num b:=1;", "LOCAL CONST num c:=2;", "! ° ok"],
    ["CONST num b:=1;", "", "CONST num c:=2;"],  # an empty line gets no indentation
    ["CONST num b:=1;", "! two\nlines"],
])
def test_declarations_given_as_lines_are_written_as_their_joined_text(source, lines):
    """`insert_declaration` takes the lines of what it inserts (kept as they are until the
    output renders, not joined into one more string): the bytes are those of the joined
    text, whatever the line ends, indentation and end of the file."""
    def rendered(text) -> bytes:
        program = parse_program(source)
        editor = Editor(program)
        editor.insert_declaration(program.modules[0], text)
        return editor.render()

    joined = rendered("\n".join(lines))
    assert rendered(list(lines)) == joined
    if source.startswith("MODULE M\n  VAR") and len(lines) == 3 and "" in lines:
        assert joined == (b"MODULE M\n  VAR num a;\n  CONST num b:=1;\n\n  CONST num c:=2;\n"
                          b"  PROC p()\n  ENDPROC\nENDMODULE\n")
