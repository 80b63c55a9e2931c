"""Every construct of the language parses, and lands in the syntax tree as written."""

from __future__ import annotations

import pytest

from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid import parse_program
from rapidfix.rapid import syntax as s


def in_proc(body: str, data: str = "") -> str:
    """A module with `data` at module level and `body` inside PROC main()."""
    return f"MODULE T\n{data}\nPROC main()\n{body}\nENDPROC\nENDMODULE\n"


STATEMENTS = [
    "x := 1;",
    "x := -y;",
    "x := +y;",
    "arr{1} := 2;",
    "buf{i+1, j} := buf{i, j - 1};",
    "p.trans.x := p.trans.x + 10;",
    "parts{2}.count := 3;",
    "Stop;",
    "Stop \\NoRegain;",
    "MoveL p10, v100, z10, tool0;",
    "MoveL \\Conc, p10, v100, z10, tool0 \\WObj:=wobj1;",
    "MoveL p10, v100, fine \\Inpos:=inpos50, tool0;",
    "MoveL p10, v100 \\T:=3, z10 \\Z:=45, tool0 \\WObj:=wobj1 \\TLoad:=load1;",
    "MoveL p10, v100\\V:=1000, z10, tool0\\WObj:=wobj1;",
    "MoveJ p10, v100, z10, tool0 \\WObj?WObj;",
    "MoveL ToPoint:=p10, Speed:=v100, Zone:=z10, Tool:=tool0;",
    "MoveL p10,\n  v100,\n  z10,\n  tool0\n  \\WObj:=wobj1;",
    "SetDO \\SDelay:=0.2, do1, 1;",
    "TPWrite \"Value: \" \\Num:=reg1;",
    "TPWrite \"a \"\"quoted\"\" \\\\ word \\41\";",
    "%\"proc\" + NumToStr(i, 0)%;",
    "%procname% \\Opt, 1, 2;",
    "IF a THEN x := 1; ENDIF",
    "IF a THEN x := 1; ELSEIF b THEN x := 2; ELSEIF c THEN x := 3; ELSE x := 4; ENDIF",
    "IF a > 1 x := 2;",
    "IF a GOTO lbl;\nlbl:",
    "IF NOT a AND NOT b OR c XOR d THEN ENDIF",
    "IF a <> b AND c <= d AND e >= f AND g < h AND i > j AND k = l THEN ENDIF",
    "IF a\n  AND b\n  AND c THEN\nENDIF",
    "FOR i FROM 1 TO 10 DO ENDFOR",
    "FOR i FROM 10 TO 1 STEP -2 DO x := i; ENDFOR",
    "WHILE TRUE DO WaitTime .5; ENDWHILE",
    "TEST x CASE 1: a := 1; CASE 2, 3, 4: a := 2; DEFAULT: a := 0; ENDTEST",
    "TEST x CASE 1: ENDTEST",
    "lbl:",
    "GOTO lbl;\nlbl:",
    "RETURN;",
    "RAISE;",
    "RAISE ERR_MY;",
    "EXIT;",
    "RETRY;",
    "TRYNEXT;",
    "CONNECT intno1 WITH trap1;",
    "CONNECT ints{2} WITH trap1;",
    "x := 0x1F + 0X0a + 0b101 + 0o17;",
    "x := 9E+09 + 1.5e-3 + .5 + 1. + 3E2;",
    "x := a * b / c DIV d MOD e - f + g;",
    "x := (a + b) * (c - d);",
    "x := Abs(-1) + Sqrt(4);",
    "p := CRobT(\\Tool:=tool1 \\WObj:=wobj0);",
    "p := RelTool(p1, 0, 0, 10 \\Rx:=5 \\Ry:=10\\Rz:=15);",
    "z := CRobT().trans.z;",
    "p := [[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
    "p := [[a,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
    "t := [TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];",
    "s := \"\";",
    "b := TRUE AND false;",
    "MoveL Offs(p10, 0, 0, 10), v100, z10, tool0;",
    "! a comment with MoveL and ; inside\nx := 1; ! trailing comment",
    "move_l10 := 1;",
    "step := 1;",
]

DATA = [
    "VAR num x;",
    "VAR num x := 1;",
    "PERS num x := 1;",
    "CONST num x := 1;",
    "LOCAL VAR num x;",
    "TASK PERS num x := 1;",
    "LOCAL PERS num x := 1;",
    "VAR num a{3} := [1, 2, 3];",
    "VAR num a{2,3} := [[1,2,3],[4,5,6]];",
    "VAR num a{2,2,2};",
    "CONST num n := 2; VAR num a{n * 2};",
    "RECORD rec num a; string b; ENDRECORD",
    "LOCAL RECORD rec num MoveL; bool Stop; pos Set; ENDRECORD",
    "ALIAS num level;",
    "LOCAL ALIAS num level;",
    "CONST robtarget p := [[1,2,3],[1,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
    "CONST robtarget p :=\n  [[1,2,3],\n   [1,0,0,0],\n   [0,0,0,0],\n"
    "   [9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
    "CONST tooldata t := [TRUE,[[0,0,0],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];",
]

ROUTINES = [
    "PROC p() ENDPROC",
    "LOCAL PROC p() ENDPROC",
    "PROC p(num a, VAR num b, PERS num c, INOUT num d) ENDPROC",
    "PROC p(\\switch On | switch Off, \\num X) ENDPROC",
    "PROC p(num a \\num b \\switch c) ENDPROC",
    "PROC p(\\num a, num b{*}, num c{*,*}) ENDPROC",
    "PROC p(\n  num a,\n  \\num b\n  \\switch c) ENDPROC",
    "PROC p() VAR num i; i := 1; ENDPROC",
    "PROC p() x := 1; BACKWARD x := 2; ERROR RETRY; UNDO x := 3; ENDPROC",
    "PROC p() ERROR (ERR_DIVZERO, 41) TRYNEXT; ENDPROC",
    "FUNC num f(num a) RETURN a * 2; ENDFUNC",
    "LOCAL FUNC bool f() RETURN TRUE; ERROR (ERR_X) RETURN FALSE; ENDFUNC",
    "TRAP t x := 1; ENDTRAP",
    "TRAP t ERROR RETURN; ENDTRAP",
]


@pytest.mark.parametrize("statement", STATEMENTS)
def test_statement_parses(statement):
    program = parse_program(in_proc(statement))
    routine = program.routines[0].syntax
    assert routine.body or routine.data  # something was parsed into the routine


@pytest.mark.parametrize("data", DATA)
def test_module_data_parses(data):
    program = parse_program(f"MODULE T\n{data}\nENDMODULE\n")
    assert program.modules[0].syntax.items


@pytest.mark.parametrize("routine", ROUTINES)
def test_routine_parses(routine):
    program = parse_program(f"MODULE T\n{routine}\nENDMODULE")
    assert len(program.routines) == 1


def test_module_attributes_and_several_modules():
    program = parse_program(
        "MODULE A(SYSMODULE, NOVIEW, NOSTEPIN, VIEWONLY, READONLY)\nENDMODULE\n"
        "module b\nendmodule\n"
    )
    assert [m.name for m in program.modules] == ["A", "b"]
    assert program.modules[0].attributes == ["SYSMODULE", "NOVIEW", "NOSTEPIN", "VIEWONLY",
                                             "READONLY"]


def test_prg_header():
    text = "%%%\n  VERSION:1\n  LANGUAGE:ENGLISH\n%%%\n\nMODULE M\nENDMODULE\n"
    program = parse_program(text)
    assert program.header == "%%%\n  VERSION:1\n  LANGUAGE:ENGLISH\n%%%"


def test_keywords_case_insensitive():
    program = parse_program(
        "module m\n proc P()\n  if A then\n   x:=1;\n  elseif b then\n  else\n  endif\n"
        "  For i from 1 to 2 step 1 do endfor\n endproc\nEndModule"
    )
    body = program.routines[0].syntax.body
    assert isinstance(body[0], s.If) and len(body[0].branches) == 2
    assert isinstance(body[1], s.For) and body[1].step is not None


def test_expression_precedence():
    program = parse_program(in_proc("x := a OR b AND NOT c = d + e * -f;"))
    value = program.routines[0].syntax.body[0].value
    assert isinstance(value, s.Binary) and value.op == "OR"
    rhs = value.right
    assert rhs.op == "AND"
    assert isinstance(rhs.right, s.Unary) and rhs.right.op == "NOT"
    relation = rhs.right.operand
    assert relation.op == "="
    assert relation.right.op == "+"
    assert relation.right.right.op == "*"
    assert isinstance(relation.right.right.right, s.Unary)


def test_arguments_kinds_and_spans():
    text = in_proc("MoveL \\Conc, p10, v100, z10, tool0 \\WObj:=wobj1 \\Corr;"
                   " Foo \\A?B, x:=1;")
    program = parse_program(text)
    move, foo = program.routines[0].syntax.body
    kinds = [(a.kind, a.name) for a in move.args]
    assert kinds == [("optional", "Conc"), ("required", None), ("required", None),
                     ("required", None), ("required", None), ("optional", "WObj"),
                     ("optional", "Corr")]
    assert text[move.args[5].start:move.args[5].end] == "\\WObj:=wobj1"
    assert text[move.start:move.end].endswith("\\Corr;")
    assert foo.args[0].kind == "conditional" and foo.args[0].condition == "B"
    assert foo.args[1].name == "x"


def test_record_field_named_like_instruction_and_reserved_context():
    program = parse_program("MODULE M\nRECORD r num MoveL; bool Stop; num Task; ENDRECORD\n"
                            "ENDMODULE")
    record = program.modules[0].syntax.items[0]
    assert [f.name for f in record.fields] == ["MoveL", "Stop", "Task"]


def test_label_on_its_own_line():
    program = parse_program(in_proc("  GOTO next;\nnext:\n  Stop;"))
    body = program.routines[0].syntax.body
    assert [type(x).__name__ for x in body[:2]] == ["Goto", "Label"]
    assert isinstance(body[2], s.ProcedureCall) and body[2].name == "Stop"


@pytest.mark.parametrize("bad", [
    "x := 1",  # missing ;
    "IF a THEN x := 1;",  # missing ENDIF
    "x := (1 + 2;",
    "MoveL p10 v100, z10, tool0;",
    "FOR i := 1 TO 2 DO ENDFOR",
    "x := 1 +;",
    "x := 1 2;",
    "ENDPROC := 1;",
])
def test_invalid_statements_are_syntax_errors(bad):
    with pytest.raises(RapidSyntaxError):
        parse_program(in_proc(bad))
