"""The fast terminals' patterns are compiled once for all lexer states, with the same tokens."""

from __future__ import annotations

from pathlib import Path

import pytest
from lark import Lark

from rapidfix.rapid.fastpath import FastSyntaxBuilder, cached_extension, fast_parser
from rapidfix.rapid.grammar import grammar_text
from rapidfix.rapid.lexer_patterns import LARGE_PATTERN, share_large_patterns
from rapidfix.rapid.readback import run_parser

SAMPLES = Path(__file__).resolve().parents[2] / "samples"


def _scanners(parser: Lark) -> list:
    lexer = parser.parser.lexer
    return [s._scanner for s in lexer.lexers.values() if s._scanner is not None]


@pytest.mark.parametrize("make", [fast_parser, run_parser], ids=["parse", "read-back"])
def test_each_large_pattern_is_one_compiled_expression_in_every_state(make):
    parser = make()
    for sample in sorted(SAMPLES.glob("*.mod")):
        parser.parse(sample.read_text(encoding="utf-8", errors="replace"))
    by_terminal: dict[str, set[int]] = {}
    states = 0
    for scanner in _scanners(parser):
        for mre in scanner._mres:
            if len(mre.pattern) > LARGE_PATTERN and len(mre.groupindex) == 1:
                (name,) = mre.groupindex
                by_terminal.setdefault(name, set()).add(id(mre))
                states += 1
    assert {"FAST_CALLS", "FAST_DECLS"} <= set(by_terminal)
    assert states > len(by_terminal)  # several states accept them ...
    assert all(len(ids) == 1 for ids in by_terminal.values())  # ... and share one each


def test_the_same_trees_as_lark_own_scanners():
    grammar = grammar_text()
    own = Lark(grammar + cached_extension(grammar), parser="lalr", lexer="contextual",
               transformer=FastSyntaxBuilder(), cache=True)
    for sample in sorted(SAMPLES.glob("*.mod")):
        text = sample.read_text(encoding="utf-8", errors="replace")
        assert repr(fast_parser().parse(text)) == repr(own.parse(text)), sample.name


def test_the_large_patterns_stay_shared_when_res_cache_is_emptied(monkeypatch):
    """A long process (a batch, the test suite, a count of many names) compiles more
    patterns than `re` keeps: the large terminals must still be compiled once for all
    states, not again in every state built after `re` dropped them."""
    import re

    from rapidfix.rapid import lexer_patterns

    build = lexer_patterns._SharingScanner._build_mres

    def build_after_churn(self, terminals, max_size):
        for k in range(600):  # more than re's cache holds
            re.compile(f"churn{k}_{id(self)}")
        return build(self, terminals, max_size)

    monkeypatch.setattr(lexer_patterns._SharingScanner, "_build_mres", build_after_churn)
    grammar = grammar_text()
    parser = share_large_patterns(Lark(grammar + cached_extension(grammar), parser="lalr",
                                       lexer="contextual", transformer=FastSyntaxBuilder(),
                                       cache=True))
    test_each_large_pattern_is_one_compiled_expression_in_every_state(lambda: parser)
