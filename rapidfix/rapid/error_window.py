"""The part of a program a syntax error can be explained from, so that the plain
grammar need not read a whole large file again to name one error near its end.

The fast parser reads a file in one pass; when it stops on a syntax error, the plain
grammar decides (and explains) what is wrong, and the plain grammar is several times
slower. Yet everything before the error was read without fault, so the module items
before the one holding the error can be left out: `window` blanks them (every
character but line breaks becomes a space, so offsets, lines and columns stay).
Inside a module item the LALR states do not depend on how many items came before
(the parse table reaches the same state on the item's first keyword), so the plain
grammar meets the same error, expects the same tokens and says the same.

A long routine is windowed the same way inside: the declarations and statements of
its body the parser had completed (it holds them on its stack) are blanked but the
last, so the parser reaches the error in the state it had after them (a body of one
item or of many: the same LALR state). A truncated CAM program, its one routine never
closed, is then explained from its last statement, not read whole again.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from lark import Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from rapidfix.rapid import syntax as s

# The first keyword of a module item at the start of a line: a routine (only ever a
# module item), or a data declaration (a module item when it is not inside a routine).
_ROUTINE = re.compile(r"^[ \t]*(?:LOCAL[ \t]+)?(PROC|FUNC|TRAP)\b", re.I | re.M)
_ROUTINE_END = re.compile(r"^[ \t]*(ENDPROC|ENDFUNC|ENDTRAP)\b", re.I | re.M)
_DATA = re.compile(r"^[ \t]*(?:(?:LOCAL|TASK)[ \t]+)*(CONST|VAR|PERS|RECORD|ALIAS)\b",
                   re.I | re.M)
_MODULE = re.compile(r"^[ \t]*MODULE\b[^\r\n]*(?:\r\n|\r|\n)", re.I | re.M)
_RECORD = re.compile(r"^[ \t]*(?:LOCAL[ \t]+)?(RECORD)\b", re.I | re.M)
_RECORD_END = re.compile(r"^[ \t]*(ENDRECORD)\b", re.I | re.M)
_NOT_BREAK = re.compile(r"[^\r\n]+")
_PREFIXES = re.compile(r"(?:(?:LOCAL|TASK)\s+)*", re.I)
_MODULE_ITEMS = (s.DataDecl, s.RecordDecl, s.AliasDecl, s.Routine)
# Below this many characters left out, the plain grammar may as well read it all.
_WORTH = 20_000


def body_span(err: UnexpectedInput) -> tuple[int, int] | None:
    """(start of the first, start of the last) of the items of the routine body a
    parser had completed when it met `err`, or None when it was not in a routine's
    body or had completed fewer than two."""
    interactive = getattr(err, "interactive_parser", None)
    if interactive is None:
        return None
    read: list = []  # the items of a token fast_blocks read, not yet reduced
    for value in reversed(interactive.parser_state.value_stack):
        if getattr(value, "data", "").startswith("___body_star"):
            items = [*value.children, *read]
        elif read and getattr(value, "type", "") in ("FAST_PROC", "FAST_FUNC"):
            items = read  # the token is the body's first
        else:
            read = list(getattr(value, "nodes", ()))
            continue
        if len(items) < 2:
            return None
        return items[0].start, items[-1].start
    return None


@dataclass(frozen=True)
class Window:
    """`text` with the module items before the error's blanked, and the completed items
    of the routine it is in but the last; `cut` is the end of the last blanked part (the
    first keyword of the item the error is in or after, or the start of the routine's
    last completed item)."""

    text: str
    cut: int


def error_offset(err: UnexpectedInput, text: str) -> int:
    """Where a Lark parse error stands in `text` (its end for an unexpected end)."""
    if isinstance(err, UnexpectedToken):
        return len(text) if err.token.type == "$END" else err.token.start_pos
    if isinstance(err, UnexpectedCharacters):
        return err.pos_in_stream
    return len(text)


def _last(pattern: re.Pattern[str], text: str, start: int, end: int) -> int:
    """Offset of the keyword of the last match of `pattern` in text[start:end], or -1.

    The keyword is matched in its whole line, so that an error inside a word does not
    cut it into one (`CONST1_a`, an error at its `1` when the parser read `CONST` as the
    keyword: no item starts there, and the window must keep the item before)."""
    found = -1
    line_end = text.find("\n", end)
    for match in pattern.finditer(text, start, len(text) if line_end < 0 else line_end):
        if match.end(1) > end:
            break
        found = match.start(1)
    return found


def window(text: str, err: UnexpectedInput) -> Window | None:
    """The window for an error `err` a parser met having read everything before it, or
    None when too little would be left out.

    The cut is the first keyword of the last module item that starts before the error
    (the parser took that keyword, so every item before it is complete): the last
    routine, or a declaration after it ends (module data). The blanked part starts on
    the line after its module's `MODULE` line. The completed items of the routine the
    error is in are blanked too, but the last (body_span)."""
    error_at = error_offset(err, text)
    cut = _last(_ROUTINE, text, 0, error_at)
    ended = _last(_ROUTINE_END, text, max(cut, 0), error_at)
    in_routine = cut >= 0 and ended < 0
    if not in_routine:  # the error is in module data: cut at its declaration
        cut = max(cut, _last(_DATA, text, max(ended, 0), error_at))
    spans = []
    module_span = _module_items(text, cut)
    if module_span is not None and _took_keyword(err, text, cut):
        spans.append(module_span)
    body = body_span(err)
    if body is not None and in_routine and cut < body[0] < body[1] < error_at:
        spans.append(body)
    if sum(end - start for start, end in spans) < _WORTH:
        return None
    out, at = [], 0
    for start, end in spans:
        out += [text[at:start], _NOT_BREAK.sub(lambda m: " " * len(m.group()), text[start:end])]
        at = end
    return Window("".join(out) + text[at:], at)


def _took_keyword(err: UnexpectedInput, text: str, at: int) -> bool:
    """Whether the parser took the text at offset `at` as the first keyword of a module
    item: it holds the keyword unreduced (alone, or in a procedure's fast head), or a
    completed item (after its LOCAL or TASK) that starts there. A `VAR` at the start of
    a line inside a declaration's value, read as a name, is no cut."""
    interactive = getattr(err, "interactive_parser", None)
    if interactive is None:
        return False
    for value in interactive.parser_state.value_stack:
        nodes = getattr(value, "nodes", None)  # a token fast_blocks read: its items
        if nodes:
            value = Tree("_read", nodes)
        if isinstance(value, Token):
            if value.start_pos == at and value.type == value.upper():
                return True
            # the fast parser's head of a procedure, `LOCAL PROC name()` in one token
            if value.type == "FAST_PROC" and value.start_pos <= at < value.end_pos:
                return True
            continue
        # a run of items (a star of the grammar, a run of fast declarations): its last
        node = value.children[-1] if isinstance(value, Tree) and value.children else value
        if (isinstance(node, _MODULE_ITEMS) and node.start <= at < node.end
                and _PREFIXES.fullmatch(text, node.start, at)):
            return True
    return False


def _module_items(text: str, cut: int) -> tuple[int, int] | None:
    """(after the MODULE line, cut): the module items before the cut, when they are
    complete (the cut a module item's keyword), else None."""
    head = -1
    for match in _MODULE.finditer(text, 0, max(cut, 0)):
        head = match.end()
    if cut < 0 or head < 0:
        return None
    # The contextual lexer reads PROC or VAR as a name where the keyword cannot stand
    # (a record's field type, a call's name in a routine): the cut is a module item only
    # when every routine and record before it, in its module, is closed.
    for opening, closing in ((_ROUTINE, _ROUTINE_END), (_RECORD, _RECORD_END)):
        if (sum(1 for _ in opening.finditer(text, head, cut))
                != sum(1 for _ in closing.finditer(text, head, cut))):
            return None
    return head, cut


def confirms(window_err: UnexpectedInput, win: Window, error_at: int) -> bool:
    """Whether the plain grammar met its error in the window where the whole text's
    parser met it (`error_at`), past the cut: then it took the item's keyword in the
    window too, and the error is the whole text's."""
    return error_offset(window_err, win.text) == error_at > win.cut
