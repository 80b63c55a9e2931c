"""The fast terminals' patterns are compiled once for all lexer states, with the same tokens."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from lark import Lark

from rapidfix.rapid.fastpath import FastSyntaxBuilder, _patterns, cached_extension, fast_parser
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


# Pieces of calls as programs write them, keywords and odd spellings among them.
_NAMES = ["p1", "v100", "tool0", "pÖver", "x_1", "Offs", "ENDPROC", "And", "not", "TRUE",
          "false", "MOD", "If", "Stop", "WObj"]
_NUMBERS = ["0", "1.5", "-2", "- 3", ".5", "1e3", "0x1F", "1.", "9E+09", "+1", "1-1"]
_AGGREGATES = ["[[1,2,3],[1,0,0,0]]", "[1, 2]", "[[1,2],3]", "[ ]", "[[-1.5e3,.5],[9E+09]]",
               "[[1,2]", "[1,[2,[3]]]"]
_SPACE = st.sampled_from(["", " ", "  ", "\t", "\n  "])
_ELEMENTS = ["p.trans.x", "path{3}", "grid{i, 2}.trans", "p . trans", "p{i+1}", "q{1}{2}",
             "r.x{2}", "p.", "p{}", "p.1", "p{-1}", "tMill.tframe.trans.z*2", "p.trans.x-1"]


@st.composite
def _plain_value(draw) -> str:
    kind = draw(st.sampled_from(["name", "number", "call", "aggregate", "element"]))
    if kind == "name":
        return draw(st.sampled_from(_NAMES))
    if kind == "element":  # components and indices, some not RAPID (`p.`, `p{}`)
        return draw(st.sampled_from(_ELEMENTS))
    if kind == "number":
        return draw(st.sampled_from(_NUMBERS))
    if kind == "aggregate":
        return draw(st.sampled_from(_AGGREGATES))
    numbers = draw(st.lists(st.sampled_from(_NUMBERS), min_size=1, max_size=4))
    # a name, an inline target, or such a call itself (`RelTool(Offs(p1,0,0,5),0,0,0)`)
    head = draw(st.sampled_from(_NAMES + _AGGREGATES + _ELEMENTS) | _plain_value())
    text = f"{draw(st.sampled_from(_NAMES))}({draw(_SPACE)}{head}"
    offsets = st.sampled_from(_NUMBERS + _NAMES + ["-nLift", "- n", "n.x", "n{2}", "nLift + 5",
                                                    "n*2", "-n / 2", "n -2", "1e-5-1",
                                                    "n MOD 2", "n + -1", "n +"])
    for number in numbers:
        text += f"{draw(_SPACE)},{draw(_SPACE)}{number}"
    for _ in range(draw(st.integers(0, 2))):  # names among them
        text += f"{draw(_SPACE)},{draw(_SPACE)}{draw(offsets)}"
    for _ in range(draw(st.integers(0, 2))):  # optional arguments of numbers or names
        text += (f"{draw(_SPACE)}\\{draw(_SPACE)}{draw(st.sampled_from(_NAMES))}"
                 f"{draw(_SPACE)}:={draw(_SPACE)}{draw(offsets)}")
    return text + f"{draw(_SPACE)})"


@st.composite
def _statement(draw) -> str:
    text = draw(st.sampled_from(_NAMES)) + draw(st.sampled_from([" ", "\t", "", " \n "]))
    text += draw(_plain_value())
    for _ in range(draw(st.integers(0, 5))):
        space = draw(_SPACE)
        if draw(st.booleans()):
            text += f"{space},{draw(_SPACE)}{draw(_plain_value())}"
            continue
        comma = draw(st.sampled_from(["", ","]))
        option = f"\\{draw(_SPACE)}{draw(st.sampled_from(_NAMES))}"
        if draw(st.booleans()):
            option += f"{draw(_SPACE)}:={draw(_SPACE)}{draw(_plain_value())}"
        text += f"{space}{comma}{draw(_SPACE)}{option}"
    return text + draw(st.sampled_from(["", " ", ",", " ;"])) + ";"


@settings(max_examples=400, deadline=None)
@given(_statement())
def test_the_plain_call_pattern_takes_no_statement_the_general_one_refuses(statement):
    """The lexer tries the pattern of plain argument lists before the general one: each
    statement the first takes, the second takes too (so they give the same tokens), and
    the first takes the calls most programs write."""
    patterns = _patterns()
    if re.fullmatch(patterns["plain_call"], statement):
        assert re.fullmatch(patterns["general_call"], statement), statement


def test_the_plain_call_pattern_takes_the_usual_moves():
    plain = _patterns()["plain_call"]
    for statement in ["MoveL p5, v200, z0, tMill\\WObj:=wPlate;",
                      "MoveJ Offs(p7,0,0,-10),v100,z1,tool0;",
                      "MoveL Offs(p7, 0, 0, -10), v1000, z50, tool1\\WObj:=wobj1;",
                      "MoveL RelTool(p7, 0, 0, -10 \\Rz:=45), v100, fine, tool1;",
                      "MoveL Offs([[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]], "
                      "0, 0, 10), v100, z1, tool1;",
                      "MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],"
                      "v100,fine,tool0\\WObj:=wobj1;",
                      "MoveC p1, p2, v100 \\V:=120, z1, tool0;",
                      "MoveL RelTool(Offs(p7,0,0,10),0,0,0 \\Rz:=45), v100, z1, tool1;",
                      "MoveL Offs( RelTool(p7, 0, 0, -20), 0, 0, nLift), v100, z1, tool1;",
                      "SetDO doGrip, 1;", "Foo a \\Switch, b \\Opt:=- 2;"]:
        assert re.fullmatch(plain, statement), statement
    assert not re.fullmatch(plain, "MoveL p1, v100, z1, tool0, ;")
    assert re.fullmatch(plain, "MoveL Offs(p1, 0, 0, -nLift), v100, z1, tool0;")
    # names with components and indices of names and numbers, in offsets and as values
    for statement in ["MoveL Offs(p1,0,0,n.z), v100, z1, tool0;",
                      "MoveL Offs(p0,tMill.tframe.trans.x*0,p0.trans.x*2,0),v100,z1,t;",
                      "MoveL path{3}, v100, z1, tool0;", "MoveL grid{i, 2}.trans, v1, z1, t;",
                      "MoveL Offs(path{3},0,0,nZ{2}),v100,z1,t;",
                      "MoveL RelTool(Offs(p{1},0,0,1),0,0,0),v100,z1,t;"]:
        assert re.fullmatch(plain, statement), statement
    assert not re.fullmatch(plain, "MoveL Offs(p1,0,0,n{i+1}), v100, z1, tool0;")
    assert not re.fullmatch(plain, "MoveL path{i+1}, v100, z1, tool0;")
    assert re.fullmatch(plain, "MoveL Offs(p1,0,0,n*2), v100, z1, tool0;")
    assert re.fullmatch(plain, "MoveL Offs(p1, nDx * 2, 0, nLift + 5), v100, z1, tool0;")
    assert not re.fullmatch(plain, "MoveL Offs(p1,0,0,n MOD 2), v100, z1, tool0;")
    assert not re.fullmatch(plain, "MoveL Offs(p1,0,0,(n+1)*2), v100, z1, tool0;")
    assert not re.fullmatch(plain, "MoveL Offs(Offs(Offs(p1,0,0,1),0,0,1),0,0,1),v1,z1,t;")
