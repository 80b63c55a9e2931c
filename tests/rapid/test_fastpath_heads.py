"""The heads of IF, ELSEIF, WHILE, FOR, TEST and CASE and the RETURN statement as single
fast tokens (rapidfix.rapid.fastpath FAST_IF, FAST_ELSEIF, FAST_WHILE, FAST_FOR, FAST_TEST,
FAST_CASE, FAST_RETURN): their conditions are read by fast_expressions' reader, and the
tree must be the plain grammar's, node for node, or both routes must refuse the text.
So must a procedure's head without parameters (FAST_PROC).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the comparisons of the fast path tests
from test_fastpath import assert_parses_as_plain, module, plain_tree, routine, shape
from test_fastpath_expressions import expression
from test_shared_operands import TARGET, TOOL, WOBJ, assert_same_model

from rapidfix.rapid import fast_blocks, fastpath
from rapidfix.rapid import syntax as s
from rapidfix.rapid.fast_expressions import NotRead, read_expression
from rapidfix.rapid.fastpath import RUN_LIMIT, fast_parser


def fast_tokens(text: str) -> list[str]:
    """The types of the fast tokens the fast parser's lexer cuts `text` into, without
    fast_blocks' reader (which reads with these terminals, and reads on where they end)."""
    seen: list[str] = []
    parser = fast_parser()
    fast_blocks.READ_AHEAD = False
    try:
        interactive = parser.parse_interactive(text)
        for token in interactive.iter_parse():
            if token.type.startswith("FAST_"):
                seen.append(token.type)
    finally:
        fast_blocks.READ_AHEAD = True
    return seen


CONDITIONS = [
    "x > 1 AND NOT bOk OR x=2",
    "x <> -1 AND x<=3 XOR DInput(di1) = 1",
    "NOT NOT TRUE",
    "nCount MOD 2 = 0",
    "s = \"a;b THEN\" OR s <> \"\"",
    "a.b{i+1}.c >= (n - 1) * 2",
    "TestDI(di1) AND NOT TestDI(di2)",
    "Abs(p.trans.x - CRobT(\\Tool:=tool0 \\WObj:=wobj0).trans.x) < 0.5",
    "p = [1,2,3]",
    "bDone = FALSE",
    "a div 2 >= b",
]


@pytest.mark.parametrize("condition", CONDITIONS)
def test_heads_are_single_fast_tokens_with_the_plain_tree(condition):
    text = module(
        "FUNC num f(num x)",
        f"  IF {condition} THEN",
        "    RETURN x * 2;",
        f"  ELSEIF {condition} THEN",
        "    RETURN;",
        "  ELSE",
        f"    RETURN {condition};",
        "  ENDIF",
        f"  WHILE {condition} DO",
        "    x := x + 1;",
        "  ENDWHILE",
        f"  FOR i FROM {condition} TO {condition} STEP {condition} DO",
        "  ENDFOR",
        f"  TEST {condition}",
        f"  CASE {condition}, {condition}:",
        "    x := 1;",
        f"  CASE {condition}:",
        "  DEFAULT:",
        "  ENDTEST",
        "ENDFUNC",
    )
    assert shape(fast_parser().parse(text)) == plain_tree(text)
    assert fast_tokens(text) == ["FAST_FUNC", "FAST_IF", "FAST_RETURN", "FAST_ELSEIF",
                                 "FAST_RETURN", "FAST_RETURN", "FAST_WHILE", "FAST_CALLS",
                                 "FAST_FOR", "FAST_TEST", "FAST_CASE", "FAST_CALLS",
                                 "FAST_CASE"]


@pytest.mark.parametrize("text", [
    routine("IF(a)THEN", "ENDIF"),
    routine("if a then", "elseif b then", "endif"),
    routine("IF bTHEN THEN", "ENDIF"),  # THEN as the end of a name is not the keyword
    routine("WHILE a < bDO DO", "ENDWHILE"),
    routine("IF a", "  AND b", "THEN", "ENDIF"),
    routine("FOR i FROM 1 TO nSTEPs DO", "ENDFOR"),
    routine("for i from 1 to 10 step -1 do", "endfor"),
    routine("FOR i FROM TOP TO \"TO\" DO", "ENDFOR"),
    routine("TEST a", "DEFAULT:", "ENDTEST"),
    routine("TEST a ENDTEST"),
    routine('TEST s CASE "a:b", "c":', "ENDTEST"),
    module("FUNC num f()", "  RETURN ;", "  RETURN\t\n;", "ENDFUNC"),
])
def test_heads_written_tightly_or_over_lines(text):
    assert shape(fast_parser().parse(text)) == plain_tree(text)
    heads = [t for t in fast_tokens(text) if t not in ("FAST_PROC", "FAST_FUNC")]
    assert heads[0] in ("FAST_IF", "FAST_WHILE", "FAST_FOR", "FAST_TEST", "FAST_RETURN")


@pytest.mark.parametrize("text", [
    # left to the plain grammar's tokens: a comment, a conditional or named argument, a
    # placeholder in the condition
    routine("IF a ! why", "THEN", "ENDIF"),
    routine("IF f(\\A?B) THEN", "ENDIF"),
    routine("IF f(x:=1) THEN", "ENDIF"),
    routine("IF <EXP> THEN", "ENDIF"),
    routine("FOR i FROM <EXP> TO 2 DO", "ENDFOR"),
    routine("TEST a", "CASE f(\\A?B):", "ENDTEST"),
])
def test_conditions_the_reader_does_not_take_keep_the_plain_tokens(text):
    assert "FAST_IF" not in fast_tokens(text)
    assert shape(fast_parser().parse(text)) == plain_tree(text)


@pytest.mark.parametrize("text", [
    routine("IF a > b > c THEN", "ENDIF"),  # relations do not chain
    routine("IF a = NOT b THEN", "ENDIF"),  # NOT only where a condition may start
    routine("IF THEN", "ENDIF"),
    routine("WHILE a AND DO", "ENDWHILE"),
    routine("IF a b THEN", "ENDIF"),
    module("FUNC num f()", "  RETURN 1, 2;", "ENDFUNC"),
    routine("FOR i FROM 1 TO DO", "ENDFOR"),
    routine("FOR i FROM 1 STEP 2 TO 3 DO", "ENDFOR"),
    routine("TEST a", "CASE 1,:", "ENDTEST"),
    routine("TEST a", "CASE :", "ENDTEST"),
    routine("TEST", "CASE 1:", "ENDTEST"),
])
def test_invalid_heads_are_refused_as_the_grammar_refuses_them(text):
    assert_parses_as_plain(text)


@pytest.mark.parametrize("text,expected", [
    ("a AND b OR c", ("OR", ("AND", "a", "b"), "c")),
    ("a OR b AND c", ("OR", "a", ("AND", "b", "c"))),
    ("NOT a = b AND c", ("AND", ("NOT", ("=", "a", "b")), "c")),
    ("a XOR b OR c", ("OR", ("XOR", "a", "b"), "c")),
    ("-a + b < c * d", ("<", ("+", ("-", "a"), "b"), ("*", "c", "d"))),
])
def test_condition_precedence(text, expected):
    """Independent of the grammar: the precedence RAPID documents (OR XOR < AND < NOT <
    relations < + - < * / DIV MOD < unary)."""
    def tree(node: s.Expr) -> object:
        if isinstance(node, s.Binary):
            return (node.op, tree(node.left), tree(node.right))
        if isinstance(node, s.Unary):
            return (node.op, tree(node.operand))
        return node.name

    assert tree(read_expression(text, 0, condition=True)) == expected


@pytest.mark.parametrize("text", ["a < b < c", "a = NOT b", "", "a AND", "NOT", "a b"])
def test_the_condition_reader_gives_up_on_what_is_not_one_condition(text):
    with pytest.raises(NotRead):
        read_expression(text, 0, condition=True)


RELATIONS = ["=", "<>", "<", "<=", ">", ">=", " = ", "<=\n"]
LOGIC = [" AND ", " OR ", " XOR ", " and ", " Or "]


@st.composite
def condition(draw: st.DrawFn, depth: int = 0) -> str:
    """Text of a condition: sums related and joined, NOT here and there; sometimes not
    valid RAPID (a chained relation, NOT after a relation), for both routes to refuse."""
    kind = draw(st.sampled_from(["sum", "relation", "relation"]
                                + (["logic", "logic", "not", "paren"] if depth < 3 else [])))
    if kind == "sum":
        return draw(expression(2))
    if kind == "relation":
        rel = draw(st.sampled_from(RELATIONS))
        extra = draw(st.sampled_from(["", "", "", f" < {draw(expression(2))}"]))
        return f"{draw(expression(2))}{rel}{draw(expression(2))}{extra}"
    if kind == "logic":
        left, right = draw(condition(depth + 1)), draw(condition(depth + 1))
        return f"{left}{draw(st.sampled_from(LOGIC))}{right}"
    if kind == "not":
        return f"NOT {draw(condition(depth + 1))}"
    return f"({draw(condition(depth + 1))})"


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(condition(), st.sampled_from(["IF", "ELSEIF", "WHILE", "RETURN", "FOR", "TEST", "CASE",
                                     "COMPACT"]))
def test_random_conditions_parse_as_with_the_plain_grammar(cond, where):
    if where == "COMPACT":  # a compact IF in a run of calls, its statement a call or not;
        # the condition as a value and in parentheses
        body = ["Stop;", f"IF {cond} MoveL p1,v100,z1,tool0;", f"IF {cond} n := {cond};",
                f"IF {cond} RETURN 1;", f"Foo {cond}, ({cond});", "Stop;"]
    elif where == "FOR":
        body = [f"FOR i FROM {cond} TO 3 STEP {cond} DO", "  Stop;", "ENDFOR"]
    elif where == "TEST":
        body = [f"TEST {cond}", "CASE 1:", "  Stop;", "ENDTEST"]
    elif where == "CASE":
        body = ["TEST a", f"CASE {cond}, {cond}:", "  Stop;", "DEFAULT:", "ENDTEST"]
    elif where == "IF":
        body = [f"IF {cond} THEN", "  Stop;", "ENDIF"]
    elif where == "ELSEIF":
        body = ["IF a THEN", f"ELSEIF {cond} THEN", "  Stop;", "ENDIF"]
    elif where == "WHILE":
        body = [f"WHILE {cond} DO", "  Stop;", "ENDWHILE"]
    else:
        body = [f"RETURN {cond};"]
    text = module("FUNC num f()", *("  " + line for line in body), "ENDFUNC")
    assert_parses_as_plain(text)


def test_moves_inside_fast_heads_build_the_plain_model():
    lines = [f"  PERS tooldata tMill:={TOOL};", f"  PERS wobjdata wPlate:={WOBJ};",
             "  VAR num n:=0;", "  VAR bool bOk:=TRUE;"]
    lines += [f"  CONST robtarget p{i}:={TARGET};" for i in range(3)]
    body = ["IF n > 1 AND bOk THEN", "  MoveL p0,v100,z1,tMill\\WObj:=wPlate;",
            "ELSEIF NOT bOk THEN", "  MoveL Offs(p1,0,0,n),v100,z1,tMill\\WObj:=wPlate;",
            "ENDIF", "WHILE n < 3 DO", "  n := n + 1;",
            "  MoveJ p2,v100,fine,tMill\\WObj:=wPlate;", "ENDWHILE"]
    text = "\n".join(["MODULE M", *lines, "  PROC main()", *("    " + b for b in body),
                      "  ENDPROC", "ENDMODULE", ""])
    program = assert_same_model(text)
    assert [m.in_loop for m in program.motions] == [False, False, True]


# ------------------------------------------------ compact IFs inside a run
@pytest.mark.parametrize("statement", [
    "IF nCount > 3 Incr nCount;", "IF DInput(diReady) = 1 SetDO doGo, 1;",
    "IF bOn MoveL p1,v100,z1,tMill\\WObj:=wPlate;", "IF NOT bOn nCount := 0;",
    "IF a AND b c;", "if x=1 Foo;", 'IF s = "a b" Foo "x;y";',
    "IF f(a) = 1 AND (b > 2) Foo \\x:=1;",
    "IF p.trans.x > 1 p.trans.x := 0;", "IF a{i+1} b{2} := 3;", "IF -1 < x Foo;",
    "IF a\n  Foo;", "IF a > 5. Stop;", "IF a MOD 2 = 0 Foo;", "IF a DIV b Foo;", "IF TRUE Foo;",
    "IF a = FALSE Foo;", "IF a.b. c Foo;", "IF a .b Foo;", "IF a\tFoo ;", "IF Ñ{1} = 1 Ö;",
    "IF (DInput(di1) = 1) AND NOT (n > f(g, 2)) x := (a + f(b)) * 2;",
    "IF a OR b MoveL Offs(p1,0,0,n),v100,z1,tool0;",
    "IF 17>=nMotionStepCount{2} GOTO MoveArcEnd;", "IF a OR b goto\n x ;", "IF a GOTO IF;",
])
def test_a_compact_if_of_a_call_is_a_statement_of_the_run(statement):
    """`IF c <call>` or `IF c GOTO label;` (no THEN) is read in the run around it, its
    condition ended where the grammar ends it (at the first operand that whitespace and
    a name follow), as the CompactIf node the grammar builds."""
    text = routine("Stop;", statement, "Stop;")
    assert fast_tokens(text) == ["FAST_PROC", "FAST_CALLS"]
    tree = fast_parser().parse(text)
    assert shape(tree) == plain_tree(text)
    assert [type(item) for item in tree.modules[0].items[0].body] == [
        s.LazyCall, s.CompactIf, s.LazyCall]


def test_compact_ifs_are_split_with_the_lexers_own_pattern():
    """split_calls reads the compact IF head's pattern from the cached grammar extension
    (not working the patterns out again): it is the one the lexer's terminal holds."""
    fastpath._compact_head.cache_clear()
    pattern = fastpath._compact_head().pattern
    assert pattern == fastpath._patterns()["compact_head"]


@pytest.mark.parametrize(("statement", "tokens"), [
    ("IF a RETURN;", ["FAST_CALLS", "FAST_RETURN", "FAST_CALLS"]),  # not a call
    ("IF a EXIT;", ["FAST_CALLS", "FAST_CALLS"]),
    ("IF a ! why\n Foo;", ["FAST_CALLS", "FAST_CALLS"]),  # a comment inside
    ("IF a = f(\\A?B) Foo;", ["FAST_CALLS", "FAST_CALLS"]),  # a conditional argument
])
def test_other_compact_ifs_keep_the_plain_tokens(statement, tokens):
    text = routine("Stop;", statement, "Stop;")
    assert shape(fast_parser().parse(text)) == plain_tree(text)
    assert fast_tokens(text) == ["FAST_PROC", *tokens]


@pytest.mark.parametrize("statement", ["GOTO lRetry;", "goto lRetry ;", "GOTO\n  IF;", "Goto x;"])
def test_a_goto_is_a_statement_of_the_run(statement):
    text = routine("Stop;", "lRetry:", statement, "Stop;")
    assert shape(fast_parser().parse(text)) == plain_tree(text)
    assert fast_tokens(text) == ["FAST_PROC", "FAST_CALLS", "FAST_CALLS"]
    assert [type(item) for item in fast_parser().parse(text).modules[0].items[0].body] == [
        s.LazyCall, s.Label, s.Goto, s.LazyCall]


def test_moves_in_compact_ifs_build_the_plain_model():
    lines = [f"  PERS tooldata tMill:={TOOL};", f"  PERS wobjdata wPlate:={WOBJ};",
             "  VAR num n:=0;", "  VAR bool bOk:=TRUE;"]
    lines += [f"  CONST robtarget p{i}:={TARGET};" for i in range(3)]
    body = ["MoveL p0,v100,z1,tMill\\WObj:=wPlate;",
            "IF n > 1 AND bOk MoveL p1,v100,z1,tMill\\WObj:=wPlate;",
            "IF NOT bOk MoveJ Offs(p2,0,0,n),v100,fine,tMill\\WObj:=wPlate;",
            "IF DInput(di1) = 1 n := n + 1;"]
    text = "\n".join(["MODULE M", *lines, "  PROC main()", *("    " + b for b in body),
                      "  ENDPROC", "ENDMODULE", ""])
    assert fast_tokens(text) == ["FAST_DECLS", "FAST_PROC", "FAST_CALLS"]
    program = assert_same_model(text)
    assert [m.name for m in program.motions] == ["MoveL", "MoveL", "MoveJ"]


PROC_BODY = ["  MoveL p1,v100,z1,tool0;", "  ERROR", "    RETURN;", "ENDPROC"]


@pytest.mark.parametrize("head", [
    "PROC main()", "LOCAL PROC p1()", "proc Path_10 ( )", "Local\tProc p()",
    "PROC\n  main\n(\n)", "PROC Ñandú()", "PROC p() ! why", "PROC IF()", "PROC p(\t)",
])
def test_a_procedure_head_without_parameters_is_one_fast_token(head):
    text = module(head, *PROC_BODY)
    assert_parses_as_plain(text)
    if "IF()" not in head:
        assert fast_tokens(text)[0] == "FAST_PROC"


@pytest.mark.parametrize(("head", "token"), [
    ("PROC p(num a)", "FAST_PROC"), ("PROC p(\\switch s)", "FAST_PROC"),
    ("PROC Pick(robtarget pPart, INOUT num nCount, \\switch Slow)", "FAST_PROC"),
    ("PROC p(VAR num a{*}, PERS robtarget g{ * , * })", "FAST_PROC"),
    ("LOCAL PROC p(num a \\num b, \\ VAR num c)", "FAST_PROC"),
    ("PROC p(var num VAR, pers num x{*} , num y)", "FAST_PROC"),
    ("proc p (\tnum a\n, num b )", "FAST_PROC"), ("PROC Ñ(num ö)", "FAST_PROC"),
    ("FUNC num f()", "FAST_FUNC"), ("FUNC num Twice(num x, \\num y)", "FAST_FUNC"),
    ("LOCAL FUNC robtarget Above(robtarget p, num h)", "FAST_FUNC"),
    ("func bool IF(INOUT num a{*})", "FAST_FUNC"),
])
def test_a_routine_head_with_parameters_is_one_fast_token(head, token):
    """A procedure's or function's head with its parameters (required, optional after a
    comma or not, with access and dimensions) is one token, read to the plain tree."""
    body = PROC_BODY if token == "FAST_PROC" else ["  RETURN 1;", "ENDFUNC"]
    text = module(head, *body)
    assert_parses_as_plain(text)
    assert fast_tokens(text)[0] == token


@st.composite
def parameter_list(draw: st.DrawFn) -> str:
    """Text of a parameter list: access words, types, names, dimensions, optional ones
    after a comma or not; now and then something the grammar refuses or the fast head
    leaves to it (a missing name, a trailing comma, alternatives, a comment)."""
    pieces = []
    for k in range(draw(st.integers(0, 4))):
        slash = draw(st.sampled_from(["", "", "\\", "\\ "]))
        access = draw(st.sampled_from(["", "", "VAR ", "pers ", "INOUT ", "VAR\t"]))
        kind = draw(st.sampled_from(["num", "robtarget", "VAR", "Ñum", "IF"]))
        name = draw(st.sampled_from(["a", "nCount", "VAR", "x1", "", "ö"]))
        dims = draw(st.sampled_from(["", "", "{*}", "{ * , * }", " {*,*,*}", "{1}"]))
        gap = draw(st.sampled_from([", ", ",", " ", "\n, ", " | ", ",)", " ! c\n,"]))
        pieces.append(("" if k == 0 else gap) + f"{slash}{access}{kind} {name}{dims}")
    return "".join(pieces)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(parameter_list(), st.sampled_from(["PROC p", "LOCAL PROC p", "FUNC num f"]))
def test_random_parameter_lists_parse_as_with_the_plain_grammar(params, head):
    body = ["  RETURN 1;", "ENDFUNC"] if "FUNC" in head else PROC_BODY
    assert_parses_as_plain(module(f"{head}({params})", *body))


@pytest.mark.parametrize("head", [
    "PROC p ! c\n()", "LOCAL ! c\n PROC p()", "TRAP t", "PROC p(<PAR>)", "PROC <ID>()",
    "LOCALPROC p()", "PROC p()()", "PROC p(", "LOCAL LOCAL PROC p()", "PROC p(\\num a | num b)",
    "PROC p(INOUT x)", "PROC p(num a,)", "PROC p(num)", "PROC p(num a b)", "FUNC num{*} f()",
    "PROC p(VARx num y)", "PROC p(num a ! c\n)",
])
def test_other_routine_heads_keep_the_plain_tokens(head):
    body = PROC_BODY if "FUNC" not in head else ["  RETURN 1;", "ENDFUNC"]
    body = ["ENDTRAP"] if "TRAP" in head else body
    text = module(head, *body)
    assert_parses_as_plain(text)


def test_a_late_error_after_many_fast_procedure_heads_is_explained_as_in_full():
    routines = [line for k in range(600) for line in
                (f"PROC Path_{k}()", "  MoveL p1,v100,z1,tool0;", "ENDPROC")]
    text = module(*routines[:-3], "PROC last()", "  MoveL p1 v100,z1,tool0;", "ENDPROC")
    assert_parses_as_plain(text)


# ------------------------------------------------ a move's target `Offs(p7,0,0,-10)`
_NUMBER_TEXTS = st.sampled_from(["0", "-0", "10", "-0.5", "1.", ".5", "-1e3", "2E-2", "0x1F",
                                 "1.5e+2", "-.25", "007"])
_HEAD_NAMES = st.sampled_from(["p1", "pHome_2", "TRUE", "false", "Año", "x", "ORIENT", "p10x",
                                "[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]",
                                "[[1, 2,3],[1,0,0,0]]", "[[1,2]", "[1-1,2]"])


_GAPS = st.sampled_from(["", "", " ", "  ", "\t", "\n  "])
# an offset: a number, or a name (negated, a component, a keyword, a digit after it), or
# arithmetic of those (an operator the one-pattern route does not take, a parenthesis)
_OFFSETS = st.one_of(_NUMBER_TEXTS, st.sampled_from(
    ["nLift", "-nLift", "- n2", "n.x", "TRUE", "MOD", "nA{2}", "f(1)", "n1e5", "nLift + 5",
     "n*2", "- n / 2", "1e-5-1", "n MOD 2", "n - -1", "(n+1)"]))


@st.composite
def named_call(draw: st.DrawFn, depth: int = 2) -> str:
    """A call of a name (or of such a call, down to `depth`) and numbers (or names) as a
    move's target, tight or spaced, perhaps with optional arguments of those, and
    perhaps with a space or a piece put anywhere."""
    if depth == 0:
        return draw(_HEAD_NAMES)
    name = draw(st.sampled_from(["Offs", "RelTool", "Foo", "offs"]))
    numbers = draw(st.lists(_OFFSETS, min_size=1, max_size=4))
    # the first argument: a name, an inline target, or such a call itself
    head = draw(_HEAD_NAMES) if draw(st.booleans()) else draw(named_call(depth - 1))
    text = f"{name}({draw(_GAPS)}{head}"
    for number in numbers:
        text += f"{draw(_GAPS)},{draw(_GAPS)}{number}"
    for _ in range(draw(st.integers(0, 2))):
        option = draw(st.sampled_from(["Rz", "Rx", "A1", "TRUE"]))
        text += f"{draw(_GAPS)}\\{draw(_GAPS)}{option}{draw(_GAPS)}:={draw(_GAPS)}"
        text += draw(_OFFSETS)
    text += f"{draw(_GAPS)})"
    if draw(st.booleans()):  # a space or a piece the one-pattern route does not take
        at = draw(st.integers(0, len(text) - 1))
        text = text[:at] + draw(st.sampled_from([" ", "\\Rz:=90,", "\n", "\\Rz", "n",
                                                 ",", "+"])) + text[at:]
    return text


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(named_call())
def test_a_call_of_a_name_and_numbers_reads_as_the_general_reader_and_the_grammar_read_it(text):
    fast = fastpath._named_call(text, 7)
    if fast is not None:  # what _value_node (through _call_node) makes, to the shared tail
        general = fastpath._value_node(text, 7)
        assert shape(fast) == shape(general) and fast.tail is general.tail
        assert shape(fast.args) == shape(general.args)
    assert_parses_as_plain(routine(f"MoveL {text},v100,z1,tool0\\WObj:=w;",
                                   f"MoveL {text}, v100, z1, tool0;"))


@pytest.mark.parametrize("text", ["Offs(p1,0,0,-10)", "RelTool(p1, 0, 0, -nDepth \\Rz:=45)",
                                  "RelTool(Offs(p1,0,0,10),0,0,0\\Rz:=45)",
                                  "Offs( RelTool( p1 , 0, 0, -20 ) , 0, 0, nLift )",
                                  "Offs(p1, nDx * 2, 0, nLift + 5 - -1)"])
def test_a_call_of_a_name_or_of_such_a_call_is_read_by_one_pattern(text):
    fast = fastpath._named_call(text, 7)
    general = fastpath._value_node(text, 7)
    assert fast is not None and shape(fast) == shape(general) and fast.tail is general.tail
    assert shape(fast.args) == shape(general.args)
    assert fastpath._named_call("Offs(Offs(Offs(p1,0,0,1),0,0,1),0,0,1)", 7) is None


# ------------------------------------------------ IF blocks of calls inside a run
@pytest.mark.parametrize(("text", "tokens"), [
    (routine("MoveL p0,v100,z1,tool0;", "IF bOn THEN MoveL p1,v100,z1,tool0; Set do1; ENDIF",
             "MoveL p2,v100,z1,tool0;"), ["FAST_CALLS"]),
    (routine("IF bOn THEN x := x + 1; Reset do1; ENDIF ! the gripper"), ["FAST_CALLS"]),
    (routine("IF bOn THEN MoveL p1, v100, z1, tool0; ! down ENDIF", "ENDIF"),
     ["FAST_IF", "FAST_CALLS"]),
    # over lines: the head is a token of its own, its body a run
    (routine("IF bOn THEN", "  ! the gripper", "  MoveL p1, v100, z1, tool0; ! down",
             "  x := x + 1;", "ENDIF"), ["FAST_IF", "FAST_CALLS"]),
    (routine("if n>2 AND NOT bStop then movel p1,v100,z1,tool0; endif"), ["FAST_CALLS"]),
    (routine('IF s = "THEN" THEN TPWrite "ENDIF;"; ENDIF'), ["FAST_CALLS"]),
    (routine("IF a THEN MoveL p1,v100,z1,tool0; ENDIF IF b THEN ENDIF Stop;"), ["FAST_CALLS"]),
    (routine("IF Ñ{1} = 1 THEN n := n + 1; ENDIF"), ["FAST_CALLS"]),
    # not calls only: the IF head is a token of its own, as before
    (routine("IF a THEN", "  MoveL p1,v100,z1,tool0;", "ELSEIF b THEN", "ENDIF"),
     ["FAST_IF", "FAST_CALLS", "FAST_ELSEIF"]),
    (routine("IF a THEN Foo; ELSE Bar; ENDIF"), ["FAST_IF", "FAST_CALLS", "FAST_CALLS"]),
    (routine("IF a THEN IF b THEN Foo; ENDIF ENDIF"), ["FAST_IF", "FAST_CALLS"]),
    (routine("IF a THEN WHILE b DO ENDWHILE ENDIF"), ["FAST_IF", "FAST_WHILE"]),
    (routine("IF a THEN " + "Foo; " * (RUN_LIMIT + 1) + "ENDIF"),
     ["FAST_IF", "FAST_CALLS", "FAST_CALLS"]),
])
def test_an_if_block_of_calls_is_a_statement_of_the_run(text, tokens):
    """`IF c THEN <calls> ENDIF` on the line of its THEN (no ELSE, nothing nested, at most
    RUN_LIMIT calls) is read in the run of calls around it, as the If node the grammar
    builds; any other IF keeps its head token."""
    assert shape(fast_parser().parse(text)) == plain_tree(text)
    assert fast_tokens(text) == ["FAST_PROC", *tokens]


def test_a_run_holding_an_if_block_is_left_to_the_full_read_back():
    """The bulk reader reads runs of plain calls; a run holding an IF block goes the full
    route (the read-back then finds the moves inside it as the model does)."""
    from rapidfix.rapid.readback import read_bulk

    plain = routine("MoveL p1,v100,z1,tool0;", "MoveL p2,v100,z1,tool0;")
    assert [c[0] for c in read_bulk(plain).calls] == ["MoveL", "MoveL"]
    assert read_bulk(routine("MoveL p1,v100,z1,tool0;",
                             "IF a THEN MoveL p2,v100,z1,tool0; ENDIF")) is None
    assert read_bulk(routine("MoveL p1,v100,z1,tool0;", "IF a MoveL p2,v100,z1,tool0;")) is None
    assert read_bulk(routine("MoveL p1,v100,z1,tool0;", "GOTO l;")) is None


# ------------------------------------------------ arcs: the tail after the first target
def test_the_tail_after_an_arcs_first_target_is_made_when_a_call_repeats_it():
    """split_calls keeps the tail after an arc's first target unmade (an arc's end point
    hardly recurs) and makes it when a call repeats it, as its tail or as the rest after
    its second argument: the same trees as the plain grammar's."""
    from rapidfix.rapid import fastpath

    fastpath.forget_texts()
    first = routine("MoveL p9, v100, z1, tool0;", "MoveC p1, p2, v100, z1, tool0;")
    assert shape(fast_parser().parse(first)) == plain_tree(first)
    assert type(fastpath._TAILS[", p2, v100, z1, tool0;"]) is tuple  # kept unmade
    again = routine("MoveC p3, p2, v100, z1, tool0;",  # the whole tail again
                    "MoveC Offs(p1,0,0,1), p2, v100, z1, tool0;",
                    "Foo a, p4, p2, v100, z1, tool0;",  # as the rest after a second
                    "MoveC p5, p6, v100, z1, tool0;", "MoveC p7, p6, v100, z1, tool0;")
    fastpath.forget_texts()
    fastpath._TAILS.clear()
    assert shape(fast_parser().parse(first)) == plain_tree(first)
    assert shape(fast_parser().parse(again)) == plain_tree(again)
    assert isinstance(fastpath._TAILS[", p2, v100, z1, tool0;"], fastpath.CallTail)
