"""Inputs that ran away: statements the fast terminals almost take, and expressions
nested thousands deep.

The fast terminals are regular expressions. Where two of their alternatives took the
same text (`1` as a single value and as a sum, `[1,2]` as a numeric aggregate and as
a group of sums), a statement that failed near its end was retried in every
combination: `Foo \\A:=1 \\A:=1 ... x;` with 20 options took 1.5 s, with 200 it did
not finish. Each case below has 64 repetitions, 2^64 combinations for the old
patterns: the guard stops the test after a minute instead of hanging the suite, the
new patterns need milliseconds. Only termination and the verdict are asserted."""

from __future__ import annotations

import signal
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the comparisons of the fast path tests
from test_fastpath import plain_tree, shape

from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid import parse_program
from rapidfix.rapid.fast_expressions import DEEPEST, NotRead, read_expression
from rapidfix.rapid.fastpath import fast_parser

N = 64
NEAR_MISSES = {
    "options": "Foo " + " ".join(["\\A:=1"] * N) + " x;",
    "options of names": "Foo " + " ".join(["\\A:=b"] * N) + " x;",
    "aggregates": "Foo " + ",".join(["[1,2]"] * N) + " x y;",
    "groups in an aggregate": "Foo [" + ",".join(["[1,2]"] * N) + "] x;",
    "function calls": "Foo " + ",".join(["f(1)"] * N) + " x;",
    "Offs arguments": "MoveL Offs(p," + ",".join(["1"] * N) + ") x;",
    "a string at the end": "Foo " + ", ".join(["1"] * N) + ', "end" x;',
    "assignment": "x := " + " ".join(["\\A:=1"] * N) + ";",
    # the heads' conditions: taken as few characters as can be, up to THEN, DO or ';'
    "condition without THEN": "IF " + " AND ".join(['f(1) = "a"'] * N) + " ;",
    "condition without DO": "WHILE " + " OR ".join(["a{1}.b < -1"] * N) + " x;",
    "strings in calls": "Foo " + ",".join(['f("a)", TRUE)'] * N) + " x;",
    "relations in arguments": "Foo " + ",".join(['a = "b" AND NOT c'] * N) + " x;",
    "FOR without TO": "FOR i FROM " + " + ".join(['f("TO")'] * N) + " DO",
    "TEST without a clause": "TEST " + " + ".join(["a{1}"] * N) + " x;",
    "CASE without its colon": "TEST a CASE " + ", ".join(["1"] * N) + " x;",
    "RETURN without its end": "RETURN " + " + ".join(["\\A:=1"] * N) + " x",
    # a compact IF's condition: up to the first operand that a name follows
    "compact IF": "IF " + " AND ".join(["f(a, 1) = (b + g(c))"] * N) + " Foo x y;",
    "compact IF of a keyword": "IF " + " OR ".join(['(a{1} > f("x"))'] * N) + " GOTO ;",
    "compact IF without a statement": "IF " + " + ".join(["(f(1) + (a))"] * N) + " ;",
    "parentheses of calls": "Foo " + ",".join(["(f(1) + (a))"] * N) + " x;",
    "a table of records": "VAR seam s{64}:=[" + ",".join(['[1,"a",[2,3]]'] * N) + "] x;",
    "two-dimensional aggregates": "VAR robtarget g{2,2}:=["
                                  + ",".join(["[[[1,2],[3]],[[4],[5]]]"] * N) + "] x;",
}


class Hang(Exception):
    pass


@pytest.fixture
def guard():
    """Stop a runaway match after a minute (SIGALRM) rather than hang the suite."""
    def stop(_signum, _frame):
        raise Hang()

    previous = signal.signal(signal.SIGALRM, stop)
    signal.alarm(60)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, previous)


@pytest.mark.parametrize("name", list(NEAR_MISSES))
def test_a_statement_the_fast_terminals_almost_take_is_refused_at_once(name, guard):
    text = f"MODULE M\n  PROC main()\n    {NEAR_MISSES[name]}\n  ENDPROC\nENDMODULE\n"
    with pytest.raises(RapidSyntaxError) as err:
        parse_program(text, "m.mod")
    assert str(err.value).startswith("m.mod:3:")


@pytest.mark.parametrize("name", ["options", "aggregates", "function calls", "compact IF",
                                  "parentheses of calls", "two-dimensional aggregates",
                                  "a table of records"])
def test_the_same_statements_when_valid_are_read_fast(name, guard):
    statement = NEAR_MISSES[name].replace(" x y;", ";").replace(" x;", ";")
    text = f"MODULE M\n  PROC main()\n    {statement}\n  ENDPROC\nENDMODULE\n"
    assert shape(fast_parser().parse(text)) == plain_tree(text)


def test_expressions_nested_beyond_the_stack_are_left_to_the_grammar():
    with pytest.raises(NotRead):
        read_expression("-" * 3000 + "1", 0)
    with pytest.raises(NotRead):
        read_expression("+".join(["a"] * (DEEPEST + 1)), 0)
    with pytest.raises(NotRead):
        read_expression("(" * 60 + "+".join(["a"] * 150) + ")" * 60, 0)
    # long and flat (a matrix written over many lines, as real programs have) is read
    matrix = "[" + ",\n    ".join(["[5, 0, 1, 6, 0, -1]", "[a, 0, 1, 6, 0, -1]"] * 200) + "]"
    assert len(read_expression(matrix, 0).items) == 400
    assert shape(read_expression("+".join(["a"] * 50), 0)) is not None


@pytest.mark.parametrize("where", ["declaration", "call", "header"])
def test_a_long_string_is_read_without_a_record_per_character(where):
    """A string repeated one character at a time as a group made the regular-expression
    engine keep a backtracking record per character (a 6 MB string: 2.7 GB). Written as
    runs between doubled quotes, a 400,000-character string costs a few MB, in the fast
    terminals and in the grammar's own; the value is the text, `""` read as one quote."""
    import tracemalloc

    body = "x" * 200_000 + '""' + "y" * 200_000
    line = {"declaration": f'CONST string s := "{body}";',
            "call": f'PROC main()\n  TPWrite "{body}";\nENDPROC',
            "header": f'PROC main()\n  IF x = "{body}" THEN\n  ENDIF\nENDPROC'}[where]
    text = f"MODULE M\n{line}\nENDMODULE\n"
    parse_program("MODULE M\nENDMODULE\n")  # the parsers are built before the count
    tracemalloc.start()
    try:
        program = parse_program(text)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 40_000_000  # the old pattern: about 180 MB for this string
    if where == "declaration":
        assert program.declaration("s").value == "x" * 200_000 + '"' + "y" * 200_000
    assert shape(fast_parser().parse(text)) == plain_tree(text)
