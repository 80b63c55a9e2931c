"""The syntax tree of a RAPID file: small nodes that know their source offsets.

Every node carries `start` and `end`, character offsets into the decoded text
(end exclusive); line and column are computed from them only when asked (see
rapidfix.rapid.span). Names keep their original spelling; `.key` is the
case-folded form RAPID compares by.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from itertools import chain
from typing import Protocol


@dataclass(slots=True, eq=False)
class Node:
    """Anything with a place in the source."""

    start: int
    end: int


# ---------------------------------------------------------------- expressions
@dataclass(slots=True, eq=False)
class Number(Node):
    value: float
    text: str


@dataclass(slots=True, eq=False)
class String(Node):
    value: str


@dataclass(slots=True, eq=False)
class Bool(Node):
    value: bool


@dataclass(slots=True, eq=False)
class NumericAggregate(Node):
    """An aggregate of numbers only (`[[1,2,3],[1,0,0,0],...]`), read in bulk."""

    value: tuple


@dataclass(slots=True, eq=False)
class Aggregate(Node):
    items: list[Expr]


@dataclass(slots=True, eq=False)
class NameRef(Node):
    name: str

    @property
    def key(self) -> str:
        return self.name.lower()


@dataclass(slots=True, eq=False)
class Index(Node):
    base: Expr
    indices: list[Expr]


@dataclass(slots=True, eq=False)
class Component(Node):
    base: Expr
    name: str


@dataclass(slots=True, eq=False)
class Call(Node):
    """A function call `Name(args)`."""

    name: str
    args: list[Argument]

    @property
    def key(self) -> str:
        return self.name.lower()


_FUNCTION_ARGS = Call.__dict__["args"]  # the slot, under LazyFunctionCall's property


class LazyFunctionCall(Call):
    """A function call `Name(args)` whose arguments after the first are a shared `tail`
    (see LazyCall): `Offs(p1,0,0,10)`, `RelTool(p2,0,0,5 \\Rz:=90)` differ from call to
    call mostly in their first argument. `args` is the list a Call holds, made when
    first asked for; the evaluator reads `head` and the tail's values without it."""

    __slots__ = ("head", "shift", "tail")

    def __init__(self, start: int, end: int, name: str, head: Argument | None,
                 tail: ArgumentTail, shift: int) -> None:
        self.start, self.end, self.name = start, end, name
        self.head, self.tail, self.shift = head, tail, shift

    @property  # type: ignore[override]
    def args(self) -> list[Argument]:
        try:
            return _FUNCTION_ARGS.__get__(self)
        except AttributeError:
            args = self.tail.arguments(self.shift)
            if self.head is not None:
                args.insert(0, self.head)
            _FUNCTION_ARGS.__set__(self, args)
            return args


@dataclass(slots=True, eq=False)
class Unary(Node):
    op: str  # '-', '+', 'NOT'
    operand: Expr


@dataclass(slots=True, eq=False)
class Binary(Node):
    op: str  # upper case: '+', 'DIV', 'AND', '<>', ...
    left: Expr
    right: Expr


@dataclass(slots=True, eq=False)
class Paren(Node):
    inner: Expr


@dataclass(slots=True, eq=False)
class Placeholder(Node):
    """A RobotStudio placeholder (`<EXP>`, `<VAR>`, `<ARG>`, `<DIM>`, or a module item
    `<TDN>`, `<DDN>`, `<RDN>`): code not yet written, which the controller loads but
    stops at with an error. Its value is never known before run time."""

    text: str  # as written, '<EXP>'


Expr = (
    Number | String | Bool | NumericAggregate | Aggregate | NameRef | Index | Component
    | Call | Unary | Binary | Paren | Placeholder
)
#: the expression nodes that hold no other node
LEAF_NODES = frozenset({Number, String, Bool, NameRef, NumericAggregate})


@dataclass(slots=True, eq=False)
class Argument(Node):
    """One argument of a call: required (`expr` or `Name:=expr`), optional
    (`\\Name`, `\\Name:=expr`) or conditional (`\\Name?Param`)."""

    kind: str  # 'required' | 'optional' | 'conditional'
    name: str | None
    value: Expr | None
    condition: str | None = None  # the parameter named after '?'

    @property
    def key(self) -> str | None:
        return None if self.name is None else self.name.lower()


# ---------------------------------------------------------------- statements
@dataclass(slots=True, eq=False)
class Statement(Node):
    """Base of every statement."""

    def bodies(self) -> Iterator[list[Statement]]:
        """The statement lists nested in this statement (none for simple ones)."""
        return iter(())


@dataclass(slots=True, eq=False)
class ProcedureCall(Statement):
    name: str
    args: list[Argument]

    @property
    def key(self) -> str:
        return self.name.lower()


class ArgumentTail(Protocol):
    """Arguments that recur after many calls' first argument, read once (see LazyCall)."""

    def arguments(self, shift: int) -> list[Argument]:
        """The tail's Argument nodes with offsets moved by `shift`."""

    def values(self) -> list[tuple[str, str | None, Expr | None]]:
        """(kind, name or None, value node or None) of each argument, the nodes standing
        anywhere (a value does not depend on where its node stands)."""


_CALL_ARGS = ProcedureCall.__dict__["args"]  # the slot, under the property below


class LazyCall(ProcedureCall):
    """A ProcedureCall whose leading argument `head` (and `second`, when the second
    changes from call to call too, as MoveC's two targets) is followed by a shared
    `tail`, shifted to where this call stands; its `args` are made when first asked for.

    A CAM program's hundred thousand moves differ only in their targets, and most
    readers never look past them: the nodes of the rest are made on demand.
    `args` is the same list of nodes a ProcedureCall holds: the optional arguments of
    a shared `lead` before `head` (`MoveJ \\Conc, p1, ...`; they stand right after the
    name), then `heads`, then the tail's.
    """

    __slots__ = ("head", "lead", "second", "shift", "tail")

    def __init__(self, start: int, end: int, name: str, head: Argument | None,
                 tail: ArgumentTail, shift: int, second: Argument | None = None,
                 lead: ArgumentTail | None = None) -> None:
        self.start, self.end, self.name = start, end, name
        self.head, self.second, self.tail, self.shift = head, second, tail, shift
        self.lead = lead

    @property
    def heads(self) -> tuple[Argument, ...]:
        """The call's own leading arguments (not shared): none, `head`, or `head` and
        `second`."""
        if self.head is None:
            return ()
        return (self.head,) if self.second is None else (self.head, self.second)

    @property  # type: ignore[override]
    def args(self) -> list[Argument]:
        try:
            return _CALL_ARGS.__get__(self)
        except AttributeError:
            args = self.tail.arguments(self.shift)
            if self.head is not None:
                args[0:0] = self.heads
            if self.lead is not None:
                args[0:0] = self.lead.arguments(self.start + len(self.name))
            _CALL_ARGS.__set__(self, args)
            return args

    def shared_args(self) -> list[Argument]:
        """`args` but `heads`: the arguments of the shared lead and tail, in order."""
        args, n = self.args, len(self.heads)
        if self.lead is None:
            return args[n:]
        at = 0  # a lead holds optional arguments only; `head` is required
        while args[at].kind != "required":
            at += 1
        return args[:at] + args[at + n:]


@dataclass(slots=True, eq=False)
class LateCall(Statement):
    """`%expr% args;` — a procedure chosen at run time."""

    target: Expr
    args: list[Argument]


@dataclass(slots=True, eq=False)
class Assignment(Statement):
    target: Expr
    value: Expr


@dataclass(slots=True, eq=False)
class If(Statement):
    branches: list[tuple[Expr, list[Statement]]]
    otherwise: list[Statement] | None

    def bodies(self) -> Iterator[list[Statement]]:
        for _cond, body in self.branches:
            yield body
        if self.otherwise is not None:
            yield self.otherwise


@dataclass(slots=True, eq=False)
class CompactIf(Statement):
    condition: Expr
    statement: Statement

    def bodies(self) -> Iterator[list[Statement]]:
        yield [self.statement]


@dataclass(slots=True, eq=False)
class For(Statement):
    variable: str
    first: Expr
    last: Expr
    step: Expr | None
    body: list[Statement]

    def bodies(self) -> Iterator[list[Statement]]:
        yield self.body


@dataclass(slots=True, eq=False)
class While(Statement):
    condition: Expr
    body: list[Statement]

    def bodies(self) -> Iterator[list[Statement]]:
        yield self.body


@dataclass(slots=True, eq=False)
class Test(Statement):
    subject: Expr
    cases: list[tuple[list[Expr], list[Statement]]]
    default: list[Statement] | None

    def bodies(self) -> Iterator[list[Statement]]:
        for _values, body in self.cases:
            yield body
        if self.default is not None:
            yield self.default


@dataclass(slots=True, eq=False)
class Label(Statement):
    name: str


@dataclass(slots=True, eq=False)
class Goto(Statement):
    label: str


@dataclass(slots=True, eq=False)
class Return(Statement):
    value: Expr | None


@dataclass(slots=True, eq=False)
class Raise(Statement):
    value: Expr | None


@dataclass(slots=True, eq=False)
class Exit(Statement):
    pass


@dataclass(slots=True, eq=False)
class Retry(Statement):
    pass


@dataclass(slots=True, eq=False)
class TryNext(Statement):
    pass


@dataclass(slots=True, eq=False)
class Connect(Statement):
    target: Expr
    trap: str


@dataclass(slots=True, eq=False)
class StatementPlaceholder(Statement):
    """`<SMT>` (a statement), `<DDN>` (a routine's data) or `<EIT>` (an ELSEIF clause)
    not yet written: the controller stops there with an error."""

    text: str  # as written, '<SMT>'


# ---------------------------------------------------------------- declarations
@dataclass(slots=True, eq=False)
class DataDecl(Node):
    """`[LOCAL] [TASK] VAR|PERS|CONST type name [{dims}] [:= init];`"""

    storage: str  # 'VAR' | 'PERS' | 'CONST'
    type_name: str
    name: str
    name_start: int
    dims: Sequence[Expr]  # () when there are none
    init: Expr | None
    local: bool = False
    task: bool = False

    @property
    def key(self) -> str:
        return self.name.lower()

    @property
    def type_key(self) -> str:
        return self.type_name.lower()


@dataclass(slots=True, eq=False)
class RecordField(Node):
    type_name: str
    name: str
    dims: list[Expr]


@dataclass(slots=True, eq=False)
class RecordDecl(Node):
    name: str
    fields: list[RecordField]
    local: bool = False


@dataclass(slots=True, eq=False)
class AliasDecl(Node):
    type_name: str
    name: str
    local: bool = False


@dataclass(slots=True, eq=False)
class Parameter(Node):
    """A routine parameter; optional ones (`\\`) may belong to a group of
    mutually exclusive alternatives (`\\a | b`)."""

    access: str | None  # None, 'VAR', 'PERS', 'INOUT'
    type_name: str
    name: str
    array_rank: int = 0
    optional: bool = False
    alternatives: tuple[str, ...] = ()

    @property
    def key(self) -> str:
        return self.name.lower()


@dataclass(slots=True, eq=False)
class Handler(Node):
    kind: str  # 'BACKWARD' | 'ERROR' | 'UNDO'
    numbers: list[Expr]
    body: list[Statement]


@dataclass(slots=True, eq=False)
class Routine(Node):
    kind: str  # 'PROC' | 'FUNC' | 'TRAP'
    name: str
    parameters: list[Parameter]
    data: list[DataDecl]
    body: list[Statement]
    handlers: list[Handler]
    return_type: str | None = None
    local: bool = False

    @property
    def key(self) -> str:
        return self.name.lower()


ModuleItem = DataDecl | RecordDecl | AliasDecl | Routine | Placeholder

# Statements that hold statement lists (those that define bodies()).
COMPOUND_STATEMENTS = frozenset({If, CompactIf, For, While, Test})


@dataclass(slots=True, eq=False)
class Module(Node):
    name: str
    attributes: list[str]
    items: list[ModuleItem]
    header_end: int  # offset just past the MODULE line's name / attribute list


@dataclass(slots=True, eq=False)
class SourceFile(Node):
    header: str | None
    modules: list[Module] = field(default_factory=list)


def walk_statements(body: list[Statement], depth: int = 0) -> Iterator[tuple[Statement, int]]:
    """Every statement in `body` and nested in it, with its loop depth (FOR/WHILE).

    In source order, each statement before those nested in it; iterative, so that
    deep nesting needs no recursion. A body of simple statements (a CAM program's
    hundred thousand moves) is one plain loop.
    """
    stack: list[tuple[Iterator[Statement], int]] = [(iter(body), depth)]
    while stack:
        statements, loops = stack[-1]
        for statement in statements:
            yield statement, loops
            if type(statement) in COMPOUND_STATEMENTS:
                inner = loops + 1 if isinstance(statement, (For, While)) else loops
                stack.append((chain.from_iterable(list(statement.bodies())), inner))
                break
        else:
            stack.pop()
