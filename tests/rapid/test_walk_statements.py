"""walk_statements visits every statement once, in source order, with its loop depth."""

from __future__ import annotations

import dataclasses

from rapidfix.rapid import load_program, parse_program
from rapidfix.rapid import syntax as s


def reference_walk(body: list[s.Statement], loops: int = 0) -> list[tuple[s.Statement, int]]:
    """The same walk written recursively from the statement fields themselves."""
    out: list[tuple[s.Statement, int]] = []
    for statement in body:
        out.append((statement, loops))
        inner = loops + 1 if isinstance(statement, (s.For, s.While)) else loops
        if isinstance(statement, s.If):
            nested = [b for _, b in statement.branches] + (
                [statement.otherwise] if statement.otherwise is not None else [])
        elif isinstance(statement, s.Test):
            nested = [b for _, b in statement.cases] + (
                [statement.default] if statement.default is not None else [])
        elif isinstance(statement, s.CompactIf):
            nested = [[statement.statement]]
        elif isinstance(statement, (s.For, s.While)):
            nested = [statement.body]
        else:
            nested = []
        for body_ in nested:
            out.extend(reference_walk(body_, inner))
    return out


NESTED = """MODULE W
PROC main()
  Foo 1;
  FOR i FROM 1 TO 2 DO
    IF a THEN
      WHILE b DO
        Bar;
        IF c Baz;
      ENDWHILE
    ELSEIF d THEN
      TEST n
      CASE 1:
        Qux;
      DEFAULT:
        FOR j FROM 1 TO 2 DO
          Quux;
        ENDFOR
      ENDTEST
    ELSE
      Corge;
    ENDIF
    Grault;
  ENDFOR
  Garply;
ENDPROC
ENDMODULE
"""


def routine_bodies(program):
    for module in program.syntax.modules:
        for item in module.items:
            if isinstance(item, s.Routine):
                yield item.body
                yield from (h.body for h in item.handlers)


def same_walk(body: list[s.Statement]) -> bool:
    got = [(id(statement), loops) for statement, loops in s.walk_statements(body)]
    return got == [(id(statement), loops) for statement, loops in reference_walk(body)]


def test_nested_statements_in_source_order_with_loop_depth():
    program = parse_program(NESTED)
    (body,) = list(routine_bodies(program))[:1]
    walked = [("ProcedureCall" if isinstance(st, s.ProcedureCall) else type(st).__name__, loops)
              for st, loops in s.walk_statements(body)]
    assert walked == [
        ("ProcedureCall", 0), ("For", 0), ("If", 1), ("While", 1), ("ProcedureCall", 2),
        ("CompactIf", 2), ("ProcedureCall", 2), ("Test", 1), ("ProcedureCall", 1),
        ("For", 1), ("ProcedureCall", 2), ("ProcedureCall", 1), ("ProcedureCall", 1),
        ("ProcedureCall", 0),
    ]
    assert same_walk(body)


def test_every_sample_walks_as_the_recursive_reference(rapid_samples):
    for path in rapid_samples:
        for body in routine_bodies(load_program(path)):
            assert same_walk(body), path.name


def test_every_statement_with_a_body_is_entered():
    """A statement type that holds statement lists must be known to the walk."""
    for cls in vars(s).values():
        if isinstance(cls, type) and issubclass(cls, s.Statement):
            holds_bodies = any("Statement" in str(f.type) for f in dataclasses.fields(cls))
            assert holds_bodies == (cls in s.COMPOUND_STATEMENTS), cls.__name__
