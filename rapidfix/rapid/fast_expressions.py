"""Arithmetic in the fast path's values: the lexer's patterns and a reader that builds
exactly the nodes of the plain grammar.

Hand-written programs compute their offsets (`Offs(pHome,0,0,-nDepth)`,
`0-rModel.numDiameter/2`, `RelTool(p,0,0,0\\Rz:=-1*nAngle)`, `[100+nStep*2,500,5000,1000]`).
The fast terminals (`fastpath`) take such values through the patterns made here, and
`read_expression` turns a value's text into the nodes rapid.lark and
transform.SyntaxBuilder build for it: unary `+` / `-` chains, `+ - * / DIV MOD` with
the grammar's precedence (sum < term < factor < postfix) and left associativity,
parentheses, numbers, strings (`"Count: " + NumToStr(n,0)`), names, array elements
`a{i}`, record components `a.b.c`, function calls, numeric aggregates and aggregates
of expressions.

The lexer's patterns decide which statements a run takes and check their argument
lists (fastpath splits those without checking them again), but for an aggregate of sums
of names and numbers (`[[x0+nStep*2,y0,z0],...]`), which they take as runs of its
characters, as they take a condition's text. A value that is not one
fastpath reads itself (PLAIN_VALUE: a name, a (negated) number, a function call, an
array element of names and numbers) goes to the reader, which checks every token
again as Lark's contextual lexer would cut it (NUMBER and NAME taken greedily, `DIV`
/ `MOD` keywords only where an operator may stand, NUMERIC_AGGREGATE tried first at
a `[`) and raises NotRead (fastpath: NotFast, so the plain grammar reads the file)
at anything it does not build exactly. A pattern repeats no part of itself where it
can help it: each list (of arguments, of operands, of indices, of items) is written
once, with a look-ahead for what may follow its last element, which keeps the
terminals short (their compile time is part of every command's start-up).
"""

from __future__ import annotations

import functools
import re
import sys
from collections.abc import Callable

from rapidfix.rapid import syntax as s
from rapidfix.rapid.transform import number_value, numeric_aggregate_value, string_value

# The grammar's WHITESPACE, NUMBER and NUMERIC_AGGREGATE (checked against rapid.lark
# by expression_patterns, whenever the fast terminals are made).
WS = r"[ \t\f\v\r\n\x1a]"
#: the characters of WS (to strip them)
WS_CHARS = " \t\f\v\r\n\x1a"
NUMBER = r"0[xX][0-9a-fA-F]+|0[bB][01]+|0[oO][0-7]+|(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_N = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
NUMERIC_AGGREGATE = (rf"\[\s*(?:{_N}|\[\s*{_N}(?:\s*,\s*{_N})*\s*\])"
                     rf"(?:\s*,\s*(?:{_N}|\[\s*{_N}(?:\s*,\s*{_N})*\s*\]))*\s*\]")
# A name as the grammar's NAME takes it, in either case: ASCII letters and the letters of
# ISO 8859-1 (`pÜbergabe`, `Año`), written with escapes (the patterns go into grammar
# text). NAME is case-insensitive, which in Python also lets a few letters outside
# ISO 8859-1 through (the Kelvin sign): a name holding one ends a fast run, and the
# plain grammar reads its statement.
LATIN1_LETTERS = r"\u00c0-\u00d6\u00d8-\u00f6\u00f8-\u00ff"
NAME_START = rf"[A-Za-z{LATIN1_LETTERS}]"
#: a character of a name after its first (a letter of ISO 8859-1, a digit or '_')
WORD_CHAR = rf"[A-Za-z0-9_{LATIN1_LETTERS}]"
NAME = rf"{NAME_START}{WORD_CHAR}*"
# A name ends where no letter (of ISO 8859-1, as rapid.lark's NAME), digit or '_' follows.
WORD_END = rf"(?!{WORD_CHAR})"
# ... and starts where none stands before it.
WORD_START = rf"(?<!{WORD_CHAR})"
# What may stand between two statements of a run: whitespace and whole-line comments
# (the grammar's COMMENT, `![^\n]*`, here with its newline: a comment cannot then be
# cut short on backtracking, so nothing inside it is ever read as a statement).
GAP = rf"{WS}*(?:![^\n]*\n{WS}*)*"
# The grammar's STRING: `""` stands for a quote; backslashes and every separator may
# stand inside. Written as runs between the doubled quotes: a repeated group of one
# character made the engine keep a backtracking record per character (a 6 MB string
# took 2.7 GB and 7 s to check).
STRING = r'"[^"\r\n]*(?:""[^"\r\n]*)*"'


def _nested(open_: str, close: str, levels: int = 3) -> str:
    """A bracketed group up to `levels` deep (its inside not checked; a bracket in a
    string does not count)."""
    o, c = re.escape(open_), re.escape(close)
    # (written as "plain characters, then strings each followed by plain characters":
    # one way only to match, so a failure is not retried in other splits)
    other = f'[^{o}{c}"]*(?:{STRING}[^{o}{c}"]*)*'
    group = rf"{o}{other}{c}"
    for _ in range(levels - 1):
        group = rf"{o}{other}(?:{group}{other})*{c}"
    return group


# A value in text the lexer has checked: strings, pieces without whitespace or
# separators, and bracketed groups (aggregates four levels deep: a two-dimensional
# array of robtargets), with whitespace between them (but not after the last).
_CHUNK = (rf"(?:{STRING}|[^\",;\\()\[\]{{}} \t\f\v\r\n\x1a]+|{_nested('(', ')')}"
          rf"|{_nested('[', ']', 4)}|{_nested('{', '}')})")
VALUE_TEXT = rf"{_CHUNK}(?:{WS}*{_CHUNK})*"


# What closes a list (and what may follow its last item) in the patterns below.
_BRACE, _BRACKET, _PAREN, _PAREN_ENDS = r"\}", r"\]", r"\)", r"[\\)]"


def expression_patterns(terminals: dict[str, str], value_name: str, plain_name: str,
                        word_end: str, aggregates: tuple[str, str]) -> dict[str, str]:
    """Lexer patterns of the fast terminals' values: `value` (of a procedure call's
    argument or a declaration), `arguments` (a procedure call's argument list, without
    its name and ';'), `plain_arguments` (the common part of `arguments`: names,
    numbers, numeric aggregates, calls of a name and numbers), `selectors` (the
    components and indices of an assignment's target after its name), `condition` (a
    head's condition, up to its keyword) and `compact_condition` (a compact IF's, up to
    its statement). A function call's arguments are sums of operands (names with their
    components and indices, numbers, signs), calls of such sums (two levels deep) and
    optional arguments; a value may also be a sum of such operands, function calls and
    parenthesised sums (calls and parentheses inside them one level deep), or an
    aggregate of sums up to three levels. `aggregates`: fastpath's loose patterns of
    numeric aggregates (two levels; three or four levels). `terminals` holds
    rapid.lark's regular expressions by terminal name: the reader follows these."""
    spaces = {c for c in map(chr, range(256)) if re.fullmatch(terminals["WHITESPACE"], c)}
    # (Lark gives the grammar's \r and \n as the characters themselves)
    string = STRING.replace(r"\r", "\r").replace(r"\n", "\n")
    if (terminals["NUMBER"], terminals["NUMERIC_AGGREGATE"], terminals["STRING"], spaces) != (
            NUMBER, NUMERIC_AGGREGATE, string, set(" \t\f\v\r\n\x1a")):  # pragma: no cover
        raise ValueError("rapid.lark's numbers, strings or whitespace changed; "
                         "update fast_expressions")
    loose, deep = aggregates
    # signs, and NOT (the reader refuses it where the grammar does not take it)
    signs = rf"(?:(?:[-+]|(?i:NOT){word_end}){WS}*)*"
    # Each list below is written once: an element, then its separator or a look at what
    # ends the list. Look-aheads on the next character spare the regular expression
    # engine the alternatives that cannot match (most values are single names).
    # After an operand: an operator and the start of a further operand, or the end.
    # (arithmetic, relations and logic: the reader checks the grammar's structure)
    operator = rf"(?:[-+*\x2f=]|<[>=]?|>=?|(?i:DIV|MOD|AND|OR|XOR){word_end})"
    follow = (rf"{WS}*(?:{operator}{WS}*(?=[-+.0-9A-Za-z{LATIN1_LETTERS}(\"])"
              rf"|(?=[,;)}}\]\\]))")
    number = f"(?=[0-9.])(?:{NUMBER})"

    def items(item: str, close: str, ends: str) -> str:
        """One `item` of a comma-separated list, with its separator, or the look at what
        ends the list (`close`, the closing character; `ends`, those that may follow)."""
        return rf"(?:{item}(?:{WS}*,{WS}*(?!{close})|{WS}*(?={ends})))"

    def postfix(item: str) -> str:
        """Components and array indices (`.x`, `{i, 2}`) after an operand."""
        index = rf"\{{{WS}*{items(item, _BRACE, _BRACE)}+\}}"
        return rf"(?:{WS}*(?:\.{WS}*{NAME}{word_end}|{index}))*"

    # an operand inside a function call or an index: its indices numbers or names
    leaf = f"(?:{number}|{value_name})"
    truth = rf"(?i:TRUE|FALSE){word_end}"
    operand = (rf"{signs}(?:{number}|(?={NAME_START})(?:{value_name}{postfix(leaf)}|{truth})"
               rf"|{STRING})")
    simple = rf"(?:{operand}{follow})+"
    # a name with its components and indices of names and numbers (`p7.trans.x`,
    # `path{3}`), the first written right after the name as programs write it (a look at
    # one character spares every plain name the postfix; `p7 .trans` goes the general
    # route)
    name_ref = rf"{value_name}(?:(?=[.{{]){postfix(leaf)})?"
    # such a name with at least one component or index, as a whole value (where quick
    # has refused the name alone)
    element = (rf"(?={NAME_START}){value_name}(?={WS}*[.{{]){postfix(leaf)}"
               rf"(?={WS}*[,;)\\])")
    # first tried: a value that is a single name, (negated) number or TRUE/FALSE, as
    # most are
    quick = (rf"(?:(?:-{WS}*)?{number}|(?={NAME_START})(?:{value_name}|(?i:TRUE|FALSE){word_end}))"
             rf"(?={WS}*[,;)\\])")
    # a string as a whole value (elsewhere it is an operand)
    string = rf"{STRING}(?={WS}*[,;\\])"
    # next tried: a function call of a name (or an aggregate of numbers, or such a call
    # itself) and offsets, as most targets moved by Offs or RelTool are
    # (`Offs(p7,0,0,-10)`, `Offs(p7, 0, 0, -nLift)`, `Offs(p7,0,0,nLift+5)`,
    # `RelTool(p7, 0, 0, 5 \\Rz:=45)`, `Offs([[...],...],0,0,5)`,
    # `RelTool(Offs(p7,0,0,10),0,0,0 \\Rz:=45)`): what `term` takes, in one pass (every
    # piece is followed by something that cannot start it again, so there is one way to
    # take each text).
    # An offset is a number or a name, negated or not, or arithmetic of those (`nLift + 5`,
    # `nDx * 2`): each term followed by an operator and the start of the next (after a
    # term, `-` is an operator, never a sign) or by what ends the offset. The term is
    # written once: these patterns are compiled in every process that parses.
    offset = (rf"(?:(?:-{WS}*)?(?:{number}|(?={NAME_START}){name_ref})"
              rf"(?:{WS}*[-+*\x2f]{WS}*(?=[-.0-9A-Za-z{LATIN1_LETTERS}])"
              rf"|(?={WS}*[,)\\])))+")
    after_first = (rf"(?:{WS}*,{WS}*{offset})+"
                   rf"(?:{WS}*\\{WS}*{plain_name}{WS}*:={WS}*{offset})*{WS}*\)")
    first = rf"(?:(?={NAME_START}){name_ref}|(?=\[){loose})"
    named_call = (rf"(?={NAME_START}){value_name}\({WS}*"
                  rf"(?:(?={NAME_START}){value_name}(?:\({WS}*{first}{after_first}|{postfix(leaf)})"
                  rf"|(?=\[){loose}){after_first}(?={WS}*[,;\\])")

    def argument(value: str) -> str:
        """`\\Name:=` or nothing before a value, or a switch `\\Name`."""
        return (rf"(?:(?:\\{WS}*{plain_name}{WS}*:={WS}*|(?!\\)){value}"
                rf"|\\{WS}*{plain_name}(?!{WS}*:=))")

    def call_list(item: str) -> str:
        """A function call's parenthesised arguments, each `item` or an optional one."""
        return rf"\({WS}*{items(argument(item), _PAREN, _PAREN_ENDS)}*\)"

    # Where two alternatives take the same text (`1` is quick and simple, `[1,2]` loose
    # and a group), the later one is guarded by a look-ahead refusing the earlier:
    # otherwise a statement that fails near its end (a syntax error, or a call the fast
    # path does not take) is retried in every combination, 2^n for n such arguments.
    either = rf"(?:{quick}|(?!{quick}){simple})"
    # a function call's arguments may be calls of sums themselves, two levels deep
    # (`Offs(RelTool(p,0,0,5),0,0,-nLift)`, `RelTool(Offs(RelTool(p,0,0,5),0,0,1),0,0,0)`)
    nested = rf"(?={NAME_START}){value_name}{WS}*{call_list(f'(?:{loose}|{either})')}"
    deeper = (rf"(?={NAME_START}){value_name}{WS}*"
              + call_list(rf"(?:{loose}|{nested}(?={WS}*[,)\\])|{either})"))
    inner = call_list(rf"(?:{loose}|{deeper}(?={WS}*[,)\\])|{either})")
    # parentheses around sums of operands, of function calls of sums and of parentheses
    # around sums (`(DInput(di1) = 1)`, `((a + b) * c)`, `(NumToStr(n, 0) + "s")`)
    def operand_or_call(paren: str, index: str) -> str:
        """An operand (its indices `index`), a function call of sums (one level), or
        `paren`."""
        return (rf"{signs}(?:{number}|(?={NAME_START})(?:{value_name}"
                rf"(?:{WS}*{call_list(either)})?{postfix(index)}|{truth})|{paren}|{STRING})")

    simple_paren = rf"\({WS}*{simple}{WS}*\)"
    paren = rf"\({WS}*(?:{operand_or_call(simple_paren, leaf)}{follow})+{WS}*\)"
    term = (rf"{signs}(?:{number}|(?={NAME_START})(?:{value_name}(?:{WS}*{inner})?{postfix(simple)}"
            rf"|{truth})|{paren}|{STRING})")
    group = rf"\[{WS}*{items(simple, _BRACKET, _BRACKET)}+\]"
    item = f"(?:{loose}|(?!{loose}){group}|{simple})"
    two_levels = rf"\[{WS}*{items(item, _BRACKET, _BRACKET)}+\]"
    # and three levels: an array of records (`[[1,"S1",0.5,[10,20,30]], ...]`)
    row = f"(?:{loose}|(?!{loose}){two_levels}|{simple})"
    aggregate = rf"\[{WS}*{items(row, _BRACKET, _BRACKET)}+\]"
    # An aggregate of up to two levels whose items are sums of names and numbers
    # (`[[x0+nStep*2,y0,z0],[1,0,0,0],...]`, `[[rb.robax.rax_1, 0, ...],rb.extax]`,
    # `[vTcp*2,500,5000,1000]`), taken loosely as runs of their characters: checked token
    # by token, an item of sums cost several times a numeric group's time. The reader
    # checks it as it checks a condition (NotFast where it is not RAPID, as for a
    # malformed number in a numeric aggregate). After `loose`, which takes most of
    # its texts faster; `aggregate` takes the rest (strings, calls, deeper nesting).
    sum_chars = rf"[-+*\x2f0-9.A-Za-z_{LATIN1_LETTERS}, \t\f\v\r\n\x1a]*"
    sums = rf"\[{sum_chars}(?:\[{sum_chars}\]{sum_chars})*\]"
    value = (f"(?:(?=\\[)(?:{loose}|(?!{loose}){sums}|{deep}"
             f"|(?!{loose}|{sums}|{deep}){aggregate})"
             f"|{quick}|{named_call}|{string}|(?!{quick}|{named_call}|{string})"
             f"(?:{term}{follow})+)")
    # a separator is refused before the list's end however much space stands between
    # (`Foo 1, ;` is not RAPID)
    arguments = rf"(?:{argument(value)}(?:{WS}*,(?!{WS}*;){WS}*|{WS}*(?=[\\;])))+"
    # Arguments as most calls write them (`p7, v100, z1, tool0\WObj:=wobj1`, or a target
    # that is a call of a name and numbers or an aggregate of numbers): each piece one of
    # `value`'s own first alternatives, each separator one that `arguments` takes, so a
    # subset of `arguments` that the lexer tries first. It has one way to take each
    # text (every alternative starts with a character of its own), and takes a plain
    # argument list in about two thirds of the general pattern's time.
    plain = rf"(?:{quick}|{named_call}|(?=\[)(?:{loose}|(?!{loose}){sums})|{element})"
    # after the first: a plain value, an optional argument of one (`\V:=120`) or a switch
    # (`\Conc`), after a comma, or without one before a `\` (`plain` written twice only)
    item = (rf"(?:(?:\\{WS}*{plain_name}{WS}*:={WS}*)?{plain}"
            rf"|\\{WS}*{plain_name}(?!{WS}*:=))")
    plain_arguments = rf"{plain}(?:(?:{WS}*,{WS}*|{WS}*(?=\\)){item})*"
    condition = condition_pattern(plain_name)
    # A compact IF's condition (`IF nCount > 3 Incr nCount;`, `IF DInput(di1) = 1 Set
    # do1;`): operands, calls of sums and parentheses, joined by operators, up to the
    # first operand that whitespace and a name follow (no operand is followed by one
    # inside a condition, so that is where its statement starts; an operator's keyword,
    # which also follows so, is refused as the statement's name by the caller's pattern).
    ends = (rf"(?:{WS}*{operator}{WS}*(?=[-+.0-9A-Za-z{LATIN1_LETTERS}(\"])"
            rf"|(?={WS}+{NAME_START}))")
    compact_condition = rf"(?:{operand_or_call(paren, simple)}{ends})+"
    return {"value": value, "arguments": arguments, "selectors": postfix(simple),
            "condition": condition, "plain_arguments": plain_arguments,
            "compact_condition": compact_condition}


def condition_pattern(name: str, stop: str | None = None) -> str:
    """The text of a condition (rapid.lark's `expr`, or a comma-separated list of them),
    up to the keyword its statement puts after it: strings, optional arguments'
    `\\Name:=` (`name` the pattern of Name), and any character but those of a comment,
    a statement's end, a conditional or named argument (`\\A?B`, `f(x:=1)`) or a
    placeholder (`<EXP>`), taken as few as can be. The reader checks all of it.

    With `stop`, no piece of the condition starts with what `stop` matches: a pattern
    that goes on after the keyword (an IF block's) cannot then take the keyword into
    the condition to find its own end further on."""
    piece = rf"(?:{STRING}|\\{WS}*{name}{WS}*:=|[^;!\"?:<]|<(?![A-Za-z]+>))"
    if stop is None:
        return piece[:-1] + ")+?"  # the same text as before `stop` was known
    return rf"(?:(?!{stop}){piece})+?"


# What the reader takes without reading it again: the values fastpath reads itself
# (a name, a (negated) number, a call or an array element of names and numbers).
_NAME = NAME
_INDEX_ITEM = f"(?:{NUMBER}|{_NAME})"
# (NOT before parentheses is the operator, not a function's name: `NOT (a)`)
_NOT = rf"(?i:NOT){WORD_END}"
PLAIN_VALUE = re.compile(
    rf"(?:-{WS}*)?(?:{NUMBER})|(?!{_NOT}){_NAME}(?:{WS}*(?:{_nested('(', ')')}"
    rf"|\{{{WS}*{_INDEX_ITEM}(?:{WS}*,{WS}*{_INDEX_ITEM})*{WS}*\}}))?")


class NotRead(Exception):
    """The text is not an expression the reader builds exactly (fastpath: NotFast)."""


_SPACE = re.compile(f"{WS}*")
_WS_CHARS = frozenset(WS_CHARS)
_NUMBER = re.compile(NUMBER)
_STRING = re.compile(STRING)
_WORD = re.compile(NAME)
_AGGREGATE = re.compile(NUMERIC_AGGREGATE)
#: where the grammar's NUMERIC_AGGREGATE matches at the start of a text (or None)
NUMERIC_AGGREGATE_MATCH = _AGGREGATE.match
# An aggregate's item that is a literal alone: (sign, number), string or TRUE / FALSE,
# then whitespace and the ',' or ']' after it (_Reader._item)
_LITERAL_ITEM = re.compile(
    rf"{WS}*(?:(?:([-+]){WS}*)?({NUMBER})|({STRING})|((?i:TRUE|FALSE))"
    rf"{WORD_END})(?={WS}*[,\]])")
_BOOLS = {"TRUE": True, "FALSE": False}
_NONE: frozenset[str] = frozenset()
# LE, GE and NE before LT, GT and EQ: the lexer takes the longest
_RELATION = re.compile("<>|<=|>=|[<>=]")
_SUM = frozenset("+-")
# What may follow a condition's last operand: where `_Reader.condition` finds one of
# these after its first, that operand is the whole condition ('' the end of the text)
_AFTER_OPERAND = frozenset([",", ")", "]", "}", ";", ":", "\\", ""])
_PRODUCT = frozenset("*/")


class _Reader:
    """Recursive descent over one value's text, following rapid.lark's expression rules."""

    __slots__ = ("base", "pos", "text")

    def __init__(self, text: str, base: int) -> None:
        self.text, self.base, self.pos = text, base, 0

    def _skip(self) -> str:
        """The next character after whitespace ('' at the end)."""
        text, pos = self.text, self.pos
        if pos >= len(text):
            return ""
        char = text[pos]
        if char not in _WS_CHARS:
            return char
        pos = self.pos = _SPACE.match(text, pos).end()
        return text[pos] if pos < len(text) else ""

    def _expect(self, char: str) -> int:
        if self._skip() != char:
            raise NotRead(self.text)
        self.pos += 1
        return self.base + self.pos

    def _operator(self, ops: frozenset[str], words: tuple[str, ...]) -> tuple[str, int] | None:
        """The operator of `ops` (or keyword of `words`) at the next token, or None."""
        char = self._skip()
        if char in ops:
            return char, 1
        if words and char.isalpha():
            word = _WORD.match(self.text, self.pos)
            if word is not None and word.group().upper() in words:
                return word.group().upper(), word.end() - word.start()
        return None

    def _chain(self, operand: Callable[[], s.Expr], ops: frozenset[str],
               words: tuple[str, ...]) -> s.Expr:
        """Operands joined by left-associative operators of one precedence level."""
        return self._chain_from(operand(), operand, ops, words)

    def _chain_from(self, left: s.Expr, operand: Callable[[], s.Expr], ops: frozenset[str],
                    words: tuple[str, ...]) -> s.Expr:
        """`_chain` whose first operand `left` has been read."""
        while (op := self._operator(ops, words)) is not None:
            self.pos += op[1]
            right = operand()
            left = s.Binary(left.start, right.end, op[0], left, right)
        return left

    def condition(self) -> s.Expr:
        """rapid.lark's `expr`: OR / XOR of AND of NOT of a relation of sums.

        Most values are one operand (an aggregate's item, an index, an argument): it is
        read by `factor`, and where no operator follows, it is the whole condition, as
        every level below would return it unchanged; else the levels go on from it."""
        if self._skip() in "nN" and self._at_not():
            return self._chain(self._and, _NONE, ("OR", "XOR"))
        left = self.factor()
        if self._skip() in _AFTER_OPERAND:
            return left
        left = self._chain_from(left, self.factor, _PRODUCT, ("DIV", "MOD"))
        left = self._chain_from(left, self.term, _SUM, ())
        left = self._relation_from(left)
        left = self._chain_from(left, self._not, _NONE, ("AND",))
        return self._chain_from(left, self._and, _NONE, ("OR", "XOR"))

    def _and(self) -> s.Expr:
        return self._chain(self._not, _NONE, ("AND",))

    def _at_not(self) -> bool:
        """Whether the next word is NOT (the next character has been skipped to)."""
        word = _WORD.match(self.text, self.pos)
        return word is not None and word.end() - word.start() == 3 and (
            word.group().upper() == "NOT")

    def _not(self) -> s.Expr:
        # NOT is a keyword only where the grammar's `not_expr` may start; elsewhere the
        # contextual lexer reads it as a name, which atom refuses
        if self._skip() in "nN" and self._at_not():
            at = self.base + self.pos
            self.pos += 3
            operand = self._not()
            return s.Unary(at, operand.end, "NOT", operand)
        return self._relation()

    def _relation(self) -> s.Expr:
        """A sum, or two compared (the grammar does not chain relations)."""
        return self._relation_from(self.expression())

    def _relation_from(self, left: s.Expr) -> s.Expr:
        """`_relation` whose sum `left` has been read."""
        self._skip()
        m = _RELATION.match(self.text, self.pos)
        if m is None:
            return left
        self.pos = m.end()
        right = self.expression()
        return s.Binary(left.start, right.end, m.group(), left, right)

    def expression(self) -> s.Expr:
        return self._chain(self.term, _SUM, ())

    def term(self) -> s.Expr:
        return self._chain(self.factor, _PRODUCT, ("DIV", "MOD"))

    def factor(self) -> s.Expr:
        char = self._skip()
        if char in _SUM and char:
            at = self.base + self.pos
            self.pos += 1
            operand = self.factor()
            return s.Unary(at, operand.end, char, operand)
        return self.postfix()

    def postfix(self) -> s.Expr:
        node = self.atom()
        while True:
            char = self._skip()
            if char == "{":
                self.pos += 1
                indices = [self.condition()]
                while self._skip() == ",":
                    self.pos += 1
                    indices.append(self.condition())
                node = s.Index(node.start, self._expect("}"), node, indices)
            elif char == ".":
                self.pos += 1
                self._skip()
                word = _WORD.match(self.text, self.pos)
                if word is None:
                    raise NotRead(self.text)
                self.pos = word.end()
                node = s.Component(node.start, self.base + self.pos, node, word.group())
            else:
                return node

    def atom(self) -> s.Expr:
        char = self._skip()
        text, pos, base = self.text, self.pos, self.base
        if char.isdigit() or char == ".":
            m = _NUMBER.match(text, pos)
            if m is None:
                raise NotRead(text)
            self.pos = m.end()
            return s.Number(base + pos, base + m.end(), number_value(m.group()), m.group())
        if char == '"':
            m = _STRING.match(text, pos)
            if m is None:
                raise NotRead(text)
            self.pos = m.end()
            return s.String(base + pos, base + m.end(), string_value(m.group()))
        if char == "(":
            self.pos += 1
            inner = self.condition()
            return s.Paren(base + pos, self._expect(")"), inner)
        if char == "[":
            m = _AGGREGATE.match(text, pos)
            if m is not None:  # Lark's NUMERIC_AGGREGATE, tried before the bracket
                self.pos = m.end()
                return s.NumericAggregate(base + pos, base + m.end(),
                                          numeric_aggregate_value(m.group()))
            self.pos += 1
            items = [self._item()]
            while self._skip() == ",":
                self.pos += 1
                items.append(self._item())
            return s.Aggregate(base + pos, self._expect("]"), items)
        word = _WORD.match(text, pos) if char else None
        if word is None:
            raise NotRead(text)
        keyword = word.group().upper()
        if keyword in _BOOLS:
            self.pos = word.end()
            return s.Bool(base + pos, base + word.end(), _BOOLS[keyword])
        if keyword == "NOT":  # a keyword here only where a condition may start (_not)
            raise NotRead(text)
        self.pos = word.end()
        name = sys.intern(word.group())
        if self._skip() == "(":
            return self.call(name, base + pos)
        return s.NameRef(base + pos, base + word.end(), name)

    def _item(self) -> s.Expr:
        """An aggregate's item: a literal alone (a signed number, a string, TRUE or FALSE
        before the next ',' or ']', as a table of records holds hundreds) made here,
        the node `condition` makes of it; anything else read by `condition`."""
        m = _LITERAL_ITEM.match(self.text, self.pos)
        if m is None:
            return self.condition()
        base = self.base
        sign, number, string, truth = m.group(1, 2, 3, 4)
        self.pos = m.end()
        if number is not None:
            node: s.Expr = s.Number(base + m.start(2), base + m.end(2), number_value(number),
                                    number)
            if sign is not None:
                node = s.Unary(base + m.start(1), node.end, sign, node)
            return node
        if string is not None:
            return s.String(base + m.start(3), base + m.end(3), string_value(string))
        return s.Bool(base + m.start(4), base + m.end(4), _BOOLS[truth.upper()])

    def call(self, name: str, start: int) -> s.Call:
        """A function call whose name stands at `start`, at its '('."""
        self.pos += 1
        args: list[s.Argument] = []
        if self._skip() != ")":
            args.append(self.argument(True))
            while True:
                char = self._skip()
                if char == ",":
                    self.pos += 1
                    args.append(self.argument(True))
                elif char == "\\":
                    args.append(self.argument(False))
                else:
                    break
        return s.Call(start, self._expect(")"), name, args)

    def argument(self, required: bool) -> s.Argument:
        """An argument (`required`: a value may stand here, else only an optional one)."""
        if self._skip() == "\\":
            at = self.base + self.pos
            self.pos += 1
            self._skip()
            word = _WORD.match(self.text, self.pos)
            if word is None:
                raise NotRead(self.text)
            self.pos = word.end()
            end = self.base + self.pos
            value = None
            if self._skip() == ":" and self.text.startswith(":=", self.pos):
                self.pos += 2
                value = self.condition()
                end = value.end
            elif self.text.startswith("?", self.pos):
                raise NotRead(self.text)  # a conditional argument: the grammar reads it
            return s.Argument(at, end, "optional", word.group(), value)
        if not required:
            raise NotRead(self.text)
        value = self.condition()
        if self._skip() == ":":  # a named required argument: the grammar reads it
            raise NotRead(self.text)
        return s.Argument(value.start, value.end, "required", None, value)


#: trees deeper than this are left to the grammar: a shared tail's operands are copied
#: by recursion (fastpath._moved), which Python's stack limits
DEEPEST = 200
# a tree this deep needs at least this many characters (an operator and an operand per
# level): shorter text is not measured
_DEEP_TEXT = 2 * DEEPEST


@functools.lru_cache(maxsize=64)
def _fields(kind: type) -> tuple[str, ...]:
    """The slots of a node type, its bases' included."""
    return tuple(name for cls in kind.__mro__ for name in getattr(cls, "__slots__", ()))


def _depth(node: s.Node) -> int:
    """How many levels of nodes `node` holds (walked without recursion). Literals and
    names hold none below them, and an aggregate only its items: a table of records
    (thousands of literals) is walked at a set lookup per item."""
    deepest, stack = 0, [(node, 1)]
    pop, push, leaves, aggregate = stack.pop, stack.append, s.LEAF_NODES, s.Aggregate
    while stack:
        item, level = pop()
        if level > deepest:
            deepest = level
        kind = type(item)
        if kind in leaves:
            continue
        if kind is aggregate:
            stack.extend([(part, level + 1) for part in item.items])
            continue
        for name in _fields(kind):
            child = getattr(item, name, None)
            for part in (child if isinstance(child, list) else (child,)):
                if isinstance(part, s.Node):
                    push((part, level + 1))
    return deepest



def _read_whole(text: str, start: int, read: Callable[[_Reader], list[s.Expr]]
                ) -> list[s.Expr]:
    """What `read` takes from the whole of `text` standing at `start`; NotRead when it
    leaves text over, or the nodes nest deeper than DEEPEST (or than Python's stack)."""
    reader = _Reader(text, start)
    try:
        nodes = read(reader)
    except RecursionError:  # nested deeper than Python's stack: the grammar's to read
        raise NotRead(text) from None
    if reader._skip() or (len(text) > _DEEP_TEXT and max(map(_depth, nodes)) > DEEPEST):
        raise NotRead(text)
    return nodes


def _conditions(reader: _Reader) -> list[s.Expr]:
    items = [reader.condition()]
    while reader._skip() == ",":
        reader.pos += 1
        items.append(reader.condition())
    return items


def read_list(text: str, start: int) -> list[s.Expr]:
    """The conditions of a comma-separated list (a CASE's values) standing at `start`;
    NotRead as read_expression."""
    return _read_whole(text, start, _conditions)


def read_expression(text: str, start: int, condition: bool = False) -> s.Expr:
    """The node rapid.lark builds for the value `text` standing at offset `start` (a sum,
    or with `condition` any `expr`: relations, NOT, AND, OR, XOR); NotRead when it is
    not such a value, exactly and whole, or nests deeper than DEEPEST."""
    (node,) = _read_whole(text, start, lambda reader: [
        reader.condition() if condition else reader.expression()])
    return node


__all__ = [
    "GAP",
    "NUMBER",
    "NUMERIC_AGGREGATE",
    "NUMERIC_AGGREGATE_MATCH",
    "PLAIN_VALUE",
    "STRING",
    "VALUE_TEXT",
    "WORD_END",
    "WS",
    "NotRead",
    "condition_pattern",
    "expression_patterns",
    "read_expression",
    "read_list",
]
