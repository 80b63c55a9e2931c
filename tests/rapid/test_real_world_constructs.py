"""Constructs met in RAPID programs written by others, each in a minimal text of our own.

A corpus of a few hundred public RAPID files (RobotStudio backups, CAM output,
student labs, system modules) was run through `rapidfix check` and `rapidfix
rewrite`; every construct it refused that the RAPID kernel manual allows has a
test here.
"""

from __future__ import annotations

import pytest

from rapidfix.cli import main
from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid import parse_program

TARGET = "[[400,-50.5,300],[0,0,1,0],[0,0,-1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"


# ---------------------------------------------------------------- ISO 8859-1 names
# RAPID's character set is ISO 8859-1: its accented letters are letters, so they
# may stand in identifiers (a Spanish cell names a routine after the letter Ñ).
LATIN1_MODULE = "\n".join([
    "MODULE Letras",
    f"  CONST robtarget pÑ:={TARGET};",
    "  PERS tooldata herramientaÉ:=[TRUE,[[0,0,120],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];",
    "  PROC Ñ()",
    "    MoveL pÑ, v100, fine, herramientaÉ;",
    "    MoveL Offs(PÑ, 0, 0, 25), v100, fine, HERRAMIENTAÉ;",
    "  ENDPROC",
    "  PROC Año_2024()",
    "    Ñ;",
    "  ENDPROC",
    "ENDMODULE",
    "",
])


def test_latin1_letters_in_names_parse_and_resolve_case_insensitively():
    program = parse_program(LATIN1_MODULE, "letras.mod")
    first, offset = program.motions
    assert first.target.name == "pÑ" and first.target.static
    assert first.target.data.trans == (400.0, -50.5, 300.0)
    assert first.tool.name == "herramientaÉ"
    # RAPID compares names without case: PÑ is pÑ, HERRAMIENTAÉ is herramientaÉ
    assert program.declaration("pñ") is program.declaration("PÑ") is not None
    assert offset.target.static and offset.target.data.trans == (400.0, -50.5, 325.0)
    assert offset.tool.declaration is program.declaration("herramientaé")


def test_latin1_names_in_a_cp1252_file_are_checked_ok(tmp_path, capsys):
    path = tmp_path / "letras.mod"
    path.write_bytes(LATIN1_MODULE.replace("\n", "\r\n").encode("cp1252"))
    assert main(["check", str(path)]) == 0
    assert "2 motion instructions" in capsys.readouterr().out


@pytest.mark.parametrize("sign", ["×", "÷"])
def test_signs_of_iso_8859_1_are_not_letters(sign):
    # × and ÷ are in the same block as the accented letters but are not letters
    with pytest.raises(RapidSyntaxError) as caught:
        parse_program(f"MODULE M\n  VAR num a{sign}b;\nENDMODULE\n", "signs.mod")
    assert (caught.value.line, caught.value.column) == (2, 12)


# ---------------------------------------------------------------- placeholders
# RobotStudio writes placeholders for code not yet written; the RAPID manual
# counts a program holding them as syntactically correct (the controller loads
# it, and stops with an error only where it meets one). Such programs are
# checked and compensated; each placeholder stays where and as it is.
PLACEHOLDER_MODULE = "\n".join([
    "MODULE Unfinished",
    "  <TDN>",
    "  <DDN>",
    f"  CONST robtarget pA:={TARGET};",
    "  PROC main()",
    "    <DDN>",
    "    VAR num a{<DIM>};",
    "    <SMT>",
    "    MoveL pA, v100, fine, tool0;",
    "    MoveL <ARG>, v100, fine, tool0;",
    "    MoveJ <EXP>, v100, fine, tool0 \\WObj:=wobj0;",
    "    <VAR> := Offs(pA, 0, 0, <EXP>);",
    "    IF a{1} = 1 THEN",
    "      <SMT>",
    "    <EIT>",
    "    ELSE",
    "      MoveL Offs(pA, 10, 0, 0), v100, fine, tool0;",
    "    ENDIF",
    "    IF a{1} = 2 <SMT>",
    "    TEST a{1}",
    "    <CSE>",
    "    CASE 2:",
    "      <ID>;",
    "    ENDTEST",
    "  ENDPROC",
    "  PROC move(<PAR> \\<ALT> | num b)",
    "    <SMT>",
    "  ENDPROC",
    "  <RDN>",
    "ENDMODULE",
    "",
])


def _line_column(text: str, needle: str, occurrence: int = 0) -> tuple[int, int]:
    at = -1
    for _ in range(occurrence + 1):
        at = text.index(needle, at + 1)
    before = text[:at]
    return before.count("\n") + 1, at - before.rfind("\n")


def test_placeholders_stand_where_their_kind_belongs():
    from rapidfix.rapid import syntax as s

    program = parse_program(PLACEHOLDER_MODULE, "unfinished.mod")
    module = program.syntax.modules[0]
    items = [i.text for i in module.items if isinstance(i, s.Placeholder)]
    assert items == ["<TDN>", "<DDN>", "<RDN>"]
    main_routine, move = (i for i in module.items if isinstance(i, s.Routine))
    statements = [st for st, _ in s.walk_statements(main_routine.body)]
    kinds = [st.text for st in statements if isinstance(st, s.StatementPlaceholder)]
    assert kinds == ["<DDN>", "<SMT>", "<SMT>", "<EIT>", "<SMT>"]
    compact = next(st for st in statements if isinstance(st, s.CompactIf))
    assert compact.statement.text == "<SMT>"
    test = next(st for st in statements if isinstance(st, s.Test))
    (placeholder_values, placeholder_body), (values, _) = test.cases
    assert [v.text for v in placeholder_values] == ["<CSE>"] and placeholder_body == []
    assert values[0].value == 2
    assert [p.name for p in move.parameters] == ["<PAR>", "<ALT>", "b"]
    assert move.parameters[1].optional and move.parameters[1].alternatives == ("<ALT>", "b")
    # every placeholder node spans exactly its text
    for node in (*module.items[:2], *(st for st in statements if hasattr(st, "text"))):
        assert PLACEHOLDER_MODULE[node.start:node.end] == node.text


def test_targets_beside_placeholders_are_resolved_and_placeholders_are_not():
    program = parse_program(PLACEHOLDER_MODULE, "unfinished.mod")
    by_text = {m.target.text: m for m in program.motions}
    assert by_text["pA"].target.static
    assert by_text["pA"].target.data.trans == (400.0, -50.5, 300.0)
    assert by_text["Offs(pA, 10, 0, 0)"].target.data.trans == (410.0, -50.5, 300.0)
    for text in ("<ARG>", "<EXP>"):
        target = by_text[text].target
        assert not target.static
        assert f"placeholder {text}" in target.reason
        assert _line_column(PLACEHOLDER_MODULE, f" {text},")[0] == by_text[text].span.line


def test_a_program_with_placeholders_is_checked_ok_and_kept_byte_for_byte(tmp_path, capsys):
    from rapidfix.rapid.edit import Editor

    path = tmp_path / "unfinished.mod"
    data = PLACEHOLDER_MODULE.replace("\n", "\r\n").encode("utf-8")
    path.write_bytes(data)
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    # check says the program is unfinished, and where the first placeholder stands
    count = sum(PLACEHOLDER_MODULE.count(p) for p in (
        "<TDN>", "<DDN>", "<DIM>", "<SMT>", "<ARG>", "<EXP>", "<VAR>", "<EIT>", "<CSE>",
        "<ID>", "<PAR>", "<ALT>", "<RDN>"))
    assert f"4 motion instructions, {count} placeholders (code not yet written, " \
           f"the first <TDN> at {_line_column(PLACEHOLDER_MODULE, '<TDN>')[0]}:3)" in out
    program = parse_program(data, str(path))
    assert program.to_bytes() == data
    move = next(m for m in program.motions if m.target.text == "pA")
    editor = Editor(program)
    editor.replace_statement(move, "MoveAbsJ jA, v100, fine, tool0;")
    rendered = editor.render()
    assert rendered == data.replace(b"MoveL pA, v100, fine, tool0;",
                                    b"MoveAbsJ jA, v100, fine, tool0;")


# ---------------------------------------------------------------- .prg headers
def test_an_unclosed_prg_header_is_named_as_such():
    with pytest.raises(RapidSyntaxError) as caught:
        parse_program("%%%\n  VERSION:1\n  LANGUAGE:ENGLISH\nMODULE M\nENDMODULE\n", "open.prg")
    assert (caught.value.line, caught.value.column) == (1, 1)
    assert caught.value.message.startswith("unclosed %%% header")
    # closed, the same text is a program
    parse_program("%%%\n  VERSION:1\n  LANGUAGE:ENGLISH\n%%%\nMODULE M\nENDMODULE\n", "closed.prg")


# ---------------------------------------------------------------- names
@pytest.mark.parametrize("text,line,column,word", [
    ("MODULE 1_T_ROB2\nENDMODULE\n", 1, 8, "1_T_ROB2"),
    ("MODULE M\n  VAR num 2nd := 1;\nENDMODULE\n", 2, 11, "2nd"),
    ("MODULE M\n  PROC 3D_print()\n  ENDPROC\nENDMODULE\n", 2, 8, "3D_print"),
])
def test_a_name_that_starts_with_a_digit_is_named_in_the_error(text, line, column, word):
    with pytest.raises(RapidSyntaxError) as caught:
        parse_program(text, "digits.mod")
    assert (caught.value.line, caught.value.column) == (line, column)
    assert caught.value.message == f"{word!r} is not a name (a RAPID name starts with a letter)"


def test_a_number_where_a_name_belongs_keeps_the_plain_message():
    with pytest.raises(RapidSyntaxError) as caught:
        parse_program("MODULE M\n  VAR num 1.5;\nENDMODULE\n", "number.mod")
    assert caught.value.message.startswith("unexpected '1.5'")


# ---------------------------------------------------------------- arc welding
# Since RobotWare 6 the weave of ArcL/ArcC/... is the optional argument \Weave;
# before, it was a required argument between Weld and Zone. Every arc welding
# call of the corpus (815) is of the newer form; both are read.
ARC_MODULE = "\n".join([
    "MODULE Weld",
    "  PERS tooldata tWeld:=[TRUE,[[0,0,400],[1,0,0,0]],[2,[0,0,100],[1,0,0,0],0,0,0]];",
    f"  CONST robtarget p1:={TARGET};",
    f"  CONST robtarget p2:={TARGET};",
    "  PROC main()",
    "    ArcLStart p1, v100, seam1, weld1 \\Weave:=weave1, fine, tWeld \\WObj:=wobj0;",
    "    ArcL p2, v100, seam1, weld1, z1, tWeld;",
    "    ArcL p1, v100, seam1, weld1, z1, tWeld;",
    "    ArcL p2, v100, seam1, weld1, weave1, z5, tWeld;",
    "    ArcC p1, p2, v100, seam1, weld1 \\Weave:=weave1, z10, tWeld;",
    "    ArcCEnd p1, p2, v100, seam1, weld1, weave1, fine, tWeld;",
    "    ArcLEnd p2, v100, seam1, weld1, fine, tWeld;",
    "  ENDPROC",
    "ENDMODULE",
    "",
])


def test_arc_welding_moves_with_and_without_a_required_weave_find_zone_and_tool():
    program = parse_program(ARC_MODULE, "weld.mod")
    rows = [(m.name, m.zone.text, m.tool.text, m.optional.get("weave") is not None,
             m.arguments.get("weave") is not None) for m in program.motions]
    assert rows == [
        ("ArcLStart", "fine", "tWeld", True, False),
        ("ArcL", "z1", "tWeld", False, False),
        ("ArcL", "z1", "tWeld", False, False),
        ("ArcL", "z5", "tWeld", False, True),   # the older form: weave required
        ("ArcC", "z10", "tWeld", True, False),
        ("ArcCEnd", "fine", "tWeld", False, True),
        ("ArcLEnd", "fine", "tWeld", False, False),
    ]
    for move in program.motions:
        assert move.tool.static and move.tool.data.tframe.trans == (0.0, 0.0, 400.0)
        assert [t.text for t in move.targets] == (["p1", "p2"] if "C" in move.name[3:]
                                                  else [move.target.text])
