"""Turn Lark's parse errors into one readable RapidSyntaxError.

`file:line:col: unexpected 'X'; expected one of ...`, with terminal names in
words a RAPID programmer knows, plus clear messages for RobotStudio's
placeholders (`<SMT>`, `<EXP>`, ...) where their kind cannot stand, and for text
after the last ENDMODULE. (Where it can stand, a placeholder is RAPID: see
rapid.lark.)
"""

from __future__ import annotations

import re

from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid.error_window import confirms, error_offset, window
from rapidfix.rapid.fast_expressions import STRING
from rapidfix.rapid.grammar import diagnosis_parser, terminal_patterns
from rapidfix.rapid.source import SourceText

_WORDS = {
    "NAME": "a name",
    "NUMBER": "a number",
    "STRING": "a string",
    "NUMERIC_AGGREGATE": None,  # always offered together with '['
    "PRG_HEADER": "a %%% header",
    "$END": "end of file",
}
_MAX_EXPECTED = 10

# Groups of terminals said in one phrase when all (or most) of them are expected.
_GROUPS: tuple[tuple[str, frozenset[str], int], ...] = (
    ("a statement", frozenset({"NAME", "IF", "FOR", "WHILE", "TEST", "GOTO", "RETURN", "RAISE",
                               "EXIT", "RETRY", "TRYNEXT", "CONNECT", "PERCENT"}), 10),
    ("a declaration", frozenset({"VAR", "PERS", "CONST", "LOCAL", "TASK"}), 3),
    ("an operator", frozenset({"AND", "OR", "XOR", "DIV", "MOD", "PLUS", "MINUS", "STAR",
                               "SLASH", "EQ", "NE", "LT", "LE", "GT", "GE"}), 8),
)

# Strings and comments are skipped so that '<SMT>' inside them is left alone.
_PLACEHOLDER_SCAN = re.compile(rf"{STRING}|![^\n]*|<[A-Z]{{2,8}}>")


def describe_terminal(name: str) -> str | None:
    """A terminal name in words: 'NAME' -> 'a name', 'SEMI' -> "';'"."""
    if name in _WORDS:
        return _WORDS[name]
    if name.startswith("PH_"):  # placeholders are not offered as what to write
        return None
    literal = terminal_patterns().get(name)
    if literal is not None:
        return f"'{literal.upper()}'" if literal.isalpha() else f"'{literal}'"
    return name.lower()


def describe_expected(names: set[str] | frozenset[str]) -> str:
    """'expected one of ...' from a set of terminal names (grouped, sorted, shortened)."""
    remaining = set(names)
    phrases = []
    for phrase, group, enough in _GROUPS:
        if len(remaining & group) >= enough:
            phrases.append(phrase)
            remaining -= group
    words = phrases + sorted({w for w in (describe_terminal(n) for n in remaining) if w})
    if not words:
        return ""
    if len(words) == 1:
        return f"expected {words[0]}"
    shown = words[:_MAX_EXPECTED]
    more = f", ... ({len(words) - _MAX_EXPECTED} more)" if len(words) > _MAX_EXPECTED else ""
    return "expected one of " + ", ".join(shown) + more


#: the placeholders RAPID knows (rapid.lark takes each where its kind belongs)
PLACEHOLDERS = frozenset({"<ALT>", "<ARG>", "<CSE>", "<DDN>", "<DIM>", "<EIT>", "<EXP>", "<ID>",
                          "<PAR>", "<RDN>", "<SMT>", "<TDN>", "<VAR>"})


def placeholders_in(text: str) -> list[tuple[int, str]]:
    """(offset, text) of every placeholder outside strings and comments, in order.
    In a program that parsed each is one RAPID takes (rapid.lark)."""
    if "<" not in text:  # most programs: no need to step over every comment and string
        return []
    return [(m.start(), m.group(0)) for m in _PLACEHOLDER_SCAN.finditer(text)
            if m.group(0).startswith("<") and m.group(0) in PLACEHOLDERS]


def find_placeholder(source: SourceText, at: int) -> tuple[int, str] | None:
    """The RobotStudio placeholder such as <SMT> that offset `at` falls in, if any.

    A syntax error inside a placeholder's text (at its `<`, or at the `>` of
    `a <EXP> THEN`, which the lexer reads as `a < EXP >`) means that placeholder
    stands where its kind cannot.
    """
    text = source.text
    line_start = text.rfind("\n", 0, at) + 1
    for match in _PLACEHOLDER_SCAN.finditer(text, line_start, source.line_end(at)):
        if match.start() > at:
            break
        if match.group(0).startswith("<") and at < match.end():
            return match.start(), match.group(0)
    return None


def _after_module(text: str) -> bool:
    """Whether `text` (everything before the error) ends a module."""
    return re.search(r"\bENDMODULE\b", text, re.IGNORECASE) is not None


# A number as RAPID writes it (rapid.lark's NUMBER), to tell `1_T_ROB2` from `1.5`.
_NUMBER_TEXT = re.compile(r"0[xX][0-9a-fA-F]+|0[bB][01]+|0[oO][0-7]+"
                          r"|(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")
# A word (letters of ISO 8859-1 included, as in names) or one other character.
_WORD = re.compile(r"[A-Za-z0-9_.\u00c0-\u00d6\u00d8-\u00f6\u00f8-\u00ff]+|\S")


def _snippet(text: str, offset: int) -> str:
    """The offending text at `offset`: one word or one character."""
    match = _WORD.match(text, offset)
    return match.group(0) if match else text[offset:offset + 1]


def _accepted(err: UnexpectedInput) -> set[str] | None:
    """Exactly the terminals the parser would have taken at the error, if Lark can say."""
    interactive = getattr(err, "interactive_parser", None)
    if interactive is None:
        return None
    try:
        return set(interactive.accepts())
    except UnexpectedInput:  # pragma: no cover - accepts() handles its own trials
        return None


def explain(source: SourceText, fallback: UnexpectedInput) -> RapidSyntaxError:
    """Re-parse `source` with the plain parser to name what was expected exactly.

    `fallback` is the plain grammar's error, met having read everything before it, so
    the re-parse may read the error's window (rapid.error_window) instead of the file."""
    text = source.text
    error_at = error_offset(fallback, text)
    # the window the error was met in (fastpath.parse_text), else one worked out here
    win = getattr(fallback, "rapidfix_window", None) or window(text, fallback)
    for candidate in ([win.text] if win is not None else []) + [text]:
        try:
            diagnosis_parser().parse(candidate)
        except UnexpectedInput as err:
            if win is None or candidate is text or confirms(err, win, error_at):
                return translate(err, source, _accepted(err))
    return translate(fallback, source)  # pragma: no cover - both parsers share a grammar


def translate(err: UnexpectedInput, source: SourceText,
              accepted: set[str] | None = None) -> RapidSyntaxError:
    """The RapidSyntaxError for a Lark parse error in `source`."""
    text = source.text
    if isinstance(err, UnexpectedToken) and err.token.type != "$END":
        offset = err.token.start_pos
        found = str(err.token)
        expected = set(err.expected)
    elif isinstance(err, UnexpectedCharacters):
        offset = err.pos_in_stream
        found = _snippet(text, offset)
        expected = set(err.allowed or ())
    else:
        offset = len(text)
        found = ""
        expected = set(getattr(err, "expected", ()) or ())
    if accepted:
        expected = accepted
    placeholder = find_placeholder(source, offset)
    if placeholder is not None:
        where, token = placeholder
        line, column = source.line_column(where)
        what = ("RobotStudio placeholder {} cannot stand here" if token in PLACEHOLDERS
                else "unknown placeholder {}").format(token)
        return RapidSyntaxError(
            f"{what} (unfinished code: replace it)",
            file=source.filename, line=line, column=column,
        )
    line, column = source.line_column(offset)
    if isinstance(err, UnexpectedEOF) or (isinstance(err, UnexpectedToken)
                                          and err.token.type == "$END"):
        message = "unexpected end of file"
    else:
        shown = found if len(found) <= 40 else found[:37] + "..."
        message = f"unexpected {shown!r}"
        word = _WORD.match(text, offset)
        if ("NAME" in expected and word and word.group(0)[0].isdigit()
                and not _NUMBER_TEXT.fullmatch(word.group(0))):
            # `MODULE 1_T_ROB2`: the lexer saw the number 1; say what is wrong
            shown = word.group(0) if len(word.group(0)) <= 40 else word.group(0)[:37] + "..."
            message = f"{shown!r} is not a name (a RAPID name starts with a letter)"
            expected = set()
        if isinstance(err, UnexpectedCharacters) and found == '"':
            expected = set()
            message = "unterminated string (a string ends on the line where it starts)"
        if expected and expected <= {"MODULE", "PRG_HEADER", "$END"}:
            if text.startswith("%%%", offset) and "%%%" not in text[offset + 3:]:
                expected = set()
                message = "unclosed %%% header (a .prg header ends with a second %%% line)"
            elif _after_module(text[:offset]):
                message = f"text after the last ENDMODULE: {shown!r}"
            else:
                message = f"unexpected {shown!r}: a RAPID file starts with MODULE"
    wanted = describe_expected(expected)
    if wanted:
        message += f"; {wanted}"
    return RapidSyntaxError(message, file=source.filename, line=line, column=column)
