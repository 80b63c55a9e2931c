"""Parse a program of simple statements and read its data and calls in bulk.

Reading back a rewritten CAM program means parsing a hundred thousand new
declarations and calls and finding, for each call, the values it names. The
fast terminals (`fastpath`) already match whole runs of simple declarations and
calls; this parser is the same Lark parser (the same grammar, fast terminals
and all) but keeps each run as one `Run` node instead of splitting it into
syntax nodes, so Lark checks the syntax of the whole text and the runs are then
read with a few regular expressions over all their statements at once: no
syntax node, operand or program model per statement.

`read_bulk` gives what a simple program declares (name -> type and value text)
and calls (name and argument texts, in order). It returns None for a program
it does not read whole (any statement other than a plain call, a declaration
with array dimensions, an expression); the caller then takes the full route
(`parse_program`), which also explains syntax errors.
"""

from __future__ import annotations

import bisect
import functools
import re
from collections import deque
from dataclasses import dataclass, field
from typing import Any

from lark import Lark, Tree, v_args
from lark.exceptions import UnexpectedInput

from rapidfix.rapid import syntax as s
from rapidfix.rapid.fastpath import (
    CALL_PIECE,
    GAP,
    TAIL_LIMIT,
    VALUE_TEXT,
    WS,
    FastSyntaxBuilder,
    Memo,
    NotFast,
    cached_extension,
    declaration_pattern,
)
from rapidfix.rapid.grammar import grammar_text


@dataclass(slots=True, eq=False)
class Run(s.Statement):
    """A run of simple calls (`kind` 'calls') or declarations ('decls') as one node."""

    kind: str
    text: str


@v_args(inline=True)
class _RunBuilder(FastSyntaxBuilder):
    """FastSyntaxBuilder that keeps each fast run whole."""

    def _fast_calls(self, children: list[Any]) -> Tree:
        tok = children[0]
        return Tree("_fast_calls", [Run(tok.start_pos, tok.end_pos, "calls", str(tok))])

    def _fast_decls(self, children: list[Any]) -> Tree:
        tok = children[0]
        return Tree("_fast_decls", [Run(tok.start_pos, tok.end_pos, "decls", str(tok))])


@functools.lru_cache(maxsize=1)
def run_parser() -> Lark:
    """The fast parser (grammar and fast terminals), building `Run` nodes for runs."""
    grammar = grammar_text()
    return Lark(grammar + cached_extension(grammar), parser="lalr", lexer="contextual",
                transformer=_RunBuilder(), cache=True)


# A declaration's type, name and value text (the storage and LOCAL / TASK are not
# needed to read values back).
_BULK_DECL = declaration_pattern(False)
# A call whose syntax the lexer has checked: its name, a first value after
# whitespace if there is one, and the text up to its ';' (values hold no ';').
_BULK_CALL = re.compile(rf"{GAP}([A-Za-z][A-Za-z0-9_]*)(?:{WS}+({VALUE_TEXT}))?([^;]*);")
_EMPTY: dict[str, tuple[str, str]] = {}


@dataclass
class BulkProgram:
    """What a program of simple statements declares and calls.

    `data` maps a scope (module, routine or None) to its declarations: name ->
    (type name, value text or '' without one), all names lower case. `calls` are
    in source order, each as (name, first value or '', the text after it up to
    its ';'); `arguments(i)` reads call i's arguments and `scope(i)` its module
    and routine.
    """

    data: dict[tuple[str, str | None], dict[str, tuple[str, str]]] = field(
        default_factory=dict)
    calls: list[tuple[str, str, str]] = field(default_factory=list)
    #: (index of its first call, module, routine) of each run of calls, in order
    runs: list[tuple[int, str, str]] = field(default_factory=list)
    _tails: Memo = field(default_factory=lambda: Memo(TAIL_LIMIT), repr=False)

    def scope(self, i: int) -> tuple[str, str]:
        """(module, routine), lower case, of call i."""
        k = bisect.bisect_right([r[0] for r in self.runs], i) - 1
        return self.runs[k][1], self.runs[k][2]

    def arguments(self, i: int) -> tuple[tuple[str, ...], dict[str, str | None]]:
        """Call i's required values as written, in order, and its optional arguments
        (lower-case name -> value text or None). A CAM program's calls share a few
        dozen texts after their first value: each is read once."""
        _name, first, rest = self.calls[i]
        parsed = self._tails.get(rest)
        if parsed is None:
            parsed = _tail_arguments(rest)
            self._tails.keep(rest, parsed)
        return ((first, *parsed[0]) if first else parsed[0]), parsed[1]

    def visible(self, module: str, routine: str) -> tuple[dict, dict]:
        """The data a call in `routine` of `module` sees: (the routine's, the module's);
        other modules' data are not looked into."""
        return self.data.get((module, routine), _EMPTY), self.data.get((module, None), _EMPTY)

    def run_scopes(self) -> list[tuple[dict, dict]]:
        """`visible` for each run of calls, in the order of `runs`."""
        return [self.visible(module, routine) for _, module, routine in self.runs]

    def lookup(self, module: str, routine: str, name: str) -> tuple[str, str | None] | None:
        """A name as a call in `routine` of `module` sees it: routine data, then module data."""
        key = name.lower()
        local, module_data = self.visible(module, routine)
        found = local.get(key) or module_data.get(key)
        return None if found is None else (found[0], found[1] or None)


def _tail_arguments(text: str) -> tuple[tuple[str, ...], dict[str, str | None]]:
    """Required values and optional arguments in checked call text after the first value."""
    required: list[str] = []
    optional: dict[str, str | None] = {}
    for piece in CALL_PIECE.finditer(text):
        slash, option, option_value, value, _semi = piece.groups()
        if value is not None:
            required.append(value)
        elif slash is not None:
            optional[option.lower()] = option_value
    return tuple(required), optional


class _Reader:
    def __init__(self) -> None:
        self.program = BulkProgram()

    def declarations(self, run_text: str, module: str, routine: str | None) -> None:
        found = _BULK_DECL.findall(run_text)
        if not found:  # pragma: no cover - a run holds at least one declaration
            return
        types, names, values = zip(*found)
        # the first declaration of a name wins, as in the model (setdefault, at C speed)
        scope = self.program.data.setdefault((module, routine), {})
        deque(map(scope.setdefault, map(str.lower, names),
                  zip(map(str.lower, types), values)), maxlen=0)

    def declaration(self, decl: s.DataDecl, text: str, module: str, routine: str | None) -> bool:
        if decl.dims:
            return False
        init = decl.init
        value = "" if init is None else text[init.start:init.end]
        self.program.data.setdefault((module, routine), {}).setdefault(
            decl.name.lower(), (decl.type_name.lower(), value))
        return True

    def calls(self, run_text: str, module: str, routine: str) -> bool:
        if "(" in run_text:  # a function call among the values (or in a comment): an
            return False     # expression, which the bulk reader leaves to the full route
        calls = self.program.calls
        self.program.runs.append((len(calls), module, routine))
        calls.extend(_BULK_CALL.findall(run_text))
        return True

    def body(self, items: list[Any], text: str, module: str, routine: str) -> bool:
        for item in items:
            kind = type(item)
            if kind is Run:
                if item.kind == "calls":
                    if not self.calls(item.text, module, routine):
                        return False
                else:
                    self.declarations(item.text, module, routine)
            elif kind is s.DataDecl:
                if not self.declaration(item, text, module, routine):
                    return False
            else:
                return False
        return True


def read_bulk(text: str) -> BulkProgram | None:
    """Declarations and calls of a program made of simple statements only, or None.

    The text is parsed by Lark with the grammar and the fast terminals; None when it
    does not parse that way or holds anything but data declarations without
    dimensions and procedure calls whose arguments are names, numbers, numeric
    aggregates and optional arguments (then parse it with `parse_program`).
    """
    try:
        tree: s.SourceFile = run_parser().parse(text)
    except (UnexpectedInput, NotFast):
        return None
    reader = _Reader()
    for module in tree.modules:
        mkey = module.name.lower()
        for item in module.items:
            kind = type(item)
            if kind is Run:
                if item.kind != "decls":  # pragma: no cover - calls stand only in routines
                    return None
                reader.declarations(item.text, mkey, None)
            elif kind is s.DataDecl:
                if not reader.declaration(item, text, mkey, None):
                    return None
            elif kind is s.Routine:
                if item.handlers or item.parameters:
                    return None
                rkey = item.name.lower()
                if not (reader.body(item.data, text, mkey, rkey)
                        and reader.body(item.body, text, mkey, rkey)):
                    return None
            else:
                return None
    return reader.program
