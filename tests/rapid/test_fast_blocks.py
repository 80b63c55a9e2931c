"""Compound statements and routines read ahead of the lexer (rapidfix.rapid.fast_blocks):
the tree must be the plain grammar's, node for node, or both routes refuse the text; what
the reader cannot read is left to the parser, and nothing is read twice."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the comparisons of the fast path tests
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from mixed_shapes import mixed_program
from test_fastpath import assert_parses_as_plain, module, plain_tree, routine, shape

from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid import fast_blocks, fastpath, parse_program
from rapidfix.rapid.fastpath import fast_parser, parse_text

MOVE = "MoveL p1,v100,z1,tool0\\WObj:=wobj0;"


def tokens(text: str) -> list[str]:
    """The types of the tokens the fast parser's lexer gives for `text`; each token's line
    and column (where it starts and ends) are checked against its offsets."""
    interactive = fast_parser().parse_interactive(fastpath.blank_comments(text))
    types = []
    for token in interactive.iter_parse():
        for line, column, at in ((token.line, token.column, token.start_pos),
                                 (token.end_line, token.end_column, token.end_pos)):
            assert (line, column) == (text.count("\n", 0, at) + 1,
                                      at - text.rfind("\n", 0, at)), token
        types.append(token.type)
    return types


def counted_runs(monkeypatch) -> list[tuple[str, int]]:
    """The (text, offset) of every run of calls or declarations split from now on, by the
    reader or by the parser's callbacks."""
    seen: list[tuple[str, int]] = []

    def counted(split):
        def counting(text: str, base: int) -> list:
            seen.append((text, base))
            return split(text, base)
        return counting

    lexer = fast_parser().parser.lexer.lex.__self__
    for name in ("split_calls", "split_decls"):
        counting = counted(getattr(fastpath, name))
        monkeypatch.setattr(lexer, name, counting)
        monkeypatch.setattr(fastpath, name, counting)
    return seen


NESTED = routine(
    "IF nMode > 0 THEN",
    "  TEST nMode",
    "  CASE 1, 2:",
    "    WHILE i < 1 DO",
    "      IF i = 0 THEN",
    f"        {MOVE}",
    "      ELSEIF i = 2 THEN",
    "        i:=3;",
    "      ELSE",
    f"        {MOVE}",
    "      ENDIF",
    "      i:=i + 1;",
    "    ENDWHILE",
    "  DEFAULT:",
    "    FOR k FROM 1 TO 3 STEP 1 DO",
    "      RETURN;",
    "    ENDFOR",
    "  ENDTEST",
    "ENDIF",
    "i:=0;",
)


def test_nested_blocks_in_routines_are_one_token_with_the_plain_tree():
    text = NESTED.replace("ENDMODULE", "PROC two()\n  WHILE TRUE DO\n    Stop;\n  ENDWHILE\n"
                          "ENDPROC\nENDMODULE")
    assert tokens(text) == ["MODULE", "NAME", "FAST_ROUTINES", "ENDMODULE"]
    assert shape(parse_text(text)) == plain_tree(text)


def test_blocks_in_a_routine_the_reader_leaves_are_one_token_from_the_first_block():
    """A routine with an ERROR handler naming a placeholder among its error numbers is read
    by the parser; inside it, the reader takes its statements from the first on."""
    text = NESTED.replace("ENDPROC", "ERROR (<EXP>, 42)\n  RETRY;\nENDPROC")
    assert tokens(text)[:6] == ["MODULE", "NAME", "FAST_PROC", "FAST_BLOCK", "ERROR", "OPEN_PAREN"]
    assert shape(parse_text(text)) == plain_tree(text)


@pytest.mark.parametrize("numbers", ["()", "(1,)", "(1;", "(1\\A)", "(1]", "[1]", "((1)"])
def test_error_numbers_that_do_not_read_are_the_parsers(numbers):
    assert_parses_as_plain(NESTED.replace("ENDPROC", f"ERROR {numbers}\n  RETRY;\nENDPROC"))


@pytest.mark.parametrize("handlers", [
    "ERROR\n  RETRY;\n", "UNDO\n  Stop;\nERROR\n  TRYNEXT;\n", "BACKWARD\n", "ERROR\n",
    "ERROR (ERR_A, 41)\n  RETRY;\n", "ERROR(ERR_X)\n", "ERROR ( (1) ,\n f(\"a)\") )\n",
])
def test_handlers_are_read_with_their_routine(handlers):
    text = NESTED.replace("ENDPROC", handlers + "ENDPROC")
    assert tokens(text) == ["MODULE", "NAME", "FAST_ROUTINES", "ENDMODULE"]
    assert shape(parse_text(text)) == plain_tree(text)


def test_traps_and_connections_are_read_with_the_routines():
    text = module("VAR intnum iStop;", "LOCAL TRAP Stopped", "  StopMove;", "ERROR",
                  "  RAISE;", "ENDTRAP", "PROC main()", "  CONNECT iStop WITH Stopped;",
                  "  ISignalDI diStop, 1, iStop;", f"  {MOVE}", "ENDPROC", "trap t2",
                  "endtrap")
    assert tokens(text) == ["MODULE", "NAME", "FAST_DECLS", "FAST_ROUTINES", "ENDMODULE"]
    assert shape(parse_text(text)) == plain_tree(text)


def test_labels_are_read_with_their_routine():
    text = NESTED.replace("i:=3;", "lRetry :\n        i:=3;\n        GOTO lRetry;")
    assert tokens(text) == ["MODULE", "NAME", "FAST_ROUTINES", "ENDMODULE"]
    assert shape(parse_text(text)) == plain_tree(text)


@pytest.mark.parametrize("data", ["PERS num n:=1;", "LOCAL VAR num n;", "TASK PERS num n:=2;"])
def test_data_after_a_run_of_declarations_in_a_routine_is_no_module_item(data):
    """After a run of declarations the parser's state is a module's and a routine body's
    at once (LALR merged them): the routine's further data is read as the routine's. (The
    routine's head, with alternative parameters, is the parser's: so is its data.)"""
    decls = [f"  VAR num a{k};" for k in range(fastpath.RUN_LIMIT + 5)]
    text = module("PROC main(\\num a | switch b)", *decls, f"  {data}", "  IF a THEN",
                  f"    {MOVE}", "  ENDIF", "ENDPROC")
    kinds = tokens(text)
    assert "FAST_ROUTINES" not in kinds and kinds.count("FAST_BLOCK") == 1
    assert shape(parse_text(text)) == plain_tree(text)


@pytest.mark.parametrize("glued", [
    "PERSspeeddata v:=[1,2,3,4];", "LOCALPERS num n:=1;", "VARnum n;", "PROCtwo()",
    "ENDMODULEx", "TASKPERS num n:=1;", "RECORDr", "CONSTnum k:=1;",
])
@pytest.mark.parametrize("before", [["VAR num a;", "VAR num b:=2;"], ["PROC main()", "ENDPROC"],
                                    ["PROC main()", "ENDPROC", "VAR num a;"]])
def test_a_word_glued_to_a_keyword_after_module_items_is_the_plain_grammars(glued, before):
    """Found by damaging real files: `PERSspeeddata` after declarations is a name to the
    plain grammar (its state there takes one) and an error; after the reader's token the
    contextual lexer read PERS out of the word. After a routine both read the keyword."""
    assert_parses_as_plain(module(*before, glued, "PROC last()", f"  {MOVE}", "ENDPROC"))


@pytest.mark.parametrize("piece", [
    '%"Vis" + "it"% <ARG>;', "CONNECT a{1} WITH tr;", "RAISE <EXP>;", "ENDFOR:",
    "Foo x:=1, <ARG>;", "<SMT>",
])
def test_a_piece_no_fast_terminal_takes_is_left_to_the_parser_and_nothing_is_read_twice(
        monkeypatch, piece):
    """Deep in a block, a statement the reader cannot read: the blocks around it are
    the parser's, what the reader had read complete is given as it was (each run of
    calls split once), and the reader reads on after it."""
    text = NESTED.replace("i:=3;", piece).replace("PROC main()", "PROC main()\n  VAR num k;")
    text = text.replace("ENDMODULE", "PROC two()\n  IF a THEN\n    Stop;\n  ENDIF\nENDPROC\n"
                        "ENDMODULE")
    runs = counted_runs(monkeypatch)
    assert shape(parse_text(text)) == plain_tree(text)
    assert len(runs) == len(set(runs)) and any("VAR num k" in run for run, _ in runs)
    kinds = tokens(text)
    assert kinds[2] == "FAST_PROC"  # the routine holding it is the parser's
    assert "FAST_ROUTINES" in kinds[-3:]  # the routine after it is read whole


def _message(text: str, monkeypatch, read_ahead: bool = True, windows: bool = True) -> str:
    from rapidfix.rapid import syntax_errors

    with monkeypatch.context() as m:
        m.setattr(fast_blocks, "READ_AHEAD", read_ahead)
        if not windows:
            m.setattr(fastpath, "window", lambda *_: None)
            m.setattr(syntax_errors, "window", lambda *_: None)
        with pytest.raises(RapidSyntaxError) as err:
            parse_program(text, "t.mod")
    return str(err.value)


@pytest.mark.parametrize("damage", [
    ("i:=3;", "i:=3"), ("ENDWHILE", "ENDFOR"), ("DEFAULT:", "DEFAULT"), ("ENDTEST", ""),
    ("      ENDIF", "      ENDIF;"), ("ENDPROC", "ENDFUNC"), ("ENDPROC", ""),
])
def test_errors_in_and_after_read_blocks_are_explained_as_without_the_reader(
        monkeypatch, damage):
    """A syntax error in the last of many read routines, or after them: the same message
    (file, line, column, what was expected) with the reader, without it, and from the
    whole text (the error windows see the reader's tokens on the parser's stack)."""
    one = NESTED[NESTED.index("PROC"):NESTED.index("ENDMODULE")]
    many = "".join(one.replace("PROC main", f"PROC r{k}") for k in range(120))
    text = "MODULE M\n" + many + one.replace(*damage) + "ENDMODULE\n"
    assert len(many) > 20_000  # error_window's _WORTH: windows are made
    message = _message(text, monkeypatch)
    assert message.startswith("t.mod:")
    assert message == _message(text, monkeypatch, read_ahead=False)
    assert message == _message(text, monkeypatch, windows=False)


@pytest.mark.parametrize("statement", [
    "pCur.trans:=[nX+(2*nDx),nY-(2*nDx),nZ];", "i:=Trunc((a-b)*1000);",
    'WaitUntil stReact=["Ready","",""];', "Foo Sqrt(Pow(p.x,2)+Pow(p.y,2));",
])
def test_statements_no_run_takes_are_read_in_the_block(statement):
    """An assignment or a call of one value whose value the runs' patterns leave out:
    found loosely, read by the expression reader, in the routine's one token."""
    text = routine("IF a THEN", f"  {statement}", f"  {MOVE}", "ENDIF")
    assert tokens(text) == ["MODULE", "NAME", "FAST_ROUTINES", "ENDMODULE"]
    assert_parses_as_plain(text)


@pytest.mark.parametrize("statement", [
    "MoveL \\Conc, Offs(p1, (i-1)*2, 0, 0), v100 \\T:=2, z10, tool0 \\WObj:=w;",
    "Foo \\A \\B:=(1+2), \\C;", "Foo\\A?B, (c);", "Foo x:=(1), 2;",
    'TPWrite "a,b\\\\c;" + s \\Num:=(n);', "Foo \\Bar:=Baz(\\A:=1, 2), (3);",
    '%"Vis" + "it"% p1, (2);', "%s%;", "% s %\\A, (1);", "Foo a{(1)},\n  [1,(2)];",
])
def test_calls_of_several_values_are_read_in_the_block(statement):
    """A call whose arguments the runs' patterns leave out (parentheses, calls inside
    them, optional, conditional and named arguments, a late-bound routine): its list split
    at the commas and backslashes outside brackets and strings, each piece read exactly."""
    text = routine("IF a THEN", f"  {statement}", f"  {MOVE}", "ENDIF")
    assert tokens(text) == ["MODULE", "NAME", "FAST_ROUTINES", "ENDMODULE"]
    assert_parses_as_plain(text)


@pytest.mark.parametrize("statement", [
    "IF (CCW=FALSE) p.trans:=[nX+(-1*X),nY+(Y),nZ];", "IF (NOT a{9}.b=[0,0]) Foo M(\\R:=j{9}),v;",
    'IF a AND b OR NOT c x := [(1)];', "if f(x) MOD 2 = 1 %\"a\"% (1);", "IF s=\"x y\" x:=(1);",
    "IF (a) THEN\n    x := (1);\n  ELSEIF (b) OR c THEN\n    Stop;\n  ENDIF",
    "WHILE (n < 3) AND f(\"DO\") DO\n    Incr n;\n  ENDWHILE", "RAISE ERR_MY_ERROR;",
    "RETURN (a + 1) * 2;", "WaitUntil(stCommand=\"\");", 'TPWrite"a";',
    "IF (a AND s<>TC_OK)\n    RAISE status;", 'IF s=["E","E"]rHome;', "IF (b) RETURN;",
    "IF d=CDate() RETURN ;", "IF (a) EXIT;", 'IF s="x"Foo (1);', "IF a{(1)} RAISE;",
])
def test_heads_and_compact_ifs_no_fast_terminal_takes_are_read_in_the_block(statement):
    """IF, ELSEIF and WHILE heads up to their THEN or DO, a compact IF's condition up to
    where a name follows an operand, RAISE and RETURN of a value, a call whose name a
    bracket or a string follows: found loosely, their pieces read exactly."""
    text = routine("IF a THEN", f"  {statement}", f"  {MOVE}", "ENDIF")
    assert tokens(text) == ["MODULE", "NAME", "FAST_ROUTINES", "ENDMODULE"]
    assert_parses_as_plain(text)


@pytest.mark.parametrize("statement", [
    "IF a AND b;", "IF a b c;", "IF (a Foo;", "IF a) Foo;", "IF a GOTO l;", "IF a b := ;",
    "IF THEN Foo; ENDIF", "IF a THEN Foo; ELSEIF THEN Stop; ENDIF", "WHILE DO ENDWHILE",
    "WHILE a Foo; ENDWHILE", "RAISE 1 2;", "RETURN <EXP>;", "IF a NOT b;", "IF a - b x:=1;",
    "Foo 1,, (2);", "Foo (1), ;", "Foo (1) \\;", "Foo (1) (2);", "Foo \\A:=;",
    "Foo \\A ? ;", "Foo \\IF, (1);", "Foo (1\\A);", "Foo (1)), 2;", "Foo [1, 2, (3);",
    "%(1)% ;", "%a%% b;", "Foo <ARG>, (1);", "Foo \\A?B:=1, (2);",
])
def test_calls_that_do_not_read_are_the_parsers(statement):
    """Argument lists the grammar refuses, or reads otherwise: the same tree or the same
    error as the plain grammar's."""
    assert_parses_as_plain(routine("IF a THEN", f"  {statement}", "ENDIF"))


@pytest.mark.parametrize("statement", [
    "x := path{\u0661};", "Foo path{\u0661};", "x := 1 2;", "Foo a := 1;", "Foo a, b := 2;",
])
def test_statements_found_loosely_are_the_grammars_or_the_parsers(statement):
    """Found by the property test: `path{١}` (an Arabic-Indic digit, a NUMBER to the
    grammar) was read as an index without its number by the runs' splitter, which trusts
    the lexer's check; the expression reader reads it as the grammar does, or leaves it."""
    assert_parses_as_plain(routine("IF a THEN", f"  {statement}", "ENDIF"))


def test_blocks_nested_deeper_than_the_limit_parse_to_the_plain_tree():
    """The outer blocks are the parser's, the inner ones read as one."""
    depth = fast_blocks.DEPTH_LIMIT + 10
    text = routine(*(["IF a THEN"] * depth), MOVE, *(["ENDIF"] * depth))
    assert shape(parse_text(text)) == plain_tree(text)
    assert tokens(text).count("FAST_BLOCK") == 1


# ------------------------------------------------------------ random programs
SIMPLE = [
    MOVE, "x := x + 1;", "Stop;", "IF a Foo;", "IF a THEN b; ENDIF", "RETURN;", "RETURN x;",
    "GOTO lbl;", "lbl:", "a :", "ERROR:", "CASE:", 'TPWrite "a;b ENDIF";',
    "MoveL Offs(p1,0,0,n*2),v100,z1,tool0;",
    "! ENDIF in a comment\n", "EXIT;", "Foo \\A:=1, b;", "RAISE;", "RETRY;",
    "CONNECT iStop WITH t;", "CONNECT a{1} WITH t;", "CONNECT with WITH WITH;",
    # assignments and calls of one value that no run takes: read loosely, then exactly
    "pCur.trans:=[nX+(2*nDx),nY,nZ];", "i:=Trunc((a-b)*1000);", "x{i+1}.y := (a+b)*2;",
    'WaitUntil stReact=["Ready","",""];', 'TPWrite "a;b" + NumToStr((n+1)*2, 0);',
    "Foo (a).b;", "Foo a := 1;", "Foo a b;", "Foo NOT b;", "Foo AND;", "Foo -(1);",
    "WaitUntil a = [1,(2)] \\MaxTime:=3;", "Foo a,\n b;", "x := ;", "x{a{1}} := (1);",
    "Foo\n  (1)\n  + 2;", "Foo DIV;", "Foo ENDIF;", "x := a\n OR b;", "x := 1 2;",
    # calls of several values that no run takes
    "MoveL \\Conc, Offs(p1,(i-1)*2,0,0), v100 \\T:=2, z10, tool0 \\WObj:=w;",
    "Foo \\A \\B:=(1+2), \\C;", "Foo \\A?B, (c);", "Foo x:=(1), 2;", "Foo 1,, (2);",
    'TPWrite "a,b\\\\c" + s \\Num:=(n);', '%"Vis" + "it"% p1, (2);', "%s%;", "Foo (1) 2;",
    "Foo \\Bar:=Baz(\\A:=1, 2), (3);", "Foo (1), ;", "Foo \\IF, (1);", "%a%% b;",
    # compact IFs, RAISE and RETURN of values, heads no fast terminal takes
    "IF (a=1) x:=[(1)];", "IF NOT (a) AND b Foo (1), 2;", "IF a b;", "IF a GOTO lbl;",
    "IF a MOD 2 %s% (1);", "RAISE ERR_X;", "RETURN (a);", "IF (a) Foo; ENDIF",
    "IF (a) RAISE x;", 'IF s=["E"]rHome;', "IF (b) RETURN;", "IF (a) EXIT;", "IF (a)\nRETRY;",
    'IF s="x"Foo;', "IF (a) RETURN (1) 2;", "IF (a)AND b Foo;", "IF (a) CONNECT i WITH t;",
    "IF (a) THEN Stop; ELSEIF (b) THEN x:=1; ENDIF", "WHILE (a) DO Stop; ENDWHILE",
]
# pieces that are wrong wherever the generator puts them (or nearly)
WRONG = ["endif", "ENDIF;", "CASE 1:", "ELSE", "RAISE"]
CONDITIONS = ["a", "n > 2 AND NOT b", "f(x) = 1", "s = \"THEN\"", "a\n  OR b",
              # conditions no head's pattern takes
              "(a) OR b", "(NOT b) AND (n > 1)", "\"DO\" = s", "a{(1)}", "(a"]


@st.composite
def statements(draw: st.DrawFn, depth: int) -> list[str]:
    out: list[str] = []
    for _ in range(draw(st.integers(0, 3))):
        if depth > 0 and draw(st.booleans()):
            out += draw(compound(depth - 1))
        else:
            out.append(draw(st.sampled_from(SIMPLE * 10 + WRONG)))
    return out


@st.composite
def compound(draw: st.DrawFn, depth: int) -> list[str]:
    cond = st.sampled_from(CONDITIONS)
    body = statements(depth)
    kind = draw(st.sampled_from(["if", "while", "for", "test"]))
    if kind == "if":
        out = [f"IF {draw(cond)} THEN", *draw(body)]
        for _ in range(draw(st.integers(0, 2))):
            out += [f"ELSEIF {draw(cond)} THEN", *draw(body)]
        if draw(st.booleans()):
            out += ["ELSE", *draw(body)]
        out.append("ENDIF")
    elif kind == "while":
        out = [f"WHILE {draw(cond)} DO", *draw(body), "ENDWHILE"]
    elif kind == "for":
        step = draw(st.sampled_from(["", " STEP 2", " STEP -n"]))
        out = [f"FOR i FROM 1 TO n{step} DO", *draw(body), "ENDFOR"]
    else:
        out = ["TEST n"]
        for _ in range(draw(st.integers(0, 2))):
            out += [f"CASE {draw(st.sampled_from(['1', '1, 2', 'a + 1']))}:", *draw(body)]
        if draw(st.booleans()):
            out += [draw(st.sampled_from(["DEFAULT:", "DEFAULT :", "DEFAULT\n  :"])), *draw(body)]
        out.append("ENDTEST")
    if draw(st.sampled_from([False] * 39 + [True])):  # damaged: a closing keyword lost or swapped
        out[-1] = draw(st.sampled_from(["", "ENDWHILE", "ENDFOR", "ENDIF", "ELSE"]))
    return out


@st.composite
def routine_text(draw: st.DrawFn) -> list[str]:
    kind = draw(st.sampled_from(["PROC p()", "LOCAL PROC q(num x, \\switch s)",
                                 "FUNC num f(num x)", "TRAP t", "LOCAL TRAP\n  if"]))
    closing = "END" + next(w for w in ("PROC", "FUNC", "TRAP") if w in kind.upper())
    out = [kind, *draw(st.lists(st.sampled_from(["VAR num k:=0;", "CONST num m:=1;"]),
                                max_size=2))]
    out += draw(statements(3))
    if draw(st.booleans()):
        out.append("VAR num late;")
        out += draw(statements(1))
    for _ in range(draw(st.integers(0, 2))):
        out += [draw(st.sampled_from(["ERROR", "ERROR (41)", "ERROR (a, (1))",
                                           "ERROR (1,)", "UNDO", "BACKWARD"])),
                *draw(statements(1))]
    out.append(draw(st.sampled_from([closing] * 38 + ["ENDFUNC", "ENDPROC"])))
    return out


@st.composite
def program_text(draw: st.DrawFn) -> str:
    items: list[str] = []
    for _ in range(draw(st.integers(1, 3))):
        if draw(st.booleans()):
            items.append("CONST num c:=1;")
        items += draw(routine_text())
    gap = draw(st.sampled_from(["\n", " ", "\r\n\t", "\n! note\n"]))
    return "MODULE M" + gap + gap.join(items) + "\nENDMODULE\n"


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(program_text())
def test_random_blocks_and_routines_parse_as_with_the_plain_grammar(text):
    assert_parses_as_plain(text)


# ------------------------------------------------------------ random argument lists
VALUES = ["(1)", "a", "(i-1)*2", "Offs(p1,(i-1)*d,0,h)", '"a,b\\\\c;"', '"q""\\\\"', "[1,(2)]",
          "a{(1)}", "Baz(\\A:=1, 2)", "CRobT(\\Tool:=t \\WObj:=w)", "NOT b", "-(1)", "x = [1,2]",
          "<ARG>", "", "1 2", "(1", "1)", "IF"]
NAMES = ["A", "Conc", "WObj", "IF", "a1", "\u00c4r"]


@st.composite
def argument(draw: st.DrawFn, first: bool) -> str:
    """One argument with what may stand before it (a comma; for an optional one a
    backslash, a comma and a backslash, or nothing but whitespace), right or wrong."""
    ws = st.sampled_from(["", " ", "\n  ", "\t"])
    name, value = draw(st.sampled_from(NAMES)), draw(st.sampled_from(VALUES))
    kind = draw(st.sampled_from(["value", "value", "named", "optional", "switch",
                                 "conditional"]))
    if kind == "value":
        text = value
    elif kind == "named":
        text = f"{name}{draw(ws)}:={draw(ws)}{value}"
    else:
        text = "\\" + draw(ws) + name + {
            "optional": f"{draw(ws)}:={draw(ws)}{value}", "switch": "",
            "conditional": f"{draw(ws)}?{draw(ws)}{draw(st.sampled_from(NAMES))}"}[kind]
    before = "" if first else draw(st.sampled_from([",", ",", ", ", " ", ",\n  "]))
    return before + draw(ws) + text


@st.composite
def call_text(draw: st.DrawFn) -> str:
    count = draw(st.integers(0, 5))
    arguments = "".join(draw(argument(k == 0)) for k in range(count))
    head = draw(st.sampled_from(["Foo ", "MoveL ", "Foo", "%s% ", '%"a" + b%', "IF "]))
    return f"{head}{arguments};"


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(call_text(), min_size=1, max_size=4))
def test_random_argument_lists_parse_as_with_the_plain_grammar(calls):
    """Calls the reader finds loosely and splits at the commas and backslashes outside
    brackets and strings: the same tree as the plain grammar's, or the same error."""
    assert_parses_as_plain(routine("IF a THEN", *(f"  {c}" for c in calls), f"  {MOVE}",
                                   "ENDIF"))


# ------------------------------------------------------------ damaged programs
DAMAGE = [",", "\\", "(", ")", "[", "]", ";", '"', "%", "\n", "IF ", " THEN", " DO", ":=",
          "?", "{", "}", " AND", "<ARG>", "RAISE ", "!", ""]


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 40), st.floats(0, 1), st.sampled_from(DAMAGE), st.integers(0, 12))
def test_damaged_mixes_of_statements_parse_or_fail_as_with_the_plain_grammar(
        seed, where, damage, cut):
    """A random mix of a cell's statements (mixed_shapes.py) with one piece of damage
    (a separator, bracket, quote or keyword put in, or characters taken out) somewhere in
    its routines: the reader and the fast terminals give the plain grammar's tree, or
    refuse the text as it does."""
    text = mixed_program(seed, 120)
    first = text.index("  PROC ")
    at = first + int(where * (len(text) - first - 12))
    assert_parses_as_plain(text[:at] + damage + text[at + (0 if damage else cut):])
