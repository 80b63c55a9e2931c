"""Lark callbacks that build rapidfix.rapid.syntax nodes while the LALR parser runs.

The transformer is handed to Lark itself, so no parse tree is ever built: each
rule becomes a node the moment it is reduced, and its span comes from the
first and last token or node inside it.
"""

from __future__ import annotations

import re
from typing import Any

from lark import Token, Transformer, v_args

from rapidfix.rapid import syntax as s

_STRING_ESCAPE = re.compile(r'""|\\\\|\\([0-9A-Fa-f]{2})')
_AGGREGATE_ITEM = re.compile(r"\[([^\[\]]*)\]|([^\s,\[\]]+)")


def _start(item: Any) -> int:
    return item.start_pos if isinstance(item, Token) else item.start


def _end(item: Any) -> int:
    return item.end_pos if isinstance(item, Token) else item.end


def number_value(text: str) -> float:
    """RAPID num literal (decimal, exponent, 0x / 0b / 0o) as a float."""
    if len(text) > 1 and text[0] == "0" and text[1] in "xXbBoO":
        return float(int(text, 0))
    return float(text)


def string_value(text: str) -> str:
    """Decode a RAPID string literal: "" is a quote, \\\\ a backslash, \\hh a byte."""
    body = text[1:-1]
    if '"' not in body and "\\" not in body:
        return body

    def repl(match: re.Match[str]) -> str:
        if match.group(1):
            return chr(int(match.group(1), 16))
        return match.group(0)[0]

    return _STRING_ESCAPE.sub(repl, body)


def numeric_aggregate_value(text: str) -> tuple:
    """Numbers of an all-numeric aggregate, nested as written: '[[1,2],3]' -> ((1.0, 2.0), 3.0)."""
    body = text.strip()[1:-1]
    if "[" not in body:
        return tuple(float(x) for x in body.split(","))
    items: list[Any] = []
    for match in _AGGREGATE_ITEM.finditer(body):
        inner, scalar = match.groups()
        if inner is not None:
            items.append(tuple(float(x) for x in inner.split(",")))
        else:
            items.append(float(scalar))
    return tuple(items)


def statements_in(children: tuple) -> list[s.Statement]:
    """The statements among a rule's children (its keywords and clauses left out)."""
    return [c for c in children if isinstance(c, s.Statement)]


@v_args(inline=True)
class SyntaxBuilder(Transformer):
    """Rule name -> syntax node. Method names follow the rule names of rapid.lark."""

    # ------------------------------------------------------------ expressions
    def number(self, tok: Token) -> s.Number:
        return s.Number(tok.start_pos, tok.end_pos, number_value(tok), str(tok))

    def string(self, tok: Token) -> s.String:
        return s.String(tok.start_pos, tok.end_pos, string_value(tok))

    def true(self, tok: Token) -> s.Bool:
        return s.Bool(tok.start_pos, tok.end_pos, True)

    def false(self, tok: Token) -> s.Bool:
        return s.Bool(tok.start_pos, tok.end_pos, False)

    def numeric_aggregate(self, tok: Token) -> s.NumericAggregate:
        return s.NumericAggregate(tok.start_pos, tok.end_pos, numeric_aggregate_value(tok))

    def aggregate(self, open_: Token, *rest: Any) -> s.Aggregate:
        return s.Aggregate(open_.start_pos, rest[-1].end_pos, list(rest[:-1]))

    def paren(self, open_: Token, inner: s.Expr, close: Token) -> s.Paren:
        return s.Paren(open_.start_pos, close.end_pos, inner)

    def name_ref(self, tok: Token) -> s.NameRef:
        return s.NameRef(tok.start_pos, tok.end_pos, str(tok))

    def index(self, base: s.Expr, *rest: Any) -> s.Index:
        return s.Index(base.start, rest[-1].end_pos, base, list(rest[:-1]))

    def component(self, base: s.Expr, name: Token) -> s.Component:
        return s.Component(base.start, name.end_pos, base, str(name))

    def call(self, name: Token, *rest: Any) -> s.Call:
        args = rest[0] if len(rest) == 2 else []
        return s.Call(name.start_pos, rest[-1].end_pos, str(name), args)

    def unary(self, op: Token, operand: s.Expr) -> s.Unary:
        return s.Unary(op.start_pos, operand.end, str(op).upper(), operand)

    def binary(self, left: s.Expr, op: Token, right: s.Expr) -> s.Binary:
        return s.Binary(left.start, right.end, str(op).upper(), left, right)

    # ------------------------------------------------------------ arguments
    def arguments(self, *args: s.Argument) -> list[s.Argument]:
        return list(args)

    def required_argument(self, *children: Any) -> s.Argument:
        if len(children) == 1:
            value = children[0]
            return s.Argument(value.start, value.end, "required", None, value)
        name, value = children
        return s.Argument(name.start_pos, value.end, "required", str(name), value)

    def optional_argument(self, slash: Token, name: Token,
                          value: s.Expr | None = None) -> s.Argument:
        end = name.end_pos if value is None else value.end
        return s.Argument(slash.start_pos, end, "optional", str(name), value)

    def conditional_argument(self, slash: Token, name: Token, param: Token) -> s.Argument:
        return s.Argument(
            slash.start_pos, param.end_pos, "conditional", str(name), None, str(param)
        )

    # ------------------------------------------------------------ statements
    def placeholder(self, tok: Token) -> s.Placeholder:
        return s.Placeholder(tok.start_pos, tok.end_pos, str(tok))

    dim_placeholder = module_placeholder = placeholder

    def statement_placeholder(self, tok: Token) -> s.StatementPlaceholder:
        return s.StatementPlaceholder(tok.start_pos, tok.end_pos, str(tok))

    def case_placeholder(self, tok: Token) -> tuple:
        # a CASE clause not yet written: no values to compare, no statements
        return ("case", [self.placeholder(tok)], [])

    def argument_placeholder(self, tok: Token) -> s.Argument:
        return s.Argument(tok.start_pos, tok.end_pos, "required", None, self.placeholder(tok))

    def parameter_placeholder(self, tok: Token) -> s.Parameter:
        # named and typed by its own text, which no data name can equal
        return s.Parameter(tok.start_pos, tok.end_pos, None, str(tok), str(tok))

    alternative_placeholder = parameter_placeholder

    def assignment(self, target: s.Expr, value: s.Expr, semi: Token) -> s.Assignment:
        return s.Assignment(target.start, semi.end_pos, target, value)

    def procedure_call(self, name: Token, *rest: Any) -> s.ProcedureCall:
        args = rest[0] if len(rest) == 2 else []
        return s.ProcedureCall(name.start_pos, rest[-1].end_pos, str(name), args)

    def late_call(self, percent: Token, target: s.Expr, *rest: Any) -> s.LateCall:
        args = rest[0] if len(rest) == 2 else []
        return s.LateCall(percent.start_pos, rest[-1].end_pos, target, args)

    def if_stmt(self, if_: Token, cond: s.Expr, then: Token, *rest: Any) -> s.If:
        return self.if_branches(if_.start_pos, cond, rest)

    @staticmethod
    def if_branches(start: int, cond: s.Expr, rest: tuple) -> s.If:
        """The If node of an IF at `start` with condition `cond`, from what follows its
        THEN (statements, ELSEIF and ELSE clauses, the ENDIF token)."""
        branches: list[tuple[s.Expr, list[s.Statement]]] = [(cond, statements_in(rest))]
        otherwise = None
        for item in rest:
            if isinstance(item, tuple) and item[0] == "elseif":
                branches.append((item[1], item[2]))
            elif isinstance(item, tuple) and item[0] == "else":
                otherwise = item[1]
        return s.If(start, rest[-1].end_pos, branches, otherwise)

    def elseif_clause(self, _kw: Token, cond: s.Expr, _then: Token, *body: Any) -> tuple:
        return ("elseif", cond, statements_in(body))

    def else_clause(self, _kw: Token, *body: Any) -> tuple:
        return ("else", statements_in(body))

    def compact_if(self, if_: Token, cond: s.Expr, statement: s.Statement) -> s.CompactIf:
        return s.CompactIf(if_.start_pos, statement.end, cond, statement)

    def for_stmt(self, for_: Token, var: Token, _from: Token, first: s.Expr, _to: Token,
                 last: s.Expr, *rest: Any) -> s.For:
        step = rest[1] if isinstance(rest[0], Token) and rest[0].type == "STEP" else None
        return s.For(for_.start_pos, rest[-1].end_pos, str(var), first, last, step,
                     statements_in(rest))

    def while_stmt(self, while_: Token, cond: s.Expr, _do: Token, *rest: Any) -> s.While:
        return s.While(while_.start_pos, rest[-1].end_pos, cond, statements_in(rest))

    def test_stmt(self, test: Token, subject: s.Expr, *rest: Any) -> s.Test:
        return self.test_clauses(test.start_pos, subject, rest)

    @staticmethod
    def test_clauses(start: int, subject: s.Expr, rest: tuple) -> s.Test:
        """The Test node of a TEST at `start` of `subject`, from its CASE and DEFAULT
        clauses and the ENDTEST token."""
        cases = [item[1:] for item in rest if isinstance(item, tuple) and item[0] == "case"]
        default = next((item[1] for item in rest if isinstance(item, tuple)
                        and item[0] == "default"), None)
        return s.Test(start, rest[-1].end_pos, subject, cases, default)

    def case_clause(self, _case: Token, *rest: Any) -> tuple:
        values = [x for x in rest if not isinstance(x, (s.Statement, Token))]
        return ("case", values, statements_in(rest))

    def default_clause(self, _default: Token, *rest: Any) -> tuple:
        return ("default", statements_in(rest))

    def label(self, name: Token, colon: Token) -> s.Label:
        return s.Label(name.start_pos, colon.end_pos, str(name))

    def goto_stmt(self, goto: Token, name: Token, semi: Token) -> s.Goto:
        return s.Goto(goto.start_pos, semi.end_pos, str(name))

    def return_stmt(self, kw: Token, *rest: Any) -> s.Return:
        return s.Return(kw.start_pos, rest[-1].end_pos, rest[0] if len(rest) == 2 else None)

    def raise_stmt(self, kw: Token, *rest: Any) -> s.Raise:
        return s.Raise(kw.start_pos, rest[-1].end_pos, rest[0] if len(rest) == 2 else None)

    def exit_stmt(self, kw: Token, semi: Token) -> s.Exit:
        return s.Exit(kw.start_pos, semi.end_pos)

    def retry_stmt(self, kw: Token, semi: Token) -> s.Retry:
        return s.Retry(kw.start_pos, semi.end_pos)

    def trynext_stmt(self, kw: Token, semi: Token) -> s.TryNext:
        return s.TryNext(kw.start_pos, semi.end_pos)

    def connect_stmt(self, kw: Token, target: s.Expr, _with: Token, trap: Token,
                     semi: Token) -> s.Connect:
        return s.Connect(kw.start_pos, semi.end_pos, target, str(trap))

    # ------------------------------------------------------------ declarations
    def dims(self, *exprs: s.Expr) -> list[s.Expr]:
        return list(exprs)

    def data_decl(self, *children: Any) -> s.DataDecl:
        first = children[0]
        local = task = False
        i = 0
        while children[i].type in ("LOCAL", "TASK"):
            local = local or children[i].type == "LOCAL"
            task = task or children[i].type == "TASK"
            i += 1
        storage = children[i].type
        type_tok, name_tok = children[i + 1], children[i + 2]
        dims: list[s.Expr] = []
        init = None
        for item in children[i + 3:-1]:
            if isinstance(item, list):
                dims = item
            else:
                init = item
        return s.DataDecl(first.start_pos, children[-1].end_pos, storage, str(type_tok),
                          str(name_tok), name_tok.start_pos, dims, init, local, task)

    def record_field(self, type_tok: Token, name: Token, *rest: Any) -> s.RecordField:
        dims = rest[0] if len(rest) == 2 else []
        return s.RecordField(type_tok.start_pos, rest[-1].end_pos, str(type_tok), str(name), dims)

    def record_decl(self, *children: Any) -> s.RecordDecl:
        local = children[0].type == "LOCAL"
        name = children[2 if local else 1]
        fields = [c for c in children if isinstance(c, s.RecordField)]
        return s.RecordDecl(children[0].start_pos, children[-1].end_pos, str(name), fields, local)

    def alias_decl(self, *children: Any) -> s.AliasDecl:
        local = children[0].type == "LOCAL"
        type_tok, name = children[-3], children[-2]
        return s.AliasDecl(children[0].start_pos, children[-1].end_pos, str(type_tok), str(name),
                           local)

    def parameter(self, *children: Any) -> s.Parameter:
        access = None
        i = 0
        if isinstance(children[0], Token) and children[0].type in ("VAR", "PERS", "INOUT"):
            access, i = children[0].type, 1
        type_tok, name = children[i], children[i + 1]
        rank, end = children[i + 2] if len(children) > i + 2 else (0, name.end_pos)
        return s.Parameter(children[0].start_pos, end, access, str(type_tok), str(name), rank)

    def parameter_dims(self, *children: Token) -> tuple[int, int]:
        return len(children) - 1, children[-1].end_pos

    def optional_parameters(self, *children: Any) -> list[s.Parameter]:
        params = [c for c in children if isinstance(c, s.Parameter)]
        names = tuple(p.name for p in params) if len(params) > 1 else ()
        for p in params:
            p.optional = True
            p.alternatives = names
        params[0].start = children[0].start_pos
        return params

    def parameters(self, *groups: Any) -> list[s.Parameter]:
        out: list[s.Parameter] = []
        for group in groups:
            if isinstance(group, list):
                out.extend(group)
            else:
                out.append(group)
        return out

    def error_numbers(self, *exprs: s.Expr) -> list[s.Expr]:
        return list(exprs)

    def backward_handler(self, kw: Token, *body: Any) -> s.Handler:
        return s.Handler(kw.start_pos, body[-1].end if body else kw.end_pos, "BACKWARD", [],
                         statements_in(body))

    def error_handler(self, kw: Token, *body: Any) -> s.Handler:
        numbers = body[0] if body and isinstance(body[0], list) else []
        statements = statements_in(body)
        end = statements[-1].end if statements else kw.end_pos
        return s.Handler(kw.start_pos, end, "ERROR", numbers, statements)

    def undo_handler(self, kw: Token, *body: Any) -> s.Handler:
        return s.Handler(kw.start_pos, body[-1].end if body else kw.end_pos, "UNDO", [],
                         statements_in(body))

    def _routine(self, kind: str, children: tuple) -> s.Routine:
        local = children[0].type == "LOCAL"
        i = 2 if local else 1  # past LOCAL? and PROC/FUNC/TRAP
        return_type = None
        if kind == "FUNC":
            return_type = str(children[i])
            i += 1
            if isinstance(children[i], list):  # FUNC num{*}: unusual but harmless
                i += 1
        name = str(children[i])
        params: list[s.Parameter] = []
        data: list[s.DataDecl] = []
        body: list[s.Statement] = []
        handlers: list[s.Handler] = []
        for item in children[i + 1:-1]:
            if isinstance(item, s.Statement):
                body.append(item)
            elif isinstance(item, s.DataDecl):
                data.append(item)
            elif isinstance(item, s.Handler):
                handlers.append(item)
            elif isinstance(item, list):
                params = item
        return s.Routine(children[0].start_pos, children[-1].end_pos, kind, name, params, data,
                         body, handlers, return_type, local)

    def proc(self, *children: Any) -> s.Routine:
        return self._routine("PROC", children)

    def func(self, *children: Any) -> s.Routine:
        return self._routine("FUNC", children)

    def trap(self, *children: Any) -> s.Routine:
        return self._routine("TRAP", children)

    def module_attributes(self, *names: Token) -> tuple[list[str], int]:
        return [str(n) for n in names[:-1]], names[-1].end_pos

    def module(self, kw: Token, name: Token, *rest: Any) -> s.Module:
        attributes: list[str] = []
        header_end = name.end_pos
        if rest and isinstance(rest[0], tuple):
            attributes, header_end = rest[0]
        items = [x for x in rest[:-1] if not isinstance(x, tuple)]
        return s.Module(kw.start_pos, rest[-1].end_pos, str(name), attributes, items, header_end)

    def start(self, *children: Any) -> s.SourceFile:
        header = None
        if isinstance(children[0], Token):
            header = str(children[0])
        modules = [c for c in children if isinstance(c, s.Module)]
        return s.SourceFile(_start(children[0]), _end(children[-1]), header, modules)
