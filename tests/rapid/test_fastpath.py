"""The fast path (whole-run tokens) builds exactly the syntax tree of the plain grammar.

Every comparison parses the same text with rapid.lark alone and with the fast
terminals added, and compares the trees node by node (types, offsets, values).
"""

from __future__ import annotations

import dataclasses
import re

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lark.exceptions import UnexpectedInput

from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid import fast_blocks, fastpath, parse_program
from rapidfix.rapid import syntax as s
from rapidfix.rapid.fastpath import (
    TAIL_LIMIT,
    Memo,
    NotFast,
    aggregate_value,
    fast_parser,
    grouped_value,
    parse_text,
    shared_aggregate_value,
)
from rapidfix.rapid.grammar import rapid_parser
from rapidfix.rapid.source import decode_source
from rapidfix.rapid.syntax import Call, ProcedureCall
from rapidfix.rapid.transform import numeric_aggregate_value

UNUSED = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"
TARGET = f"[[1,-2.5,3E2],[1,0,0,0],[0,-1,2,0],{UNUSED}]"
# as many programs are written by hand: whitespace after the commas, groups on their lines
SPACED = TARGET.replace(",", ", ").replace("], [", "],\n\t[", 1)


def shape(node: object) -> object:
    """A syntax tree as nested tuples: node type, then every field."""
    if dataclasses.is_dataclass(node):
        return (
            # a LazyCall is a ProcedureCall (a LazyFunctionCall a Call) whose args are
            # made when asked for
            "ProcedureCall" if isinstance(node, ProcedureCall)
            else "Call" if isinstance(node, Call) else type(node).__name__,
            *(shape(getattr(node, f.name)) for f in dataclasses.fields(node)),
        )
    if isinstance(node, (list, tuple)):
        return tuple(shape(item) for item in node)
    return node


def plain_tree(text: str) -> object:
    return shape(rapid_parser().parse(text))


def module(*lines: str, newline: str = "\n") -> str:
    return newline.join(["MODULE M", *lines, "ENDMODULE", ""])


def routine(*lines: str) -> str:
    return module("PROC main()", *("  " + line for line in lines), "ENDPROC")


def test_every_sample_takes_the_fast_path_to_the_same_tree(rapid_samples):
    for path in rapid_samples:
        text = decode_source(path.read_bytes(), str(path)).text
        assert shape(fast_parser().parse(text)) == plain_tree(text), path.name


FAST = {
    "moves": routine("MoveL p1,v100,z1,tool0\\WObj:=wobj1;", "MoveJ p2, v200, fine, tool0;"),
    "switch first, no comma before an option": routine(
        "MoveL \\Conc, p1, v100, z10, tool0 \\WObj:=w1;", "MoveL p1, v100, z10, tool0\\Conc;"
    ),
    "spread over lines": routine("MoveL p1,\n    v100,\r\n    z1, tool0 \\WObj:=w;"),
    "CRLF and Ctrl-Z": module(
        "PROC main()", "  MoveL p1,v100,z1,tool0;\x1a", "ENDPROC", newline="\r\n"
    ),
    "inline targets": routine(
        f"MoveL {TARGET},v100,z1,tool0;", f"MoveC {TARGET}, {TARGET}, v100, z1, tool0;"
    ),
    "numbers": routine("Foo 0x1F, 0b101, 0o17, .5, 9E+09, 1.5e-3, 2.;", "WaitTime 0.5;"),
    "no arguments": routine("Stop;", "Path_10;", "ENDPROCx;"),
    "long and unusual argument lists": routine(
        "Foo 1, 2, 3, 4, 5, 6, 7, 8;",
        "Foo 1, 2, 3, 4, 5, 6, 7, 8, 9 \\A:=3;",
        "Foo a \\A \\B \\C \\D \\E:=1;",
        "Foo \\A, \\B, a;",
        "Foo a \\B, c;",
        "Foo a, [1,2], [[1,2],[3]] \\V:=[1,2,3,4] \\W:=.5;",
        "MoveL p1 , v100 , z1 , tool0 \\WObj := w , \\Conc ;",
        "Foo.5;WaitTime 1;Stop ;",
    ),
    "function calls and negated numbers": routine(
        "MoveL Offs(p1,0,0,-10),v100,z1,tool0\\WObj:=w;",
        "MoveL RelTool( p1 , 0, -0.5, 5 \\Rz:=-90 \\Ry:=2.5), v100, z1, tool0;",
        "MoveC Offs(p1,0,1,0), Offs (p2,[1,2],- 0x1F,.5e-3), v100, z1, tool0;",
        "Foo -1, - 2.5 \\A:=-3, Abs(-1), f(), g(\\B), h(a \\B:=1, c);",
        "Foo\n  Offs(\r\n p1,\t0,0,\n1), v100;",
    ),
    "calls of calls": module(
        f"CONST robtarget p1:={TARGET};",
        "CONST robtarget q:=Offs(RelTool(p1,0,0,1),0,0,1);",
        "PROC main()",
        "  MoveL Offs(RelTool(p1,0,0,0),0,0,0),v100,z1,tMill\\WObj:=wPlate;",
        "  MoveL Offs( RelTool (p1, 0, 0, 0.75 \\Rz:=2) ,0.75,0,0), v100, z1, t;",
        "  MoveL RelTool(Offs(p1,1,2,3),0,0,-1\\Rx:=5),v100,z1,t;",
        "  Foo f(g(), h(\\A), k(1 \\B:=2, [1,2])), -1;",
        "  MoveC Offs(RelTool(c1,0,0,1),0,1,0), p2, v100, z1, t;",
        "ENDPROC",
    ),
    "comments between statements": module(
        "! head", "CONST num a:=1; ! a", "! MoveL p1; CONST num b:=2;", "CONST num c:=3;",
        "PROC main()", "  MoveL p1,v100,z1,tool0; ! to p1", "  ! MoveL p2,v1,z1,t; ;;",
        "", "  !", "  MoveL p2,v100,z1,tool0;\r", "  ! crlf\r", "  Stop; !", "ENDPROC",
        "! last, without a newline after ENDMODULE",
    ),
    "keywords as plain names": routine("MoveL Step, v100, z1, tool0 \\WObj:=Default;"),
    "module data": module(
        "CONST robtarget p1:=" + TARGET + ";",
        "const robtarget p2 := " + TARGET + " ;",
        "LOCAL PERS num n:=3;",
        "TASK VAR num k;",
        "LOCAL TASK PERS num m := k;",
        "VAR robtarget p3;",
        "PERS loaddata l:=[1.8,[0,0,40],[1,0,0,0],0,0,0];",
        "CONST speeddata v:=[40,500,5000,1000];",
    ),
    "routine data": routine(
        "VAR num i;", "VAR num j:=2;", "CONST num k := 5;", "Foo i;", "VAR num late:=1;"
    ),
    "nested bodies": routine(
        "IF a THEN",
        "  Foo 1;",
        "  Bar;",
        "ELSEIF b THEN",
        "  Baz;",
        "ELSE",
        "  Qux;",
        "ENDIF",
        "FOR i FROM 1 TO 3 DO",
        "  Foo i;",
        "ENDFOR",
        "WHILE c DO",
        "  Foo;",
        "ENDWHILE",
        "TEST n",
        "CASE 1, 2:",
        "  Foo;",
        "DEFAULT:",
        "  Bar;",
        "ENDTEST",
    ),
    "handlers": module(
        "PROC main()",
        "  Foo;",
        "ERROR",
        "  Bar;",
        "  RETRY;",
        "UNDO",
        "  Baz;",
        "ENDPROC",
        "FUNC num f()",
        "  Foo;",
        "  RETURN 1;",
        "ERROR (1, 2)",
        "  Bar;",
        "  TRYNEXT;",
        "ENDFUNC",
    ),
    "ISO 8859-1 letters in names": module(
        f"CONST robtarget pÑ:={TARGET};", f"CONST robtarget Año:={TARGET};", "VAR num ß;",
        "PROC Ñandú()", "  MoveL pÑ,v100,z1,tool0;", "  MoveL p1,v100,z1,herramientaÑ;",
        "  MoveL Offs(Año,0,0,ß),v100,z1,tool0\\WObj:=mesaÉ;", "  Ünter;", "  MoveL p1,v1,z1,t;",
        "  Foo \\Ø;", "  Bar;", "ENDPROC",
    ),
    "dimensions given by names": module(
        "CONST num nMax:=10;", "VAR robtarget buf{nMax};",
        "PERS num grid{nRows, 2}:=[[1,2],[3,4]];", "VAR num e{ 2 , nCols };",
        "PROC main()", "  Stop;", "ENDPROC",
    ),
}

MIXED = {
    "statement keywords in a run": routine(
        "Foo;", "EXIT;", "Bar;", "RETURN;", "Baz;", "GOTO lbl;", "lbl:", "Qux;"
    ),
    "expression arguments": routine(
        "Foo TRUE, FALSE;", "Foo NOT b;", "Foo a + 1;", "Foo -1;", 'TPWrite "x";', "Foo p.x, a{2};"
    ),
    "named and conditional arguments": routine(
        "MoveL ToPoint:=p1, v100, z1, tool0;", "Foo \\A?B;", "Foo \\A:=1+2;"
    ),
    "comments inside and between": routine(
        "MoveL p1, v100, ! note\n z1, tool0;", "Foo; ! after", "! line", "Bar;"
    ),
    "other aggregates": routine(
        "Foo [ 1, 2 ];", "Foo [[[1]]];", "Foo [1,[2,3]];", "Foo [a, 1];", "Foo Offs(p1, 0, 0, 10);"
    ),
    "calls the fast path leaves to the grammar": routine(
        "Foo f(g(h(1)));", "Foo f(1+2);", "Foo f(-a);", "Foo f(x:=1);",
        "Foo f(\\A?B);", "Foo f(1) + 1;", "Foo -1 * 2;", "Foo f(\"s\");", "Foo --1;",
        "Foo f(TRUE);", "Foo f(NOT a);", "Foo 1 -1;", "Foo f (1);",
    ),
    "other data": module(
        "CONST num n := -1;",
        'CONST string s := "x";',
        "VAR num a{3} := [1,2,3];",
        "CONST bool b := TRUE;",
        "CONST num m := n * 2;",
    ),
    "compact IF and assignments": routine(
        "IF a MoveL p1, v100, z1, tool0;", "x := 1;", "IF a Foo;", "Foo;", '%"name"% 1;'
    ),
    "RobotStudio placeholders between simple statements": module(
        "<TDN>", "CONST num n:=1;", "<DDN>", "VAR num a{<DIM>};", "PROC main()",
        "  MoveL p1,v100,z1,tool0;", "  <SMT>", "  MoveL p2,v100,z1,tool0;", "  <DDN>",
        "  MoveL <ARG>,v100,z1,tool0;", "  MoveL p3,v100,z1,tool0;", "  Foo <EXP>, <ID>;",
        "  <VAR> := 1;", "  Bar;", "  IF a THEN", "    Foo;", "  <EIT>", "  ENDIF",
        "  IF a <SMT>", "  TEST a", "  <CSE>", "  ENDTEST", "ENDPROC",
        "PROC p(<PAR>, \\<ALT>)", "ENDPROC", "<RDN>",
    ),
    "calls whose second argument varies too": routine(
        # the text after the first argument is new, after the second known: two
        # leading arguments and a shared tail; then the same call again, one
        "MoveL p1, v100, z1, tool0;", "MoveC c1, p2, v100, z1, tool0;",
        "MoveC c2, p3, v100, z1, tool0;", "MoveL p4, v200, z1, tool0;",
        "MoveL p5, v200, z1, tool0;", "MoveC Offs(c1,0,1,0), -1, v100, z1, tool0;",
        "MoveC c1, RelTool(p2,0,0,1 \\Rz:=5), v100, z1, tool0;", "MoveC c1, p2, v100, z1, tool0;",
        "Foo 1, [1,2], \\A, v100, z1, tool0;", "Foo 1, [1,2],v100, z1, tool0;",
        "Foo 2, [1,2],v100, z1, tool0;",
    ),
    "arrays of targets and their elements": module(
        f"CONST robtarget path{{3}}:=[{TARGET},{TARGET},\n  {TARGET}];",
        f"VAR robtarget grid{{2,1}} := [ {TARGET} ,\n\t{TARGET} ];",
        "CONST num n{2}:=[1,2];", "PERS num m{ 3 }:=[[1],[2],[3]];", "VAR num e{2};",
        "CONST robtarget odd{2}:=[[[1,2]],[[3]]];",
        # two-dimensional arrays of targets: aggregates four levels deep, rows over lines
        f"CONST robtarget grid2{{2,2}}:=[[{TARGET},{TARGET}],\n    [{TARGET},{TARGET}]];",
        f"PERS robtarget grid3{{1,2}} := [ [ {TARGET} , {TARGET} ] ];", "PROC main()",
        "  MoveL path{1},v100,z1,tool0;", "  MoveL path {n{1}}, v100, z1, tool0;",
        "  MoveL grid{2, 1},v100,z1,tool0 \\WObj:=w;", "  MoveL path{i},v100,z1,tool0;",
        "  Foo path{0x2}, e{1} \\A:=n{2};", "  MoveL Offs(path{1},0,0,1),v100,z1,tool0;",
        "  MoveL grid2{2,1},v100,z1,tool0;", "  MoveL grid2{12,007},v100,z1,tool0;",
        "ENDPROC",
    ),
}


@pytest.mark.parametrize("name", sorted(FAST))
def test_simple_statements_take_the_fast_path_to_the_same_tree(name):
    text = FAST[name]
    assert shape(fast_parser().parse(text)) == plain_tree(text)


@pytest.mark.parametrize("name", ["function calls and negated numbers", "calls of calls",
                                  "ISO 8859-1 letters in names", "dimensions given by names"])
def test_calls_of_values_and_latin1_names_are_read_in_runs(name):
    from rapidfix.rapid.readback import Run, run_parser

    module = run_parser().parse(FAST[name]).modules[0]
    body = next(item for item in module.items if isinstance(item, s.Routine)).body
    assert body and all(isinstance(item, Run) for item in body)
    assert all(isinstance(item, (Run, s.Routine)) for item in module.items)


def test_comments_between_statements_stay_in_one_run():
    from rapidfix.rapid.readback import Run, read_bulk, run_parser

    text = FAST["comments between statements"]
    module = run_parser().parse(text).modules[0]
    assert [type(item).__name__ for item in module.items] == ["Run", "Routine"]
    assert len(module.items[1].body) == 1 and isinstance(module.items[1].body[0], Run)
    bulk = read_bulk(text)
    assert [c[0] for c in bulk.calls] == ["MoveL", "MoveL", "Stop"]
    assert sorted(bulk.data[("m", None)]) == ["a", "c"]


@pytest.mark.parametrize("name", sorted(MIXED))
def test_other_statements_parse_to_the_same_tree(name):
    text = MIXED[name]
    assert shape(parse_text(text)) == plain_tree(text)


def test_a_bad_number_in_an_aggregate_falls_back_and_is_reported():
    text = routine("MoveL [[1.2.3,0,0],[1,0,0,0],[0,0,0,0]," + UNUSED + "],v100,z1,tool0;")
    with pytest.raises(NotFast):
        fast_parser().parse(text)
    with pytest.raises(RapidSyntaxError) as err:
        parse_program(text, "bad.mod")
    assert err.value.file == "bad.mod" and err.value.line == 3


def test_errors_are_those_of_the_plain_grammar():
    text = routine("MoveL p1,v100,z1,tool0;", "MoveL p2,v100 z1,tool0;", "MoveL p3,v1,z1,t;")
    with pytest.raises(RapidSyntaxError) as err:
        parse_program(text, "cam.mod")
    assert (err.value.line, err.value.column) == (4, 17)
    assert "unexpected 'z1'" in err.value.message


@pytest.mark.parametrize(
    "text",
    [
        "[1,2,3]",
        "[[1,2],[3]]",
        "[1.8,[0,0,40],[1,0,0,0],0,0,0]",
        "[[1e3,-2.5E-2,+.5,7.]]",
        "[[1],2]",
        "[ 1 , 2 ]",
        "[[1, 2, 3], [0, 0, 1, 0], [-1, 0, -1, 0], [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]]",
        "[\n  [1,2],\n\t[3]\n]",
        "[1.8, [0,0,40], 0]",
    ],
)
def test_aggregate_values_match_the_grammar_reader(text):
    assert aggregate_value(text) == numeric_aggregate_value(text)


@pytest.mark.parametrize("text", ["[1.2.3]", "[1,,2]", "[[1,2],,[3]]", "[-]", "[1e]", "[[],1]",
                                  # whitespace inside a number, or in place of a comma
                                  "[1 2]", "[[1, 2] [3]]", "[- 1]", "[1 .5]", "[[1 2],[3]]"])
def test_malformed_aggregates_are_left_to_the_grammar(text):
    with pytest.raises(NotFast):
        aggregate_value(text)


number_chars = st.text(alphabet="-+0123456789.eE,", max_size=8)


@st.composite
def loose_aggregate(draw: st.DrawFn) -> str:
    """Text of the shape the lexer's loose aggregate pattern lets through."""
    items = draw(st.lists(number_chars.map(lambda c: f"[{c}]") | number_chars, max_size=5))
    return "[" + draw(st.sampled_from([",", ""])).join(items) + "]"


def read(fn, *args):
    try:
        return repr(fn(*args))
    except NotFast:
        return "NotFast"


spaced_chars = st.text(alphabet="-+0123456789.eE, \t\n", max_size=10)


@st.composite
def spaced_aggregate(draw: st.DrawFn) -> str:
    """Text of the loose aggregate pattern's shape, whitespace anywhere in it."""
    items = draw(st.lists(spaced_chars.map(lambda c: f"[{c}]") | spaced_chars, max_size=5))
    return "[" + draw(st.sampled_from([",", ", ", " , ", "", " "])).join(items) + "]"


@settings(max_examples=500, deadline=None)
@given(spaced_aggregate())
def test_aggregates_with_whitespace_are_read_as_the_grammar_reads_them(text):
    # what the loose pattern lets through is a NUMERIC_AGGREGATE of the grammar, read as
    # its rule reads it, or it is left to the plain grammar (never a number made of two)
    exact = re.compile(next(t.pattern.to_regexp() for t in rapid_parser().terminals
                            if t.name == "NUMERIC_AGGREGATE"))
    expected = repr(numeric_aggregate_value(text)) if exact.fullmatch(text) else "NotFast"
    assert read(aggregate_value, text) == expected


@settings(max_examples=300, deadline=None)
@given(st.lists(loose_aggregate(), min_size=1, max_size=4))
def test_sharing_what_follows_a_leading_group_reads_the_same_values(texts):
    rests = Memo(TAIL_LIMIT)
    for text in texts + ["[[1" + t[t.find("]"):] for t in texts if "]" in t[:-1]]:
        assert read(shared_aggregate_value, text, rests) == read(aggregate_value, text)


@settings(max_examples=300, deadline=None)
@given(st.lists(loose_aggregate() | spaced_aggregate(), min_size=1, max_size=4))
def test_a_grouped_value_is_the_aggregate_value_or_none(texts):
    # the reading of an inline target (its position every time, the rest once): where it
    # takes a text, the values of the grammar's reader; arithmetic left to the grammar
    rests = Memo(TAIL_LIMIT)
    for text in texts + ["[[1" + t[t.find("]"):] for t in texts if "]" in t[:-1]]:
        if not text.startswith("[["):
            continue
        got = read(grouped_value, text, rests)
        if got != "None":
            assert got == read(aggregate_value, text)


def test_a_grouped_value_reads_the_rest_once():
    rests = Memo(TAIL_LIMIT)
    first = grouped_value(TARGET, rests)
    second = grouped_value(TARGET.replace("[1,-2.5,3E2]", "[4, 5,6]"), rests)
    assert first == ((1.0, -2.5, 300.0), (1.0, 0.0, 0.0, 0.0), (0.0, -1.0, 2.0, 0.0),
                     (9e9,) * 6)
    assert second[0] == (4.0, 5.0, 6.0) and second[1] is first[1] and second[3] is first[3]
    assert grouped_value("[[1,2],3]", rests) is None  # not a group after the first
    # whitespace between the groups: read too, the rest once per distinct text
    spaced = grouped_value("[[1, 2],\n\t[3]]", rests)
    assert spaced == ((1.0, 2.0), (3.0,)) == numeric_aggregate_value("[[1, 2],\n\t[3]]")
    assert grouped_value("[[5, 6],\n\t[3]]", rests)[1] is spaced[1]
    with pytest.raises(NotFast):
        grouped_value("[[1-1,2],[3]]", rests)


PIECES = [
    "MoveL p1,v100,z1,tool0;",
    "MoveL Offs(p1,t.tframe.trans.z*2,p1.trans.x,0),v1,z1,t;",  # components, elements
    "MoveL path{2},v1,z1,t; MoveL Offs(path{2},0,0,nZ{1}),v1,z1,t;",
    "MoveL grid{1, 2}.trans, v1, z1, t; MoveL p . trans, v1, z1, t;",
    "IF a THEN MoveL p1,v100,z1,tool0; Set do1; ENDIF",  # IF blocks: in a run when of calls
    "if n > 1 then\n ! c\n x := 1;\nendif",
    "IF b THEN ENDIF",
    "IF a THEN Foo; ELSE Bar; ENDIF",
    "IF a THEN IF b THEN Foo; ENDIF ENDIF",
    "MoveL p2, v200, fine, tool0 \\WObj:=w;",
    "Stop;",
    f"MoveJ {TARGET},v100,z1,tool0;",
    "Foo 1, 0x1F;",
    "EXIT;",
    "x := 1;",
    "Foo TRUE;",
    "IF a Foo;",
    "lbl:",
    "Foo \\A?B;",
    "MoveL p1, ! c\n v1, z1, t;",
    "Foo [1,,2];",
    "Foo p1 v1;",
    "RETURN;",
    "Foo [[1,2],3];",
    "MoveL Offs(p1,0,0,-10),v100,z1,tool0;",
    "MoveL RelTool(p1, 0, 0, 5 \\Rz:=90), v100, z1, tool0 \\WObj:=w;",
    "Foo -1, - 2.5 \\A:=Abs(-1);",
    "Foo f(), g(a \\B, [1,2]);",
    "Foo f(g(1));",
    "Foo f(g(h(1)));",
    "Foo f(,1);",
    "Foo f(1,);",
    "Foo f(g(1,),2);",
    "Foo f(g(,1));",
    "Foo f(g(1 2));",
    "Foo f( g( \\A:=1 , 2 ) \\B);",
    "MoveL Offs(RelTool(p1,0,0,1 \\Rz:=90),0,0,1),v100,z1,tool0;",
    "Foo f(1)+1;",
    "! MoveL p1,v1,z1,t;\n",
    "Foo; ! x;\nBar;",
    "Foo ;;",
    "Bar",
    "MoveL pÑ,v100,z1,tool0;",
    "MoveC c1,p2,v100,z1,tool0;",
    "MoveL path{1},v100,z1,tool0;",
    "MoveL path{007},v100,z1,tool0;",
    "MoveL path{ 2 },v100,z1,tool0;",
    "MoveL path{0x2},v100,z1,tool0;",
    "Foo grid{i, 2}, [[[1,2]],[[3]]];",
    "Foo [[[1,2]],[3]];",
    "MoveC Offs(c1,0,1,0), p3 ,v100,z1,tool0;",
    "MoveC c1,-1,v100,z1,tool0 \\WObj:=w;",
    "Foo Añ, ñ \\Ø:=é;",
    "<SMT>",
    "MoveL <ARG>,v1,z1,t;",
    "Foo <EXP>, <ID>;",
    "MoveJ \\Conc, p1, v1000, z50, tool0;",
    "MoveJ \\Conc,Offs(p1,0,0,1),v100,z1,tool0\\WObj:=w;",
    "Foo \\A \\B:=-1, [1,2], 2 \\C;",
    "WaitTime \\InPos, 0.5;",
    "Foo \\A;",
    "Foo \\A:=f(1,2) , x.y;",
    f"MoveL {SPACED}, v100, z1, tool0;",
    "Foo [[1, 2] , [3]], [[1,\x1a2], [3]], [[1 -1, 2], [3]], [[ 1 ,2 ],\r\n[3 ]];",
    # compact IFs, and function calls inside parentheses
    "IF a > 1 Foo;",
    "IF (f(x) = 1) AND b MoveL p1,v100,z1,tool0;",
    "IF NOT b x := (a + f(b)) * 2;",
    "IF a\r\n  Foo \\A;",
    "IF a GOTO l;",
    "IF a AND Foo;",
    "WaitUntil (DInput(di1) = 1) \\MaxTime:=(n * 2);",
    "Foo ((a + g(b, -1)) * c), (NOT f(x));",
]
DATA = [
    f"CONST robtarget p:={TARGET};",
    "VAR num i;",
    "LOCAL PERS num n:=2;",
    "CONST num m:=-1;",
    "VAR num a{2};",
    f"CONST robtarget path{{2}}:=[{TARGET},\n {TARGET}];",
    "VAR num b{2,3}:=[[1,2,3],[4,5,6]];",
    "CONST num q:=[1,2.3.4];",
    f"CONST robtarget s := {SPACED};",
    "VAR num c{2,2}:=[[1, 2],\n [3, 4]];",
    "VAR num d{2,2}:=[[1 -1, 2], [3, 4]];",
    "VAR num e{2,2}:=[[1,\x1a2], [3, 4]];",
    f"CONST robtarget g{{2,1}}:=[[{TARGET}],\n [{TARGET}]];",
    f"CONST robtarget h{{2,1}}:=[[{TARGET}], [[1,2,3]]];",
    "VAR num k{1,1,2}:=[[[[1,2]]]];",
    'CONST seam t{2}:=[[1,"a",[2,x]],\n [2,"b;",[4,5]]];',
]
GAPS = ["\n", " ", "\r\n  ", "\n! note\n", "\t", ""]


@st.composite
def program_text(draw: st.DrawFn) -> str:
    data = draw(st.lists(st.sampled_from(DATA), max_size=4))
    body = draw(st.lists(st.sampled_from(PIECES + DATA[:3]), max_size=10))
    gap = st.sampled_from(GAPS)
    return (
        "MODULE M"
        + "".join(draw(gap) + "\n" + d for d in data)
        + "\nPROC main()"
        + "".join(draw(gap) + b for b in body)
        + "\nENDPROC\nENDMODULE"
    )


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(program_text())
def test_random_programs_parse_as_with_the_plain_grammar(text):
    assert_parses_as_plain(text)


def assert_parses_as_plain(text: str) -> None:
    """parse_text gives the plain grammar's tree, or refuses the text as it does, with
    fast_blocks' reader and with the fast terminals alone."""
    try:
        expected = plain_tree(text)
    except UnexpectedInput:
        expected = None
    for read_ahead in (True, False):
        fast_blocks.READ_AHEAD = read_ahead
        try:
            if expected is None:
                with pytest.raises(UnexpectedInput):
                    parse_text(text)
            else:
                assert shape(parse_text(text)) == expected
        finally:
            fast_blocks.READ_AHEAD = True


# Calls of calls whose texts differ only in their digits (`#`): the later ones are split
# where the first of their shape was (fastpath._call_node), their values read from them.
CALL_SHAPES = [
    "MoveL Offs(RelTool(Offs(p#,#,0,-#),0,0,#\\Rz:=#),nDx*#,0,#),v100,z1,t;",
    "MoveJ RelTool( Offs( RelTool(p#, 0, #, 5), 0, -#.#, 0), 0, 0, -#E#), v200, z5, t;",
    "Foo Fn#(Gn#(path{#},#),#);",
    "Foo f(g(grid{#,#}.trans.x*#,-#),#), h(k(p#.trans,#) \\A:=#);",
    "Foo f(g(h(#)),#);",
    "Foo Offs(RelTool([[#,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],0,0,#),0,0,#);",
    "Foo Offs(RelTool(p#,0,0,#),0,0,#) \\B:=f(g(#)), #;",
    "Foo f(g(0x#),#), f(g(\"#\"),#);",
]


DIGITS = st.text("0123456789", min_size=1, max_size=3)


def _filled(draw: st.DrawFn, templates: list[str]) -> str:
    """One of `templates` with each `#` drawn digits."""
    pieces = draw(st.sampled_from(templates)).split("#")
    return pieces[0] + "".join(draw(DIGITS) + piece for piece in pieces[1:])


@st.composite
def reshaped_calls(draw: st.DrawFn) -> str:
    return routine(*(_filled(draw, CALL_SHAPES) for _ in range(draw(st.integers(2, 6)))))


@settings(max_examples=100, deadline=None)
@given(reshaped_calls())
def test_calls_of_the_same_shape_parse_as_with_the_plain_grammar(text):
    assert_parses_as_plain(text)


# Rows of tables of records (`#`: digits): a table longer than fastpath.READ_KEPT_CHARS is
# read row by row, a row of a shape read before made from it (fastpath._rows_read).
ROW_SHAPES = [
    '[#,"S#",#.#,[#,#,0]]',
    '[ -#, "a[#]b", [#,-#.#E-#], nX# ]',
    '["say ""#""", "\\#A", TRUE, [#, "x,#"]]',
    '[#,"",0x#,[-#]]',
    '[#, "p#"]',
]


@st.composite
def record_table(draw: st.DrawFn) -> str:
    rows = [_filled(draw, ROW_SHAPES) for _ in range(draw(st.integers(12, 30)))]
    gap = draw(st.sampled_from([",", ", ", ",\n    ", " ,\r\n\t", ",\n! a row\n"]))
    return module(f"CONST seam table{{{len(rows)}}}:=[" + gap.join(rows) + "];",
                  "PROC main()", "  MoveL table{1}.p, v100, z1, tool0;", "ENDPROC")


@settings(max_examples=60, deadline=None)
@given(record_table())
def test_tables_of_records_parse_as_with_the_plain_grammar(text):
    assert_parses_as_plain(text)


# ------------------------------------------------------- comments inside statements
def _blanked_by_hand(text: str) -> str:
    """blank_comments, written as a lexer reads the text character by character: a
    string (rapid.lark's STRING) or the `%%%` header at the start is taken whole, a `!`
    elsewhere starts a comment to the end of its line."""
    string = re.compile(r'"(?:[^"\r\n]|"")*"')
    out, i, at_start = list(text), 0, True
    while i < len(text):
        c = text[i]
        if c == "!":
            end = text.find("\n", i)
            end = len(text) if end < 0 else end
            out[i:end] = [" " if ch != "\r" else ch for ch in text[i:end]]
            i = end
            continue
        m = string.match(text, i) if c == '"' else None
        if m is not None:
            i, at_start = m.end(), False
            continue
        if at_start and text.startswith("%%%", i) and text.find("%%%", i + 3) >= 0:
            i, at_start = text.find("%%%", i + 3) + 3, False
            continue
        at_start = at_start and c in " \t\f\v\r\n\x1a"
        i += 1
    return "".join(out)


@settings(max_examples=400, deadline=None)
@given(st.lists(st.sampled_from(["!", '"', "a", " ", "\n", "\r", "%%%", '""', "%"]),
                max_size=30))
def test_comments_are_blanked_where_the_lexer_reads_comments(pieces):
    from rapidfix.rapid.fastpath import blank_comments

    text = "".join(pieces)
    assert blank_comments(text) == _blanked_by_hand(text)


INNER = [
    "MoveL p1, v100, z1, tool0;",
    "MoveL Offs(p1, 0, 0, -10), v100, fine, tool0 \\WObj:=w;",
    f"MoveJ {TARGET}, v100, z1, tool0;",
    "MoveC c1, p2, v100, z1, tool0;",
    'TPWrite "stop! now" \\Num:=1;',
    'TPWrite "say ""hi!""";',
    "x := Offs(p1, 1, 2, 3);",
    f"CONST robtarget q:={TARGET};",
]


@pytest.mark.parametrize("piece", INNER)
def test_a_comment_inside_a_statement_keeps_it_in_the_fast_run(piece):
    """A comment in place of any space of a statement (never inside its strings): the
    plain grammar's tree, and calls stay fast-run nodes (LazyCall), not the plain
    grammar's."""
    strings = [m.span() for m in re.finditer(r'"(?:[^"]|"")*"', piece)]
    spaces = [i for i, c in enumerate(piece) if c == " "
              and not any(a <= i < b for a, b in strings)]
    assert spaces
    for i in spaces:
        statement = piece[:i] + " ! note \"x\" !\n   " + piece[i + 1:]
        text = (module(statement) if piece.startswith("CONST")
                else routine("Stop;", statement, "Stop;"))
        tree = parse_text(text)
        assert shape(tree) == plain_tree(text)
        if not piece.startswith(("CONST", "x :=")):
            body = tree.modules[0].items[0].body
            assert [type(node) for node in body] == [s.LazyCall] * 3, statement


def test_two_dimensional_arrays_of_targets_are_declared_in_one_run():
    """A 2-D array's aggregate is four levels deep; its rows may stand on lines of their
    own. Each row is the three-level aggregate of an array of targets."""
    text = module("VAR num n:=1;",
                  f"CONST robtarget g{{2,2}}:=[[{TARGET},{TARGET}],\n    [{TARGET},{TARGET}]];",
                  f"PERS robtarget h{{1,2}} := [ [ {TARGET} , {TARGET} ] ];", "VAR num k:=2;")
    interactive = fast_parser().parse_interactive(text)
    assert [t.type for t in interactive.iter_parse()
            if t.type.startswith("FAST_")] == ["FAST_DECLS"]
    tree = fast_parser().parse(text)
    assert shape(tree) == plain_tree(text)
    grid = tree.modules[0].items[1].init
    assert [type(row) for row in grid.items] == [s.Aggregate, s.Aggregate]
    assert [type(item) for item in grid.items[1].items] == [s.NumericAggregate] * 2


@pytest.mark.parametrize("index", ["1", "007", " 2 ", "0x2", "i", "n{1}", "1, 2", "١", "12,3",
                                   "1,2,30", "1,0x2", "1,n"])
def test_array_elements_are_read_as_the_grammar_reads_them(index):
    text = routine(f"MoveL path{{{index}}},v100,z1,tool0;", f"x := path{{{index}}};")
    assert_parses_as_plain(text)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.sampled_from(["1,2,3", " 1 , -2 ,3E2 ", "+1.5,.5,5.", "1e5,2E-3,-0",
                                 "a,b,c", "1+1,2,3", "1,,2", "1 2,3,4", "\x1a1,2,3", "1,2",
                                 "-1,-2,-3,-4", "x.y,2,3", "1,2,3e", "", "inf,0,0"]),
                min_size=1, max_size=6),
       st.sampled_from(["[1,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]",
                        "[1,0,0,0],[0,-1,2,0]", "[1, 0, 0, 0], conf, [1]"]))
def test_inline_targets_after_a_known_rest_are_read_as_the_grammar_reads_them(groups, rest):
    """Once a rest (all after the first group) has been read as a plain aggregate, an
    inline target with the same rest after any first group gives the grammar's tree."""
    from rapidfix.rapid.fastpath import forget_texts

    forget_texts()
    known = f"MoveL [[0,0,0],{rest}],v100,z1,tool0;"  # the rest, read as a plain aggregate
    for group in groups:  # each in a program of its own: a bad one fails alone
        assert_parses_as_plain(routine(known, f"MoveL [[{group}],{rest}],v100,z1,tool0;"))


def test_the_bulk_reader_takes_comments_inside_statements_as_the_model_does():
    """The read-back's bulk reader reads a rewritten program with comments inside its
    statements and declarations (kept from the original) in its runs, with the targets
    the full program model gives."""
    import numpy as np

    from rapidfix.rapid.readback import read_bulk, read_targets_full, read_targets_in_bulk

    joints = "[[1,2,3,4,5,6],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    text = module(
        f"CONST jointtarget j1:={joints};",
        "CONST jointtarget j2:= ! its value next\n  [[1,2,3,4,5,7],"
        "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]; ! \"quoted\"",
        f"CONST robtarget p1:={TARGET};",
        "PROC main()",
        "  MoveAbsJ j1, ! to j1 \"x\n    v100, z1, tool0;",
        "  MoveAbsJ j2,\n    v100, ! speed\n    fine, tool0 \\WObj:=w; ! done",
        "  MoveL p1, v100, ! z\n z1, tool0;",
        "ENDPROC")
    assert read_bulk(text) is not None
    program = parse_program(text, "commented.mod")
    motion = np.arange(len(program.motions))
    slot = np.zeros(len(motion), dtype=np.int64)
    bulk = read_targets_in_bulk(text, list(range(len(program.motions))), motion, slot)
    full = read_targets_full(program.motions, motion, slot)
    assert bulk is not None
    for name in ("joint", "robax", "trans", "rot", "conf"):
        assert np.array_equal(getattr(bulk, name), getattr(full, name)), name
    assert bulk.joint.tolist() == [True, True, False]
    assert bulk.robax[1].tolist() == [1, 2, 3, 4, 5, 7]


# Declarations of the common form (`_PLAIN_DECL`, read without `_DECL` and
# `grouped_value`) and the texts next to it that go the general way.
PLAIN_DECLARATIONS = [
    "CONST robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
    "LOCAL PERS robtarget p1 := [[-1.5e3,.5,+3.],[1,0,0,0],[0,-1,0,1],"
    "[9E+09,9E9,9E9,9E9,9E9,9E9]] ;",
    "task var robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
    "CONST num a:=[[1,2,3],[4]];",
    "CONST robtarget p1:=[[1-1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
    "CONST robtarget p1:=[[1,2,3],[1,0,0,0-1],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
    "CONST robtarget p1:=[[1,2,3],[1e,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
    "CONST robtarget p1:=[[],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
    "CONST robtarget p1:=[[1,2,3], [1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
    "CONST robtarget p1:=[[1, 2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
    "CONST num a{2}:=[[1,2],[3,4]];",
    "CONST num a:=[[1,2,3]];",
    "CONST num a:=[[[1,2],[3]],[[4],[5]]];",
    "CONST robtarget p1 := [ [ 1, 2, 3 ], [ 1, 0, 0, 0 ], [ 0, 0, 0, 0 ], [ 9E9, 9E9, 9E9, 9E9, "
    "9E9, 9E9 ] ];",
    "CONST robtarget p1:=[\n    [1,2,3],\n    [1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]\n];",
    "CONST robtarget p1:=[[1 2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
    "CONST robtarget p1:=[[1,2,3], [1,0, 0 0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];",
]


def test_the_common_declaration_form_takes_spaced_targets():
    plain, spaced = fastpath._PLAIN_DECL.compiled, fastpath._SPACED_DECL.compiled
    for text in PLAIN_DECLARATIONS[:3]:
        assert plain.match(text) and spaced.match(text).groups() == plain.match(text).groups()
    for text in PLAIN_DECLARATIONS[-4:-2]:
        assert not plain.match(text) and spaced.match(text), text


# Whitespace as people put it in a target (`[ [500, 0, 400], [1, 0, 0, 0], ...]`): at
# every junction and around the numbers; in one example of ten, now and then a character
# the grammar's whitespace has and float() has not (\x1a)
_TARGET_GAPS = ["", "", "", " ", "  ", "\t", "\n    "]


@st.composite
def spaced_target(draw: st.DrawFn, position: int, gaps: st.SearchStrategy[str]) -> str:
    """A robtarget aggregate at `position`, spaced anywhere by `gaps`, its first group's
    last number now and then not one (`1 2`)."""
    def group(numbers: list[str]) -> str:
        return "[" + ",".join(f"{draw(gaps)}{n}{draw(gaps)}" for n in numbers) + "]"
    last = draw(st.sampled_from(["3", "3", "1e2", "+.5", "1 2"]))
    first = group([f"{position}.5", "-2", last])
    rest = [group(["1", "0", "0", "0"]), group(["0", "-1", "0", "1"]), group(["9E9"] * 6)]
    text = f"[{draw(gaps)}{first}"
    for item in rest:
        text += f"{draw(gaps)},{draw(gaps)}{item}"
    return text + f"{draw(gaps)}]"


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_spaced_targets_declared_and_inline_parse_to_the_plain_tree(data):
    """Declarations (`_SPACED_DECL`, `grouped_value`) and inline targets (`_inline_target`
    after a first one) with whitespace anywhere: the plain grammar's tree, values and
    all, or its refusal. Several share their text after the first group, as a
    program's targets do, so the second and later are read from what the first left."""
    odd = data.draw(st.integers(0, 9)) == 0
    gaps = st.sampled_from(_TARGET_GAPS + [" \x1a"] * odd)
    targets = [data.draw(spaced_target(k + 1, gaps)) for k in range(3)]
    if data.draw(st.booleans()):  # the same spacing after the first group in all three
        cut = targets[0].index("]")
        targets = [t[:t.index("]")] + targets[0][cut:] for t in targets]
    decls = [f"CONST robtarget p{k} :={data.draw(gaps)}{t};" for k, t in enumerate(targets)]
    moves = [f"MoveL {t}, v100, z1, tool0;" for t in targets]
    for text in (module(*decls), routine(*moves)):
        fastpath.forget_texts()
        assert_parses_as_plain(text)


@pytest.mark.parametrize("gap", ["\x1a", " \x1a", "\x1a\n  "])
def test_a_dos_end_of_file_inside_a_target_reads_as_the_grammar_reads_it(gap):
    """\\x1a is the grammar's whitespace between tokens, but not inside its
    NUMERIC_AGGREGATE (whose `\\s` lacks it): a target with one there is an aggregate
    of items, also after targets of the same text without it (whose rests are kept)."""
    plain = "[[1.5,-2,3],[1,0,0,0],[0,-1,0,1],[9E9,9E9,9E9,9E9,9E9,9E9]]"
    odd = [f"[{gap}[3.5,-2,3],[1,0,0,0],[0,-1,0,1],[9E9,9E9,9E9,9E9,9E9,9E9]]",
           f"[[3.5,-2,3],{gap}[1,0,0,0],[0,-1,0,1],[9E9,9E9,9E9,9E9,9E9,9E9]]",
           f"[[3.5,-2,3],[1,0,0,0],[0,-1,0,1],[9E9,9E9,9E9,9E9,9E9,9E9]{gap}]"]
    for target in odd:
        for text in (module(f"CONST robtarget p0 :={plain};", f"CONST robtarget p1 :={target};"),
                     routine(f"MoveL {plain}, v100, z1, tool0;",
                             f"MoveL {target}, v100, z1, tool0;")):
            fastpath.forget_texts()
            assert_parses_as_plain(text)
            assert "'Aggregate'" in repr(shape(parse_text(text)))


@pytest.mark.parametrize("declaration", PLAIN_DECLARATIONS)
def test_declarations_of_the_common_form_parse_to_the_plain_tree(declaration):
    """Each alone, and in a run with the others around it (the plain form read first,
    the general one where it does not fit)."""
    assert_parses_as_plain(module(declaration))
    assert_parses_as_plain(module(PLAIN_DECLARATIONS[0].replace("p1", "p0"), declaration,
                                  "! a note", PLAIN_DECLARATIONS[2].replace("p1", "p2")))
