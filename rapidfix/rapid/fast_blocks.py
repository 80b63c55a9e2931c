"""Whole compound statements, and whole routines, as one token each.

The fast terminals (rapidfix.rapid.fastpath) take runs of simple statements and the
head of each compound statement, but Lark's LALR loop still steps through every
head, every `ELSE`, `ENDIF`, `ENDWHILE`, `DEFAULT`, `ENDTEST`, and every routine's
head and `ENDPROC`, at some 20 µs a token. A program whose moves stand inside nested
IF / WHILE / TEST blocks, or in many small routines, spent half its parse there.

Here the contextual lexer is given a reader that runs ahead of it. Where the parser
may take a statement, or a module item and the text opens a routine, the reader reads
as far as it can read exactly, with the fast terminals' own patterns (runs of calls
and of declarations, compound heads) and the keywords that close each construct, and
builds the syntax nodes the grammar's rules build (through the fast path's own
callbacks). What no run or head takes (an assignment, a call, a late-bound call, a
compact IF, RAISE or RETURN of a value; an IF, ELSEIF or WHILE head) is found loosely:
split where the grammar must split it (an argument list at the commas and backslashes
outside brackets and strings, a head at its THEN or DO), its pieces read by the
expression reader, which builds exactly what the grammar builds or gives up. What it
read becomes one token, FAST_BLOCK or FAST_ROUTINES, holding those nodes; inlined rules
(`_fast_block`, `_fast_routines`) splice them where the parser stands. A piece it
cannot read (a placeholder, a record type, a syntax error) ends the token before the
outermost construct that holds it, and Lark reads on from there as before.

Inside a construct that fails, what was read complete (each run of calls or of a
routine's declarations, each statement) is kept by position, and the lexer hands it
out when the parser reaches it; reading ahead starts again past the failure. So
nothing is read twice, however deep the failure, and the reader's work stays linear in
the text. The grammar stays the definition of the language: the reader takes a
construct only where every piece is one the lexer would give that parser state, and
the equivalence tests parse everything both ways (tests/rapid/test_fast_blocks.py).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from types import SimpleNamespace
from typing import Any

from lark import Token
from lark.exceptions import UnexpectedCharacters

from rapidfix.rapid.fast_expressions import (
    GAP,
    LATIN1_LETTERS,
    NAME,
    STRING,
    WORD_CHAR,
    WORD_END,
    WORD_START,
    WS,
    WS_CHARS,
)
from rapidfix.rapid.lexer_patterns import compiled_alone

BLOCK = "FAST_BLOCK"
ROUTINES = "FAST_ROUTINES"
# The two terminals' patterns: they never match, so only the reader gives these tokens.
NEVER = r"\x00(?!)\x00"
# The fast terminals the reader reads with.
_HEADS = ("if", "elseif", "while", "for", "test", "case", "return", "proc", "func")
PATTERNS = ("FAST_CALLS", "FAST_DECLS", *(f"FAST_{kind.upper()}" for kind in _HEADS))
# The syntax builder's callbacks the reader makes nodes with.
_CALLBACKS = ("fast_if_stmt", "fast_elseif_clause", "else_clause", "fast_while_stmt",
              "fast_for_stmt", "fast_test_stmt", "fast_case_clause", "default_clause",
              "fast_return_stmt", "retry_stmt", "trynext_stmt", "exit_stmt", "raise_stmt",
              "connect_stmt", "name_ref", "label", "procedure_call", "late_call",
              "if_stmt", "elseif_clause", "while_stmt", "compact_if", "return_stmt",
              "arguments", "required_argument", "optional_argument", "conditional_argument",
              "error_handler", "error_numbers", "undo_handler", "backward_handler",
              "_fast_routine", "trap")
#: whether the lexer has the reader read ahead (off: the fast terminals alone, as tests of
#: those terminals see them)
READ_AHEAD = True
#: compound statements nested deeper than this are left to the parser (Python's stack)
DEPTH_LIMIT = 48

# Whitespace and comments, as between the statements of a run.
_GAP = re.compile(GAP)
# The keywords that close a statement list (a clause, a routine's body or handler).
_CLOSING = re.compile(
    rf"(?i:ENDIF|ELSEIF|ELSE|ENDWHILE|ENDFOR|ENDTEST|ENDPROC|ENDFUNC|ENDTRAP|ERROR|UNDO|BACKWARD"
    rf"|CASE|DEFAULT){WORD_END}")
_CLOSING_FIRST = frozenset("EeUuBbCcDd")
# An ENDIF later on the line: an IF head may then begin an IF block that a run takes.
_ENDIF_ON_LINE = re.compile(r"[^\n]*(?i:ENDIF)")
_DEFAULT_COLON = re.compile(rf"{WS}*:")
# The statements a fast head opens (or is: RETURN), by their first letter.
_OPENED_BY = {letter: kind for kind in ("if", "while", "for", "test", "return")
              for letter in (kind[0], kind[0].upper())}
# The first letters of what the lexer has the reader try: a statement where the parser
# may take one, a routine (or a declaration) where it may take a module item.
_STATEMENT_OPENERS = frozenset(
    "%ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
    + "".join(map(chr, [*range(0xC0, 0xD7), *range(0xD8, 0xF7), *range(0xF8, 0x100)])))
_ITEM_OPENERS = frozenset("PpFfLlTt")
# The statements of a keyword and `;` (in error handlers mostly).
_KEYWORD_STATEMENT = re.compile(
    rf"(?i:(RETRY|TRYNEXT|EXIT|RAISE)){WORD_END}{WS}*;")
# The start of a routine's head.
_ROUTINE_HEAD = re.compile(rf"(?i:(?:LOCAL{WS}+)?(?:PROC|FUNC|TRAP)){WORD_END}")
# A trap routine's head (no fast terminal takes it): LOCAL, TRAP and the name in groups.
_NAME = rf"{NAME}{WORD_END}"
_TRAP_HEAD = re.compile(rf"(?:(?i:(LOCAL)){WS}+)?(?i:(TRAP)){WORD_END}{WS}*({_NAME})")
# `CONNECT name WITH trap;`, its names in groups.
_CONNECT = re.compile(rf"(?i:CONNECT){WORD_END}{WS}*({_NAME}){WS}*(?i:(WITH)){WORD_END}{WS}*"
                      rf"({_NAME}){WS}*;")
# An assignment found loosely (its pieces are read exactly, or it is left to the parser):
# a target (a name, components, indices without braces inside), `:=` (group 2), a value
# up to the first `;` outside a string.
_ASSIGNMENT = re.compile(
    rf"({_NAME})(?:{WS}*(?:\.{WS}*{_NAME}|\{{(?:[^{{}};\"]|{STRING})*\}}))*{WS}*(:=)"
    rf"(?:[^;\"]|{STRING})*;")
# A procedure call found loosely (its arguments are read exactly, or it is left to the
# parser): the name, then whitespace, or an optional argument's backslash, a bracket or
# a string, the arguments (group 2) up to the first `;` outside a string.
_CALL = re.compile(
    rf"({_NAME})(?:{WS}+(?![:=,;])|{WS}*(?=[\\(\[\"]))((?:[^;\"]|{STRING})+);")
# A call without arguments (`Stop;`: runs take it, but not as a compact IF's statement).
_BARE_CALL = re.compile(rf"({_NAME}){WS}*;")
# A late-bound call, `%expr% arguments;`: the expression (group 1: up to the next `%`
# outside a string) and the arguments (group 2, perhaps none) up to the `;`.
_LATE_CALL = re.compile(rf"%((?:[^%;\"]|{STRING})+)%((?:[^;\"]|{STRING})*);")
# What splits a list of arguments or values (a comma, a backslash), what it steps over
# (strings, and brackets of every kind: the commas and backslashes inside them are an
# item's own), and the `;` no such list holds outside a string.
_LIST_MARKS = re.compile(rf"{STRING}|[,\\()\[\]{{}};]")
_OPENERS, _CLOSERS = frozenset("([{"), frozenset(")]}")
# An optional argument's name after its backslash.
_OPTIONAL_NAME = re.compile(rf"{WS}*({_NAME}){WS}*")
# A required argument given by name, `name := value`: the name.
_NAMED = re.compile(rf"{WS}*({_NAME}){WS}*:=")
# A head no fast terminal takes (its condition one the patterns leave out): the keyword
# (group 1), the condition (group 2) and the word after it (group 3: THEN or DO, the
# first outside a string; neither stands in an expression).
_LOOSE_HEADS = {
    kind: re.compile(rf"(?i:({kind})){WORD_END}((?:[^;\"]|{STRING})*?){WORD_START}"
                     rf"(?i:({after})){WORD_END}")
    for kind, after in (("if", "THEN"), ("elseif", "THEN"), ("while", "DO"))}
# A compact IF's condition: where a name (or a late call's `%`) follows the end of an
# operand, at the top level, the condition has ended (no name continues an expression
# but the word operators). Group 1: a word's last character, with whitespace and a name
# after it; a string or a closing bracket may have a name straight after it
# (_STATEMENT_AHEAD). Strings and brackets are stepped over.
_COMPACT_IF = re.compile(rf"(?i:IF){WORD_END}{WS}*")
_CONDITION_MARKS = re.compile(
    rf"{STRING}|[()\[\]{{}}]|({WORD_CHAR}){WS}+(?=[A-Za-z{LATIN1_LETTERS}%])"
    rf"|;")
_STATEMENT_AHEAD = re.compile(rf"{WS}*(?=[A-Za-z{LATIN1_LETTERS}%])")
_WORD_OPERATORS = frozenset(("AND", "OR", "XOR", "NOT", "DIV", "MOD"))
_OPERATOR_WORD = re.compile(rf"(?i:AND|OR|XOR|NOT|DIV|MOD){WORD_END}")
_WORD_CHAR = re.compile(WORD_CHAR)
# RAISE or RETURN of a value no fast terminal takes: the keyword, the value (group 2).
_VALUED = re.compile(rf"(?i:(RAISE|RETURN)){WORD_END}((?:[^;\"]|{STRING})+);")
# A word that begins with a keyword of a module item, or ENDMODULE, and goes on
# (`PERSspeeddata`, `LOCALPERS`): a name, or the keyword read out of it (module_items).
_GLUED_KEYWORD = re.compile(
    rf"(?i:LOCAL|TASK|VAR|PERS|CONST|PROC|FUNC|TRAP|RECORD|ALIAS|ENDMODULE)"
    rf"{WORD_CHAR}")
# A statement's first word.
_FIRST_WORD = re.compile(_NAME)
# A label, `name:` (not `name:=`), its name in a group.
_LABEL = re.compile(rf"({_NAME}){WS}*:(?!=)")
# What follows ERROR when its handler names error numbers.
_NUMBERS = re.compile(rf"{WS}*\(")


class _Unread(Exception):
    """The reader met something it does not read exactly, at `at`."""

    def __init__(self, at: int) -> None:
        self.at = at


class _ReadToken(Token):
    """A FAST_BLOCK or FAST_ROUTINES token, with the nodes read for it."""

    __slots__ = ("nodes",)


class _Word:
    """A keyword or head the reader hands the builder's callbacks: what they read of the
    token the lexer would have made (its type, offsets and text), at a fraction of a
    Lark Token's cost."""

    __slots__ = ("end_pos", "start_pos", "text", "type")

    def __init__(self, kind: str, text: str, start: int, end: int) -> None:
        self.type, self.text, self.start_pos, self.end_pos = kind, text, start, end

    def __str__(self) -> str:
        return self.text[self.start_pos:self.end_pos]


def _semi(text: str, end: int) -> _Word:
    """The `;` that ends at `end`."""
    return _Word("SEMI", text, end - 1, end)


class _LooseHead:
    """A head found loosely, its condition read exactly: what the constructs read of a
    head's match (where it starts and ends), and the plain grammar's pieces of it."""

    __slots__ = ("closing", "cond", "keyword")

    def __init__(self, keyword: _Word, cond: Any, closing: _Word) -> None:
        self.keyword, self.cond, self.closing = keyword, cond, closing

    def start(self) -> int:
        return self.keyword.start_pos

    def end(self) -> int:
        return self.closing.end_pos


class Reader:
    """Reads statement lists, compound statements and routines of one text, with what
    `lexer` (the BlockLexer) holds: the compiled fast terminals, the fast path's syntax
    builder (its callbacks make the nodes), its splitters of runs of calls and of
    declarations, the grammar's keywords (upper case), and its readers of an assignment
    (its text, where it starts, its `:=` and its end) and of a value (its text and where
    it stands) that no run takes, each None where it does not read.
    """

    def __init__(self, text: str, lexer: BlockLexer) -> None:
        self.text = text
        self.keywords = lexer.keywords
        self.assignment = lexer.assignment
        self.value = lexer.value
        patterns = lexer.patterns()
        self.calls = patterns["FAST_CALLS"].match
        self.decls = patterns["FAST_DECLS"].match
        self.heads = {kind: patterns[f"FAST_{kind.upper()}"].match for kind in _HEADS}
        self.heads["trap"] = _TRAP_HEAD.match
        self.builder = lexer.builder
        self.split_calls = lexer.split_calls
        self.split_decls = lexer.split_decls
        # complete pieces of a failed read, by the position before their gap:
        # (their end, their nodes)
        self.done: dict[int, tuple[int, list]] = {}
        # where the last read failed: before it, only what that read completed is given
        self.resume = -1
        self.depth = 0

    # ------------------------------------------------------------ statements
    def statements(self, pos: int, top: bool = False) -> tuple[list, int, str | None, int, int]:
        """The statements from `pos` on: them, where the last ends, and the closing
        keyword that ended them (upper case, its start and end; None and where reading
        stopped when something else did). Inside a construct each piece read is kept
        (`done`) until the construct is complete; at the `top`, a compound statement that
        does not read ends the statements before it."""
        text, gap, calls, heads = self.text, _GAP.match, self.calls, self.heads
        done = {} if top else self.done
        known_pieces = self.done
        out: list = []
        while True:
            known = known_pieces.get(pos)
            if known is not None:
                pos = known[0]
                out += known[1]
                continue
            if pos < self.resume:  # before where a read failed: what it read only
                return out, pos, None, pos, pos
            at = gap(text, pos).end()
            first = text[at:at + 1]
            if first in _CLOSING_FIRST:
                keyword = _CLOSING.match(text, at)
                if keyword is not None:
                    return out, pos, keyword.group().upper(), at, keyword.end()
            # A run of calls starts with a name, IF or GOTO, never with another keyword;
            # with IF, only as a compact IF (no THEN) or an IF block on one line.
            kind = _OPENED_BY.get(first)
            head = heads[kind](text, at) if kind is not None else None
            if head is None or (kind == "if" and _ENDIF_ON_LINE.match(text, head.end())):
                m = calls(text, at)
                if m is not None:
                    nodes = self.split_calls(m.group(), at)
                    done[pos] = (m.end(), nodes)
                    out += nodes
                    pos = m.end()
                    continue
                if head is None and kind in _LOOSE_HEADS:
                    head = self._loose_head(kind, at)
            if head is not None:
                if kind == "return":
                    node = self.builder.fast_return_stmt(
                        _Word("FAST_RETURN", text, at, head.end()))
                elif top:
                    try:
                        node = self.compound(kind, head)
                    except _Unread as unread:
                        self.resume = max(self.resume, unread.at)
                        return out, pos, None, at, at
                else:
                    node = self.compound(kind, head)
                done[pos] = (node.end, [node])
                out.append(node)
                pos = node.end
                continue
            node = self._loose(at)
            if node is None:
                return out, pos, None, at, at
            done[pos] = (node.end, [node])
            out.append(node)
            pos = node.end

    def _keyword_statement(self, at: int) -> Any:
        """The node of RETRY, TRYNEXT, EXIT or RAISE and `;` at `at`, or None."""
        text = self.text
        m = _KEYWORD_STATEMENT.match(text, at)
        if m is None:
            return None
        word = m.group(1).upper()
        return getattr(self.builder, f"{word.lower()}_stmt")(
            _Word(word, text, at, m.end(1)), _semi(text, m.end()))

    def _loose(self, at: int, simple: bool = False) -> Any:
        """The node of a statement at `at` that no run or head takes, found loosely by
        its first word (with `simple`, a compact IF's statement), or None."""
        text = self.text
        if text.startswith("%", at):
            return self._late_call(at)
        word = _FIRST_WORD.match(text, at)
        if word is None:
            return None
        upper = word.group().upper()
        if upper not in self.keywords:
            return self._assignment(at) or (None if simple else self._label(at)) \
                or self._call(at)
        if upper == "IF":
            return None if simple else self._compact_if(at)
        if upper == "CONNECT":
            return self._connect(at)
        node = self._keyword_statement(at) or self._valued(at)
        if node is None and simple and upper == "RETURN":
            head = self.heads["return"](text, at)
            if head is not None:
                node = self.builder.fast_return_stmt(_Word("FAST_RETURN", text, at, head.end()))
        return node

    def _assignment(self, at: int) -> Any:
        """The node of an assignment at `at` that no run of calls takes (its value an
        expression the patterns of runs leave out: parentheses in an aggregate, calls in
        a sum), or None."""
        m = _ASSIGNMENT.match(self.text, at)
        if m is None or m.group(1).upper() in self.keywords:
            return None
        return self.assignment(self.text, at, m.start(2), m.end())

    def _loose_head(self, kind: str, at: int) -> _LooseHead | None:
        """The head of an IF, ELSEIF or WHILE (`kind`) at `at` whose condition no fast
        terminal takes, up to its THEN or DO, or None."""
        text = self.text
        m = _LOOSE_HEADS[kind].match(text, at)
        if m is None:
            return None
        cond = self._value(*m.span(2))
        if cond is None:
            return None
        return _LooseHead(_Word(kind.upper(), text, *m.span(1)), cond,
                          _Word(m.group(3).upper(), text, *m.span(3)))

    def _compact_if(self, at: int) -> Any:
        """The node of a compact IF at `at` (`IF (a = 1) OR b x := f(2);`) whose statement
        is an assignment or a call no run takes, or None."""
        text = self.text
        m = _COMPACT_IF.match(text, at)
        if m is None:
            return None
        start, depth = m.end(), 0
        for mark in _CONDITION_MARKS.finditer(text, start):
            if mark.group(1) is not None:  # a word's end, whitespace and a name
                if depth:
                    continue
                end, statement_at = mark.start() + 1, mark.end()
            else:
                char = text[mark.start()]
                if char in _OPENERS:
                    depth += 1
                    continue
                if char == ";":
                    return None
                if char in _CLOSERS:
                    depth -= 1
                    if depth < 0:
                        return None
                ahead = _STATEMENT_AHEAD.match(text, mark.end())
                if depth or ahead is None:  # (after a closing bracket or a string)
                    continue
                end, statement_at = mark.end(), ahead.end()
            if self._operator_around(start, end, statement_at):
                continue
            cond = self._value(start, end)
            statement = self._loose(statement_at, simple=True)
            if cond is None or statement is None:
                return None
            return self.builder.compact_if(_Word("IF", text, at, at + 2), cond, statement)
        return None

    def _operator_around(self, start: int, end: int, after: int) -> bool:
        """Whether a word operator ends the text from `start` (a condition's start) to
        `end` or starts at `after` (`a AND b`, `NOT b`): then the condition goes on."""
        text = self.text
        if _OPERATOR_WORD.match(text, after) is not None:
            return True
        begin = end
        while begin > start and _WORD_CHAR.match(text, begin - 1):
            begin -= 1
        return text[begin:end].upper() in _WORD_OPERATORS

    def _valued(self, at: int) -> Any:
        """The node of RAISE or RETURN of a value no fast terminal takes, or None."""
        text = self.text
        m = _VALUED.match(text, at)
        if m is None:
            return None
        value = self._value(*m.span(2))
        if value is None:
            return None
        word = m.group(1).upper()
        make = self.builder.raise_stmt if word == "RAISE" else self.builder.return_stmt
        return make(_Word(word, text, *m.span(1)), value,
                    _semi(text, m.end()))

    def _call(self, at: int) -> Any:
        """The node of a procedure call at `at` that no run of calls takes (values the
        runs' patterns leave out: `MoveL Offs(p, (i-1)*d, 0, h), v500, z10, t;`,
        `WaitUntil a = [1,2] \\MaxTime:=3;`), or None."""
        text = self.text
        m = _CALL.match(text, at)
        if m is None:
            bare = _BARE_CALL.match(text, at)
            if bare is None or bare.group(1).upper() in self.keywords:
                return None
            return self.builder.procedure_call(_Word("NAME", text, *bare.span(1)),
                                               _semi(text, bare.end()))
        if m.group(1).upper() in self.keywords:
            return None
        arguments = self._arguments(*m.span(2))
        if arguments is None:
            return None
        return self.builder.procedure_call(
            _Word("NAME", text, *m.span(1)), arguments,
            _semi(text, m.end()))

    def _late_call(self, at: int) -> Any:
        """The node of a late-bound call `%expr% arguments;` at `at`, or None."""
        text, builder = self.text, self.builder
        m = _LATE_CALL.match(text, at)
        if m is None:
            return None
        target = self._value(*m.span(1))
        if target is None:
            return None
        semi = _semi(text, m.end())
        percent = _Word("PERCENT", text, at, at + 1)
        if not m.group(2).strip(WS_CHARS):
            return builder.late_call(percent, target, semi)
        arguments = self._arguments(*m.span(2))
        if arguments is None:
            return None
        return builder.late_call(percent, target, arguments, semi)

    def _arguments(self, start: int, end: int) -> Any:
        """The `arguments` node of text[start:end], read as the grammar reads them (the
        first required or optional, each later one required after a comma or optional
        after a backslash, perhaps with a comma before it), or None."""
        text = self.text
        cuts: list[int] = []  # each `,` and `\\` outside brackets and strings
        depth = 0
        for m in _LIST_MARKS.finditer(text, start, end):
            char = text[m.start()]
            if char in _OPENERS:
                depth += 1
            elif char in _CLOSERS:
                depth -= 1
                if depth < 0:
                    return None
            elif depth == 0 and char != '"':
                cuts.append(m.start())
        if depth:
            return None
        arguments = []
        bounds = [start - 1, *cuts, end]  # piece k lies between bounds k and k + 1
        for k in range(len(bounds) - 1):
            mark = bounds[k] if k else None
            first, last = bounds[k] + 1, bounds[k + 1]
            if mark is not None and text[mark] == "\\":
                argument = self._optional(mark, first, last)
            elif not text[first:last].strip(WS_CHARS):
                # nothing before a first optional argument, or a comma before one
                if last < end and text[last] == "\\":
                    continue
                return None
            else:
                argument = self._required(first, last)
            if argument is None:
                return None
            arguments.append(argument)
        return self.builder.arguments(*arguments)

    def _required(self, start: int, end: int) -> Any:
        """A required argument (a value, or `name := value`) in text[start:end], or None."""
        text, builder = self.text, self.builder
        named = _NAMED.match(text, start, end)
        if named is None:
            value = self._value(start, end)
            return None if value is None else builder.required_argument(value)
        if named.group(1).upper() in self.keywords:
            return None
        value = self._value(named.end(), end)
        if value is None:
            return None
        return builder.required_argument(_Word("NAME", text, *named.span(1)), value)

    def _optional(self, slash: int, start: int, end: int) -> Any:
        """The optional argument whose backslash is at `slash` (`\\name`, `\\name :=
        value` or, conditional, `\\name ? name`), its text after the backslash
        text[start:end], or None."""
        text, builder = self.text, self.builder
        m = _OPTIONAL_NAME.match(text, start, end)
        if m is None or m.group(1).upper() in self.keywords:
            return None
        backslash = _Word("BACKSLASH", text, slash, slash + 1)
        name = _Word("NAME", text, *m.span(1))
        rest = m.end()
        if rest == end:
            return builder.optional_argument(backslash, name)
        if text.startswith(":=", rest):
            value = self._value(rest + 2, end)
            return None if value is None else builder.optional_argument(backslash, name, value)
        if text[rest] == "?":
            param = _OPTIONAL_NAME.match(text, rest + 1, end)
            if param is None or param.end() != end or param.group(1).upper() in self.keywords:
                return None
            return builder.conditional_argument(backslash, name,
                                                _Word("NAME", text, *param.span(1)))
        return None

    def _value(self, start: int, end: int) -> Any:
        """The expression node of text[start:end] (whitespace around it), or None."""
        raw = self.text[start:end]
        value = raw.strip(WS_CHARS)
        if not value:
            return None
        return self.value(value, start + len(raw) - len(raw.lstrip(WS_CHARS)))

    def _label(self, at: int) -> Any:
        """The node of a label `name:` at `at` (its name no keyword), or None."""
        m = _LABEL.match(self.text, at)
        if m is None or m.group(1).upper() in self.keywords:
            return None
        text = self.text
        return self.builder.label(_Word("NAME", text, *m.span(1)),
                                  _Word("COLON", text, m.end() - 1, m.end()))

    def _connect(self, at: int) -> Any:
        """The node of `CONNECT name WITH trap;` at `at`, or None."""
        m = _CONNECT.match(self.text, at)
        if m is None:
            return None
        text, builder = self.text, self.builder
        target = builder.name_ref(_Word("NAME", text, m.start(1), m.end(1)))
        return builder.connect_stmt(
            _Word("CONNECT", text, at, at + 7), target, _Word("WITH", text, *m.span(2)),
            _Word("NAME", text, *m.span(3)), _semi(text, m.end()))

    def _body(self, pos: int, *closing: str) -> tuple[list, str, int, int]:
        """Statements up to one of the `closing` keywords, or _Unread."""
        body, _, word, at, end = self.statements(pos)
        if word not in closing:
            raise _Unread(at)
        return body, word, at, end

    def compound(self, kind: str, head: re.Match[str]) -> Any:
        """The node of the compound statement whose head `head` matched, or _Unread."""
        if self.depth >= DEPTH_LIMIT:
            raise _Unread(head.start())
        mark = len(self.done)
        self.depth += 1
        try:
            if kind == "if":
                node = self._if(head)
            elif kind == "test":
                node = self._test(head)
            else:
                closing = "ENDWHILE" if kind == "while" else "ENDFOR"
                body, _, at, end = self._body(head.end(), closing)
                last = _Word(closing, self.text, at, end)
                if type(head) is _LooseHead:
                    node = self.builder.while_stmt(head.keyword, head.cond, head.closing,
                                                   *body, last)
                else:
                    make = self.builder.fast_while_stmt if kind == "while" else \
                        self.builder.fast_for_stmt
                    node = make(_Word(f"FAST_{kind.upper()}", self.text, head.start(),
                                      head.end()), *body, last)
        finally:
            self.depth -= 1
        self._forget_inside(mark)
        return node

    def _forget_inside(self, mark: int) -> None:
        """Forget the pieces kept since `done` held `mark` of them: the construct that
        holds them is complete (and kept itself, if it is inside another)."""
        done = self.done
        while len(done) > mark:
            done.popitem()

    def _if(self, head: re.Match[str]) -> Any:
        """An IF's node from its head on: its branches, an ELSE, the ENDIF."""
        text, builder = self.text, self.builder
        rest, word, at, end = self._body(head.end(), "ELSEIF", "ELSE", "ENDIF")
        clauses, word, at, end = self._clauses("elseif", word, at, end, "ELSE", "ENDIF")
        rest += clauses
        if word == "ELSE":
            else_token = _Word("ELSE", text, at, end)
            body, word, at, end = self._body(end, "ENDIF")
            rest.append(builder.else_clause(else_token, *body))
        endif = _Word("ENDIF", text, at, end)
        if type(head) is _LooseHead:
            return builder.if_stmt(head.keyword, head.cond, head.closing, *rest, endif)
        return builder.fast_if_stmt(_Word("FAST_IF", text, head.start(), head.end()), *rest,
                                    endif)

    def _clauses(self, kind: str, word: str, at: int, end: int, *after: str
                 ) -> tuple[list, str, int, int]:
        """The ELSEIF (`kind` 'elseif') or CASE ('case') clauses from the keyword `word`
        at `at` (ending at `end`) on, each its head and statements up to its own keyword
        or one of `after` (else _Unread); then the keyword after them, its start and
        end."""
        text, keyword = self.text, kind.upper()
        make = self.builder.fast_elseif_clause if kind == "elseif" else \
            self.builder.fast_case_clause
        clauses: list = []
        while word == keyword:
            clause = self.heads[kind](text, at)
            if clause is None and kind == "elseif":
                clause = self._loose_head(kind, at)
            if clause is None:
                raise _Unread(at)
            body, word, next_at, end = self._body(clause.end(), keyword, *after)
            if type(clause) is _LooseHead:
                clauses.append(self.builder.elseif_clause(clause.keyword, clause.cond,
                                                          clause.closing, *body))
            else:
                clauses.append(make(_Word(f"FAST_{keyword}", text, at, clause.end()), *body))
            at = next_at
        return clauses, word, at, end

    def _test(self, head: re.Match[str]) -> Any:
        """A TEST's node from its head on: CASE clauses, a DEFAULT, the ENDTEST."""
        text, builder = self.text, self.builder
        at = _GAP.match(text, head.end()).end()
        keyword = _CLOSING.match(text, at)
        if keyword is None:
            raise _Unread(at)
        clauses, word, at, end = self._clauses("case", keyword.group().upper(), at,
                                               keyword.end(), "DEFAULT", "ENDTEST")
        if word == "DEFAULT":
            default_token = _Word("DEFAULT", text, at, end)
            colon = _DEFAULT_COLON.match(text, default_token.end_pos)
            if colon is None:
                raise _Unread(at)
            body, word, at, end = self._body(colon.end(), "ENDTEST")
            clauses.append(builder.default_clause(default_token, *body))
        if word != "ENDTEST":
            raise _Unread(at)
        return builder.fast_test_stmt(_Word("FAST_TEST", text, head.start(), head.end()),
                                      *clauses, _Word("ENDTEST", text, at, end))

    # ------------------------------------------------------------ routines
    def routine(self, head: re.Match[str], kind: str) -> Any:
        """The node of the routine whose head `head` matched (`kind` 'proc', 'func' or
        'trap'), or _Unread."""
        text = self.text
        closing = f"END{kind.upper()}"
        items: list = []
        pos = head.end()
        handlers = False
        mark = len(self.done)
        while True:
            at = _GAP.match(text, pos).end()
            decls = None if handlers else self.decls(text, at)
            if decls is not None:
                # kept as a piece too: were the routine not to read, the parser gets its
                # data where it reaches it, among its statements (a body takes both)
                nodes = self.split_decls(decls.group(), at)
                self.done[pos] = (decls.end(), nodes)
                items += nodes
                pos = decls.end()
                continue
            body, pos, word, at, end = self.statements(pos)
            items += body
            if word is None and not handlers and body and self.decls(text, at) is not None:
                continue
            if word == closing:
                break
            if word not in ("ERROR", "UNDO", "BACKWARD"):
                raise _Unread(at)
            handler_token = _Word(word, text, at, end)
            numbers: list = []
            opened = _NUMBERS.match(text, end) if word == "ERROR" else None
            if opened is not None:
                listed = self._error_numbers(opened.end() - 1)
                if listed is None:
                    raise _Unread(at)
                numbers, end = [listed[0]], listed[1]
            body, word, at, end = self._handler_body(end, closing)
            handler = {"ERROR": self.builder.error_handler, "UNDO": self.builder.undo_handler,
                       "BACKWARD": self.builder.backward_handler}[handler_token.type]
            items.append(handler(handler_token, *numbers, *body))
            handlers = True
            if word == closing:
                break
            pos = at  # the next handler's keyword
        self._forget_inside(mark)
        end_word = _Word(closing, text, at, end)
        if kind == "trap":  # the plain rule's words: LOCAL? TRAP NAME
            local = head.start(1) >= 0
            words = [_Word("LOCAL", text, head.start(1), head.end(1))] if local else []
            words += [_Word("TRAP", text, head.start(2), head.end(2)),
                      _Word("NAME", text, head.start(3), head.end(3))]
            return self.builder.trap(*words, *items, end_word)
        return self.builder._fast_routine(
            kind.upper(), _Word(f"FAST_{kind.upper()}", text, head.start(), head.end()),
            (*items, end_word))

    def _error_numbers(self, opened: int) -> tuple[Any, int] | None:
        """The error numbers of an ERROR handler, `(expr, ...)` with its `(` at `opened`:
        their node and where the `)` ends, or None."""
        text, values = self.text, []
        depth, piece = 0, opened + 1
        for mark in _LIST_MARKS.finditer(text, opened):
            char = text[mark.start()]
            if char in _OPENERS:
                depth += 1
            elif char in _CLOSERS:
                depth -= 1
                if depth == 0:
                    if char != ")":
                        return None
                    values.append(self._value(piece, mark.start()))
                    if any(value is None for value in values):
                        return None
                    return self.builder.error_numbers(*values), mark.end()
            elif char == "," and depth == 1:
                values.append(self._value(piece, mark.start()))
                piece = mark.end()
            elif char in ";\\" and depth:
                return None
        return None

    def _handler_body(self, pos: int, closing: str) -> tuple[list, str, int, int]:
        return self._body(pos, "ERROR", "UNDO", "BACKWARD", closing)

    def module_items(self, pos: int) -> tuple[list, int]:
        """Routines and declarations from `pos` on, as far as they read: a routine that
        does not read ends them."""
        text, heads = self.text, self.heads
        out: list = []
        decls_from: tuple[int, int] | None = None  # before the last items, if declarations
        while pos >= self.resume:
            at = _GAP.match(text, pos).end()
            decls = self.decls(text, at)
            if decls is not None:
                decls_from = (pos, len(out))
                out += self.split_decls(decls.group(), at)
                pos = decls.end()
                continue
            for kind in ("proc", "func", "trap"):
                head = heads[kind](text, at)
                if head is not None:
                    break
            else:
                if decls_from is not None and _GLUED_KEYWORD.match(text, at):
                    # after declarations the plain grammar's state takes a name (LALR
                    # merged a module's data with a routine body's): `PERSspeeddata` is
                    # a name there, and wrong; after this token no name is taken, and
                    # the contextual lexer would read PERS out of the word. The
                    # declarations are left to the parser, which meets it as a name.
                    pos, count = decls_from
                    del out[count:]
                break
            try:
                node = self.routine(head, kind)
            except _Unread as unread:
                self.resume = max(self.resume, unread.at)
                break
            out.append(node)
            pos = node.end
            decls_from = None
        return out, pos


def _advance(line_ctr: Any, text: str, end: int) -> None:
    """Lark's LineCounter.feed of text[line_ctr.char_pos:end], without the copy."""
    start = line_ctr.char_pos
    newlines = text.count("\n", start, end)
    if newlines:
        line_ctr.line += newlines
        line_ctr.line_start_pos = text.rindex("\n", start, end) + 1
    line_ctr.char_pos = end
    line_ctr.column = end - line_ctr.line_start_pos + 1


class BlockLexer:
    """The `lex` of a contextual lexer, with the reader run ahead where it may."""

    def __init__(self, lexer: Any, builder: Any, split_calls: Callable[[str, int], list],
                 split_decls: Callable[[str, int], list],
                 assignment: Callable[[str, int, int, int], Any],
                 value: Callable[[str, int], Any]) -> None:
        self.lexer = lexer
        self.assignment = assignment
        self.value = value
        self._patterns: dict[str, re.Pattern[str]] | None = None
        # the builder's callbacks, bound once (each lookup of a Lark v_args method makes
        # a wrapper)
        self.builder = SimpleNamespace(**{
            name: getattr(method, "base_func", method)
            for name in _CALLBACKS for method in (getattr(builder, name),)})
        self.split_calls = split_calls
        self.split_decls = split_decls
        accepts = {state: {t.name for t in basic.terminals}
                   for state, basic in lexer.lexers.items()}
        # (upper case: a label is no keyword)
        self.keywords = frozenset(
            t.pattern.value.upper() for t in lexer.root_lexer.terminals
            if t.pattern.type == "str" and t.pattern.value.isalpha())
        self.block_states = frozenset(s for s, names in accepts.items() if BLOCK in names)
        self.routine_states = frozenset(s for s, names in accepts.items() if ROUTINES in names)

    def patterns(self) -> dict[str, re.Pattern[str]]:
        """The fast terminals the reader matches with, compiled when first read with (the
        large ones are those the lexer's scanners share)."""
        if self._patterns is None:
            root = self.lexer.root_lexer
            self._patterns = {name: compiled_alone(root, name) for name in PATTERNS}
        return self._patterns

    def lex(self, lexer_state: Any, parser_state: Any) -> Iterator[Token]:
        """Lark's ContextualLexer.lex, giving FAST_BLOCK / FAST_ROUTINES tokens where the
        reader reads ahead."""
        if not READ_AHEAD:
            yield from type(self.lexer).lex(self.lexer, lexer_state, parser_state)
            return
        lexers, either = self.lexer.lexers, self.block_states | self.routine_states
        raw = lexer_state.text
        text = getattr(raw, "text", raw)
        reader: Reader | None = None  # made where first needed
        line_ctr = lexer_state.line_ctr
        try:
            while True:
                state = parser_state.position
                if state in either:
                    pos = line_ctr.char_pos
                    token = None
                    if reader is not None and pos in reader.done:  # (statements only)
                        token = self._read(reader, True, pos)
                    elif reader is None or pos >= reader.resume:
                        statements = self._opens(state, text, _GAP.match(text, pos).end())
                        if statements is not None:
                            if reader is None:
                                reader = Reader(text, self)
                            token = self._read(reader, statements, pos)
                    if token is not None:
                        _advance(line_ctr, text, token.start_pos)  # the gap, as Lark skips it
                        token.line, token.column = line_ctr.line, line_ctr.column
                        _advance(line_ctr, text, token.end_pos)
                        token.end_line, token.end_column = line_ctr.line, line_ctr.column
                        lexer_state.last_token = token
                        yield token
                        continue
                try:
                    token = lexers[state].next_token(lexer_state, parser_state)
                except UnexpectedCharacters:
                    # Lark's own loop meets the same characters in the same state, and
                    # says what it says of them
                    yield from type(self.lexer).lex(self.lexer, lexer_state, parser_state)
                    return
                yield token
        except EOFError:
            pass

    def _opens(self, state: int, text: str, at: int) -> bool | None:
        """What the reader may find at `at` in parser state `state`: statements from a
        compound one (True), module items from a routine (False), or nothing (None).

        (A state after a run of declarations is both a module's and a routine body's:
        LALR merges them, and a routine's head tells which it is.)"""
        first = text[at:at + 1]
        if state not in self.routine_states:
            return True if first in _STATEMENT_OPENERS else None
        if state not in self.block_states:
            return False if first in _ITEM_OPENERS else None
        # both: a routine's head is no statement, and only a routine's head tells a
        # module from a routine's body (PERS, LOCAL and TASK start either's data)
        if _ROUTINE_HEAD.match(text, at):
            return False
        return True if first in _STATEMENT_OPENERS else None

    @staticmethod
    def _read(reader: Reader, statements: bool, pos: int) -> _ReadToken | None:
        """The token read at `pos`, or None if nothing was."""
        text = reader.text
        if statements:
            nodes, end, _, _, _ = reader.statements(pos, top=True)
        else:
            nodes, end = reader.module_items(pos)
        if not nodes:
            return None
        start = nodes[0].start
        if _GAP.match(text, pos).end() != start:  # pragma: no cover - the lexer's own then
            return None
        # (its value: the first line of the text it stands for, which may be a whole
        # module; its offsets say where all of it is)
        line_end = text.find("\n", start, end)
        token = _ReadToken(BLOCK if statements else ROUTINES,
                           text[start:end if line_end < 0 else line_end], start_pos=start,
                           end_pos=end)
        token.nodes = nodes
        if reader.done:  # what a failed read kept: the parser is past these
            reader.done = {k: v for k, v in reader.done.items() if k >= end}
        return token
