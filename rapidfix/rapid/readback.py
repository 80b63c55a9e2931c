"""Read a rewritten program back: in bulk where its statements are simple, else through
the full program model, with the one name-lookup rule of RAPID data.

This module owns the read-back: `read_targets_in_bulk` (the bulk reader below),
`read_targets_full` (its fallback, from the program model's motions) and the scope
rule (`rapidfix.rapid.scope`: `find_visible`, `visible_names`) that the program model
(`model_builder`, `Program.declaration`) and the bulk reader share; it sits in a module
of its own so that parsing a program does not load what reading back needs (numpy).

The bulk reader: parse a program of simple statements and read its data and calls
in bulk.

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
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from lark import Lark, Tree, v_args
from lark.exceptions import UnexpectedInput

from rapidfix.exceptions import RapidSemanticError
from rapidfix.rapid import syntax as s
from rapidfix.rapid.fast_expressions import NAME
from rapidfix.rapid.fastpath import (
    BLOCK_WORDS,
    CALL_PIECE,
    GAP,
    TAIL_LIMIT,
    VALUE_TEXT,
    WS,
    FastSyntaxBuilder,
    Memo,
    NotFast,
    aggregate_value,
    blank_comments,
    cached_extension,
    declaration_pattern,
    shape_key,
)
from rapidfix.rapid.grammar import grammar_text
from rapidfix.rapid.instructions import motion_spec
from rapidfix.rapid.lexer_patterns import share_large_patterns
from rapidfix.rapid.scope import find_visible, visible_names
from rapidfix.rapid.values import fits_type

if TYPE_CHECKING:
    from rapidfix.rapid.program import MotionInstruction



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
    return share_large_patterns(Lark(grammar + cached_extension(grammar), parser="lalr",
                                     lexer="contextual", transformer=_RunBuilder(),
                                     cache=True))


# A declaration's type, name and value text (the storage and LOCAL / TASK are not
# needed to read values back).
_BULK_DECL = declaration_pattern(False)
# A call whose syntax the lexer has checked: its name, a first value after
# whitespace if there is one, and the text up to its ';' (values hold no ';').
_BULK_CALL = re.compile(rf"{GAP}({NAME})(?:{WS}+({VALUE_TEXT}))?([^;]*);")
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
        dozen texts after their first value: each is read once. Calls of two targets
        (`MoveC p1,p2,...`) share theirs after the second: a text after the first value
        that starts with a value is read as that value and the text after it."""
        _name, first, rest = self.calls[i]
        tails = self._tails
        parsed = tails.get(rest)
        if parsed is None:
            piece = CALL_PIECE.compiled
            head = piece.search(rest)
            lead: dict[str, str | None] = {}
            while head is not None and head.group(1) is not None:
                # optional arguments before the first value (`MoveAbsJ \ID:=10, j1, ...`):
                # read on each call (a MultiMove program numbers every move)
                lead[head.group(2).lower()] = head.group(3)
                head = piece.match(rest, head.end())
            if head is not None and head.group(4) is not None:
                after = rest[head.end():]
                later = tails.get(after)
                if later is None:
                    later = _tail_arguments(after)
                    tails.keep(after, later)
                parsed = ((head.group(4), *later[0]), {**lead, **later[1]} if lead
                          else later[1])
            else:
                parsed = _tail_arguments(rest)
            if first or not lead:
                tails.keep(rest, parsed)
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
        found = find_visible(name.lower(), *self.visible(module, routine))
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

    def declarations(self, run_text: str, module: str, routine: str | None) -> bool:
        if "{" in run_text:  # arrays (or a brace in a comment): the full route reads them
            return False
        found = _BULK_DECL.findall(run_text)
        if not found:  # pragma: no cover - a run holds at least one declaration
            return True
        types, names, values = zip(*found)
        # the first declaration of a name wins, as in the model (setdefault, at C speed)
        scope = self.program.data.setdefault((module, routine), {})
        deque(map(scope.setdefault, map(str.lower, names),
                  zip(map(str.lower, types), values)), maxlen=0)
        return True

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
        found = _BULK_CALL.findall(run_text)
        if any(name.upper() in BLOCK_WORDS for name, _, _ in found):
            return False  # an IF block in the run: its calls are the full route's to read
        calls = self.program.calls
        self.program.runs.append((len(calls), module, routine))
        calls.extend(found)
        return True

    def body(self, items: list[Any], text: str, module: str, routine: str) -> bool:
        for item in items:
            kind = type(item)
            if kind is Run:
                if item.kind == "calls":
                    if not self.calls(item.text, module, routine):
                        return False
                elif not self.declarations(item.text, module, routine):
                    return False
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
    aggregates and optional arguments (then parse it with `parse_program`). Comments
    are read as the whitespace they are to the grammar (`blank_comments`), so a
    statement with one inside stays in its run.
    """
    text = blank_comments(text)
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
                if not reader.declarations(item.text, mkey, None):
                    return None
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


# ---------------------------------------------------------------- targets read back
@dataclass(frozen=True)
class ReadBack:
    """The targets the output commands, per checked pose (rows of `Expected`):
    `joint` (K,) True for a jointtarget, else a robtarget; `robax` (K,6) degrees of
    the jointtargets; `trans` (K,3), `rot` (K,4), `conf` (K,4) of the robtargets
    (rows of the other kind hold zeros)."""

    joint: np.ndarray
    robax: np.ndarray
    trans: np.ndarray
    rot: np.ndarray
    conf: np.ndarray

    @classmethod
    def empty(cls, k: int) -> ReadBack:
        return cls(np.zeros(k, bool), np.zeros((k, 6)), np.zeros((k, 3)), np.zeros((k, 4)),
                   np.zeros((k, 4)))


class NotBulk(Exception):
    """The bulk reader met a target it does not read (the full route decides)."""


_JOINT_LITERAL = re.compile(r"\[\[([-+0-9.eE,]*)\],\[([-+0-9.eE,]*)\]\]")


def _read_bulk_targets(bulk: BulkProgram, order: list[int], motion: np.ndarray,
                       slot: np.ndarray) -> ReadBack:
    calls = bulk.calls
    if len(calls) != len(order):
        raise NotBulk
    index_of = [0] * len(order)  # statement id -> its call
    for i, ident in enumerate(order):
        index_of[ident] = i
    k = motion.shape[0]
    out = ReadBack.empty(k)
    call_of_row = np.asarray(index_of)[motion].tolist() if k else []
    run_of_row = (np.searchsorted([r[0] for r in bulk.runs], call_of_row, side="right") - 1
                  ).tolist() if k else []
    scopes = bulk.run_scopes()  # per run of calls: the routine's data, then the module's
    if k and len(set(map(id, (d for pair in scopes for d in pair)))) <= 2:
        quick = _jointtargets_named_first(bulk, call_of_row, slot, scopes[0])
        if quick is not None:
            return quick
    layouts: dict[str, tuple[tuple[int, ...], str]] = {}
    joint_rows: list[int] = []
    joint_texts: list[str] = []
    rob_rows: list[int] = []
    rob_texts: list[str] = []
    for i, (c, run, which) in enumerate(zip(call_of_row, run_of_row, slot.tolist())):
        name, first, _rest = calls[c]
        layout = layouts.get(name)
        if layout is None:
            spec = motion_spec(name)
            if spec is None:
                raise NotBulk
            layout = layouts[name] = (
                tuple(spec.parameters.index(p) for p in spec.target_parameters),
                spec.target_kind)
        where, inline_type = layout
        if which >= len(where):
            raise NotBulk
        position = where[which]
        if position == 0 and first:
            text = first
        else:
            required = bulk.arguments(c)[0]
            if position >= len(required):
                raise NotBulk
            text = required[position]
        if text[0] == "[":
            type_name = inline_type
        else:
            key = text.lower()
            found = find_visible(key, *scopes[run])
            if found is None or not found[1]:
                raise NotBulk
            type_name, text = found
        if type_name == "jointtarget":
            joint_rows.append(i)
            joint_texts.append(text)
        elif type_name == "robtarget":
            rob_rows.append(i)
            rob_texts.append(text)
        else:
            raise NotBulk
    if joint_rows:
        out.joint[joint_rows] = True
        out.robax[joint_rows] = joint_values(joint_texts)
    if rob_rows:
        out.trans[rob_rows], out.rot[rob_rows], out.conf[rob_rows] = robtarget_values(
            rob_texts)
    return out


def _jointtargets_named_first(bulk: BulkProgram, call_of_row: list[int], slot: np.ndarray,
                              scope: tuple[dict, dict]) -> ReadBack | None:
    """The usual case at list speed: every checked pose is a jointtarget data name written
    as the first argument of a call whose first parameter is its target, all calls in one
    scope. None when that is not so (the general loop decides)."""
    calls = bulk.calls
    rows = [calls[c] for c in call_of_row]
    if slot.any():
        return None
    if not all(first for _, first, _ in rows):  # (optional arguments before it: its first
        # value from the call's arguments)
        rows = [row if row[1] else (row[0], (bulk.arguments(c)[0] or ("",))[0], row[2])
                for row, c in zip(rows, call_of_row)]
        if not all(first for _, first, _ in rows):
            return None
    for name in {name for name, _, _ in rows}:
        spec = motion_spec(name)
        if spec is None or spec.target_kind != "jointtarget" or not spec.target_parameters \
                or spec.parameters.index(spec.target_parameters[0]) != 0:
            return None
    names = visible_names(*scope)  # routine data first, then the module's
    found = list(map(names.get, [first.lower() for _, first, _ in rows]))
    if None in found or any(type_name != "jointtarget" or not text
                            for type_name, text in found):
        return None
    out = ReadBack.empty(len(rows))
    out.joint[:] = True
    out.robax[:] = joint_values([text for _, text in found])
    return out


_NUMBERS = "[-+0-9.eE]+"
# A robtarget literal as the rewrite writes it (no whitespace): its numbers are read as
# joint_values reads a jointtarget's.
_ROBTARGET_LITERAL = re.compile(
    rf"\[\[({_NUMBERS}(?:,{_NUMBERS}){{2}})\],\[({_NUMBERS}(?:,{_NUMBERS}){{3}})\],"
    rf"\[({_NUMBERS}(?:,{_NUMBERS}){{3}})\],\[({_NUMBERS}(?:,{_NUMBERS}){{5}})\]\]")


def robtarget_values(texts: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(trans (K,3), rot (K,4), conf (K,4)) of robtarget literals, as `_robtarget_value`
    reads each: those written without whitespace (what the rewrite writes) in one pass,
    any other one by one. Raises NotBulk where it does."""
    compact = _compact_robtargets(texts)
    if compact is not None:
        return compact
    distinct = {text: _robtarget_value(text) for text in texts}
    trans, rot, conf = zip(*map(distinct.__getitem__, texts))
    return np.array(trans, dtype=float), np.array(rot, dtype=float), np.array(conf, dtype=float)


# One robtarget literal as the rewrite writes it on each line of a text
_ROBTARGET_LINES = re.compile(f"^{_ROBTARGET_LITERAL.pattern}$", re.MULTILINE)


def _compact_robtargets(texts: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """`robtarget_values` of literals all written without whitespace, found by one
    regular-expression pass over them all; None when one is written otherwise."""
    found = _by_line(_ROBTARGET_LINES, texts)
    return None if found is None else _robtarget_numbers(found)


def _by_line(pattern: re.Pattern[str], texts: list[str]) -> list[Any] | None:
    """The groups of `pattern` (anchored at a line's start and end) in each text, found by
    one pass over them all; None when a text holds a line break or does not match."""
    joined = "\n".join(texts)
    if joined.count("\n") != len(texts) - 1:
        return None
    found = pattern.findall(joined)
    return found if len(found) == len(texts) else None  # one match per line: every line


def _declarations_by_line(pattern: re.Pattern[str], texts: list[str]
                          ) -> tuple[list[Any], list[str]] | None:
    """`_by_line` of declarations written in ASCII whose first group is the declared name,
    and those names in lower case; None also where a name is a keyword."""
    found = _by_line(pattern, texts) if all(map(str.isascii, texts)) else None
    if found is None:
        return None
    lowered = "\n".join([match[0] for match in found]).lower().split("\n")
    return None if not reserved_words().isdisjoint(lowered) else (found, lowered)


def _robtarget_numbers(found: list[tuple[str, str, str, str]]
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(trans, rot, conf) of robtargets whose groups of numbers `_ROBTARGET_LITERAL` found
    ((trans, rot, conf, extax) texts each); NotBulk where a number is not one or a
    confdata not finite."""
    if not found:
        return np.zeros((0, 3)), np.zeros((0, 4)), np.zeros((0, 4))
    trans, rot, conf, extax = zip(*found)
    if not all(map(_numbers, set(extax))):
        raise NotBulk
    try:
        values = [np.array(",".join(groups).split(","), dtype=float).reshape(-1, width)
                  for groups, width in ((trans, 3), (rot, 4), (conf, 4))]
    except ValueError:
        raise NotBulk from None
    if not np.isfinite(values[2]).all():  # a confdata fits_type refuses
        raise NotBulk
    return values[0], values[1], values[2]


def _robtarget_value(text: str) -> tuple:
    try:
        value = aggregate_value(text)
    except NotFast:
        raise NotBulk from None
    if not fits_type("robtarget", value):  # the full route decides
        raise NotBulk
    return value[:3]


def joint_values(texts: list[str]) -> np.ndarray:
    """Robot axes (K,6) of jointtarget literals `[[j1..j6],[e1..e6]]`, read in one pass."""
    match = _JOINT_LITERAL.fullmatch
    groups = []
    extax_ok: dict[str, bool] = {}
    for text in texts:
        m = match(text)
        if m is None:
            raise NotBulk
        robax, extax = m.groups()
        ok = extax_ok.get(extax)
        if ok is None:
            ok = extax_ok[extax] = extax.count(",") == 5 and _numbers(extax)
        if not ok or robax.count(",") != 5:
            raise NotBulk
        groups.append(robax)
    try:
        values = np.array(",".join(groups).split(","), dtype=float).reshape(-1, 6)
    except ValueError:
        raise NotBulk from None
    if not np.isfinite(values).all():  # the full route decides (and reports) those
        raise NotBulk
    return values


# A jointtarget declaration as the rewrite writes it, on a line of its own: a data
# declaration the grammar reads (CONST, a type name, a name, an all-numeric aggregate of
# two groups of six numbers). A number here is any run of the characters a number is
# written with; Python's `float` then reads exactly the grammar's numbers among those
# (an optional sign, digits with an optional point, an optional exponent) and refuses
# the rest.
_NUMBER_CHARS = "[-+0-9.eE]+"
_SIX = rf"{_NUMBER_CHARS}(?:,{_NUMBER_CHARS}){{5}}"
_JOINTTARGET_DECLARATION = re.compile(
    rf"^(?:LOCAL )?CONST jointtarget ([A-Za-z][A-Za-z0-9_]*):=\[\[({_SIX})\],\[({_SIX})\]\];$",
    re.MULTILINE)


@functools.lru_cache(maxsize=1)
def reserved_words() -> frozenset[str]:
    """The grammar's keywords, lower case (a name that is one may lex as the keyword)."""
    from lark.lexer import PatternStr

    return frozenset(t.pattern.value.lower() for t in run_parser().terminals
                     if isinstance(t.pattern, PatternStr) and t.pattern.value.isalpha())


def read_jointtarget_declarations(texts: list[str]) -> tuple[list[str], np.ndarray] | None:
    """The names (lower case) and robot axes (K,6) of declarations that are each exactly
    `[LOCAL ]CONST jointtarget name:=[[j1,...,j6],[e1,...,e6]];` — checked by one
    regular-expression pass over all of them, the numbers read by one `np.array` —, or
    None when a text is not of that form, a name is a keyword or a number is not finite
    (the grammar, through the full route, decides those)."""
    if not texts:
        return [], np.zeros((0, 6))
    read = _declarations_by_line(_JOINTTARGET_DECLARATION, texts)
    if read is None:
        return None
    found, lowered = read
    _names, robax, extax = zip(*found)
    numbers = ",".join(robax).split(",")
    try:
        values = np.fromiter(map(float, numbers), float, len(numbers)).reshape(-1, 6)
        external = [float(v) for group in set(extax) for v in group.split(",")]
    except ValueError:
        return None
    if not (np.isfinite(values).all() and np.isfinite(external).all()):
        return None
    return lowered, values


# A robtarget declaration with a literal written as the rewrite writes it, on a line of
# its own: a new one (`CONST robtarget ft_p1:=[[...],...];`) or one whose value was
# replaced (the words before the value as the program wrote them, on one line; the
# keywords and the type name in any case, as RAPID reads them).
_ROBTARGET_DECLARATION = re.compile(
    r"^(?i:(?:LOCAL[ \t]+)?(?:TASK[ \t]+)?(?:CONST|PERS|VAR)[ \t]+robtarget[ \t]+)"
    rf"([A-Za-z][A-Za-z0-9_]*)[ \t]*:=[ \t]*{_ROBTARGET_LITERAL.pattern}[ \t]*;$",
    re.MULTILINE)


def read_robtarget_declarations(texts: list[str]
                                ) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray] | None:
    """The names (lower case) and (trans (K,3), rot (K,4), conf (K,4)) of robtarget
    declarations each exactly `[LOCAL ][TASK ]CONST|PERS|VAR robtarget name:=literal;` with
    the literal written without whitespace — checked by one regular-expression pass over
    all of them, the numbers read as `robtarget_values` reads them —, or None when a text
    is not of that form, a name is a keyword or a number is not one (the grammar, through
    the full route, decides those)."""
    if not texts:
        return [], np.zeros((0, 3)), np.zeros((0, 4)), np.zeros((0, 4))
    read = _declarations_by_line(_ROBTARGET_DECLARATION, texts)
    if read is None:
        return None
    found, lowered = read
    try:
        trans, rot, conf = _robtarget_numbers([match[1:] for match in found])
    except NotBulk:
        return None
    return lowered, trans, rot, conf


def read_robtarget_literals(texts: list[str]
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(trans (K,3), rot (K,4), conf (K,4)) of robtarget literals each written without
    whitespace (what the rewrite writes), read as `robtarget_values` reads them; None
    when one is written otherwise or a number is not one (the full route decides)."""
    try:
        return _compact_robtargets(texts)
    except NotBulk:
        return None


def _numbers(group: str) -> bool:
    try:
        tuple(map(float, group.split(",")))
    except ValueError:
        return False
    return True


# A call's name at the start of the text before its first target.
_CALL_NAME = re.compile(rf"{WS}*({NAME})")


def one_per_shape(templates: Iterable[tuple[str, ...]]) -> dict[tuple[str, ...], None]:
    """One of each group of statement templates (the texts around a call's targets) that
    differ only in their digits, the call's name aside. Digits stand in numbers and
    names, whose tokens another digit keeps as they are, so the templates of a group
    name the same instruction and place its targets alike (`MoveAbsJ \\ID:=11, ` and
    `MoveAbsJ \\ID:=12, `: a MultiMove program numbers every move). A template holding a
    string, a radix prefix or a comment is a group of its own (`shape_key`)."""
    kept: dict[tuple, tuple[str, ...]] = {}
    for texts in dict.fromkeys(templates):  # (a program's templates are mostly alike)
        keys = tuple(map(shape_key, texts))
        name = _CALL_NAME.match(texts[0]) if texts else None
        if None in keys or name is None or any("!" in text for text in texts):
            kept.setdefault(texts, texts)
        else:
            kept.setdefault((name.group(1), keys), texts)
    return dict.fromkeys(kept.values())


def read_targets_full(motions: list[MotionInstruction], motion: np.ndarray,
                      slot: np.ndarray) -> ReadBack:
    """The fallback: the targets read from the motions of the full program model
    (`motions`, by statement id), row i being target `slot[i]` of motion `motion[i]`."""
    k = motion.shape[0]
    out = ReadBack.empty(k)
    for i, (m, which) in enumerate(zip(motion.tolist(), slot.tolist())):
        operand = motions[m].targets[which]
        value = operand.value if operand.static else None
        if value is None or operand.type_name not in ("jointtarget", "robtarget"):
            raise RapidSemanticError(
                f"rewritten target {operand.text!r} cannot be read back: {operand.reason}",
                file=motions[m].span.file, line=motions[m].span.line,
                hint="please report this as a rapidfix bug")
        # raw values, already checked against their type by the RAPID layer
        if operand.type_name == "jointtarget":
            out.joint[i] = True
            out.robax[i] = value[0]
        else:
            out.trans[i], out.rot[i], out.conf[i] = value[:3]
    return out


def read_targets_in_bulk(text: str, order: list[int], motion: np.ndarray,
                         slot: np.ndarray) -> ReadBack | None:
    """The targets of a program of simple statements read in bulk: row i is target
    `slot[i]` of the call that is statement `motion[i]` (`order`: the statement id of
    each call, in text order). None when the bulk reader does not take the text or a
    target (`read_targets_full` decides then)."""
    bulk = read_bulk(text)
    if bulk is None:
        return None
    try:
        return _read_bulk_targets(bulk, order, motion, slot)
    except NotBulk:
        return None
