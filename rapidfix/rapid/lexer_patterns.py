"""One compiled regular expression per large terminal, shared by every lexer state.

Lark's contextual lexer gives each parser state a scanner of the terminals that state
accepts, compiled as one alternation on first use. The fast terminals
(`fastpath`: a whole run of declarations or calls, several kilobytes of pattern) are
accepted in several states, so every one of those compiled them again: about 0.1 s
of a small file's `rapidfix check`, more than its parse. Here a scanner matches each
large terminal at the head of its list with its own pattern, compiled once for every
state, and the rest as Lark does. Tried in the same
order as the alternation would try them, the first that matches wins, so the tokens
are the same.
"""

from __future__ import annotations

from typing import Any

import lark.lexer
from lark import Lark
from lark.lexer import BasicLexer, Scanner

#: a terminal whose pattern is longer than this is matched on its own
LARGE_PATTERN = 1000


# Each large terminal's compiled expression, by its name, pattern and flags: kept here,
# not left to `re`'s own cache, which a long process (a batch, the test suite) fills
# with other patterns and empties oldest first.
_COMPILED: dict[tuple[str, str, Any, Any], list[Any]] = {}


class _SharingScanner(Scanner):
    """Lark's scanner, with the leading large terminals each compiled alone, once."""

    def _build_mres(self, terminals: list[Any], max_size: int) -> list[Any]:
        head = 0
        while head < len(terminals) and len(terminals[head].pattern.to_regexp()) > LARGE_PATTERN:
            head += 1
        mres = []
        for terminal in terminals[:head]:
            key = (terminal.name, terminal.pattern.to_regexp(), self.g_regex_flags, self.re_)
            compiled = _COMPILED.get(key)
            if compiled is None:
                compiled = _COMPILED[key] = super()._build_mres([terminal], 1)
            mres.extend(compiled)
        rest = terminals[head:]
        return mres + (super()._build_mres(rest, len(rest)) if rest else [])


def _build_sharing_scanner(lexer: BasicLexer) -> Scanner:
    """Lark's own `_build_scanner` (it sets the lexer's callbacks too), making ours.
    (Were another thread to build a scanner meanwhile, it would get ours: the same tokens.)"""
    lark.lexer.Scanner = _SharingScanner
    try:
        return BasicLexer._build_scanner(lexer)
    finally:
        lark.lexer.Scanner = Scanner


def share_large_patterns(parser: Lark) -> Lark:
    """Make `parser`'s contextual lexer compile each large terminal once (see the module)."""
    lexer = parser.parser.lexer
    states = [*getattr(lexer, "lexers", {}).values(), getattr(lexer, "root_lexer", None)]
    for state in {id(s): s for s in states if isinstance(s, BasicLexer)}.values():
        state._build_scanner = lambda state=state: _build_sharing_scanner(state)
    return parser


def compiled_alone(lexer: BasicLexer, name: str) -> Any:
    """Terminal `name` of `lexer` compiled on its own as its scanners compile it (a large
    one is then the very pattern they match with, compiled once)."""
    terminal = lexer.terminals_by_name[name]
    scanner = _SharingScanner([terminal], lexer.g_regex_flags, lexer.re, lexer.use_bytes)
    return scanner._mres[0]


__all__ = ["LARGE_PATTERN", "compiled_alone", "share_large_patterns"]
