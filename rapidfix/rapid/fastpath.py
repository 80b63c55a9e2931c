"""Whole-run tokens for the simple statements that make up large programs.

A CAM program is almost entirely lines of two shapes,
`CONST robtarget p1:=[[...],[...],[...],[...]];` and
`MoveL p1,v100,z1,tool\\WObj:=wobj;`. Lark's pure-Python LALR parser spends
microseconds on every token and every reduction, and such a line has up to a
dozen tokens and fifty reductions. This module adds two terminals to the
grammar, each matching a whole run of such statements at once:

- FAST_DECLS: declarations `[LOCAL] [TASK] VAR|PERS|CONST type name [:= value];`
- FAST_CALLS: procedure calls `Name [arg {, arg}];`, each argument a value or
  `\\Name[:=value]` (an optional argument, with or without a comma before it),
  and assignments `target := value;` (the target a name with components and indices),

a value being a name, an unsigned number or an all-numeric aggregate of up to
two levels, with only whitespace between the pieces. The callbacks split a token
into exactly the syntax nodes the grammar's own rules build (same node types,
offsets and values), so nothing downstream can tell the difference. Values may
also be negated numbers and function calls of such values (`Offs(p1,0,0,-10)`),
whose required arguments may be such calls themselves, two levels deep
(`Offs(RelTool(p1,0,0,5),0,0,-10)`, `Offs(RelTool(Offs(p1,0,0,1),0,0,5),0,0,-10)`),
and whole-line comments may stand between the statements of a run. Values may also
be arithmetic (rapidfix.rapid.fast_expressions):
signs, `+ - * / DIV MOD`, parentheses, record components and array elements
(`Offs(pHome,0,0,-nDepth)`, `0-rModel.numDiameter/2`, `RelTool(p,0,0,0\\Rz:=-1*nAngle)`,
`vWeld{i+1}`), and aggregates of such sums (`[100+nStep*2,500,5000,1000]`); those
values are read by fast_expressions' reader, which follows the grammar's expression
rules and gives up (NotFast) on anything it does not build exactly. A value may also
be TRUE or FALSE, a string (`TPWrite "Point 1, reached; ok"`, also in sums, calls and
parentheses: `"Count: " + NumToStr(n,0)`), or a condition (`WaitUntil di1 = 1 AND NOT
bStop`). Anything else in a statement — a comment inside it, another keyword, a named
or conditional argument, calls nested deeper — ends the run, and that statement is
parsed by the full grammar as before. A run also takes an IF block whose branch holds
such calls only, written on the line of its THEN, `IF c THEN <calls> ENDIF` (no ELSE,
nothing nested): hand-written cells guard moves and signals that way, and each such
block cost the LALR parser three tokens and their reductions. So it takes a compact IF
of a call or a GOTO (`IF bOn Set do1;`, `IF n > 3 GOTO lDone;`), whose condition ends
at the first operand that whitespace and a name follow, and a GOTO alone.

More terminals take the head of a compound statement whole (head_patterns):
`IF c THEN`, `ELSEIF c THEN`, `WHILE c DO`, `FOR v FROM a TO b [STEP s] DO`, `TEST e`,
`CASE a, b:` and `RETURN [e];`. Their patterns only find where each condition ends (the
fewest characters up to the next keyword, no comment, `;`, conditional or named argument
or placeholder inside); fast_expressions' reader then reads it as rapid.lark's `expr`
(relations, NOT, AND, OR, XOR), or gives up (NotFast). A procedure's or function's
head, `[LOCAL] PROC name(parameters)` or `[LOCAL] FUNC type name(parameters)`, is one
terminal too (a program of many small routines spent a Lark step on each of its
words), its parameters without alternatives (`\\a | b`) or placeholders.

Whole compound statements and whole routines go further: rapidfix.rapid.fast_blocks
reads them ahead of the lexer with these terminals and hands the parser one token
(FAST_BLOCK, FAST_ROUTINES) holding their nodes, made by this module's callbacks.

Lark stays the parser: a run is an inlined rule (`_fast_calls`, `_fast_decls`)
added where the grammar allows a statement or a declaration, whose nodes Lark
splices into the enclosing list as it does for every rule named with `_`; the
contextual lexer offers the terminals only where such a run may start.
`grammars/rapid.lark` stays the definition of the language: whenever the fast
parser fails, the plain parser decides (parse_text), and syntax errors are
explained by the plain grammar (rapidfix.rapid.syntax_errors), so messages and
positions do not depend on this module.
"""

from __future__ import annotations

import dataclasses
import functools
import re
import sys
from collections.abc import Callable
from typing import Any

from lark import Lark, Token, Tree, v_args
from lark.exceptions import UnexpectedInput

from rapidfix.rapid import fast_blocks, fast_expressions
from rapidfix.rapid import syntax as s
from rapidfix.rapid.error_window import confirms, error_offset, window
from rapidfix.rapid.fast_expressions import (  # (WS and GAP: also readback's)
    GAP,
    LATIN1_LETTERS,
    NAME,
    NAME_START,
    PLAIN_VALUE,
    STRING,
    WORD_END,
    WORD_START,
    WS,
    NotRead,
    condition_pattern,
    expression_patterns,
    read_expression,
    read_list,
)
from rapidfix.rapid.fast_expressions import VALUE_TEXT as _EXPRESSION_TEXT
from rapidfix.rapid.fast_expressions import WS_CHARS as _WS_CHARS
from rapidfix.rapid.grammar import diagnosis_parser, grammar_text, rapid_parser
from rapidfix.rapid.lexer_patterns import share_large_patterns
from rapidfix.rapid.transform import (
    SyntaxBuilder,
    number_value,
    numeric_aggregate_value,
    statements_in,
    string_value,
)

# Whitespace inside an aggregate of numbers: the grammar's NUMERIC_AGGREGATE takes
# Python's `\s` there, which holds every character of WS but \x1a (a DOS end of file,
# whitespace between tokens): an aggregate with one inside is the grammar's aggregate of
# items, which the general route reads.
_AGGREGATE_WS = r"[ \t\f\v\r\n]"
# An aggregate of numbers, up to two levels deep, matched loosely for speed; its numbers
# are checked when they are read (_number_group, aggregate_value). Runs of number
# characters, commas and whitespace (`[[600, 0, 650], [1, 0, 0, 0], ...]`) are taken
# whole (one step of the regex engine, not one per character); as they hold no bracket,
# this never backtracks.
_GROUP_CHARS = r"[-+0-9.eE, \t\f\v\r\n]*"
_LOOSE_AGGREGATE = rf"\[{_GROUP_CHARS}(?:\[{_GROUP_CHARS}\]{_GROUP_CHARS})*\]"
# An aggregate of such aggregates, three levels deep, each item two levels deep (an
# array of robtargets, `[[[...],[...],[...],[...]], ...]`), perhaps over several lines.
_ITEM = r"\[[-+0-9.eE,]*(?:\[[-+0-9.eE,]*\][-+0-9.eE,]*)+\]"
_DEEP_AGGREGATE = rf"\[{WS}*{_ITEM}(?:{WS}*,{WS}*{_ITEM})*{WS}*\]"
# An aggregate of those, four levels deep (a two-dimensional array of robtargets, its
# rows perhaps over lines).
_DEEPER_AGGREGATE = rf"\[{WS}*{_DEEP_AGGREGATE}(?:{WS}*,{WS}*{_DEEP_AGGREGATE})*{WS}*\]"
# How a three-level aggregate of the fast terminals starts (a two-level one never does),
# and a four-level one (a three-level one never does).
_DEEP_START = re.compile(rf"\[{WS}*\[[-+0-9.eE,]*\[")
_DEEPER_START = re.compile(rf"\[{WS}*\[{WS}*\[[-+0-9.eE,]*\[")
_DEEP_AGGREGATES = f"(?:{_DEEP_AGGREGATE}|{_DEEPER_AGGREGATE})"
# A value without a call, for splitting a token whose syntax has been checked already:
# an aggregate (up to four levels), a negated number, a name or a number.
# (an expression too: fast_expressions)
_SIMPLE_TEXT = _EXPRESSION_TEXT
# A function call of such values (`Offs(p1,0,0,-10)`).
_CALL_TEXT = rf'{NAME}{WS}*\([^()"]*(?:{STRING}[^()"]*)*\)'
# A value: a function call whose arguments are such values or such calls
# (`Offs(RelTool(p1,0,0,5),0,0,-10)`), an element of an array (`path{3}`, `grid{i,2}`),
# arithmetic of them, or one of them.
VALUE_TEXT = _EXPRESSION_TEXT


class NotFast(Exception):
    """A fast token held something the fast path does not read exactly (an
    aggregate with a malformed number or of mixed depth); parse_text then parses
    the whole file with the plain grammar."""


def _keywords() -> dict[str, str]:
    """Keyword terminal name -> its text (`ENDPROC` -> 'ENDPROC')."""
    return {t.name: t.pattern.value for t in diagnosis_parser().terminals
            if t.pattern.type == "str" and t.pattern.value.isalpha()}


def _keywords_after(prefix: str) -> list[str]:
    """The keywords the plain parser accepts right after `prefix`; elsewhere the
    contextual lexer reads the same letters as a NAME."""
    interactive = diagnosis_parser().parse_interactive(prefix)
    interactive.exhaust_lexer()
    keywords = _keywords()
    return [keywords[t] for t in interactive.accepts() if t in keywords]


def _name(excluded: list[str]) -> str:
    """The NAME terminal, refusing the `excluded` keywords (grouped by first letter)."""
    name = f"{NAME}{WORD_END}"
    if not excluded:
        return name
    by_letter: dict[str, list[str]] = {}
    # a fixed order (longest first, then alphabetical): the grammar text, and so the key
    # of Lark's cached parse table, must not change with the hash seed of the process
    for word in sorted({w.upper() for w in excluded}, key=lambda w: (-len(w), w)):
        by_letter.setdefault(word[0], []).append(re.escape(word[1:]))
    alternatives = "|".join(f"{first}(?:{'|'.join(rest)})" for first, rest in by_letter.items())
    return f"(?!(?i:{alternatives}){WORD_END}){name}"


@functools.lru_cache(maxsize=1)
def _patterns() -> dict[str, str]:
    """Regular expressions of the fast terminals."""
    terminals = {t.name: t for t in diagnosis_parser().terminals}
    latin1 = "\u00c0-\u00d6\u00d8-\u00f6\u00f8-\u00ff"
    # (the placeholder <ID> is a name too; fast names never take it)
    expected_name = f"(?i:[a-z{latin1}][a-z0-9_{latin1}]*|<ID>)"
    if terminals["NAME"].pattern.to_regexp() != expected_name:  # pragma: no cover
        raise ValueError("rapid.lark's NAME changed; update rapidfix.rapid.fastpath")
    after = {words: {w.upper() for w in _keywords_after(f"MODULE m\nPROC p({words}")}
             for words in ("", "\\", "VAR ", "num ")}
    if (after[""], after["\\"], after["VAR "], after["num "]) != (
            set(ACCESS_WORDS), set(ACCESS_WORDS), set(), set()):  # pragma: no cover
        raise ValueError("rapid.lark's parameters changed; update rapidfix.rapid.fastpath")
    call_name = _name(list(_keywords().values()))
    plain_name = _name(_keywords_after("MODULE m\nPROC p()\nx \\"))
    type_name = _name(_keywords_after("MODULE m\nVAR "))
    data_name = _name(_keywords_after("MODULE m\nVAR num "))
    value_name = _name(_keywords_after("MODULE m\nPROC p()\nx "))
    number = f"(?:{terminals['NUMBER'].pattern.to_regexp()})"
    # a value: an aggregate, a (negated) number, a name, an array element, a function
    # call, or arithmetic of them (fast_expressions). Every piece is written once where
    # it can be: the contextual lexer compiles these patterns into each of its scanners,
    # at a cost that grows with their length.
    expression = expression_patterns(
        {name: t.pattern.to_regexp() for name, t in terminals.items()}, value_name,
        plain_name, WORD_END, (_LOOSE_AGGREGATE, _DEEP_AGGREGATES))
    value = expression["value"]
    # a procedure call, or an assignment: its value is taken by the arguments' pattern
    # (written once), and split_calls refuses (NotFast) what is more than one value
    general_call = (f"{call_name}(?:{expression['selectors']}{WS}*:={WS}*)?"
                    f"(?:{WS}*{expression['arguments']})?{WS}*;")
    # first tried: a call whose arguments are all plain, as most are (a subset of the
    # general pattern's statements, so the same tokens)
    plain_call = f"{call_name}{WS}+{expression['plain_arguments']}{WS}*;"
    # either, perhaps as a compact IF's statement (`IF bOn Set do1;`): the IF and its
    # condition before it (split_calls finds the condition's end with compact_head)
    compact = expression["compact_condition"]
    # or a GOTO (`GOTO lRetry;`, or `IF n > 3 GOTO lDone;`)
    label = _name(_keywords_after("MODULE m\nPROC p()\nGOTO "))
    goto = f"(?i:GOTO){WORD_END}{WS}*{label}{WS}*;"
    compact_head = (f"(?i:IF){WORD_END}{WS}*({compact}){WS}+"
                    f"(?={call_name}|(?i:GOTO){WORD_END})")
    call = (f"(?:(?i:IF){WORD_END}{WS}*{compact}{WS}+)?"
            f"(?:{plain_call}|{general_call}|{goto})")
    # array dimensions: numbers or names of constants (`{50}`, `{2,3}`, `{nChannels,10}`)
    dim = f"(?:{number}|{value_name})"
    dims = rf"\{{{WS}*{dim}(?:{WS}*,{WS}*{dim})*{WS}*\}}"
    decl = (f"(?i:(?:LOCAL{WS}+)?(?:TASK{WS}+)?(?:VAR|PERS|CONST)){WS}+{type_name}{WS}+"
            f"{data_name}{WS}*(?:{dims}{WS}*)?(?::={WS}*{value}{WS}*)?;")
    # an IF block's head: its condition cannot take the THEN in (the block's pattern
    # goes on after the THEN, and would otherwise find its ENDIF past an ELSEIF's THEN)
    then = _keyword("THEN")
    # (an ENDIF later on the line first: an IF over lines fails at once)
    block_head = (rf"(?i:IF){WORD_END}(?=[^\n]*(?i:ENDIF))"
                  rf"{condition_pattern(plain_name, then)}{then}")
    return {"call": call, "plain_call": plain_call, "general_call": general_call,
            "decl": decl, "block_head": block_head, "compact_head": compact_head,
            **head_patterns(expression["condition"], False)}


def _keyword(words: str) -> str:
    """A keyword after a condition: a whole word (`IF bTHEN THEN`)."""
    return rf"{WORD_START}(?i:{words}){WORD_END}"


# A routine's parameters, as rapid.lark's `parameters` takes them but for alternatives
# (`\a | b`) and placeholders: `[\][VAR|PERS|INOUT] type name [{*, ...}]`, separated by
# commas (an optional one may follow without). The first word is the access keyword where
# it is one (the only keywords the grammar takes there: checked by `_patterns`); any
# word after it, or after the type, is a name.
ACCESS_WORDS = ("VAR", "PERS", "INOUT")
_ACCESS = rf"(?i:{'|'.join(ACCESS_WORDS)}){WORD_END}"
_PARAMETER = (rf"(?:\\{WS}*)?(?:{_ACCESS}{WS}*{NAME}|(?!{_ACCESS}){NAME}){WORD_END}{WS}*"
              rf"{NAME}{WORD_END}(?:{WS}*\{{{WS}*\*(?:{WS}*,{WS}*\*)*{WS}*\}})?")
PARAMETERS = rf"{_PARAMETER}(?:(?:{WS}*,{WS}*|{WS}*(?=\\)){_PARAMETER})*"


def head_patterns(condition: str, groups: bool) -> dict[str, str]:
    """The patterns of the statements' heads that are one fast token each, by kind: the
    keywords, and between them the conditions (`condition`), a CASE's list of them or a
    FOR's variable; with `groups`, each of those in a group of its own (for splitting a
    token, whose syntax the lexer has checked)."""
    c = f"({condition})" if groups else condition
    name = f"({NAME}){WORD_END}" if groups else f"{NAME}{WORD_END}"
    params = f"({PARAMETERS})?" if groups else f"(?:{PARAMETERS})?"

    return {
        "if": rf"(?i:IF){WORD_END}{c}{_keyword('THEN')}",
        "elseif": rf"(?i:ELSEIF){WORD_END}{c}{_keyword('THEN')}",
        "while": rf"(?i:WHILE){WORD_END}{c}{_keyword('DO')}",
        "for": (rf"(?i:FOR){WORD_END}{WS}*{name}{WS}*(?i:FROM){WORD_END}{c}{_keyword('TO')}"
                rf"{c}(?:{_keyword('STEP')}{c})?{_keyword('DO')}"),
        # (up to its first clause, which stays a token of its own: a token split is
        # that far already)
        "test": rf"(?i:TEST){WORD_END}{c}"
                + ("" if groups else f"(?={_keyword('CASE|DEFAULT|ENDTEST')})"),
        "case": rf"(?i:CASE){WORD_END}{c}:",
        "return": rf"(?i:RETURN){WORD_END}(?:{c})?;",
        # a procedure's head up to its body (`LOCAL PROC Path_10()`, `PROC Pick(robtarget
        # p, \switch Slow)`), a function's (`FUNC num Twice(num x)`)
        "proc": (rf"(?:(?i:{'(LOCAL)' if groups else 'LOCAL'}){WS}+)?(?i:PROC){WORD_END}"
                 rf"{WS}*{name}{WS}*\({WS}*{params}{WS}*\)"),
        "func": (rf"(?:(?i:{'(LOCAL)' if groups else 'LOCAL'}){WS}+)?(?i:FUNC){WORD_END}"
                 rf"{WS}*{name}{WS}*{name}{WS}*\({WS}*{params}{WS}*\)"),
    }


# The statements whose head is one fast token: the rule each is an alternative of
# (its head token, then what follows the plain head in rapid.lark), and the plain rule
# (checked against rapid.lark).
_HEAD_RULES = {
    "if": ("fast_if_stmt", "_statement* elseif_clause* else_clause? ENDIF",
           "if_stmt: IF expr THEN"),
    "elseif": ("elseif_clause", "_statement* -> fast_elseif_clause",
               "elseif_clause: ELSEIF expr THEN"),
    "while": ("fast_while_stmt", "_statement* ENDWHILE", "while_stmt: WHILE expr DO"),
    "for": ("fast_for_stmt", "_statement* ENDFOR",
            "for_stmt: FOR NAME FROM expr TO expr (STEP expr)? DO"),
    "test": ("fast_test_stmt", "(case_clause | case_placeholder)* default_clause? ENDTEST",
             "test_stmt: TEST expr"),
    "case": ("case_clause", "_statement* -> fast_case_clause",
             'case_clause: CASE expr ("," expr)* ":"'),
    "return": ("return_stmt", "-> fast_return_stmt", "return_stmt: RETURN expr? SEMI"),
    "proc": ("proc", "_body handler* ENDPROC -> fast_proc",
             'proc: LOCAL? PROC NAME "(" parameters? ")"'),
    "func": ("func", "_body handler* ENDFUNC -> fast_func",
             'func: LOCAL? FUNC NAME dims? NAME "(" parameters? ")"'),
}
_BODY_RULE = "_body: (data_decl | _statement)*"
#: statements in one fast token at most. Python's regular expression engine keeps a
#: backtracking record per repetition, so one token for a whole CAM program's hundred
#: thousand statements would hold a few hundred MB and match at half the speed;
#: a longer run simply becomes several tokens in a row.
RUN_LIMIT = 256


def grammar_extension(grammar: str) -> str:
    """Lark grammar text that adds the fast terminals to the rules of `grammar`.

    A run of declarations may stand wherever a declaration may, so `_body` is
    restated with it; the check below keeps that in step with rapid.lark.
    """
    if _BODY_RULE not in grammar:  # pragma: no cover - guards a change of rapid.lark
        raise ValueError(f"rapid.lark no longer says {_BODY_RULE!r}; update fastpath")
    p = _patterns()
    # a run starts with a statement (the gap before the first matches nothing)
    # an IF block of calls on the line of its THEN is one statement of a run (split_calls
    # builds its If node); an IF over lines fails here at its THEN's line end, before
    # its body (which may hold an ELSE) is read twice
    # (the calls in it by the general pattern alone: a block is rare, and each copy of
    # the plain one lengthens what every process compiles)
    if_block = (f"{p['block_head']}(?:[ \t]*{p['general_call']}){{0,{RUN_LIMIT}}}"
                f"[ \t]*(?i:ENDIF){WORD_END}")
    # (each statement starts with a letter: said after the gap too, so that where the run
    # ends the engine does not try every statement's pattern at every shorter gap)
    calls = (f"(?={NAME_START})(?:{GAP}(?={NAME_START})(?:{p['call']}|{if_block}))"
             f"{{1,{RUN_LIMIT}}}")
    decls = f"(?={NAME_START})(?:{GAP}(?={NAME_START}){p['decl']}){{1,{RUN_LIMIT}}}"
    heads = {kind: p[kind] for kind in _HEAD_RULES}
    if "/" in calls + decls + "".join(heads.values()):  # pragma: no cover
        raise ValueError("a terminal pattern holds '/'")  # a Lark regex literal ends at '/'
    for _, rest, plain in _HEAD_RULES.values():
        if f"{plain} {rest.split('->')[0]}".rstrip() not in grammar:  # pragma: no cover
            raise ValueError(f"rapid.lark no longer says {plain!r} ...; update fastpath")
    new_rules = [rule for rule, _, _ in _HEAD_RULES.values() if rule.startswith("fast_")]
    return (
        f"\n%extend _statement: _fast_calls | {' | '.join(new_rules)} | _fast_block\n"
        "%extend _module_item: _fast_decls | _fast_routines\n"
        "%override _body: (data_decl | _fast_decls | _statement)*\n"
        "_fast_calls: FAST_CALLS\n"
        "_fast_decls: FAST_DECLS\n"
        # (given by fast_blocks' reader only: their patterns never match)
        f"_fast_block: {fast_blocks.BLOCK}\n"
        f"_fast_routines: {fast_blocks.ROUTINES}\n"
        f"{fast_blocks.BLOCK}: /{fast_blocks.NEVER}/\n"
        f"{fast_blocks.ROUTINES}: /{fast_blocks.NEVER}/\n"
        + "".join(f"{'' if rule.startswith('fast_') else '%extend '}{rule}: "
                  f"FAST_{kind.upper()} {rest}\n"
                  for kind, (rule, rest, _) in _HEAD_RULES.items())
        + f"FAST_CALLS.9: /{calls}/\n"
        f"FAST_DECLS.9: /{decls}/\n"
        + "".join(f"FAST_{kind.upper()}.9: /{pattern}/\n" for kind, pattern in heads.items())
        # (a comment to Lark: what split_calls splits compact IFs with, kept with the rest)
        + f"{_COMPACT_HEAD_COMMENT}{p['compact_head']}\n"
    )


_COMPACT_HEAD_COMMENT = "// compact_head: "


class LazyPattern:
    """A regular expression compiled on its first use. The splitting patterns below hold
    the values' pattern several times (a few ms each to compile): a command that reads
    one small file with the plain grammar (rapidfix.rapid.parse) never needs them."""

    __slots__ = ("_compiled", "_text")

    def __init__(self, text: str) -> None:
        self._text, self._compiled = text, None

    @property
    def compiled(self) -> re.Pattern[str]:
        if self._compiled is None:
            self._compiled = re.compile(self._text)
        return self._compiled

    def match(self, text: str, pos: int = 0) -> re.Match[str] | None:
        return self.compiled.match(text, pos)

    def finditer(self, text: str) -> Any:
        return self.compiled.finditer(text)

    def findall(self, text: str) -> list[Any]:
        return self.compiled.findall(text)


# Splitting a call whose syntax the lexer has checked: after its name (or its
# first argument), one piece is an optional argument, a required value or the ';'.
CALL_PIECE = LazyPattern(
    rf"{WS}*(?:,{WS}*)?(?:(\\){WS}*({NAME})(?:{WS}*:={WS}*({VALUE_TEXT}))?"
    rf"|({VALUE_TEXT})|(;))"
)


def _declaration_head(modifiers: bool) -> str:
    """A checked declaration up to its dimensions or value: (LOCAL, TASK, storage,) type
    and name, the groups in parentheses only with `modifiers`."""
    def group(pattern: str) -> str:
        return f"({pattern})" if modifiers else pattern

    return (rf"{GAP}(?:(?i:{group('LOCAL')}){WS}+)?(?:(?i:{group('TASK')}){WS}+)?"
            rf"{group('(?i:VAR|PERS|CONST)')}{WS}+"
            rf"({NAME}){WS}+({NAME}){WS}*")


def declaration_pattern(modifiers: bool) -> LazyPattern:
    """Splits a declaration whose syntax has been checked: (LOCAL, TASK, storage,) type,
    name, (the inside of its dimensions' braces,) and value text; the groups in
    parentheses only with `modifiers`."""
    braces = "([^{}]*)" if modifiers else "[^{}]*"
    return LazyPattern(
        _declaration_head(modifiers)
        + rf"(?:\{{{braces}\}}{WS}*)?"
        rf"(?::={WS}*({VALUE_TEXT}){WS}*)?;"
    )


_DECL = declaration_pattern(True)
# The declaration most programs are made of, `CONST robtarget p1:=[[x,y,z],[...],...];`
# written without whitespace in its value, with the value's first group and what follows
# it in groups of their own (LOCAL, TASK, storage, type, name, value, the first group's
# numbers, the rest): the text `_DECL` and `grouped_value` would take apart.
_PLAIN_DECL = LazyPattern(
    _declaration_head(True) + rf":={WS}*"
    r"(\[\[([-+0-9.eE,]*)\](,\[[-+0-9.eE,]*\](?:,\[[-+0-9.eE,]*\])*\]))"
    rf"{WS}*;")
# The same spaced as people write it (`[ [x, y, z], [...], ... ]`), the same groups: tried
# after the tight form, which it would take too, but more slowly.
_SPACED_DECL = LazyPattern(
    _declaration_head(True) + rf":={WS}*"
    rf"(\[{_AGGREGATE_WS}*\[({_GROUP_CHARS})\]"
    rf"((?:{_AGGREGATE_WS}*,{_AGGREGATE_WS}*\[{_GROUP_CHARS}\])+{_AGGREGATE_WS}*\]))"
    rf"{WS}*;")


class Memo(dict):
    """The one cache policy of the fast path: pure results kept across tokens and files,
    keyed by their text, emptied at once when `limit` entries are reached (a CAM program
    repeats a few dozen texts, so a cleared cache refills at once)."""

    __slots__ = ("limit",)

    def __init__(self, limit: int) -> None:
        super().__init__()
        self.limit = limit

    def keep(self, key: str, value: object) -> None:
        """Store `value` under `key`, emptying the cache first when it is full."""
        if len(self) >= self.limit:
            self.clear()
        self[key] = value


# Groups of numbers recur in CAM programs ([0,0,0,0], [9E+09,...]); read each once.
_GROUP_CACHE: Memo = Memo(65536)


def _number_group(text: str, keep: bool = True) -> tuple[float, ...]:
    """'1,-2.5,9E+09' -> (1.0, -2.5, 9e9), kept in the cache unless `keep` is False.
    The loose lexer pattern let through only the characters -+0-9.eE and whitespace, and
    of such strings float() takes exactly those that RAPID's number syntax takes (a
    number with whitespace around it, never inside); anything else raises NotFast."""
    try:
        value = tuple(map(float, text.split(",")))
    except ValueError:
        raise NotFast(text) from None
    if keep:
        _GROUP_CACHE.keep(text, value)
    return value


@functools.lru_cache(maxsize=1)
def _exact_aggregate() -> re.Pattern[str]:
    terminal = next(t for t in diagnosis_parser().terminals if t.name == "NUMERIC_AGGREGATE")
    return re.compile(terminal.pattern.to_regexp())


def aggregate_value(text: str) -> tuple:
    """The value of a loosely matched numeric aggregate, as the grammar's
    NUMERIC_AGGREGATE would give it (see transform.numeric_aggregate_value)."""
    body = text[1:-1]
    if "[" not in body:
        return _GROUP_CACHE.get(body) or _number_group(body)
    if body[0] == "[" and body[-1] == "]":
        inner = body[1:-1]
        groups = inner.split("],[")
        if inner.count("[") == len(groups) - 1 == inner.count("]"):  # only groups
            cached = _GROUP_CACHE.get
            return tuple([cached(g) or _number_group(g) for g in groups])
    if _exact_aggregate().fullmatch(text):  # numbers and groups mixed: [1.8,[0,0,40],...]
        compact = "".join(text.split())
        if len(compact) < len(text):
            # whitespace around the groups (`[[600, 0, 650], [1, 0, 0, 0]]`): a grammar
            # token whose numbers hold none (its `\s`, which str.split takes), so the same
            # numbers without it, the groups read as above
            return aggregate_value(compact)
        return numeric_aggregate_value(text)
    raise NotFast(text)


# Splitting the inside of a checked function call: one piece is an optional
# argument, a required value or the closing parenthesis.
_INNER_PIECE = LazyPattern(
    rf"{WS}*(?:,{WS}*)?(?:(\\){WS}*({NAME})(?:{WS}*:={WS}*({_SIMPLE_TEXT}))?"
    rf"|({_CALL_TEXT}|{_SIMPLE_TEXT})|(\)))"
)


def _call_node(text: str, start: int) -> s.Call:
    """The Call node of checked function call text `Name(args)` at `start`: its first
    argument, and the rest as a tail read once per distinct text (a LazyFunctionCall,
    like split_calls' LazyCall: `Offs(p1,0,0,10)` and `Offs(p2,0,0,10)` share `,0,0,10)`).

    A text of a shape read before (`shape_key`: `Offs(RelTool(Offs(p8,0,0,-5),...),...)`
    after `p7`'s) is split where that one was, its values read from it (`_reshaped`),
    without matching its arguments again: calls of calls cost a pattern match a level."""
    return _by_shape(_CALL_SHAPES, shape_key(text), text, start, _split_call)


def _split_call(text: str, start: int) -> s.LazyFunctionCall:
    """`_call_node` of a text read in full."""
    open_at = text.index("(")
    name = text[:open_at].rstrip(_WS_CHARS)
    first = _INNER_PIECE.compiled.match(text, open_at + 1)
    value = first.group(4)
    if value is None:  # an optional argument first, or no argument
        head, tail_at = None, open_at + 1
    else:
        node = _value_node(value, start + first.start(4))
        head = s.Argument(node.start, node.end, "required", None, node)
        tail_at = first.end()
    return s.LazyFunctionCall(start, start + len(text), sys.intern(name), head,
                              _inner_tail(text[tail_at:]), start + tail_at)


def _inner_tail(text: str) -> CallTail:
    """The CallTail of a function call's arguments after its first, read once per
    distinct text; a text new but of a known shape (its digits aside: `,p7.trans.x*0,0)`
    after `,p6.trans.x*0,0)`) is the known one's with the values that differ read again."""
    return _tail_by_shape(text, _INNER_TAILS, _TAIL_SHAPES, _INNER_PIECE)


def _lead(text: str) -> CallTail:
    """The CallTail of the optional arguments before a call's first required one, read as
    `_inner_tail` reads its text: `\\ID:=11, ` after `\\ID:=10, ` (a MultiMove program
    numbers every move) is the known lead with its number read again."""
    return _tail_by_shape(text, _LEADS, _LEAD_SHAPES, CALL_PIECE)


def _tail_by_shape(text: str, texts: Memo, shapes: Memo, pieces: LazyPattern) -> CallTail:
    """The CallTail of `text` split by `pieces`, kept in `texts` by text and in `shapes`
    by the text's shape (`shape_key`)."""
    tail = texts.get(text)
    if tail is None:
        key = shape_key(text)
        if key is not None:
            known = shapes.get(key)
            if known is not None:
                tail = known[1].reshaped(known[0], text)
                if tail is None:  # an option named with a digit: read in full
                    key = None
        if tail is None:
            tail = CallTail(text, pieces)
            if key is not None:
                shapes.keep(key, (text, tail))
        texts.keep(text, tail)
    return tail


_BOOLS = {"TRUE": True, "FALSE": False}


def _value_node(text: str, start: int) -> s.Expr:
    """The node the grammar builds for a value the fast terminals take, at `start`: a
    name, a number, a numeric aggregate, a negated number, a function call, TRUE/FALSE
    or a whole string; any other (arithmetic, components, aggregates of expressions)
    from fast_expressions."""
    if text[0] == "[":
        inline = _inline_target(text, start)
        if inline is not None:
            return inline
    if len(text) <= 5 and text.upper() in _BOOLS:
        return s.Bool(start, start + len(text), _BOOLS[text.upper()])
    if text[0] == '"' and _WHOLE_STRING.fullmatch(text):
        return s.String(start, start + len(text), string_value(text))
    if not (PLAIN_VALUE.fullmatch(text) or _PLAIN_AGGREGATE.fullmatch(text)):
        return _read(text, start)
    end = start + len(text)
    first = text[0]
    if first == "[":
        try:
            if _DEEP_START.match(text):
                if _DEEPER_START.match(text):
                    return s.Aggregate(start, end, [
                        _deep_aggregate(m.group(), start + m.start(), _RESTS)
                        for m in _DEEP_ROW.finditer(text, 1)])
                return _deep_aggregate(text, start, _RESTS)
            # an inline target: its position read, the rest once per distinct text
            grouped = grouped_value(text, _RESTS)
            if grouped is not None:
                _PLAIN_RESTS.keep(text[text.find("]") + 1:], grouped[1:])
                return s.NumericAggregate(start, end, grouped)
            return s.NumericAggregate(start, end, aggregate_value(text))
        except NotFast:  # the loose pattern let arithmetic through: [1-1,2]
            return _read(text, start)
    if first.isdigit() or first == ".":
        return s.Number(start, end, number_value(text), text)
    if first == "-":
        rest = text[1:].lstrip(_WS_CHARS)
        operand = _value_node(rest, end - len(rest))
        return s.Unary(start, operand.end, "-", operand)
    if text[-1] == ")":
        return _call_node(text, start)
    if text[-1] == "}":
        return _index_node(text, start)
    return s.NameRef(start, end, sys.intern(text))


_WHOLE_STRING = re.compile(STRING)
_NUMBER_GROUP = re.compile(_GROUP_CHARS)


def _inline_target(text: str, start: int) -> s.NumericAggregate | None:
    """The node of `[[x,y,z],...]` whose text after its first group is one `_value_node`
    has read as a plain aggregate already (a CAM program's inline targets differ in
    their position), or None: then `_value_node` reads it in full."""
    cut = text.find("]")
    items = _PLAIN_RESTS.get(text[cut + 1:])
    if items is None:
        return None
    first = _group_start(text)
    if not first or not _NUMBER_GROUP.fullmatch(text, first, cut):
        return None
    try:
        group = tuple(map(float, text[first:cut].split(",")))
    except ValueError:  # not numbers after all: read in full, as before
        return None
    return s.NumericAggregate(start, start + len(text), (group, *items))


def _read(text: str, start: int) -> s.Expr:
    """read_expression(text, start) of a condition (NotFast where it gives up). A program
    repeats its expressions (`nCount + 1`, `nCount < 3`): each text is read once, and
    read again as the first's nodes moved to where it stands (the first use gets the
    nodes as read). A long text (a table of
    records, `[[0,11,1,"s7j46w0-0",...],...]`) hardly ever recurs (2 of 125 in the real
    corpus): it is read where it stands and not kept, which spares copying its nodes."""
    if text.startswith("[["):
        grouped = _grouped_read(text, start)
        if grouped is not None:
            return grouped
    if len(text) > READ_KEPT_CHARS:
        if text[0] == "[" and '"' in text:
            rows = _rows_read(text, start)
            if rows is not None:
                return rows
        try:
            return read_expression(text, start, condition=True)
        except NotRead:
            raise NotFast(text) from None
    known = _READ.get(text)
    if known is not None:
        return _moved(known, start - known.start)
    try:
        node = _read_by_shape(text, start)
    except NotRead:
        raise NotFast(text) from None
    # kept as read: syntax nodes are never changed, and a later use of the text gets
    # its own copy (moved), so this tree stays the only one that holds these nodes
    _READ.keep(text, node)
    return node


#: the longest expression text _read keeps (see there)
READ_KEPT_CHARS = 256

# A row of a table of records: an aggregate of values, strings among them, holding
# aggregates one level down (`[17,"S17",3.5,[2,1,0]]`); and a table of such rows.
_ROW_TEXT = rf'\[(?:[^\[\]"]|{STRING}|\[(?:[^\[\]"]|{STRING})*\])*\]'
_ROW = re.compile(_ROW_TEXT)
_ROWS = re.compile(rf"\[{WS}*{_ROW_TEXT}(?:{WS}*,{WS}*{_ROW_TEXT})*{WS}*\]")


def _rows_read(text: str, start: int) -> s.Aggregate | None:
    """_read of a table of records (`[[17,"S17",3.5,[2,1,0]],[18,"S18",4.5,[3,2,0]],...]`,
    strings in its rows), row by row: a row of a shape read before (its digits made 1s,
    in its strings too, where a digit changes a value but never where the row splits) is
    that row's nodes at the new place with the new values (`_reshaped`); None for any
    other text, and where a row does not read (then the whole is read in full)."""
    if _ROWS.fullmatch(text) is None:
        return None
    items: list[s.Expr] = []
    for m in _ROW.finditer(text, 1):
        row = m.group()
        try:
            items.append(_by_shape(_ROW_SHAPES, shape_key(row, in_strings=True), row,
                                   start + m.start(), _read_in_full))
        except NotRead:
            return None
    return s.Aggregate(start, start + len(text), items)


# Every digit made a 1: texts that differ only in their digits (`Offs(p17,0,0,-nZ*2)`,
# `Offs(p18,0,0,-nZ*3)`) have one shape.
_ONES = bytes.maketrans(b"0123456789", b"1111111111")
# A radix prefix (0x1F, 0b101, 0o17): its digits decide how the text is read, so such a
# text has no shape (also where it is only part of a name, `p0x`: read in full)
_RADIX = re.compile(r"0[xXbBoO]").search


def shape_key(text: str, in_strings: bool = False) -> bytes | None:
    """`text` with every digit made a 1, or None where its digits decide how it is read
    (after a radix prefix; in a string, unless `in_strings`: a table's rows, whose
    strings the reshapers decode again)."""
    if (not in_strings and '"' in text) or _RADIX(text) is not None:
        return None
    return text.encode("utf-8", "surrogatepass").translate(_ONES)


class _NoShape(Exception):
    """A node _reshaped cannot make from a text's shape (read the text in full)."""


def _read_by_shape(text: str, start: int) -> s.Expr:
    """read_expression(text, start, condition=True), read once per shape of the text.

    Digits do not change how a value is read: they stand in numbers and names, whose
    tokens a different digit keeps as they are (but after `0x`, `0b`, `0o`, and in a
    string, which are read in full). So the nodes of a text whose digits alone differ
    from one read before are that one's nodes at the new place, with the numbers and
    names taken from the new text (_reshaped): a program's expressions often differ only
    in the target they name or the numbers they hold. NotRead as read_expression."""
    return _by_shape(_SHAPES, shape_key(text), text, start, _read_in_full)


def _read_in_full(text: str, start: int) -> s.Expr:
    return read_expression(text, start, condition=True)


def _by_shape(memo: Memo, key: bytes | None, text: str, start: int,
              read: Callable[[str, int], Any]) -> Any:
    """`read(text, start)`, or, where `memo` holds a node of the same shape (`key`, None
    for a text without one), that node moved to `start` and read from `text`
    (`_reshaped`). `memo`: shape -> (node, where its text stood), or None for a shape
    whose nodes hold what is not moved (then read in full)."""
    if key is not None:
        known = memo.get(key)
        if known is not None:
            node, at = known
            try:
                return _reshaped(node, start - at, text, at)
            except _NoShape:
                memo[key] = None
                key = None
    node = read(text, start)
    if key is not None and key not in memo:
        memo.keep(key, (node, start))
    return node


def _reshaped(node: Any, shift: int, text: str, at: int) -> Any:
    """A copy of a node of a text standing at `at`, moved by `shift`, its numbers and
    names read from `text` (another text of the same shape, standing at `at + shift`)."""
    make = _RESHAPERS.get(type(node))
    if make is None:
        raise _NoShape(type(node).__name__)
    return make(node, shift, text, at)


def _reshaped_argument(n: s.Argument, d: int, text: str, at: int) -> s.Argument:
    name = n.name
    if name is not None and not name.isalpha():  # a digit may be in it: not moved
        raise _NoShape(name)
    return s.Argument(n.start + d, n.end + d, n.kind, name,
                      None if n.value is None else _reshaped(n.value, d, text, at))


def _reshaped_number(n: s.Number, d: int, text: str, at: int) -> s.Number:
    number = text[n.start - at:n.end - at]
    return s.Number(n.start + d, n.end + d, number_value(number), number)


_intern = sys.intern
# How each node type read_expression makes is made from a text's shape (by exact type).
_RESHAPERS: dict[type, Callable[[Any, int, str, int], Any]] = {
    s.NameRef: lambda n, d, t, a: s.NameRef(n.start + d, n.end + d,
                                            _intern(t[n.start - a:n.end - a])),
    s.Number: _reshaped_number,
    s.Bool: lambda n, d, t, a: s.Bool(n.start + d, n.end + d, n.value),
    # (only in a table's rows, whose shapes keep their strings: `_rows_read`)
    s.String: lambda n, d, t, a: s.String(n.start + d, n.end + d,
                                          string_value(t[n.start - a:n.end - a])),
    s.NumericAggregate: lambda n, d, t, a: s.NumericAggregate(
        n.start + d, n.end + d, numeric_aggregate_value(t[n.start - a:n.end - a])),
    s.Binary: lambda n, d, t, a: s.Binary(n.start + d, n.end + d, n.op,
                                          _reshaped(n.left, d, t, a),
                                          _reshaped(n.right, d, t, a)),
    s.Unary: lambda n, d, t, a: s.Unary(n.start + d, n.end + d, n.op,
                                        _reshaped(n.operand, d, t, a)),
    s.Paren: lambda n, d, t, a: s.Paren(n.start + d, n.end + d, _reshaped(n.inner, d, t, a)),
    # (a component's name ends the node)
    s.Component: lambda n, d, t, a: s.Component(
        n.start + d, n.end + d, _reshaped(n.base, d, t, a),
        _intern(t[n.end - a - len(n.name):n.end - a])),
    s.Index: lambda n, d, t, a: s.Index(n.start + d, n.end + d, _reshaped(n.base, d, t, a),
                                        [_reshaped(i, d, t, a) for i in n.indices]),
    s.Aggregate: lambda n, d, t, a: s.Aggregate(n.start + d, n.end + d,
                                                [_reshaped(i, d, t, a) for i in n.items]),
    # (a call's name starts the node)
    s.Call: lambda n, d, t, a: s.Call(n.start + d, n.end + d,
                                      _intern(t[n.start - a:n.start - a + len(n.name)]),
                                      [_reshaped(arg, d, t, a) for arg in n.args]),
    s.Argument: _reshaped_argument,
    s.LazyFunctionCall: lambda n, d, t, a: _reshaped_call(n, d, t, a),
}


def _reshaped_call(n: s.LazyFunctionCall, d: int, text: str, at: int) -> s.LazyFunctionCall:
    """A LazyFunctionCall made by `_split_call`, moved and read from `text` (see
    `_reshaped`): its first argument's value reshaped, its tail the one of its new text.
    An inline target first is read in full (its items are shared by text, see
    `_inline_target`)."""
    head = n.head
    if head is not None:
        value = head.value
        if type(value) is s.NumericAggregate or type(value) is s.Aggregate:
            raise _NoShape("aggregate")
        value = _reshaped(value, d, text, at)
        head = s.Argument(value.start, value.end, "required", None, value)
    name_at, tail_at = n.start - at, n.shift - at
    return s.LazyFunctionCall(n.start + d, n.end + d,
                              _intern(text[name_at:name_at + len(n.name)]), head,
                              _inner_tail(text[tail_at:n.end - at]), n.shift + d)


def _grouped_read(text: str, start: int) -> s.Aggregate | None:
    """_read of an aggregate `[[g...],b,...]` whose first item is a flat group (no
    bracket nor string inside): the group read every time, the items after it once per
    distinct text and moved to where they stand, as `grouped_value` does for numbers. A
    robtarget whose position holds arithmetic (`[[x0+nStep*2,y0,z0],[1,0,0,0],...]`)
    shares its orientation, confdata and axes with its neighbours. None for any other
    text (then read in full)."""
    cut = text.find("]")
    if (cut < 0 or not text.startswith(",", cut + 1) or "[" in text[2:cut]
            or '"' in text[:cut] or len(text) - cut > READ_KEPT_CHARS
            or fast_expressions.NUMERIC_AGGREGATE_MATCH(text) is not None):
        return None  # (an aggregate of numbers is the grammar's NUMERIC_AGGREGATE)
    rest = text[cut + 1:]
    items = _AGGREGATE_RESTS.get(rest)
    try:
        first = _read_by_shape(text[1:cut + 1], start + 1)
        if items is None:  # read after a stand-in first item (a name), at offset 0
            items = read_expression("[x" + rest, 0, condition=True)
            if type(items) is not s.Aggregate:
                return None
            _AGGREGATE_RESTS.keep(rest, items)
    except NotRead:
        return None  # read in full (which decides)
    shift = start + cut + 1 - 2
    return s.Aggregate(start, start + len(text),
                       [first, *[_moved(item, shift) for item in items.items[1:]]])


# The aggregates read above without fast_expressions: those of the patterns' loose forms.
_PLAIN_AGGREGATE = re.compile(f"{_LOOSE_AGGREGATE}|{_DEEP_AGGREGATE}|{_DEEPER_AGGREGATE}")
# A row of a four-level aggregate (a three-level one).
_DEEP_ROW = re.compile(_DEEP_AGGREGATE)
# An index of an array element, or a dimension: a number or a name.
_INDEX_ITEM = re.compile(rf"[A-Za-z0-9_.+\-{LATIN1_LETTERS}]+")


def _index_node(text: str, start: int) -> s.Index:
    """The Index node of checked array element text `name{i, ...}` at `start`."""
    open_at = text.index("{")
    name = text[:open_at].rstrip(_WS_CHARS)
    base = s.NameRef(start, start + len(name), sys.intern(name))
    inner = text[open_at + 1:-1]
    # `path{12}`, `grid{12,3}`: decimals, read as _value_node reads them
    if inner.replace(",", "").isdigit() and inner.isascii():
        numbers = []
        at = start + open_at + 1
        for digits in inner.split(","):
            if not digits:
                break  # `{1,,2}`: read in full (which decides)
            numbers.append(s.Number(at, at + len(digits), float(digits), digits))
            at += len(digits) + 1
        else:
            return s.Index(start, start + len(text), base, numbers)
    indices = [_value_node(m.group(), start + m.start())
               for m in _INDEX_ITEM.finditer(text, open_at + 1)]
    return s.Index(start, start + len(text), base, indices)


_DEEP_ITEM = re.compile(r"\[[^\[\]]*(?:\[[^\[\]]*\][^\[\]]*)*\]")


def _deep_aggregate(text: str, start: int, rests: Memo) -> s.Aggregate:
    """The Aggregate node of a checked three-level aggregate at `start` (an array of
    robtargets): the grammar reads each item as a NUMERIC_AGGREGATE."""
    items: list[s.Expr] = []
    for m in _DEEP_ITEM.finditer(text, 1):
        at = start + m.start()
        items.append(s.NumericAggregate(at, start + m.end(),
                                        shared_aggregate_value(m.group(), rests)))
    return s.Aggregate(start, start + len(text), items)


def _moved(node: Any, shift: int) -> Any:
    """A copy of an expression or argument node with its offsets moved by `shift`."""
    mover = _MOVERS.get(type(node))
    if mover is None:  # a node the fast path does not make: copied field by field
        return dataclasses.replace(node, start=node.start + shift, end=node.end + shift)
    return mover(node, shift)


def _moved_or_none(node: Any, shift: int) -> Any:
    return None if node is None else _moved(node, shift)


# How each node type is copied (by its exact type: a dictionary look-up, where a chain of
# isinstance tests cost more than the copy of a leaf; a shared tail's operands and a
# repeated expression's nodes are copied for every use).
_MOVERS: dict[type, Callable[[Any, int], Any]] = {
    s.NameRef: lambda n, d: s.NameRef(n.start + d, n.end + d, n.name),
    s.Number: lambda n, d: s.Number(n.start + d, n.end + d, n.value, n.text),
    s.String: lambda n, d: s.String(n.start + d, n.end + d, n.value),
    s.Bool: lambda n, d: s.Bool(n.start + d, n.end + d, n.value),
    s.NumericAggregate: lambda n, d: s.NumericAggregate(n.start + d, n.end + d, n.value),
    s.Binary: lambda n, d: s.Binary(n.start + d, n.end + d, n.op, _moved(n.left, d),
                                    _moved(n.right, d)),
    s.Unary: lambda n, d: s.Unary(n.start + d, n.end + d, n.op, _moved(n.operand, d)),
    s.Paren: lambda n, d: s.Paren(n.start + d, n.end + d, _moved(n.inner, d)),
    s.Component: lambda n, d: s.Component(n.start + d, n.end + d, _moved(n.base, d),
                                          n.name),
    s.Index: lambda n, d: s.Index(n.start + d, n.end + d, _moved(n.base, d),
                                  [_moved(index, d) for index in n.indices]),
    s.Aggregate: lambda n, d: s.Aggregate(n.start + d, n.end + d,
                                          [_moved(item, d) for item in n.items]),
    s.Call: lambda n, d: s.Call(n.start + d, n.end + d, n.name,
                                [_moved(a, d) for a in n.args]),
    s.LazyFunctionCall: lambda n, d: s.LazyFunctionCall(
        n.start + d, n.end + d, n.name, _moved_or_none(n.head, d), n.tail, n.shift + d),
    s.Argument: lambda n, d: s.Argument(n.start + d, n.end + d, n.kind, n.name,
                                        _moved_or_none(n.value, d)),
}


def _nested(start: int, end: int, template: s.Expr) -> s.Expr:
    """A nested node (negation, call) of a tail, moved to stand at `start`."""
    return _moved(template, start - template.start)


#: the keywords a statement of a run of calls may start with (split_calls): an IF block's
#: or a compact IF's, an IF block's end, GOTO
BLOCK_WORDS = frozenset({"IF", "ENDIF", "GOTO"})

# A call's name and its first argument when that is a value after whitespace (a
# value may follow the name without any: `WaitTime.5;`, and is then left to the tail).
_CALL_HEAD = LazyPattern(rf"{GAP}({NAME})(?:{WS}+({VALUE_TEXT}))?")
# The rest of a checked statement, up to its ';' (strings may hold one).
_STATEMENT_END = re.compile(rf'(?:[^;"]+|{STRING})*;')
# Distinct argument tails kept (a CAM program has a few dozen).
TAIL_LIMIT = 4096

# One argument of a tail, offsets relative to the tail: (kind, start, end,
# optional name, value node type or None, value start, value end, what the node
# holds besides its span, the value's node as read at some other place or None).
_TailArgument = tuple[str, int, int, "str | None", Any, int, int, tuple, Any]


def _value_entry(text: str, start: int) -> tuple[Any, int, int, tuple, s.Expr]:
    """(node type, start, end, other fields, the node as read at offset 0) of the node
    _value_node makes. Each text is read once: tails that differ (`v100\\V:=120`,
    `v100\\V:=135`) share their pieces."""
    known = _ENTRIES.get(text)
    if known is None:
        node = _value_node(text, 0)
        known = (*_node_entry(node, 0), node)
        _ENTRIES.keep(text, known)
    kind, _, length, fields, node = known
    return kind, start, start + length, fields, node


def _node_entry(node: s.Expr, start: int) -> tuple[Any, int, int, tuple]:
    """(node type, start, end, other fields) of a value node, standing at `start`."""
    end = start + node.end - node.start
    if isinstance(node, s.Number):
        return s.Number, start, end, (node.value, node.text)
    if isinstance(node, s.NumericAggregate):
        return s.NumericAggregate, start, end, (node.value,)
    if isinstance(node, s.NameRef):
        return s.NameRef, start, end, (node.name,)
    if isinstance(node, s.String):
        return s.String, start, end, (node.value,)
    return _nested, start, end, (node,)


def _tail(text: str, pieces: LazyPattern) -> tuple[_TailArgument, ...]:
    """The arguments in checked call text that follows a call's name or first argument,
    split by `pieces` (CALL_PIECE, or _INNER_PIECE inside a function call)."""
    entries: list[_TailArgument] = []
    for piece in pieces.finditer(text):
        slash, option, option_value, value, semi = piece.groups()
        if value is not None:
            node, at, end, fields, read = _value_entry(value, piece.start(4))
            entries.append(("required", at, end, None, node, at, end, fields, read))
        elif slash is not None:
            if option_value is None:
                entry: tuple = (None, 0, 0, (), None)
            else:
                entry = _value_entry(option_value, piece.start(3))
            entries.append(("optional", piece.start(1), piece.end(), sys.intern(option), *entry))
        elif semi is not None:
            break
    return tuple(entries)


class CallTail:
    """The arguments after a call's name or first argument, read once per distinct
    text and made into nodes for every call that ends with that text
    (rapidfix.rapid.syntax.LazyCall, LazyFunctionCall)."""

    __slots__ = ("entries",)

    def __init__(self, text: str | None, pieces: LazyPattern = CALL_PIECE) -> None:
        self.entries = () if text is None else _tail(text, pieces)

    def after_first(self) -> CallTail | None:
        """The tail of the arguments after this tail's first, when that is a required
        value (None otherwise): what CallTail reads from the text after it."""
        entries = self.entries
        if not entries or entries[0][0] != "required":
            return None
        cut = entries[0][2]
        rest = CallTail(None)
        rest.entries = tuple(
            (kind, start - cut, end - cut, option, node, value_start - cut, value_end - cut,
             fields, read)
            for kind, start, end, option, node, value_start, value_end, fields, read
            in entries[1:])
        return rest

    def with_first(self, node: s.Expr, cut: int) -> CallTail:
        """This tail after a required value `node` (its text `cut` characters long after
        the start of the new tail, the separator included): what CallTail reads from
        the text of both."""
        start = cut - (node.end - node.start)
        kind, at, end, fields = _node_entry(node, start)
        both = CallTail(None)
        both.entries = (("required", at, end, None, kind, at, end, fields, node), *(
            (kind, start + cut, end + cut, option, read_node, value_start + cut,
             value_end + cut, fields, read)
            for kind, start, end, option, read_node, value_start, value_end, fields, read
            in self.entries))
        return both

    def arguments(self, shift: int) -> list[s.Argument]:
        """The Argument nodes of the tail standing at offset `shift`. Where a value ends
        (and, a required one, starts) with its argument, both nodes hold one int object:
        a call's offsets are most of the ints of a large program's model."""
        argument = s.Argument
        made: list[s.Argument] = []
        append = made.append
        for kind, start, end, option, node, value_start, value_end, fields, _ in self.entries:
            at, to = shift + start, shift + end
            append(argument(at, to, kind, option, None if node is None else node(
                at if value_start == start else shift + value_start,
                to if value_end == end else shift + value_end, *fields)))
        return made

    def reshaped(self, text: str, other: str) -> CallTail | None:
        """The tail of `other`, a text of the same shape as this tail's `text` (the same
        but for digits, none after a radix prefix nor in a string): the same splits,
        each value whose text differs read again as `_tail` reads it; None where an
        option's name holds a digit (then `other` is read in full)."""
        entries = []
        for entry in self.entries:
            start, end, option, value_start, value_end = (
                entry[1], entry[2], entry[3], entry[5], entry[6])
            if option is not None and not option.isalpha():
                return None
            if (value_end > value_start
                    and text[value_start:value_end] != other[value_start:value_end]):
                read = _value_entry(other[value_start:value_end], value_start)
                entry = ((entry[0], *read[1:3], None, *read) if option is None
                         else (entry[0], start, end, option, *read))
            entries.append(entry)
        tail = CallTail(None)
        tail.entries = tuple(entries)
        return tail

    def values(self) -> list[tuple[str, str | None, s.Expr | None]]:
        """(kind, option name or None, the value's node or None) of each argument, the
        nodes as they were read at some other place: what a reader of values needs (a
        value does not depend on where its node stands), without making the nodes."""
        return [(entry[0], entry[3], entry[8]) for entry in self.entries]


# Distinct call tails kept across tokens and files (a CAM program has a few dozen),
# of procedure calls and of function calls, and the expressions read by _read.
_TAILS: Memo = Memo(TAIL_LIMIT)
_INNER_TAILS: Memo = Memo(TAIL_LIMIT)
# The shape of a function call's tail (its digits made 1s) -> (a text of that shape, its
# CallTail): see _inner_tail.
_TAIL_SHAPES: Memo = Memo(TAIL_LIMIT)
_READ: Memo = Memo(TAIL_LIMIT)
# The shape of an expression text (its digits made 1s) -> its nodes and where the text
# stood (see _read_by_shape), or None for a shape whose nodes are read in full.
_SHAPES: Memo = Memo(TAIL_LIMIT)
# The shape of a function call's text -> its node and where it stood (see _call_node), or
# None for a shape read in full; the same for the rows of tables (see _rows_read).
_CALL_SHAPES: Memo = Memo(TAIL_LIMIT)
_ROW_SHAPES: Memo = Memo(TAIL_LIMIT)
# The optional arguments before a call's first required one (see split_calls), by text
# and by shape.
_LEADS: Memo = Memo(TAIL_LIMIT)
_LEAD_SHAPES: Memo = Memo(TAIL_LIMIT)
# The argument values of tails, read once per distinct text (see _value_entry).
_ENTRIES: Memo = Memo(4 * TAIL_LIMIT)
# What follows an aggregate's first group -> the aggregate read with a stand-in first
# item (see _grouped_read).
_AGGREGATE_RESTS: Memo = Memo(TAIL_LIMIT)


def split_calls(text: str, base: int) -> list[s.Statement]:
    """The ProcedureCall (and Assignment) nodes of a FAST_CALLS token starting at
    offset `base`.

    A call is its name, its leading arguments and a tail of further arguments. In
    a CAM program the first argument (the target) changes from line to line but
    the tail (speed, zone, tool, work object) recurs, so each distinct tail is
    read once (CallTail), and each call is a LazyCall that makes the tail's nodes,
    shifted to where it stands, only when they are asked for. When the text after
    the first argument is new but the text after the second is known (MoveC's two
    targets, or any call whose second argument varies too), the call's tail is
    taken after its second argument. Names are interned. An IF block of calls (the
    lexer has checked that it holds calls only and ends with its ENDIF, all on one line)
    becomes the If node the grammar builds, its condition read as `_head_parts` reads a
    FAST_IF head.
    """
    calls: list[s.Statement] = []
    blocks: list[tuple[list[s.Statement], int, s.Expr]] = []  # the IF blocks open
    tails = _TAILS
    argument, lazy_call, intern = s.Argument, s.LazyCall, sys.intern
    head, find, piece_at = _CALL_HEAD.compiled.match, text.index, CALL_PIECE.compiled.match
    quote, statement_end = text.find, _STATEMENT_END.match
    pos, size = 0, len(text)
    compact = None  # a compact IF whose statement comes next: (calls, start, condition)
    while pos < size:
        if compact is not None and calls:
            calls, compact = _compact_if(compact, calls[0]), None
        m = head(text, pos)
        name = m.group(1)
        if len(name) in (2, 4, 5) and name[0] in "IiEeGg":  # (no call has a keyword's name)
            word = name.upper()  # one of BLOCK_WORDS, or a call's name
            if word == "GOTO":
                pos = find(";", m.end(1)) + 1
                calls.append(s.Goto(base + m.start(1), base + pos, m.group(2)))
                continue
            if word == "IF":
                block = _head_splitters()["if"].match(text, m.start(1))
                if block is None:  # no THEN: a compact IF, its statement next
                    block = _compact_head().match(text, m.start(1))
                    compact = (calls, base + m.start(1), _condition(block, base))
                    calls, pos = [], block.end()
                    continue
                blocks.append((calls, base + m.start(1), _condition(block, base)))
                calls, pos = [], block.end()
                continue
            if word == "ENDIF":
                outer, start, condition = blocks.pop()
                outer.append(s.If(start, base + m.end(1), [(condition, calls)], None))
                calls, pos = outer, m.end(1)
                continue
        first = m.group(2)
        tail_at = m.end()
        pos = find(";", tail_at) + 1
        if quote('"', tail_at, pos) >= 0:  # a string may hold ';'
            pos = statement_end(text, tail_at).end()
        tail_text = text[tail_at:pos]
        if first is None or first[0] in ":.{":  # an assignment, or a call without one
            name_end = m.end(1)
            assign = text.find(":=", name_end, pos)
            if assign >= 0 and text[name_end:assign].lstrip(_WS_CHARS)[:1] in ("", ".", "{"):
                calls.append(_assignment(text, base, m.start(1), assign, pos))
                continue
        tail = tails.get(tail_text)
        if type(tail) is tuple:
            tail = _made_tail(tails, tail_text, tail)
        lead = head_arg = second_arg = None
        if first is None and tail is None:  # optional arguments first (`MoveJ \Conc, p1`)?
            piece = piece_at(text, tail_at)
            while piece.group(1) is not None:
                piece = piece_at(text, piece.end())
            first = piece.group(4)
            if first is not None and piece.start(4) > tail_at:
                # the switches before the first required value are a lead read once,
                # the value is the call's own, and the rest a tail as after any head
                lead = _lead(text[tail_at:piece.start(4)])
                at = base + piece.start(4)
                node = _head_node(first, at)
                head_arg = argument(at, node.end, "required", None, node)
                tail_at = piece.end()
                tail_text = text[tail_at:pos]
                tail = tails.get(tail_text)
                if type(tail) is tuple:
                    tail = _made_tail(tails, tail_text, tail)
        elif first is not None:
            at = base + m.start(2)
            node = _head_node(first, at)
            head_arg = argument(at, node.end, "required", None, node)
            if tail is None:
                piece = piece_at(text, tail_at)
                second = piece.group(4)
                if second is not None:
                    rest_at = piece.end()
                    rest_text = text[rest_at:pos]
                    rest = tails.get(rest_text)
                    if type(rest) is tuple:
                        rest = _made_tail(tails, rest_text, rest)
                    if rest is not None:  # the rest is known: two leading arguments
                        at = base + piece.start(4)
                        node = _value_node(second, at)
                        second_arg = argument(at, node.end, "required", None, node)
                        # and the tail after the first, for calls that repeat all of it:
                        # made when one does (an arc's tail names its end point, which
                        # hardly recurs)
                        tails.keep(tail_text, (rest, node, rest_at - tail_at))
                        tail, tail_at = rest, rest_at
                    else:
                        tail = CallTail(tail_text)
                        tails.keep(tail_text, tail)
                        rest = tail.after_first()
                        if rest is not None:
                            tails.keep(rest_text, rest)
        if tail is None:
            tail = CallTail(tail_text)
            tails.keep(tail_text, tail)
        shift = base + tail_at
        last = head_arg if second_arg is None else second_arg
        if last is not None and last.end == shift:  # one int object, not two equal ones
            shift = last.end
        calls.append(lazy_call(base + m.start(1), base + pos, intern(name), head_arg,
                               tail, shift, second_arg, lead))
    if compact is not None:
        calls = _compact_if(compact, calls[0])
    if blocks:  # pragma: no cover - the lexer takes an IF block with its ENDIF only
        raise NotFast(text[:40])
    return calls


def _compact_if(pending: tuple[list[s.Statement], int, s.Expr],
                statement: s.Statement) -> list[s.Statement]:
    """The statements before a compact IF (`pending`: them, the IF's start and its
    condition), with the IF of `statement` after them."""
    outer, start, condition = pending
    outer.append(s.CompactIf(start, statement.end, condition, statement))
    return outer


@functools.lru_cache(maxsize=1)
def _compact_head() -> re.Pattern[str]:
    """A compact IF's head as the lexer took it, up to its statement, the condition in
    group 1 (the lexer's own pattern: the condition ends where it found it to). Read
    from the cached grammar extension: working out the patterns again costs 30 ms."""
    extension = cached_extension(grammar_text())
    at = extension.rindex(_COMPACT_HEAD_COMMENT) + len(_COMPACT_HEAD_COMMENT)
    return re.compile(extension[at:extension.index("\n", at)])


def _made_tail(tails: Memo, text: str, pending: tuple[CallTail, s.Expr, int]) -> CallTail:
    """The CallTail split_calls kept for `text` as (the tail after its first argument,
    that argument's node, where the rest starts): made now, and kept in its place."""
    rest, node, cut = pending
    tail = tails[text] = rest.with_first(node, cut)
    return tail


def _condition(head: re.Match[str], base: int) -> s.Expr:
    """The condition of an IF head matched by the "if" head splitter in a token at
    `base`, read as `_head_parts` reads that of a FAST_IF token."""
    return _read(*_stripped_group(head, 1, base))


def _stripped_group(m: re.Match[str], index: int, base: int) -> tuple[str, int]:
    """Group `index` of a head splitter's match in a token at `base`, without the
    whitespace around it, and the offset where it then starts."""
    text = m.group(index)
    return (text.strip(_WS_CHARS),
            base + m.start(index) + len(text) - len(text.lstrip(_WS_CHARS)))


def _head_node(text: str, at: int) -> s.Expr:
    """The node of a call's first required value `text` at `at`: a name (not `a.b`,
    `a+1`, `f(x)`, `a{i}`, TRUE or FALSE) made at once, a function call of a name and
    numbers by `_named_call`, any other by _value_node."""
    if text.isidentifier() and (len(text) > 5 or text.upper() not in _BOOLS):
        return s.NameRef(at, at + len(text), sys.intern(text))
    if text[-1] == ")":
        call = _named_call(text, at)
        if call is not None:
            return call
    return _value_node(text, at)


# A function call of a data name and decimal numbers or names (or arithmetic of them),
# with optional arguments of those (`Offs(p7,0,0,-10)`, `Offs(p7, 0, 0, -nLift)`,
# `Offs(p7,0,0,nLift+5)`, `RelTool(p3,0,0,5\Rz:=90)`),
# or of such a call and those (`RelTool(Offs(p7,0,0,10),0,0,0\Rz:=90)`): a move's target
# as most programs write it. (The tail after the first argument is read as `_call_node`
# reads it: whatever stands there, this only says that the call is of that form.)
_TERM = rf"(?:-{WS}*)?(?:\d+(?:\.\d*)?(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?|{NAME})"
_OFFSET = rf"{_TERM}(?:{WS}*[-+*/]{WS}*{_TERM})*"
_AFTER_FIRST = (rf"(?:{WS}*,{WS}*{_OFFSET})+"
                rf"(?:{WS}*\\{WS}*{NAME}{WS}*:={WS}*{_OFFSET})*{WS}*\)")
_NAMED_CALL = re.compile(
    rf"({NAME})\({WS}*({NAME}(\({WS}*({NAME})({_AFTER_FIRST}))?)({_AFTER_FIRST})")


def _named_call(text: str, start: int) -> s.LazyFunctionCall | None:
    """What _value_node makes of `text` (through _call_node) when it is a call of a name
    (or of such a call) and numbers (`_NAMED_CALL`), read by one pattern; None for any
    other text."""
    m = _NAMED_CALL.fullmatch(text)
    if m is None:
        return None
    name_at, name_end = m.span(4)
    if name_at < 0:  # `Offs(p7,...)`
        name_at, name_end = m.span(2)
    name = text[name_at:name_end]
    if len(name) <= 5 and name.upper() in _BOOLS:  # TRUE, FALSE: not names
        return None
    node: s.Expr = s.NameRef(start + name_at, start + name_end, sys.intern(name))
    if name_end != m.end(2):  # `RelTool(Offs(p7,...),...)`: the inner call around it
        inner_at = m.start(2)
        node = _lazy_call(text[inner_at:m.start(3)], node, m.group(5), start + inner_at,
                          start + name_end, start + m.end(2))
    return _lazy_call(m.group(1), node, m.group(6), start, start + m.start(6),
                      start + len(text))


def _lazy_call(name: str, first: s.Expr, tail_text: str, start: int, tail_at: int,
               end: int) -> s.LazyFunctionCall:
    """The LazyFunctionCall `name(first<tail_text>` from `start` to `end`, its tail at
    `tail_at`."""
    return s.LazyFunctionCall(start, end, sys.intern(name),
                              s.Argument(first.start, first.end, "required", None, first),
                              _inner_tail(tail_text), tail_at)


def _assignment(text: str, base: int, start: int, assign: int, end: int) -> s.Assignment:
    """The Assignment node of `target := value;` in a run (text[start:end]), `assign` the
    offset of its `:=`. The run's pattern takes arguments after the `:=`: more than one
    value there is not RAPID, and NotFast lets the plain grammar say so."""
    target_text = text[start:assign].rstrip(_WS_CHARS)
    target = _value_node(target_text, base + start)
    raw = text[assign + 2:end - 1]
    value_text = raw.strip(_WS_CHARS)
    if not value_text or value_text[0] == "\\":
        raise NotFast(value_text)
    value = _value_node(value_text, base + assign + 2 + len(raw) - len(raw.lstrip(_WS_CHARS)))
    return s.Assignment(target.start, base + end, target, value)


# What the grammar's `target` builds (an assignment's left side).
_TARGETS = (s.NameRef, s.Index, s.Component)


def read_assignment(text: str, start: int, assign: int, end: int) -> s.Assignment | None:
    """The Assignment node of text[start:end] (a target, `:=` at `assign`, a value up to
    the `;` before `end`) that no fast terminal took, its pieces read by the expression
    reader (exact: the lexer has checked nothing here), or None where they do not read
    (fast_blocks then leaves the statement to the parser)."""
    raw = text[assign + 2:end - 1]
    value_text = raw.strip(_WS_CHARS)
    if not value_text:
        return None
    target = read_value(text[start:assign].rstrip(_WS_CHARS), start)
    if type(target) not in _TARGETS:
        return None
    value = read_value(value_text, assign + 2 + len(raw) - len(raw.lstrip(_WS_CHARS)))
    return None if value is None else s.Assignment(target.start, end, target, value)


def read_value(text: str, start: int) -> s.Expr | None:
    """The node of an expression `text` at `start` that no fast terminal took, read by
    the expression reader (exact), or None where it does not read."""
    try:
        return _read(text, start)
    except NotFast:
        return None


# The end of an aggregate's first group and the start of the next, with whitespace
# (`[[x, y, z], [q1, ...], ...]`, as many programs are written by hand)
_NEXT_GROUP = re.compile(rf"\]{_AGGREGATE_WS}*,{_AGGREGATE_WS}*\[")
_FIRST_GROUP = re.compile(rf"\[{_AGGREGATE_WS}*\[")


def _group_start(text: str) -> int:
    """Where the numbers of an aggregate's first group start (`[[1,2,3],...]`, or spaced
    as people write it, `[ [1, 2, 3], ...]`), or 0 when it does not open with a group."""
    if text.startswith("[["):
        return 2
    m = _FIRST_GROUP.match(text)
    return 0 if m is None else m.end()


def grouped_value(value: str, rests: Memo) -> tuple | None:
    """The value of a plain aggregate `[[x,y,z],[...],...]` whose first item is a group
    of numbers: that group read every time (a position seldom recurs, so it is not
    kept), what follows it once per distinct text (`rests`). None for any other shape;
    NotFast where the loose pattern let arithmetic by (`[[1-1,2],[3]]`)."""
    start = _group_start(value)
    if not start:
        return None
    cut = value.find("]")
    group = value[start:cut]
    if "[" in group or not (value.startswith("],[", cut) or _NEXT_GROUP.match(value, cut)):
        return None
    rest = value[cut + 1:]
    items = rests.get(rest)
    if items is None:  # the same after any group
        items = aggregate_value("[[0]" + rest)[1:]
        rests.keep(rest, items)
    try:
        return (tuple(map(float, group.split(","))), *items)
    except ValueError:
        raise NotFast(value) from None


def shared_aggregate_value(text: str, rests: Memo) -> tuple:
    """aggregate_value(text), reading what follows a leading group once per distinct text.

    A CAM program's robtargets differ in their first group (the position) and
    mostly share the rest (orientation, confdata, external axes).
    """
    if text[1] == "[":
        cut = text.find("]")
        if text.startswith("],[", cut) or _NEXT_GROUP.match(text, cut):
            rest = text[cut + 1:]
            items = rests.get(rest)
            if items is None:
                items = aggregate_value("[[0]" + rest)[1:]  # the same items after any group
                rests.keep(rest, items)
            # a CAM program's positions rarely recur: not worth keeping
            return (_number_group(text[2:cut], keep=False), *items)
    return aggregate_value(text)


# What follows the leading group of an aggregate, read once (see shared_aggregate_value);
# kept across tokens and files like the call tails.
_RESTS: Memo = Memo(TAIL_LIMIT)
# What follows the first group of inline targets `_value_node` has read as plain two-level
# aggregates (`],[q1,q2,q3,q4],[cf1,...],[e1,...]]`) -> its items: the same text after a
# group of numbers is then such an aggregate again, without matching it whole.
_PLAIN_RESTS: Memo = Memo(TAIL_LIMIT)


# A storage keyword as written -> as the grammar gives it ('const' -> 'CONST'): one string
# object shared by every declaration, not one made per declaration.
_STORAGES: dict[str, str] = {}


def split_decls(text: str, base: int) -> list[s.DataDecl]:
    """The DataDecl nodes of a FAST_DECLS token starting at offset `base`.

    The common value, an aggregate of groups `[[x,y,z],[...],...]`, is read here (as
    shared_aggregate_value reads it: the first group every time, the rest once per
    distinct text), without a call per declaration."""
    decls: list[s.DataDecl] = []
    append = decls.append
    rests, storages = _RESTS, _STORAGES
    data_decl, numeric_aggregate, intern = s.DataDecl, s.NumericAggregate, sys.intern
    plain, spaced = _PLAIN_DECL.compiled.match, _SPACED_DECL.compiled.match
    general = _DECL.compiled.search
    pos, size = 0, len(text)
    while pos < size:
        m = plain(text, pos)
        if m is None:
            m = spaced(text, pos)
        if m is not None:  # the common form: its value read here
            local, task, storage, type_name, name, value, group, rest = m.groups()
            items = rests.get(rest)
            try:
                if items is None:  # the same after any group (as grouped_value reads it)
                    items = aggregate_value("[[0]" + rest)[1:]
                    rests.keep(rest, items)
                position = tuple(map(float, group.split(",")))
            except (NotFast, ValueError):  # arithmetic the loose pattern let by
                m = None
            else:
                at = base + m.start(6)
                init: Any = numeric_aggregate(at, at + len(value), (position, *items))
                sizes: Any = ()
        if m is None:
            m = general(text, pos)
            if m is None or m.start() != pos:  # pragma: no cover - the lexer took it
                raise NotFast(text[pos:pos + 40])
            local, task, storage, type_name, name, dims, value = m.groups()
            init = None
            if value is not None:
                at = base + m.start(7)
                # two levels, or three or four (an array's items), of numbers only (an
                # aggregate of sums, `[[x+1,...],...]`, is fast_expressions' to read)
                if _group_start(value) and _PLAIN_AGGREGATE.fullmatch(value):
                    try:
                        grouped = grouped_value(value, rests)
                    except NotFast:  # arithmetic the loose pattern let by
                        grouped = None
                    if grouped is not None:
                        init = numeric_aggregate(at, at + len(value), grouped)
                if init is None:
                    init = _value_node(value, at)
            if dims is None:
                sizes = ()
            else:
                at = base + m.start(6)
                sizes = [_value_node(d.group(), at + d.start())
                         for d in _INDEX_ITEM.finditer(dims)]
        pos = m.end()
        spans = m.regs  # (both patterns number LOCAL, TASK, storage, type and name alike)
        first = 1 if local is not None else 2 if task is not None else 3
        upper = storages.get(storage)
        if upper is None:
            upper = storages[storage] = storage.upper()
        append(data_decl(
            base + spans[first][0], base + spans[0][1], upper, intern(type_name),
            # interned: the moves that name it then hold the same string
            intern(name), base + spans[5][0], sizes, init, local is not None, task is not None,
        ))
    return decls


def forget_texts() -> None:
    """Empty the texts the fast path keeps across files (call tails and their values,
    aggregate rests and number groups): their memory back, and the next file read from a
    known start."""
    for memo in (_TAILS, _INNER_TAILS, _TAIL_SHAPES, _READ, _SHAPES, _CALL_SHAPES,
                 _ROW_SHAPES, _LEADS, _LEAD_SHAPES, _ENTRIES, _AGGREGATE_RESTS, _RESTS,
                 _PLAIN_RESTS, _GROUP_CACHE):
        memo.clear()


@v_args(inline=True)
class FastSyntaxBuilder(SyntaxBuilder):
    """SyntaxBuilder plus the callbacks of the fast terminals."""

    # Rules named with '_' are inlined: Lark splices the children of the Tree
    # they return into the enclosing statement or module item list.
    def _fast_calls(self, children: list[Any]) -> Tree:
        tok = children[0]
        return Tree("_fast_calls", split_calls(str(tok), tok.start_pos))

    def _fast_decls(self, children: list[Any]) -> Tree:
        tok = children[0]
        return Tree("_fast_decls", split_decls(str(tok), tok.start_pos))

    # the nodes fast_blocks' reader made for its token
    def _fast_block(self, children: list[Any]) -> Tree:
        return Tree("_fast_block", children[0].nodes)

    def _fast_routines(self, children: list[Any]) -> Tree:
        return Tree("_fast_routines", children[0].nodes)

    # The heads: the plain rules' nodes, their conditions read from the token's text.
    def fast_if_stmt(self, head: Token, *rest: Any) -> s.If:
        (cond,) = _head_parts(head, "if")
        return self.if_branches(head.start_pos, cond, rest)

    def fast_elseif_clause(self, head: Token, *body: Any) -> tuple:
        (cond,) = _head_parts(head, "elseif")
        return ("elseif", cond, statements_in(body))

    def fast_while_stmt(self, head: Token, *rest: Any) -> s.While:
        (cond,) = _head_parts(head, "while")
        return s.While(head.start_pos, rest[-1].end_pos, cond, statements_in(rest))

    def fast_for_stmt(self, head: Token, *rest: Any) -> s.For:
        var, first, last, step = _head_parts(head, "for")
        return s.For(head.start_pos, rest[-1].end_pos, var, first, last, step,
                     statements_in(rest))

    def fast_test_stmt(self, head: Token, *rest: Any) -> s.Test:
        (subject,) = _head_parts(head, "test")
        return self.test_clauses(head.start_pos, subject, rest)

    def fast_case_clause(self, head: Token, *body: Any) -> tuple:
        (values,) = _head_parts(head, "case")
        return ("case", values, statements_in(body))

    def fast_return_stmt(self, head: Token) -> s.Return:
        (value,) = _head_parts(head, "return")
        return s.Return(head.start_pos, head.end_pos, value)

    def fast_proc(self, head: Token, *rest: Any) -> s.Routine:
        return self._fast_routine("PROC", head, rest)

    def fast_func(self, head: Token, *rest: Any) -> s.Routine:
        return self._fast_routine("FUNC", head, rest)

    def _fast_routine(self, kind: str, head: Token, rest: tuple) -> s.Routine:
        """The routine of a head token of `kind`: the plain rule's tokens at the head's
        start (LOCAL? PROC|FUNC, a function's type, the name), then its parameters."""
        m = _head_splitters()[kind.lower()].fullmatch(str(head))
        local, *names, params = m.groups()
        start = head.start_pos
        words = [Token("LOCAL", local, start_pos=start)] if local else []
        words += [Token(kind, kind, start_pos=start), *(Token("NAME", n) for n in names)]
        at = start + m.start(len(names) + 2)
        return self._routine(kind, (*words, _parameters(params, at), *rest))


# One parameter of a checked head's list: the backslash of an optional one, the access
# keyword, type, name and the stars of its dimensions.
_PARAMETER_PARTS = re.compile(
    rf"(?:{WS}*,)?{WS}*(\\{WS}*)?(?:({_ACCESS}){WS}*(?={NAME}))?({NAME}){WS}*({NAME})"
    rf"(?:{WS}*\{{([^}}]*)\}})?")


def _parameters(text: str | None, start: int) -> list[s.Parameter]:
    """The Parameter nodes of a routine head's parameter list `text` at `start`, as
    rapid.lark's `parameters` builds them."""
    params: list[s.Parameter] = []
    if text is None:
        return params
    for m in _PARAMETER_PARTS.finditer(text):
        slash, access, type_name, name, stars = m.groups()
        first = m.start(1) if slash is not None else m.start(2) if access else m.start(3)
        end = m.end() if stars is not None else m.end(4)
        params.append(s.Parameter(
            start + first, start + end, None if access is None else access.upper(), type_name,
            name, 0 if stars is None else stars.count("*"), slash is not None))
    return params


@functools.lru_cache(maxsize=1)
def _head_splitters() -> dict[str, re.Pattern[str]]:
    """head_patterns with groups, compiled (the lexer has checked the tokens they split,
    so a name needs no keyword refused)."""
    condition = condition_pattern(NAME)
    return {kind: re.compile(pattern)
            for kind, pattern in head_patterns(condition, True).items()}


def _head_parts(head: Token, kind: str) -> list[Any]:
    """What the groups of a head token of `kind` hold, read: a condition (None where an
    optional one is absent), a CASE's list of them, a FOR's variable name."""
    m = _head_splitters()[kind].fullmatch(str(head))
    parts: list[Any] = []
    for index, text in enumerate(m.groups(), 1):
        if text is None or (kind == "return" and not text.strip(_WS_CHARS)):  # `RETURN ;`
            parts.append(None)
        elif kind == "for" and index == 1:
            parts.append(text)
        else:
            value, start = _stripped_group(m, index, head.start_pos)
            if kind != "case":
                parts.append(_read(value, start))
                continue
            try:
                parts.append(read_list(value, start))
            except NotRead:
                raise NotFast(value) from None
    return parts


def cached_extension(grammar: str) -> str:
    """grammar_extension(grammar), kept in the temporary folder beside Lark's own cache.

    Working it out needs the plain parser's tables and an interactive parse (about
    0.06 s); a command that checks one small file would spend a fifth of its time on
    it. The key covers the grammar, this module's, fast_expressions' and fast_blocks'
    sources and Lark's version.
    """
    import os
    import tempfile
    from pathlib import Path

    import lark

    from rapidfix.digest import sha256_bytes

    source = b"".join(Path(module.__file__).read_bytes()
                      for module in (sys.modules[__name__], fast_expressions, fast_blocks))
    key = sha256_bytes(grammar.encode() + source + lark.__version__.encode())
    user = getattr(os, "getuid", lambda: "user")()
    path = Path(tempfile.gettempdir()) / f".rapidfix_fastpath_{user}_{key[:40]}.lark"
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        pass
    extension = grammar_extension(grammar)
    try:
        scratch = path.with_name(f"{path.name}.{os.getpid()}.tmp")
        scratch.write_text(extension, encoding="utf-8")
        os.replace(scratch, path)
    except OSError:  # pragma: no cover - a read-only temporary folder: work it out each time
        pass
    return extension


@functools.lru_cache(maxsize=1)
def fast_parser() -> Lark:
    """The grammar's LALR parser with the fast terminals, building syntax nodes directly."""
    grammar = grammar_text()
    builder = FastSyntaxBuilder()
    parser = share_large_patterns(Lark(
        grammar + cached_extension(grammar),
        parser="lalr",
        lexer="contextual",
        transformer=builder,
        cache=True,
    ))
    lexer = parser.parser.lexer  # its lex, with fast_blocks' reader ahead of it
    lexer.lex = fast_blocks.BlockLexer(lexer, builder, split_calls, split_decls,
                                       read_assignment, read_value).lex
    return parser


# Whitespace and comments before a .prg's `%%%` header, and the header (rapid.lark's
# PRG_HEADER), which may hold a `!` or a `"` that is neither a comment nor a string.
_BEFORE_HEADER = re.compile(rf"(?:{WS}|![^\n]*)*")
_PRG_HEADER = re.compile(r"%%%[\s\S]*?%%%")
# A line read as the lexer reads it: strings whole, a comment's `!`, other characters.
_LINE_LEXEMES = re.compile(rf"{STRING}|(!)|[^\"!\n]+|\"")
_NOT_CR = re.compile(r"[^\r]")


def blank_comments(text: str) -> str:
    """`text` with each comment's characters (but a carriage return) made spaces: the
    same tokens at the same offsets, since the grammar ignores comments as it ignores
    whitespace (`%ignore COMMENT`).

    The fast terminals take whitespace anywhere in a statement but comments only between
    statements, so a statement with a comment inside (`MoveL p1, ! to the hole` and its
    speed on the next line) would leave the fast run for the plain grammar, some ten
    times slower; blanked, it stays in the run. A `!` starts a comment unless it stands
    in a string (strings never span lines, so only a line with a `"` before its `!` is
    read token by token) or in the `%%%` header of a .prg."""
    at = text.find("!")
    if at < 0:
        return text
    header = _PRG_HEADER.match(text, _BEFORE_HEADER.match(text).end())
    header_start, header_end = header.span() if header is not None else (0, 0)
    pieces: list[str] = []
    done = 0
    while at >= 0:
        if header_start <= at < header_end:
            at = text.find("!", header_end)
            continue
        line_start = text.rfind("\n", 0, at) + 1
        if line_start < header_end <= at:  # on the header's last line, after it
            line_start = header_end
        end = text.find("\n", at)
        end = len(text) if end < 0 else end
        if text.find('"', line_start, at) >= 0:
            at = _comment_on_line(text, line_start, end)
            if at < 0:  # every `!` of the line stands in a string
                at = text.find("!", end)
                continue
        comment = text[at:end]
        pieces += (text[done:at], " " * len(comment) if "\r" not in comment
                   else _NOT_CR.sub(" ", comment))
        done = end
        at = text.find("!", end)
    pieces.append(text[done:])
    return "".join(pieces)


def _comment_on_line(text: str, start: int, end: int) -> int:
    """Where a comment starts in text[start:end] (one line, or its part after the
    header), read as the lexer reads it, or -1 if every `!` there stands in a string."""
    for m in _LINE_LEXEMES.finditer(text, start, end):
        if m.group(1) is not None:
            return m.start()
    return -1


def parse_text(text: str) -> s.SourceFile:
    """The syntax tree of `text`, from the fast parser when it reads the file
    exactly, else from the plain one.

    The fast parser gives up on an aggregate it does not read exactly (NotFast)
    and on any syntax error: the contextual lexer may offer a fast token where
    the LALR table merged states, and the plain parser then decides. Its
    UnexpectedInput passes on for rapidfix.rapid.syntax_errors to explain. After a
    syntax error the plain grammar reads the error's window (rapid.error_window) first.
    """
    try:
        return fast_parser().parse(blank_comments(text))
    except NotFast:
        return rapid_parser().parse(text)
    except UnexpectedInput as err:
        error_at = error_offset(err, text)
        win = window(text, err)
    if win is not None:
        try:
            rapid_parser().parse(win.text)
        except UnexpectedInput as err:
            if confirms(err, win, error_at):
                err.rapidfix_window = win  # for syntax_errors.explain: read it again
                raise
    return rapid_parser().parse(text)
