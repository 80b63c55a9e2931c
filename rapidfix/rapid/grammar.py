"""Find grammars/rapid.lark at run time and build the LALR parser once.

An installed wheel carries the grammar as package data at
`rapidfix/grammars/rapid.lark`; a source tree or an editable install reads it
from `<repo>/grammars/rapid.lark`.
"""

from __future__ import annotations

import functools
from importlib import resources
from pathlib import Path

from lark import Lark

from rapidfix.exceptions import RapidfixError
from rapidfix.rapid.transform import SyntaxBuilder

GRAMMAR_NAME = "rapid.lark"
#: where a source checkout (or an editable install) keeps the grammar
SOURCE_TREE_GRAMMAR = Path(__file__).resolve().parents[2] / "grammars" / GRAMMAR_NAME


def grammar_text() -> str:
    """The text of rapid.lark, from the installed package or else the source tree."""
    try:
        packaged = resources.files("rapidfix").joinpath("grammars", GRAMMAR_NAME)
        if packaged.is_file():
            return packaged.read_text(encoding="utf-8")
    except (FileNotFoundError, ModuleNotFoundError, NotADirectoryError):
        pass
    if SOURCE_TREE_GRAMMAR.is_file():
        return SOURCE_TREE_GRAMMAR.read_text(encoding="utf-8")
    raise RapidfixError(
        f"the RAPID grammar {GRAMMAR_NAME} is missing from the installed package "
        f"and from the source tree ({SOURCE_TREE_GRAMMAR})",
        hint="reinstall rapidfix",
    )


@functools.lru_cache(maxsize=1)
def rapid_parser() -> Lark:
    """The LALR parser with the contextual lexer; it builds syntax nodes directly.

    Lark caches the analysed parse table in the temporary folder, keyed by the
    grammar text, so later processes start faster.
    """
    return Lark(
        grammar_text(),
        parser="lalr",
        lexer="contextual",
        transformer=SyntaxBuilder(),
        cache=True,
    )


@functools.lru_cache(maxsize=1)
def diagnosis_parser() -> Lark:
    """The same grammar without the transformer, used only to explain a syntax error:
    its interactive parser can tell exactly which tokens would have been accepted."""
    return Lark(grammar_text(), parser="lalr", lexer="contextual", cache=True)


@functools.lru_cache(maxsize=1)
def terminal_patterns() -> dict[str, str | None]:
    """Terminal name -> its literal text (None for a regular expression)."""
    parser = rapid_parser()
    return {
        term.name: (term.pattern.value if term.pattern.type == "str" else None)
        for term in parser.terminals
    }
